"""Observations of the non-overlapping multi-camera setting (seed 002, section 1.4.1;
seed 000, section 2) and their validation.

One observation ``y_k = (o_k, d_k)`` summarises one pass of a person through one
camera's field of view: appearance ``o_k`` (``obs_dim = r``) and spatio-temporal part
``d_k = (l_k, te_k, tq_k, be_k, bq_k)``: camera, enter / quit time, enter / quit border.
Observations are ordered by quit time (a camera reports a pass when the person leaves).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from dbn.checks import MAX_SCALE, refuse_complex
from dbn.errors import InputError, NonFiniteError, ShapeError, TimeOrderError

__all__ = [
    "Observations",
    "validate_observations",
    "concat_observations",
    "take",
    "MAX_APPEARANCE",
    "MAX_TIME",
]

#: Largest accepted ``|appearance|`` entry. Appearance features (colour descriptors,
#: histograms) are expected of order 1-1000; beyond 1e6 their squares in the Gaussian /
#: Normal-inverse-Wishart updates lose all precision (an appearance of 1e50 put NaN into
#: the ADF state, issue 14), so they are rejected and must be rescaled.
MAX_APPEARANCE = 1e6

#: Largest accepted ``|t_enter|``, ``|t_quit|`` (seconds): :data:`dbn.checks.MAX_SCALE`.
#: The travel-time Gaussians square time differences; a t_enter of -1e300 ran both trackers
#: to rc 0 (-1e308 with an overflow warning). Such a time is a unit mistake, so it is
#: rejected (the bound of the trackers' time settings).
MAX_TIME = MAX_SCALE


class Observations(NamedTuple):
    """A batch of ``num_obs`` observations, time ordered by quit time.

    Attributes
    ----------
    appearance : float (num_obs, obs_dim)   finite, |value| <= MAX_APPEARANCE (1e6)
    camera : int (num_obs,)          camera index l_k in [0, num_cameras)
    t_enter : float (num_obs,)       te_k, |te_k| <= MAX_TIME (1e100)
    t_quit : float (num_obs,)        tq_k >= te_k, nondecreasing in k, |tq_k| <= MAX_TIME
    border_enter : int (num_obs,)    be_k in [0, num_borders)
    border_quit : int (num_obs,)     bq_k in [0, num_borders)
    """

    appearance: np.ndarray
    camera: np.ndarray
    t_enter: np.ndarray
    t_quit: np.ndarray
    border_enter: np.ndarray
    border_quit: np.ndarray

    @property
    def num_obs(self) -> int:
        """Number of observations (``len()`` of a NamedTuple is its field count, 6)."""
        return int(np.shape(self.camera)[0])


def take(obs: Observations, index) -> Observations:
    """The observations selected by ``index`` (slice, int array or bool mask)."""
    return Observations(*(np.asarray(x)[index] for x in obs))


def concat_observations(parts) -> Observations:
    """Concatenate several :class:`Observations` along the observation axis."""
    parts = list(parts)
    return Observations(*(np.concatenate([np.asarray(p[i]) for p in parts]) for i in range(6)))


def _check_index_range(name: str, v: np.ndarray, limit: int) -> None:
    """Raise a :class:`ShapeError` naming the first entry of ``v`` (integers, or floats
    with integer values) outside ``0..limit - 1``, as given (before any cast)."""
    out = (v < 0) | (v >= limit)
    if out.any():
        k = int(np.argmax(out))
        what = "camera" if name == "camera" else "border"
        raise ShapeError(f"{name}[{k}] = {v[k]}: unknown {what} (valid: 0..{limit - 1})")


def validate_observations(
    obs: Observations,
    obs_dim: int,
    num_cameras: int,
    num_borders: int,
    last_t_quit: float = -np.inf,
) -> Observations:
    """Check a batch of observations and return it as clean numpy arrays.

    Raises (all ``ValueError`` subclasses of :mod:`dbn.errors`, message naming the
    field, the observation index and the value): :class:`ShapeError` for a wrong shape
    or appearance dimension, :class:`NonFiniteError` for NaN / inf,
    :class:`~dbn.errors.InputError` (``ShapeError``) for an unknown camera or border,
    :class:`TimeOrderError` for quit before enter or quit times going backwards
    (also against ``last_t_quit``, the last quit time a tracker has seen).
    """
    app, fields, ints = _as_arrays(obs)
    if app.ndim != 2 or app.shape[1] != obs_dim:
        raise ShapeError(f"appearance: expected shape (num_obs, {obs_dim}), got {app.shape}")
    n = app.shape[0]
    for name, v in {**fields, **ints}.items():
        if v.shape != (n,):
            raise ShapeError(f"{name}: expected shape ({n},), got {v.shape}")
    _check_appearance_values(app)
    for name, v in fields.items():
        if not np.isfinite(v).all():
            k = int(np.argmax(~np.isfinite(v)))
            raise NonFiniteError(f"{name}[{k}] = {v[k]} is not finite")
        if (np.abs(v) > MAX_TIME).any():
            k = int(np.argmax(np.abs(v) > MAX_TIME))
            raise InputError(f"{name}[{k}] = {v[k]:g}: |time| must be <= {MAX_TIME:g} s")
    limits = {"camera": num_cameras, "border_enter": num_borders, "border_quit": num_borders}
    clean = {name: _index_column(name, v, limits[name]) for name, v in ints.items()}
    te, tq = fields["t_enter"], fields["t_quit"]
    _check_quit_times(te, tq, last_t_quit)
    return Observations(app, clean["camera"], te, tq, clean["border_enter"], clean["border_quit"])


def _as_arrays(obs: Observations) -> tuple[np.ndarray, dict[str, np.ndarray], dict[str, np.ndarray]]:
    """The observations as numpy arrays: appearance (float64, a single 1-D observation made
    a row), the times (float64) and the indices (as given); complex or unreadable input
    raises, as does an object without :class:`Observations`' fields."""
    missing = [name for name in Observations._fields if not hasattr(obs, name)]
    if missing:
        raise InputError(f"expected Observations (fields {', '.join(Observations._fields)}), "
                         f"got {type(obs).__name__}")  # fmt: skip
    for name in Observations._fields:
        refuse_complex(name, getattr(obs, name))
    try:
        app = np.asarray(obs.appearance, dtype=np.float64)
        fields = {
            "t_enter": np.asarray(obs.t_enter, dtype=np.float64),
            "t_quit": np.asarray(obs.t_quit, dtype=np.float64),
        }
        ints = {
            "camera": np.asarray(obs.camera),
            "border_enter": np.asarray(obs.border_enter),
            "border_quit": np.asarray(obs.border_quit),
        }
    except (TypeError, ValueError) as exc:
        raise ShapeError(f"observations: cannot read as arrays ({exc})") from exc
    if app.ndim == 1:
        app = app[None, :]
        fields = {k: v.reshape(-1) for k, v in fields.items()}
        ints = {k: v.reshape(-1) for k, v in ints.items()}
    return app, fields, ints


def _check_appearance_values(app: np.ndarray) -> None:
    """Every appearance entry finite and at most :data:`MAX_APPEARANCE` in magnitude."""
    bad = ~np.isfinite(app)
    if bad.any():
        k, i = np.argwhere(bad)[0]
        raise NonFiniteError(f"appearance[{k}, {i}] = {app[k, i]} is not finite")
    big = np.abs(app) > MAX_APPEARANCE
    if big.any():
        k, i = np.argwhere(big)[0]
        raise InputError(
            f"appearance[{k}, {i}] = {app[k, i]:g}: |appearance| must be <= {MAX_APPEARANCE:g}"
            " (features are expected of order 1-1000; rescale them)"
        )


def _index_column(name: str, v: np.ndarray, limit: int) -> np.ndarray:
    """An index column (camera or border) as int64: integers (or integral floats) in
    ``[0, limit)``."""
    if v.dtype.kind == "f":
        if not np.isfinite(v).all():
            k = int(np.argmax(~np.isfinite(v)))
            raise NonFiniteError(f"{name}[{k}] = {v[k]} is not finite")
        if (v != np.round(v)).any():
            k = int(np.argmax(v != np.round(v)))
            raise ShapeError(f"{name}[{k}] = {v[k]} is not an integer index")
    elif v.dtype.kind not in "iu":
        raise ShapeError(f"{name}: expected integer indices, got dtype {v.dtype}")
    _check_index_range(name, v, limit)  # before the cast: 1e300 must not wrap
    return v.astype(np.int64)


def _check_quit_times(te: np.ndarray, tq: np.ndarray, last_t_quit: float) -> None:
    """Quit after enter, and quit times non-decreasing (from ``last_t_quit`` on)."""
    if (tq < te).any():
        k = int(np.argmax(tq < te))
        raise TimeOrderError(f"t_quit[{k}] = {tq[k]} is before t_enter[{k}] = {te[k]} (quit before enter)")
    prev = np.concatenate([[last_t_quit], tq[:-1]])
    if (tq < prev).any():
        k = int(np.argmax(tq < prev))
        raise TimeOrderError(
            f"t_quit[{k}] = {tq[k]} is earlier than the previous observation's t_quit = {prev[k]}"
            " (observations must be ordered by quit time)"
        )
