"""Running the localisation filters: a stateful :class:`Localizer` and offline helpers.

The algorithms are the generic ones of :mod:`inference.particle` (bootstrap/SIR and the
auxiliary particle filter of seed 002, eqs. 1.11-1.13); this module only wires a
:class:`~models.localization.model.RobotModel` to them, validates input before any state
changes, and pre-processes observations outside jit (the k-d tree of eq. 1.14).
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from dbn.checks import refuse_complex
from dbn.errors import InputError, NonFiniteError, ShapeError, TimeOrderError
from inference.evidence_columns import as_column
from inference.particle import (
    ParticleInfo,
    ParticleState,
    auxiliary_filter,
    bootstrap_filter,
    is_registered_model,
    run,
    run_model,
    systematic,
)
from inference.precision import honours_dtype, precision_scope
from models.localization.model import (
    TWO_PI,
    KNNLocalizationModel,
    KNNObservation,
    RangeBearingLocalizationModel,
    RangeBearingObservation,
    RobotModel,
    circular_mean,
)

__all__ = [
    "Localizer",
    "LocalizationResult",
    "check_observation",
    "check_sequence",
    "check_timestamp",
    "localize",
    "make_filter",
    "pose_summary",
    "position_errors",
]

ALGORITHMS = {"sir": bootstrap_filter, "apf": auxiliary_filter}


def make_filter(
    model: RobotModel,
    num_particles: int,
    algorithm: str = "apf",
    *,
    dtype: Any = jnp.float64,
    ess_threshold: float = 0.5,
    resampler=systematic,
):
    """The :class:`~inference.particle.ParticleFilter` of ``algorithm`` ('sir' or 'apf') for ``model``."""
    if algorithm not in ALGORITHMS:
        raise InputError(f"algorithm = {algorithm!r}, expected one of {sorted(ALGORITHMS)}")
    return ALGORITHMS[algorithm](
        model, num_particles, dtype=dtype, ess_threshold=ess_threshold, resampler=resampler
    )


def pose_summary(state: ParticleState):
    """The filter's mean pose ``(3,)`` (circular mean for the heading): the ``summary`` the
    scans record. Module-level, so jit's cache sees the same function every call."""
    return circular_mean(state.particles, state.log_weights)


class LocalizationResult(NamedTuple):
    """Offline run: filtered mean poses ``(num_timesteps, 3)`` and the stacked step infos."""

    means: np.ndarray
    infos: ParticleInfo
    final_state: ParticleState


@honours_dtype
def localize(
    key: jax.Array,
    model: RobotModel,
    odometry: np.ndarray,
    observations: Any,
    num_particles: int,
    algorithm: str = "apf",
    *,
    dtype: Any = jnp.float64,
    ess_threshold: float = 0.5,
    initial_state: ParticleState | None = None,
) -> LocalizationResult:
    """Filter a whole sequence with ``lax.scan`` (a registered model, the range-bearing one,
    through :func:`~inference.particle.filters.run_model`: one compilation for every noise
    setting of a sequence's shape).

    Parameters
    ----------
    key : PRNG key
    model : RobotModel (k-NN or range-bearing)
    odometry : (num_timesteps, 4) ``(dx, dy, dtheta, dt)``
    observations : leaves with leading axis num_timesteps: for the k-NN model raw scans
        ``(num_timesteps, obs_dim)`` (pre-processed here) or the
        :meth:`KNNSensor.preprocess` output; for the range-bearing model a stacked
        :class:`RangeBearingObservation` of ``(num_timesteps, max_meas)`` arrays. Checked
        on the host before tracing (:func:`check_sequence`).
    num_particles : int
    algorithm : 'apf' (seed 002, eqs. 1.11-1.13) or 'sir'

    Returns
    -------
    LocalizationResult
    """
    actions = model.prepare_actions(odometry)
    if actions.ndim != 3:
        raise ShapeError(f"odometry has shape {np.shape(odometry)}, expected (num_timesteps, 4)")
    pf = make_filter(model, num_particles, algorithm, dtype=dtype, ess_threshold=ess_threshold)
    observations = check_sequence(model, observations, actions.shape[0], dtype)
    steps = jnp.asarray(actions, dtype)
    if is_registered_model(model):  # the range-bearing model: its noise traced, not compiled in
        final, infos, means = run_model(
            key, model, observations, steps, algorithm=ALGORITHMS[algorithm],
            num_particles=num_particles, dtype=dtype, ess_threshold=ess_threshold,
            initial_state=initial_state, summary=pose_summary)  # fmt: skip
    else:
        final, infos, means = run(
            key, pf, observations, steps, initial_state=initial_state, summary=pose_summary
        )
    return LocalizationResult(np.asarray(means), infos, final)


def check_sequence(model: RobotModel, observations: Any, num_steps: int, dtype: Any = jnp.float64):
    """Validate a whole sequence for :func:`localize` on the host, before any tracing.

    Raw k-NN scans ``(num_steps, obs_dim)`` are checked and pre-processed; a
    :class:`KNNObservation` or stacked :class:`RangeBearingObservation` must have leading
    axis ``num_steps`` and pass the checks of :func:`check_observation` at every step.

    Raises
    ------
    ShapeError, NonFiniteError, InputError
    """
    if isinstance(model, KNNLocalizationModel):
        if isinstance(observations, KNNObservation):
            leaves = [np.asarray(a) for a in observations]
            if any(a.ndim == 0 or a.shape[0] != num_steps for a in leaves):
                raise ShapeError(f"observations: every field needs leading axis {num_steps}")
            if not all(np.all(np.isfinite(a)) for a in leaves if a.dtype.kind == "f"):
                raise NonFiniteError("observations hold NaN or infinity")
            return observations
        y = model.sensor.check(observations, "observations")
        if y.ndim != 2 or y.shape[0] != num_steps:
            raise ShapeError(f"observations have shape {y.shape}, expected ({num_steps}, obs_dim)")
        return model.sensor.preprocess(y, dtype=dtype)
    if isinstance(model, RangeBearingLocalizationModel):
        if not isinstance(observations, RangeBearingObservation):
            raise InputError(
                "observations must be a stacked RangeBearingObservation, "
                f"got {type(observations).__name__}"
            )
        lm = np.asarray(observations.landmark)
        if lm.ndim != 2 or lm.shape[0] != num_steps:
            raise ShapeError(
                f"observations.landmark has shape {lm.shape}, expected ({num_steps}, m)"
            )
        # the per-step checks of check_observation, on the whole (num_steps, m) block
        flat = RangeBearingObservation(*(np.asarray(a).reshape(-1) for a in observations))
        if any(np.shape(a) != lm.shape for a in observations):
            raise ShapeError("observations: landmark, range, bearing, mask must share one shape")
        clean = check_observation(model, flat, dtype)
        return RangeBearingObservation(*(jnp.reshape(a, lm.shape) for a in clean))
    return observations


def position_errors(means: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """Euclidean position errors ``(..., num_timesteps)`` between estimated poses
    ``(..., num_timesteps, 3)`` (leading axes: runs) and true poses of the same shape or
    ``(num_timesteps, 3)``. Other shapes are a :class:`ShapeError` (one true pose broadcast
    against every estimate; a truth one step longer raised numpy's broadcast error)."""
    means, truth = np.asarray(means, dtype=np.float64), np.asarray(truth, dtype=np.float64)
    ok = (means.ndim >= 2 and truth.ndim >= 2 and min(means.shape[-1], truth.shape[-1]) >= 2
          and means.shape[-2] == truth.shape[-2] and truth.shape[:-2] in ((), means.shape[:-2]))
    if not ok:
        raise ShapeError(f"means {means.shape} and truth {truth.shape}: expected "
                         "(..., num_timesteps, 3) and (num_timesteps, 3) or the same shape")
    return np.hypot(means[..., 0] - truth[..., 0], means[..., 1] - truth[..., 1])


def check_timestamp(timestamp: Any, last: float | None) -> float | None:
    """``timestamp`` as a float (None stays None) that comes after ``last``; else
    :class:`NonFiniteError`, :class:`InputError` or :class:`TimeOrderError`."""
    if timestamp is None:
        return None
    real = isinstance(timestamp, (int, float, np.integer, np.floating))
    if isinstance(timestamp, bool) or not real:
        raise InputError(f"timestamp must be a number, got {timestamp!r}")
    ts = float(timestamp)
    if not math.isfinite(ts):
        raise NonFiniteError(f"timestamp = {timestamp!r} is not finite")
    if last is not None and ts <= last:
        raise TimeOrderError(f"timestamp = {ts} does not come after {last}")
    return ts


def check_observation(model: RobotModel, observation: Any, dtype: Any = jnp.float64):
    """Validate and pre-process one step's observation for ``model`` (before any state change).

    A raw scan ``(obs_dim,)`` for the k-NN model (projected, looked up, outlier-tested), or
    a :class:`RangeBearingObservation` of ``(max_meas,)`` arrays; raises
    :class:`ShapeError`, :class:`NonFiniteError` or :class:`InputError` naming the field.
    """
    m = model
    if isinstance(m, KNNLocalizationModel):
        return m.sensor.preprocess(m.sensor.check(observation, "observation"), dtype=dtype)
    if isinstance(m, RangeBearingLocalizationModel):
        if not isinstance(observation, RangeBearingObservation):
            raise InputError(
                f"observation must be a RangeBearingObservation, got {type(observation).__name__}"
            )
        for name in RangeBearingObservation._fields:
            refuse_complex(f"observation.{name}", getattr(observation, name))
        lm = np.asarray(observation.landmark)
        if not np.issubdtype(lm.dtype, np.integer):
            raise InputError(f"observation.landmark must hold integer ids, got dtype {lm.dtype}")
        fields = {
            "range": as_column("observation.range", observation.range, "field", np.float64),
            "bearing": as_column("observation.bearing", observation.bearing, "field", np.float64),
            "mask": np.asarray(observation.mask),
        }
        if fields["mask"].dtype != bool:  # "x" or 2 was read as True
            dtype = fields["mask"].dtype
            raise InputError(f"observation.mask must hold booleans, got dtype {dtype}")
        for name, arr in fields.items():
            if arr.shape != lm.shape or lm.ndim != 1:
                raise ShapeError(f"observation.{name} has shape {arr.shape}, landmark {lm.shape}")
        for name in ("range", "bearing"):
            arr = fields[name]
            if not np.all(np.isfinite(arr)):
                i = int(np.flatnonzero(~np.isfinite(arr))[0])
                raise NonFiniteError(f"observation.{name}[{i}] = {arr[i]} is not finite")
        if np.any(fields["range"] < 0):
            i = int(np.flatnonzero(fields["range"] < 0)[0])
            raise InputError(f"observation.range[{i}] = {fields['range'][i]} is negative")
        turns = fields["mask"] & (np.abs(fields["bearing"]) > TWO_PI)
        if np.any(turns):  # a bearing in degrees was taken as radians
            i = int(np.flatnonzero(turns)[0])
            raise InputError(f"observation.bearing[{i}] = {fields['bearing'][i]} is beyond one "
                             "turn: bearings are radians (degrees?)")
        if np.any((lm < 0) | (lm >= len(m.landmarks))):
            raise InputError(f"observation.landmark {lm.tolist()} out of [0, {len(m.landmarks)})")
        return RangeBearingObservation(
            jnp.asarray(lm, jnp.int32),
            jnp.asarray(fields["range"], dtype),
            jnp.asarray(fields["bearing"], dtype),
            jnp.asarray(fields["mask"], bool),
        )
    return observation


class Localizer:
    """A running localiser: one validated ``update`` per time step (seed 002, section 1.3).

    Parameters
    ----------
    key : PRNG key
        Draws the initial particle cloud.
    model : KNNLocalizationModel or RangeBearingLocalizationModel
    num_particles : int
    algorithm : 'apf' or 'sir'
    dtype : float dtype
    ess_threshold : float

    Every ``update`` checks its input (shapes, NaN/inf, time order) before touching the
    state: a rejected input leaves the localiser exactly as it was.
    """

    @honours_dtype
    def __init__(
        self,
        key: jax.Array,
        model: RobotModel,
        num_particles: int,
        algorithm: str = "apf",
        *,
        dtype: Any = jnp.float64,
        ess_threshold: float = 0.5,
    ) -> None:
        self.model = model
        self.dtype = dtype
        self._pf = make_filter(
            model, num_particles, algorithm, dtype=dtype, ess_threshold=ess_threshold
        )
        self._step = jax.jit(self._pf.step)
        self.state: ParticleState = self._pf.init(key)
        self.timestamp: float | None = None
        self.last_info: ParticleInfo | None = None

    def _check_observation(self, observation: Any):
        return check_observation(self.model, observation, self.dtype)

    def update(
        self,
        key: jax.Array,
        odometry: np.ndarray,
        observation: Any,
        timestamp: float | None = None,
    ) -> np.ndarray:
        """Advance one step: move by ``odometry`` ``(4,)``, weigh by ``observation``.

        Parameters
        ----------
        key : PRNG key of this step
        odometry : (4,) ``(dx, dy, dtheta, dt)``
        observation : a raw scan ``(obs_dim,)`` for the k-NN model (projected, looked up and
            outlier-tested here), or a :class:`RangeBearingObservation` of ``(max_meas,)`` arrays
        timestamp : float, optional
            Log time; must increase from update to update.

        Returns
        -------
        (3,) the filtered mean pose.

        Raises
        ------
        ShapeError, NonFiniteError, InputError, TimeOrderError
            Before any change of state.
        """
        ts = check_timestamp(timestamp, self.timestamp)
        with precision_scope(self.dtype):  # float64 by default, whatever jax's global mode
            step = jnp.asarray(self.model.prepare_actions(odometry), self.dtype)
            if step.shape != (4, 3):
                raise ShapeError(f"odometry has shape {np.shape(odometry)}, expected (4,)")
            obs = self._check_observation(observation)
            new_state, info = self._step(key, self.state, obs, step)
        self.state, self.last_info = new_state, info
        if ts is not None:
            self.timestamp = ts
        return self.mean()

    def mean(self) -> np.ndarray:
        """Filtered mean pose ``(3,)`` (circular mean for the heading)."""
        with precision_scope(self.dtype):
            return np.asarray(circular_mean(self.state.particles, self.state.log_weights))
