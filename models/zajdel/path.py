r"""The path model of the multi-camera tracker (seed 002, eq. 1.19; seed 000, eq. 2):
where and when a person re-appears after leaving a camera.

* Returning person, last seen at observation j:
  :math:`p_\delta(d_k \mid d_j) = P(l_k, b^e_k \mid l_j, b^q_j)\;
  \mathrm{TN}(t^e_k - t^q_j;\ \mu(l_j,l_k),\ \sigma^2(l_j,l_k),\ [0, t_{max}])`:
  a camera-and-border transition table times a truncated-normal travel time.
* New person: :math:`p_{\delta_0}(d_k) = P(l_k, b^e_k) / W`, the entry table times a
  uniform density of the entry time over a window of length W (units 1/time, so that
  "continue a track" and "new person" are both densities in time: rescaling every time,
  travel-time parameter and W by one factor leaves every posterior unchanged).

Impossible moves (transition probability 0, negative or over-long travel time) give a
log-probability of ``-inf``, never NaN. The quit border and the dwell time in a field
of view are not modelled (constant factors, seed 000 section 3).
"""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp
import numpy as np
from jax.scipy.special import log_ndtr as _jlog_ndtr
from scipy.special import log_ndtr as _log_ndtr

from dbn.checks import real_array
from dbn.errors import CPDShapeError, ModelError, NegativeProbabilityError, NotNormalizedError

__all__ = [
    "PathModel",
    "make_path_model",
    "log_p_delta",
    "log_p_delta_jax",
    "travel_log_norm",
    "log_p_delta_cached",
    "log_p_delta0",
    "pairwise_path_logprob",
    "continuation_horizon",
    "log_stay_prob",
    "stay_table",
    "log_stay_lookup",
    "log_new_rate",
]


_HALF_LOG_2PI = 0.5 * float(np.log(2.0 * np.pi))


class PathModel(NamedTuple):
    """Parameters of the path model (arrays; ``C`` cameras, ``B`` borders per camera).

    Attributes
    ----------
    log_trans : (C, B, C, B)  log P(l_k, be_k | l_j, bq_j); for each (l_j, bq_j) the
        last two axes sum to 1 in probability
    log_entry : (C, B)        log P(l_k, be_k) of a new person (sums to 1)
    travel_mean : (C, C)      mu(l_j, l_k), time units
    travel_std : (C, C)       sigma(l_j, l_k) > 0
    max_travel : ()           upper truncation of the travel time (may be inf)
    window : ()               W, length of the entry-time window of a new person
    new_rate : ()             lambda, new people entering per unit time (1/time; NaN:
        not set), used by the ADF's birth-leave link prior (``ADFConfig.birth_leave``)
    leave_prob : ()           probability that a pass is a person's last (they leave the
        building; NaN: not set), same use
    rate_bin : ()             birth-leave model: ``new_rate`` may be an arrival-rate
        profile, shape (num_bins,), piecewise constant over bins of this length from
        time 0 (the last bin extends to infinity); inf (default): one constant rate
    """

    log_trans: np.ndarray
    log_entry: np.ndarray
    travel_mean: np.ndarray
    travel_std: np.ndarray
    max_travel: np.ndarray
    window: np.ndarray
    new_rate: np.ndarray = np.float64(np.nan)
    leave_prob: np.ndarray = np.float64(np.nan)
    rate_bin: np.ndarray = np.float64(np.inf)

    @property
    def num_cameras(self) -> int:
        return int(np.shape(self.log_entry)[0])

    @property
    def num_borders(self) -> int:
        return int(np.shape(self.log_entry)[1])

    def rescale_time(self, factor: float) -> PathModel:
        """The same model in a time unit ``factor`` times smaller (times multiplied)."""
        return self._replace(
            travel_mean=np.asarray(self.travel_mean) * factor,
            travel_std=np.asarray(self.travel_std) * factor,
            max_travel=np.asarray(self.max_travel) * factor,
            window=np.asarray(self.window) * factor,
            new_rate=np.asarray(self.new_rate) / factor,
            rate_bin=np.asarray(self.rate_bin) * factor,
        )


def make_path_model(
    trans: np.ndarray,
    entry: np.ndarray,
    travel_mean: np.ndarray,
    travel_std: np.ndarray,
    window: float,
    max_travel: float = np.inf,
) -> PathModel:
    """Validate probability tables and travel-time parameters and build a :class:`PathModel`.

    Parameters
    ----------
    trans : (C, B, C, B) probabilities P(l_k, be_k | l_j, bq_j)
    entry : (C, B) probabilities P(l_k, be_k) of a new person
    travel_mean, travel_std : (C, C)
    window : W > 0
    max_travel : upper bound of a travel time (> 0, may be inf)
    """
    trans, entry = real_array("trans", trans, ModelError), real_array("entry", entry, ModelError)
    if entry.ndim != 2:
        raise CPDShapeError(f"entry: expected shape (num_cameras, num_borders), got {entry.shape}")
    C, B = entry.shape
    if trans.shape != (C, B, C, B):
        raise CPDShapeError(f"trans: expected shape {(C, B, C, B)}, got {trans.shape}")
    for name, t in (("trans", trans), ("entry", entry)):
        if not np.isfinite(t).all() or (t < 0).any():
            raise NegativeProbabilityError(f"{name}: holds a negative or non-finite entry")
    rows = trans.reshape(C * B, C * B).sum(1)
    if np.abs(rows - 1).max() > 1e-9:
        i = int(np.argmax(np.abs(rows - 1)))
        raise NotNormalizedError(f"trans[{i // B}, {i % B}] sums to {rows[i]}, not 1")
    if abs(entry.sum() - 1) > 1e-9:
        raise NotNormalizedError(f"entry sums to {entry.sum()}, not 1")
    mu, sd = (real_array(n, v, ModelError) for n, v in (("travel_mean", travel_mean),
                                                          ("travel_std", travel_std)))
    try:
        mu, sd = (np.broadcast_to(v, (C, C)).copy() for v in (mu, sd))
    except ValueError:
        raise CPDShapeError(f"travel_mean {mu.shape} / travel_std {sd.shape}: expected "
                            f"{(C, C)} or a shape that broadcasts to it") from None
    if not np.isfinite(mu).all() or not np.isfinite(sd).all() or (sd <= 0).any():
        raise ModelError("travel_mean / travel_std: must be finite with travel_std > 0")
    window, max_travel = (real_array(n, v, ModelError) for n, v in (("window", window),
                                                                    ("max_travel", max_travel)))
    if window.shape or max_travel.shape:
        raise ModelError(f"window, max_travel: expected numbers, got shapes {window.shape}, "
                         f"{max_travel.shape}")  # fmt: skip
    if not (np.isfinite(window) and window > 0):
        raise ModelError(f"window = {window}: must be finite and > 0")
    if not max_travel > 0:
        raise ModelError(f"max_travel = {max_travel}: must be > 0")
    with np.errstate(divide="ignore"):
        return PathModel(
            np.log(trans), np.log(entry), mu, sd, np.float64(max_travel), np.float64(window)
        )


def _trunc_normal_logpdf(xp, log_ndtr, x, mu, sd, upper):
    """log TN(x; mu, sd^2, [0, upper]); -inf outside [0, upper]; never NaN."""
    ok = (x >= 0) & (x <= upper)
    xs = xp.where(ok, x, mu)
    z = (xs - mu) / sd
    a = mu / sd  # Phi(mu/sd) = P(X > 0)
    lo = log_ndtr(a)
    b = (mu - upper) / sd  # P(X > upper) = Phi(b)
    hi = log_ndtr(xp.where(xp.isfinite(b), b, -40.0))
    lognorm = lo + xp.log1p(-xp.exp(xp.minimum(hi - lo, 0.0)) * xp.isfinite(b))
    val = -0.5 * z * z - _HALF_LOG_2PI - xp.log(sd) - lognorm
    return xp.where(ok, val, -xp.inf)


def _log_p_delta(xp, log_ndtr, path, cam_j, bq_j, tq_j, cam, be, te):
    lt = path.log_trans[cam_j, bq_j, cam, be]
    mu = path.travel_mean[cam_j, cam]
    sd = path.travel_std[cam_j, cam]
    tn = _trunc_normal_logpdf(xp, log_ndtr, te - tq_j, mu, sd, path.max_travel)
    return xp.where(xp.isfinite(lt), lt + tn, -xp.inf)


def log_p_delta(path: PathModel, cam_j, bq_j, tq_j, cam, be, te) -> np.ndarray:
    r"""log p_delta(d_k | d_j) (numpy, broadcasting), seed 002 eq. 1.19 / seed 000 eq. 2.

    Parameters
    ----------
    path : PathModel
    cam_j, bq_j, tq_j : camera, quit border, quit time of the earlier observation j
    cam, be, te : camera, enter border, enter time of observation k

    Returns
    -------
    array of the broadcast shape; -inf for an impossible move.
    """
    p = PathModel(*(np.asarray(x) for x in path))
    return _log_p_delta(
        np,
        _log_ndtr,
        p,
        np.asarray(cam_j),
        np.asarray(bq_j),
        np.asarray(tq_j, float),
        np.asarray(cam),
        np.asarray(be),
        np.asarray(te, float),
    )


def log_p_delta_jax(path: PathModel, cam_j, bq_j, tq_j, cam, be, te):
    """jax twin of :func:`log_p_delta` (jit-able)."""
    return _log_p_delta(jnp, _jlog_ndtr, path, cam_j, bq_j, tq_j, cam, be, te)


def travel_log_norm(path: PathModel):
    r"""The data-free part of the travel-time density, one entry per camera pair (jax):
    :math:`-\tfrac12\log 2\pi - \log\sigma(l_j, l_k) - \log P(0 \le X \le
    \text{max\_travel})`, shape (C, C). Computed once per model so that the per-link
    path term (:func:`log_p_delta_cached`) needs no special function."""
    mu, sd = path.travel_mean, path.travel_std
    lo = _jlog_ndtr(mu / sd)
    b = (mu - path.max_travel) / sd
    hi = _jlog_ndtr(jnp.where(jnp.isfinite(b), b, -40.0))
    lognorm = lo + jnp.log1p(-jnp.exp(jnp.minimum(hi - lo, 0.0)) * jnp.isfinite(b))
    return -_HALF_LOG_2PI - jnp.log(sd) - lognorm


def log_p_delta_cached(path: PathModel, log_norm, cam_j, bq_j, tq_j, cam, be, te):
    """:func:`log_p_delta_jax` with the camera-pair normalisers precomputed
    (``log_norm = travel_log_norm(path)``); equal to it up to rounding."""
    lt = path.log_trans[cam_j, bq_j, cam, be]
    mu = path.travel_mean[cam_j, cam]
    x = te - tq_j
    ok = (x >= 0) & (x <= path.max_travel)
    z = (jnp.where(ok, x, mu) - mu) / path.travel_std[cam_j, cam]
    tn = jnp.where(ok, -0.5 * z * z + log_norm[cam_j, cam], -jnp.inf)
    return jnp.where(jnp.isfinite(lt), lt + tn, -jnp.inf)


def continuation_horizon(path: PathModel, eps: float) -> np.ndarray:
    r"""Birth-leave model: per (camera, quit border), shape (C, B), the time since a pass
    after which the person is continued with probability below ``eps``:
    :math:`(1-\rho) S(\Delta) / (\rho + (1-\rho) S(\Delta)) < \varepsilon` with
    :math:`S(\Delta) = \sum_{c', b'} P(c', b' \mid c, b)\, P(X_{c c'} > \Delta)` (the
    truncated-normal travel time; :math:`\rho` = ``path.leave_prob``). ``inf`` when
    ``leave_prob`` is not set. Solved once per model by bisection (S is decreasing)."""
    from scipy.special import ndtr

    rho = float(path.leave_prob)
    C, B = np.shape(path.log_entry)
    if not np.isfinite(rho):
        return np.full((C, B), np.inf)
    target = eps * rho / ((1.0 - rho) * (1.0 - eps))
    mu, sd, tmax = (
        np.asarray(x, float) for x in (path.travel_mean, path.travel_std, path.max_travel)
    )
    hi = ndtr((mu - tmax) / sd) if np.isfinite(tmax) else np.zeros_like(mu)
    norm = ndtr(mu / sd) - hi
    trans = np.exp(np.asarray(path.log_trans, float)).sum(axis=-1)  # (C, B, C)

    def surv(d):  # d (C, B) -> S (C, B)
        sf = np.clip(
            (ndtr((mu[:, None, :] - d[..., None]) / sd[:, None, :]) - hi[:, None, :])
            / norm[:, None, :],
            0,
            1,
        )
        return (trans * sf).sum(-1)

    lo = np.zeros((C, B))
    up = np.full((C, B), float(np.max(mu + 40.0 * sd)))
    if np.isfinite(tmax):
        up = np.minimum(up, tmax)
    for _ in range(100):
        mid = 0.5 * (lo + up)
        below = surv(mid) < target
        up, lo = np.where(below, mid, up), np.where(below, lo, mid)
    return up


def log_stay_prob(path: PathModel, cam_j, bq_j, delta) -> np.ndarray:
    r"""Birth-leave model (numpy): :math:`\log g_j(\Delta) = \log(\rho + (1-\rho)
    S_j(\Delta))`, the probability that a person last seen leaving camera ``cam_j``
    through border ``bq_j`` makes no further pass within ``delta`` (>= 0) time: they
    left the building (:math:`\rho` = ``path.leave_prob``), or their travel time, a
    truncated normal after a move drawn from the transition table, is longer
    (:math:`S_j(\Delta) = \sum_{c'} P(c' \mid c_j, b_j)\, P(X_{c_j c'} > \Delta)`).
    Decreases from 1 at ``delta = 0`` to :math:`\log\rho`. ``cam_j, bq_j, delta``
    broadcast together; the result has their shape."""
    from scipy.special import ndtr

    rho = float(path.leave_prob)
    trans = np.exp(np.asarray(path.log_trans, float)).sum(axis=-1)[cam_j, bq_j]  # (..., C)
    mu = np.asarray(path.travel_mean, float)[cam_j]
    sd = np.asarray(path.travel_std, float)[cam_j]
    tmax = float(path.max_travel)
    hi = ndtr((mu - tmax) / sd) if np.isfinite(tmax) else np.zeros_like(mu)
    d = np.maximum(np.asarray(delta, float), 0.0)[..., None]
    sf = np.clip((ndtr((mu - d) / sd) - hi) / (ndtr(mu / sd) - hi), 0.0, 1.0)
    return np.log(rho + (1.0 - rho) * (trans * sf).sum(-1))


def stay_table(path: PathModel, horizon: float, num: int = 512) -> tuple[np.ndarray, float]:
    """:func:`log_stay_prob` tabulated per (camera, quit border) on ``num`` equally
    spaced times over ``[0, horizon]``: ``(table (C, B, num), step)``, for
    :func:`log_stay_lookup` (the filter's per-step work needs no special function)."""
    C, B = np.shape(path.log_entry)
    step = float(horizon) / (num - 1)
    d = np.arange(num) * step
    c, b = np.meshgrid(np.arange(C), np.arange(B), indexing="ij")
    return log_stay_prob(path, c[..., None], b[..., None], d), step


def log_new_rate(path: PathModel, te):
    """log lambda(te) (jax): the birth-leave arrival rate at time ``te``, constant or
    the profile of ``path.rate_bin``-long bins (``te`` before 0 in the first bin)."""
    rate = jnp.atleast_1d(path.new_rate)
    i = jnp.clip(jnp.floor(te / path.rate_bin), 0, rate.shape[0] - 1).astype(jnp.int32)
    return jnp.log(rate[i])


def log_stay_lookup(table, step, cam_j, bq_j, delta):
    """:func:`log_stay_prob` (jax) by linear interpolation in the table of
    :func:`stay_table`; past the table's horizon its last value (about log rho)."""
    num = table.shape[-1]
    u = jnp.clip(jnp.maximum(delta, 0.0) / step, 0.0, num - 1.0)
    i = jnp.minimum(jnp.floor(u).astype(jnp.int32), num - 2)
    f = u - i
    row = table[cam_j, bq_j]
    lo = jnp.take_along_axis(row, i[..., None], axis=-1)[..., 0]
    hi = jnp.take_along_axis(row, (i + 1)[..., None], axis=-1)[..., 0]
    return lo + f * (hi - lo)


def log_p_delta0(path: PathModel, cam, be) -> np.ndarray:
    r""":math:`\log p_{\delta_0}(d_k) = \log P(l_k, b^e_k) - \log W` (numpy, broadcasting)."""
    return np.asarray(path.log_entry)[np.asarray(cam), np.asarray(be)] - np.log(path.window)


def pairwise_path_logprob(obs, path: PathModel) -> tuple[np.ndarray, np.ndarray]:
    """Path log-probabilities of every (earlier, later) pair of a batch of observations.

    Parameters
    ----------
    obs : :class:`models.zajdel.data.Observations` with ``num_obs`` observations
    path : PathModel

    Returns
    -------
    logp0 : (num_obs,)            log p_delta0(d_k) (starts a track)
    logpd : (num_obs, num_obs)    logpd[j, k] = log p_delta(d_k | d_j) for j < k, -inf else
    """
    K = obs.num_obs
    lp = log_p_delta(
        path,
        obs.camera[:, None],
        obs.border_quit[:, None],
        obs.t_quit[:, None],
        obs.camera[None, :],
        obs.border_enter[None, :],
        obs.t_enter[None, :],
    )
    j, k = np.indices((K, K))
    logpd = np.where(j < k, lp, -np.inf)
    return log_p_delta0(path, obs.camera, obs.border_enter), logpd
