r"""The robot of seed 002, section 1.3, declared for the particle engine.

State :math:`s_k = (x, y, \theta)` (metres, radians). Action :math:`u_k` = odometry as a
relative pose in the robot frame plus the elapsed time, ``(dx, dy, dtheta, dt)``, turned
into a ``(4, 3)`` motion step by :meth:`RobotModel.prepare_actions` outside jit. Motion
model (seed 002, section 1.3: Gaussian, mean from the action):

.. math::

    s_k = s_{k-1} \oplus (dx, dy, d\theta) + \epsilon_k, \quad
    \epsilon_k \sim N(0, \mathrm{diag}(\sigma_{xy}^2, \sigma_{xy}^2, \sigma_\theta^2)),

    \sigma_{xy} = a_{xy}\sqrt{dt} + b_{xy}\,\|(dx, dy)\|, \quad
    \sigma_\theta = a_\theta\sqrt{dt} + b_\theta |d\theta|.

Two sensor models share it:

* :class:`KNNLocalizationModel`, the non-parametric sensor model of eq. 1.14: the
  observation is pre-processed outside jit by :class:`KNNSensor` (PCA feature, ``J``
  nearest training features in a k-d tree, outlier test) into a :class:`KNNObservation`
  whose likelihood over all particles is a ``J``-component Gaussian kernel mixture.
* :class:`RangeBearingLocalizationModel`, a parametric range-bearing likelihood to known
  landmarks (for the real MRCLAM data), with a small uniform outlier component.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array
from scipy.spatial import cKDTree

from dbn.checks import (
    MIN_SCALE,
    check_count,
    check_numbers,
    is_real_number,
    real_array,
    refuse_complex,
)
from dbn.errors import InputError, ModelError, NonFiniteError, ShapeError
from inference.evidence_columns import as_column
from inference.particle import StateSpaceModel, register_model
from inference.precision import honours_dtype

__all__ = [
    "MotionNoise",
    "compose",
    "relative_pose",
    "wrap_angle",
    "RobotModel",
    "PCA",
    "fit_pca",
    "KNNObservation",
    "KNNSensor",
    "KNNLocalizationModel",
    "RangeBearingObservation",
    "RangeBearingLocalizationModel",
    "circular_mean",
]

TWO_PI = 2.0 * math.pi


def wrap_angle(a):
    r"""Wrap angles to :math:`[-\pi, \pi)` (numpy or jax arrays, any shape)."""
    xp = jnp if isinstance(a, jax.Array) else np
    return a - TWO_PI * xp.floor((a + math.pi) / TWO_PI)


def compose(poses, delta):
    r"""Pose composition :math:`s \oplus \delta` (delta in the frame of ``s``).

    Parameters
    ----------
    poses : array, shape (..., 3)
    delta : array, shape (..., 3) or (3,)
        ``(dx, dy, dtheta)`` in the robot frame of ``poses``.

    Returns
    -------
    array, shape (..., 3), angle wrapped.
    """
    xp = jnp if isinstance(poses, jax.Array) or isinstance(delta, jax.Array) else np
    x, y, th = poses[..., 0], poses[..., 1], poses[..., 2]
    dx, dy, dth = delta[..., 0], delta[..., 1], delta[..., 2]
    c, s = xp.cos(th), xp.sin(th)
    return xp.stack([x + c * dx - s * dy, y + s * dx + c * dy, wrap_angle(th + dth)], axis=-1)


def relative_pose(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    r"""The ``delta`` with ``a (+) delta = b``: ``b`` in the frame of ``a``; shapes ``(..., 3)``."""
    dx, dy = b[..., 0] - a[..., 0], b[..., 1] - a[..., 1]
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    return np.stack([c * dx + s * dy, -s * dx + c * dy, wrap_angle(b[..., 2] - a[..., 2])], axis=-1)


def circular_mean(particles: Array, log_weights: Array) -> Array:
    """Weighted mean pose ``(x, y, theta)``, the angle by its mean resultant; shape ``(3,)``."""
    w = jnp.exp(log_weights)
    x = w @ particles[:, 0]
    y = w @ particles[:, 1]
    th = jnp.arctan2(w @ jnp.sin(particles[:, 2]), w @ jnp.cos(particles[:, 2]))
    return jnp.stack([x, y, th])


_THETA_MASK = np.array([0.0, 0.0, 1.0])


def _move(particles: Array, step: Array, key: Array | None = None) -> Array:
    """``particles (+) odometry`` (+ Gaussian noise when ``key`` is given), angle wrapped.

    ``step`` is a prepared motion step ``(4, 3)`` (:meth:`RobotModel.prepare_actions`):
    rows ``a, b, c, std`` with ``s' = s + cos(theta) a + sin(theta) b + c + std * z``.
    The per-step numbers are computed outside jit on purpose: inside, XLA on CPU fused
    their scalar arithmetic into the per-particle loop, which ran 3-4x slower.
    """
    dt = particles.dtype
    step = step.astype(dt)
    th = particles[:, 2:3]
    out = particles + jnp.cos(th) * step[0] + jnp.sin(th) * step[1] + step[2]
    if key is not None:
        z = jax.random.normal(key, (3, particles.shape[0]), dtype=dt)
        out = out + z.T * step[3]
    mask = jnp.asarray(_THETA_MASK, dt)
    return out - mask * (TWO_PI * jnp.floor((out + math.pi) * (1.0 / TWO_PI)))


class MotionNoise(NamedTuple):
    """Odometry noise: ``sigma_xy = a_xy sqrt(dt) + b_xy * dist``, ``sigma_theta = a_theta sqrt(dt) + b_theta |dtheta|``."""

    a_xy: float = 0.02
    b_xy: float = 0.1
    a_theta: float = 0.02
    b_theta: float = 0.1


DEFAULT_NOISE = MotionNoise()


def _scale(name: str, value: Any) -> float:
    """A spread the likelihood divides by: a float in ``[MIN_SCALE, MAX_SCALE]``."""
    v = float(check_numbers(name, value, 1)[0])
    if not MIN_SCALE <= v:
        raise ModelError(f"{name} = {v!r} must be >= {MIN_SCALE:g} (the likelihood divides by it)")
    return v


class RobotModel(StateSpaceModel):
    """Initial belief and motion model of the robot (seed 002, section 1.3).

    Parameters
    ----------
    initial_pose : array (3,)
        Mean of the Gaussian initial belief :math:`p(s_0)` (the "initial state estimate").
    initial_std : array (3,)
        Its standard deviations ``(sx, sy, stheta)``.
    noise : MotionNoise
    """

    def __init__(self, initial_pose, initial_std, noise: MotionNoise = DEFAULT_NOISE) -> None:
        self.initial_pose = check_numbers("initial_pose", initial_pose, 3)
        self.initial_std = check_numbers("initial_std", initial_std, 3, low=0.0)
        self.noise = MotionNoise(*check_numbers("noise", noise, len(MotionNoise._fields), low=0.0))

    def sample_initial(self, key: Array, num_particles: int, dtype: Any) -> Array:
        """``(num_particles, 3)`` poses from the Gaussian initial belief (angle wrapped)."""
        z = jax.random.normal(key, (num_particles, 3), dtype=dtype)
        s = jnp.asarray(self.initial_pose, dtype) + z * jnp.asarray(self.initial_std, dtype)
        return s.at[:, 2].set(wrap_angle(s[:, 2]))

    def prepare_actions(self, odometry) -> np.ndarray:
        r"""Motion steps ``(num_timesteps, 4, 3)`` (or ``(4, 3)``) from odometry ``(..., 4)``.

        Odometry rows are ``(dx, dy, dtheta, dt)`` (relative pose in the robot frame and the
        elapsed time). The step holds ``a = (dx, dy, 0)``, ``b = (-dy, dx, 0)``,
        ``c = (0, 0, dtheta)`` and the noise standard deviations
        ``(sigma_xy, sigma_xy, sigma_theta)``, so that the filter computes
        :math:`s \oplus u + \epsilon` with whole-array operations (seed 002, section 1.3).

        Raises
        ------
        ShapeError, NonFiniteError, InputError (negative ``dt``)
        """
        refuse_complex("odometry", odometry)
        u = as_column("odometry", odometry, "observation field", np.float64)
        if u.shape[-1:] != (4,) or u.ndim not in (1, 2):
            raise ShapeError(
                f"odometry has shape {u.shape}, expected (..., 4) = (dx, dy, dtheta, dt)"
            )
        if not np.all(np.isfinite(u)):
            bad = tuple(np.argwhere(~np.isfinite(u))[0])
            raise NonFiniteError(f"odometry{[int(i) for i in bad]} = {u[bad]} is not finite")
        if np.any(u[..., 3] < 0):
            bad = tuple(np.argwhere(u[..., 3] < 0)[0])
            raise InputError(f"odometry dt{[int(i) for i in bad]} = {u[..., 3][bad]} is negative")
        n = self.noise
        dx, dy, dth, dt = (u[..., i] for i in range(4))
        zero = np.zeros_like(dx)
        sxy = n.a_xy * np.sqrt(dt) + n.b_xy * np.hypot(dx, dy)
        sth = n.a_theta * np.sqrt(dt) + n.b_theta * np.abs(dth)
        rows = [
            np.stack([dx, dy, zero], -1),
            np.stack([-dy, dx, zero], -1),
            np.stack([zero, zero, dth], -1),
            np.stack([sxy, sxy, sth], -1),
        ]
        return np.stack(rows, axis=-2)

    def transition_mean(self, particles: Array, action: Array) -> Array:
        r"""Look-ahead point :math:`\mu = s \oplus u` (seed 002, eq. 1.12); shape (num_particles, 3).

        ``action`` is a prepared motion step ``(4, 3)`` (:meth:`prepare_actions`).
        """
        return _move(particles, jnp.asarray(action))

    def sample_transition(self, key: Array, particles: Array, action: Array) -> Array:
        r"""Draw :math:`s_k \sim N(s_{k-1} \oplus u_k, \mathrm{diag}(\sigma^2))`; shape (num_particles, 3).

        ``action`` is a prepared motion step ``(4, 3)`` (:meth:`prepare_actions`).
        """
        return _move(particles, jnp.asarray(action), key)

    def summary(self, state) -> Array:
        """Filtered mean pose (circular mean for the angle); shape (3,)."""
        return circular_mean(state.particles, state.log_weights)


# --- the non-parametric sensor model of seed 002, section 1.3.2 --------------------------------
class PCA(NamedTuple):
    """Linear projection ``z = (y - mean) @ components.T``.

    Attributes
    ----------
    mean : (obs_dim,)
    components : (feature_dim, obs_dim), orthonormal rows
    """

    mean: np.ndarray
    components: np.ndarray

    def project(self, y: np.ndarray) -> np.ndarray:
        """Features ``(..., feature_dim)`` of observations ``(..., obs_dim)``."""
        return (np.asarray(y, dtype=np.float64) - self.mean) @ self.components.T


def fit_pca(y: np.ndarray, feature_dim: int) -> PCA:
    """PCA of training observations ``(num_train, obs_dim)`` (eigenvectors of the scatter matrix; seed 002, section 1.3.2)."""
    y = np.asarray(y, dtype=np.float64)
    if y.ndim != 2 or not 1 <= feature_dim <= min(y.shape):
        raise ShapeError(f"training observations {y.shape} cannot give {feature_dim} components")
    mean = y.mean(0)
    yc = y - mean
    scatter = yc.T @ yc  # (obs_dim, obs_dim): eigh of it is far cheaper than an SVD of y
    evals, evecs = np.linalg.eigh(0.5 * (scatter + scatter.T))
    order = np.argsort(evals)[::-1][:feature_dim]
    return PCA(mean, evecs[:, order].T.copy())


class KNNObservation(NamedTuple):
    r"""A pre-processed observation for the k-NN likelihood of eq. 1.14 (one step or stacked).

    Attributes
    ----------
    centres : (..., J, 3)
        Training poses :math:`s_j^*` of the ``J`` nearest training features, nearest first.
    log_lambda : (..., J)
        :math:`\log \lambda_j = \log(2(J-j+1)/(J(J+1)))`.
    valid : (...,) bool
        False when the outlier rule fired (nearest neighbour farther than the threshold):
        the filter then only propagates.
    nn_distance : (...,)
        Distance from the feature to its first neighbour.
    """

    centres: Any
    log_lambda: Any
    valid: Any
    nn_distance: Any


class KNNSensor:
    r"""Nearest-neighbour sensor model :math:`p(z|s) = \alpha\sum_j \lambda_j(z)\phi(s|s_j^*)` (seed 002, eq. 1.14).

    Parameters
    ----------
    train_poses : array (num_train, 3)
        Grid of training poses :math:`s_n^*`.
    train_observations : array (num_train, obs_dim)
        Observations :math:`y_n^*` taken there.
    feature_dim : int
        PCA components kept (the feature :math:`z`).
    num_neighbours : int
        ``J``.
    cell_xy, cell_theta : float
        Grid bin sizes; the kernel bandwidths are half of them (seed 002, section 1.3.2).
    threshold : float
        Outlier rule: an observation whose feature is farther than this from its first
        neighbour is skipped (``valid = False``). ``inf`` disables it.
    """

    def __init__(
        self,
        train_poses: np.ndarray,
        train_observations: np.ndarray,
        *,
        feature_dim: int = 16,
        num_neighbours: int = 10,
        cell_xy: float,
        cell_theta: float,
        threshold: float = math.inf,
    ) -> None:
        poses = real_array("train_poses", train_poses, ModelError)
        obs = real_array("train_observations", train_observations, ModelError)
        if (
            poses.ndim != 2
            or poses.shape[1] != 3
            or obs.ndim != 2
            or obs.shape[0] != poses.shape[0]
        ):
            raise ShapeError(
                f"train_poses {poses.shape} / train_observations {obs.shape} do not match"
            )
        if not (np.all(np.isfinite(poses)) and np.all(np.isfinite(obs))):
            raise NonFiniteError("training poses/observations hold NaN or inf")
        J = check_count("num_neighbours", num_neighbours)  # 2.5 ran as 2, True as 1
        if not J <= poses.shape[0]:
            raise InputError(f"num_neighbours = {num_neighbours} not in [1, {poses.shape[0]}]")
        check_count("feature_dim", feature_dim)  # 1.5 raised Python's slice TypeError
        cell_xy, cell_theta = check_numbers("cell_xy, cell_theta", (cell_xy, cell_theta), 2,
                                            low=MIN_SCALE)  # 0 or NaN: a NaN kernel
        if not (is_real_number(threshold) and threshold > 0):  # NaN, <= 0: skipped every one
            raise ModelError(f"threshold = {threshold!r}: a distance > 0 (inf: no outliers)")
        self.train_poses = poses
        stride = max(1, len(obs) // 6000)  # PCA from <= ~6000 evenly spaced training rows
        self.pca = fit_pca(obs[::stride], feature_dim)
        self.train_features = self.pca.project(obs)
        self.tree = cKDTree(self.train_features)
        self.num_neighbours = J
        self.bandwidth = np.array([cell_xy / 2.0, cell_xy / 2.0, cell_theta / 2.0])
        self.threshold = float(threshold)
        j = np.arange(1, J + 1)
        self.log_lambda = np.log(2.0 * (J - j + 1) / (J * (J + 1)))
        self.obs_dim = obs.shape[1]

    def check(self, observations: np.ndarray, name: str = "observations") -> np.ndarray:
        """Validate raw observations ``(num_timesteps, obs_dim)`` or ``(obs_dim,)``; raise before any use."""
        refuse_complex(name, observations)
        y = np.asarray(observations, dtype=np.float64)
        if y.shape[-1:] != (self.obs_dim,) or y.ndim not in (1, 2):
            raise ShapeError(f"{name} has shape {y.shape}, expected (..., {self.obs_dim})")
        if not np.all(np.isfinite(y)):
            bad = tuple(np.argwhere(~np.isfinite(y))[0])
            raise NonFiniteError(f"{name}{[int(i) for i in bad]} = {y[bad]} is not finite")
        return y

    def nearest_distance(self, observations: np.ndarray) -> np.ndarray:
        """Feature distance to the first training neighbour, shape ``(num_timesteps,)``."""
        d, _ = self.tree.query(self.pca.project(self.check(observations)), k=1)
        return np.atleast_1d(d)

    @honours_dtype
    def preprocess(self, observations: np.ndarray, dtype: Any = np.float64) -> KNNObservation:
        """Project, query the k-d tree and apply the outlier rule, outside jit.

        Parameters
        ----------
        observations : array (num_timesteps, obs_dim) or (obs_dim,)
        dtype : float dtype of the returned arrays (float64 is kept whatever jax's mode)

        Returns
        -------
        KNNObservation
            Stacked over time (leading axis num_timesteps) or for one step.
        """
        y = self.check(observations)
        single = y.ndim == 1
        y2 = y[None] if single else y
        dist, idx = self.tree.query(self.pca.project(y2), k=self.num_neighbours)
        dist = dist.reshape(len(y2), -1)
        idx = idx.reshape(len(y2), -1)
        centres = self.train_poses[idx].astype(dtype)
        log_lam = np.broadcast_to(self.log_lambda, idx.shape).astype(dtype)
        valid = dist[:, 0] <= self.threshold
        out = KNNObservation(centres, log_lam, valid, dist[:, 0].astype(dtype))
        if single:
            out = KNNObservation(*(a[0] for a in out))
        return KNNObservation(*(jnp.asarray(a) for a in out))


def _knn_quadratic(xt: Array, observation: KNNObservation, inv_bandwidth: Array) -> Array:
    """Log kernel terms ``(J, num_particles)``: log lambda_j - |(s - s_j^*) / h|^2 / 2 (angle wrapped).

    Coordinates are scaled by the inverse bandwidths first (per particle and per centre),
    so the ``J x num_particles`` loop only subtracts, wraps and squares.
    """
    dt = xt.dtype
    ib = inv_bandwidth.astype(dt)
    xs = xt * ib[:, None]  # (3, num_particles), scaled
    cs = observation.centres.astype(dt) * ib[None, :]  # (J, 3), scaled
    period = TWO_PI * ib[2]
    dx = xs[0][None, :] - cs[:, 0:1]
    dy = xs[1][None, :] - cs[:, 1:2]
    dth = xs[2][None, :] - cs[:, 2:3]
    dth = dth - period * jnp.round(dth * (1.0 / period))
    return observation.log_lambda.astype(dt)[:, None] - 0.5 * (dx * dx + dy * dy + dth * dth)


def knn_log_likelihood(
    particles: Array, observation: KNNObservation, inv_bandwidth: Array, log_norm: float
) -> Array:
    r""":math:`\log\sum_j \lambda_j \phi(s|s_j^*)` for every particle (eq. 1.14, without :math:`\alpha`).

    :math:`\phi` is a Gaussian kernel in ``(x, y, theta)`` (angle difference wrapped to
    :math:`[-\pi, \pi)`) with standard deviations ``1 / inv_bandwidth``. Computed with the
    components along the leading axis (fast on CPU). Every term is at most
    :math:`\log\lambda_j \le 0`, so ``log(sum(exp(q + c))) - c`` with a fixed shift ``c``
    (80 in float32, 700 in float64) cannot overflow; if any particle's sum underflows
    (a particle farther than about 18 bandwidths from every centre) the whole batch takes
    the exact max-shifted path instead. Both paths compute the same number.

    Parameters
    ----------
    particles : (num_particles, 3)
    observation : KNNObservation for one step (centres (J, 3), log_lambda (J,), valid ())
    inv_bandwidth : (3,) reciprocal kernel standard deviations
    log_norm : float, log normaliser of the 3-D Gaussian kernel

    Returns
    -------
    (num_particles,); zeros when ``observation.valid`` is False (only propagate).
    """
    dt = particles.dtype

    def skip(_):
        return jnp.zeros(particles.shape[0], dt)

    def evaluate(_):
        q = _knn_quadratic(particles.T, observation, inv_bandwidth)
        shift = 80.0 if dt == jnp.float32 else 700.0
        ones = jnp.ones((q.shape[0],), dt)
        total = ones @ jnp.exp(q + jnp.asarray(shift, dt))
        tiny = jnp.finfo(dt).tiny

        def fast(_):
            return jnp.log(total) - jnp.asarray(shift, dt)

        def exact(_):
            m = jax.lax.fori_loop(1, q.shape[0], lambda j, m: jnp.maximum(m, q[j]), q[0])
            safe = jnp.where(jnp.isfinite(m), m, jnp.zeros_like(m))
            return safe + jnp.log(ones @ jnp.exp(q - safe[None, :]))

        ll = jax.lax.cond(jnp.all(total >= tiny), fast, exact, None)
        return ll + jnp.asarray(log_norm, dt)

    return jax.lax.cond(observation.valid, evaluate, skip, None)


class KNNLocalizationModel(RobotModel):
    """Robot + k-NN sensor model (seed 002, eqs. 1.12-1.14); observations are :class:`KNNObservation`.

    Parameters
    ----------
    sensor : KNNSensor
    initial_pose, initial_std, noise : as :class:`RobotModel`
    """

    def __init__(
        self, sensor: KNNSensor, initial_pose, initial_std, noise: MotionNoise = DEFAULT_NOISE
    ) -> None:
        super().__init__(initial_pose, initial_std, noise)
        self.sensor = sensor
        self._inv_bw = 1.0 / sensor.bandwidth
        self._log_norm = float(-np.sum(np.log(sensor.bandwidth)) - 1.5 * math.log(TWO_PI))

    def log_likelihood(self, particles: Array, observation: KNNObservation) -> Array:
        """Kernel-mixture log-likelihood of every particle; zeros for a skipped outlier."""
        return knn_log_likelihood(
            particles, observation, jnp.asarray(self._inv_bw, particles.dtype), self._log_norm
        )


# --- parametric range-bearing sensor (MRCLAM) ---------------------------------------------------
class RangeBearingObservation(NamedTuple):
    """Range-bearing measurements of one step, padded to ``max_meas`` (or stacked over time).

    Attributes
    ----------
    landmark : (..., max_meas) int, index into the landmark table
    range : (..., max_meas) metres
    bearing : (..., max_meas) radians, robot frame
    mask : (..., max_meas) bool, which slots hold a measurement
    """

    landmark: Any
    range: Any
    bearing: Any
    mask: Any


class RangeBearingLocalizationModel(RobotModel):
    r"""Robot + range-bearing likelihood to known landmarks (parametric; same engine).

    .. math::

        \log p(y_k|s_k) = \sum_m \log\big[(1-\epsilon) N(r_m; \hat r_m, \sigma_r^2)
        N(b_m; \hat b_m, \sigma_b^2) + \epsilon / (r_{\max} 2\pi)\big]

    with :math:`\hat r_m, \hat b_m` the range and bearing of landmark :math:`l_m` from
    :math:`s_k`; the :math:`\epsilon` term absorbs outlier measurements.

    Parameters
    ----------
    landmarks : (num_landmarks, 2) positions
    sigma_range, sigma_bearing : float
    outlier_prob : float, :math:`\epsilon`
    max_range : float, :math:`r_{\max}`
    range_bias : float, added to the predicted range (sensor calibration)
    initial_pose, initial_std, noise : as :class:`RobotModel`
    """

    def __init__(
        self,
        landmarks,
        initial_pose,
        initial_std,
        noise: MotionNoise = DEFAULT_NOISE,
        *,
        sigma_range: float = 0.15,
        sigma_bearing: float = 0.05,
        outlier_prob: float = 0.05,
        max_range: float = 10.0,
        range_bias: float = 0.0,
    ) -> None:
        super().__init__(initial_pose, initial_std, noise)
        shape = np.shape(landmarks)
        if len(shape) != 2 or shape[1] != 2 or shape[0] < 1:
            raise ShapeError(f"landmarks has shape {shape}, expected (num_landmarks >= 1, 2)")
        self.landmarks = check_numbers("landmarks", landmarks, shape[0] * 2).reshape(shape)
        self.sigma_range = _scale("sigma_range", sigma_range)
        self.sigma_bearing = _scale("sigma_bearing", sigma_bearing)
        self.outlier_prob = float(check_numbers("outlier_prob", outlier_prob, 1)[0])
        if not 0.0 < self.outlier_prob < 1.0:  # its log and log1p(-it) are taken
            raise ModelError(f"outlier_prob = {self.outlier_prob!r} must lie in (0, 1)")
        self.max_range = _scale("max_range", max_range)
        self.range_bias = float(check_numbers("range_bias", range_bias, 1)[0])

    def log_likelihood(self, particles: Array, observation: RangeBearingObservation) -> Array:
        """Sum over the step's measurements; shape (num_particles,)."""
        dt = particles.dtype
        lm = jnp.asarray(self.landmarks, dt)[observation.landmark]  # (M, 2)
        dx = lm[None, :, 0] - particles[:, None, 0]
        dy = lm[None, :, 1] - particles[:, None, 1]
        r_hat = jnp.sqrt(dx * dx + dy * dy) + self.range_bias
        b_hat = jnp.arctan2(dy, dx) - particles[:, None, 2]
        er = (observation.range.astype(dt)[None] - r_hat) / self.sigma_range
        eb = wrap_angle(observation.bearing.astype(dt)[None] - b_hat) / self.sigma_bearing
        log_gauss = (
            -0.5 * (er * er + eb * eb)
            - _log(TWO_PI * self.sigma_range * self.sigma_bearing)
            + _log1p(-self.outlier_prob)
        )
        log_out = _log(self.outlier_prob / (self.max_range * TWO_PI))
        ll = jnp.logaddexp(log_gauss, jnp.asarray(log_out, dt))
        return jnp.sum(jnp.where(observation.mask[None], ll, 0.0), axis=1)


def _log(x):
    """``log(x)``: by :mod:`math` for a number (a constant the compiled filter holds, as a
    model built with numbers always had), by :mod:`jax.numpy` for a traced parameter
    (:func:`~inference.particle.filters.run_model`)."""
    return math.log(x) if isinstance(x, int | float) else jnp.log(x)


def _log1p(x):
    """``log(1 + x)``, by :mod:`math` or :mod:`jax.numpy` as :func:`_log`."""
    return math.log1p(x) if isinstance(x, int | float) else jnp.log1p(x)


register_model(RangeBearingLocalizationModel, (
    "initial_pose", "initial_std", "noise", "landmarks", "sigma_range", "sigma_bearing",
    "outlier_prob", "max_range", "range_bias"))  # fmt: skip
