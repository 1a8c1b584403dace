"""Parameters of the multi-camera tracking model (seed 002, section 1.4)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from dbn.checks import MAX_SCALE, check_type, is_real_number, real_array
from dbn.errors import ModelError
from inference.adf.niw import NIW
from models.zajdel.path import PathModel

__all__ = ["ZajdelParams", "default_prior", "check_params", "check_p_new"]


class ZajdelParams(NamedTuple):
    """Everything the tracker, the oracle and the greedy baseline need.

    Attributes
    ----------
    prior : NIW        theta_0 = (a, kappa, eta, C), scalar batch shape, obs_dim r
    path : PathModel   transition / entry tables, travel times, window W
    p_new : float or None
        None: the seed's uniform label prior over {1..c+1} (seed 002, eq. 1.16);
        a float in (0, 1): P(new person) = p_new, each known person (1 - p_new) / c.
    """

    prior: NIW
    path: PathModel
    p_new: float | None = None

    @property
    def obs_dim(self) -> int:
        return int(np.shape(self.prior.a)[-1])


def default_prior(mean: np.ndarray, within_std: float, between_std: float, dof_extra: float = 4.0) -> NIW:
    r"""A NIW prior theta_0 whose draws match a simulator's appearance model on average:
    :math:`E[V] = \mathrm{within\_std}^2 I` and :math:`\mathrm{Cov}(m) = E[V]/\kappa =
    \mathrm{between\_std}^2 I`; :math:`\eta = r + 1 + \mathrm{dof\_extra}`.

    Parameters
    ----------
    mean : (r,) prior mean of the appearance means
    """
    mean = np.asarray(mean, float)
    r = mean.shape[0]
    eta = r + 1.0 + dof_extra
    C = (eta - r - 1.0) * within_std**2 * np.eye(r)
    kappa = within_std**2 / between_std**2
    return NIW(mean, np.float64(kappa), np.float64(eta), C)


def check_params(params: ZajdelParams) -> None:
    """Raise :class:`~dbn.errors.ModelError` for an invalid prior or label prior."""
    check_type("params", params, ZajdelParams)
    check_type("prior", params.prior, NIW, ModelError)
    a, kappa, eta, C = (_finite(f"prior.{n}", x) for n, x in zip(NIW._fields, params.prior))
    if kappa.shape or eta.shape:
        raise ModelError(f"prior.kappa, prior.eta: expected numbers, got shapes {kappa.shape}, "
                         f"{eta.shape}")  # fmt: skip
    if a.ndim != 1:
        raise ModelError(f"prior.a: expected shape (obs_dim,), got {a.shape}")
    r = a.shape[0]
    if C.shape != (r, r):
        raise ModelError(f"prior.C: expected shape {(r, r)}, got {C.shape}")
    if not kappa > 0:
        raise ModelError(f"prior.kappa = {kappa}: must be > 0")
    if not eta > r + 1:
        raise ModelError(f"prior.eta = {eta}: must be > obs_dim + 1 = {r + 1}")
    try:
        np.linalg.cholesky(C)
    except np.linalg.LinAlgError as exc:
        raise ModelError("prior.C: not symmetric positive definite") from exc
    check_p_new(params.p_new)


def check_p_new(p_new) -> None:
    """A :class:`ModelError` unless ``p_new`` (the label prior's probability of a new
    person) is None or a number in (0, 1): NaN, a bool or text were refused by Python's
    errors or not at all."""
    if p_new is not None and not (is_real_number(p_new) and 0.0 < p_new < 1.0):
        raise ModelError(f"p_new = {p_new!r}: must be None or a number in (0, 1)")


def _finite(name: str, value) -> np.ndarray:
    """``value`` as float64, finite and ``|x| <=`` :data:`~dbn.checks.MAX_SCALE`; else
    :class:`ModelError` naming ``name`` (a NaN prior mean or scale matrix ran to NaN
    posteriors, and text raised numpy's ValueError)."""
    v = real_array(name, value, ModelError)
    if not np.all(np.isfinite(v)) or np.any(np.abs(v) > MAX_SCALE):
        raise ModelError(f"{name}: every number must be finite, |x| <= {MAX_SCALE:g}")
    return v
