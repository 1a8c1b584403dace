"""Robot localisation (seed 002, sec. 1.3) under the tracker protocol.

The stateful :class:`~models.localization.tracker.Localizer` keeps its particle cloud and
last timestamp on the object; here both live in an immutable :class:`LocalizationState`
(the cloud is an :class:`inference.particle.ParticleState` of jax arrays, so a step makes
a new one and copies nothing). ``step`` validates the odometry, the observation and the
time order before computing, then runs the library's filter step (APF or SIR) jitted, in
the filter's dtype (float64 by default, via :func:`inference.precision.precision_scope`).
Info is :class:`inference.particle.ParticleInfo`; its ``log_likelihood`` is the one-step
``log p(y_k | y_1..y_{k-1})`` estimate.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from dbn.checks import check_type
from dbn.errors import CheckpointError, InputError, ShapeError
from inference.checkpoint import load_arrays, save_arrays
from inference.particle import ParticleInfo, ParticleState
from inference.precision import precision_scope
from models.localization.landmarks import measure_landmarks
from models.localization.model import (
    RangeBearingLocalizationModel,
    RangeBearingObservation,
    RobotModel,
)
from models.localization.tracker import check_observation, check_timestamp, make_filter
from models.protocol import Example, StepTracker, check_key, seed_from_key

__all__ = ["LocalizationStep", "LocalizationState", "LocalizationTracker", "make", "example"]

_FORMAT = "dbntrack-localization-state-1"


class LocalizationStep(NamedTuple):
    """One step's input: ``odometry`` (4,) ``(dx, dy, dtheta, dt)``, the sensor reading,
    and an optional log time (must increase)."""

    odometry: Any
    observation: Any
    timestamp: float | None = None


class LocalizationState(NamedTuple):
    """The particle cloud and the last timestamp seen (None if none)."""

    particles: ParticleState
    timestamp: float | None = None


class LocalizationTracker(StepTracker):
    """Protocol adapter of the localisation particle filters for one :class:`RobotModel`."""

    name = "localization"
    score_field = "log_likelihood"
    can_save = True

    def __init__(self, model: RobotModel, num_particles: int, algorithm: str = "apf", *,
                 dtype: Any = jnp.float64, ess_threshold: float = 0.5) -> None:  # fmt: skip
        self.model = check_type("model", model, RobotModel)
        self.dtype = dtype
        self._pf = make_filter(
            model, num_particles, algorithm, dtype=dtype, ess_threshold=ess_threshold
        )
        self._step = jax.jit(self._pf.step)

    def init(self, key: jax.Array) -> LocalizationState:
        """The initial cloud drawn with ``key`` (``model.sample_initial``)."""
        check_key(key)  # else jax's TypeError "invalid PRNG key data"
        with precision_scope(self.dtype):
            return LocalizationState(self._pf.init(key), None)

    def step(
        self, key: jax.Array, state: LocalizationState, obs
    ) -> tuple[LocalizationState, ParticleInfo]:
        """Move by the odometry, weigh by the observation (all input checked first)."""
        check_key(key)
        if not isinstance(obs, tuple) or len(obs) not in (2, 3):
            raise InputError(
                f"obs must be (odometry, observation[, timestamp]), got {type(obs).__name__}"
            )
        obs = LocalizationStep(*obs)
        ts = check_timestamp(obs.timestamp, state.timestamp)
        with precision_scope(self.dtype):
            action = jnp.asarray(self.model.prepare_actions(obs.odometry), self.dtype)
            if action.shape != (4, 3):
                raise ShapeError(f"odometry has shape {np.shape(obs.odometry)}, expected (4,)")
            y = check_observation(self.model, obs.observation, self.dtype)
            particles, info = self._step(key, state.particles, y, action)
        return LocalizationState(particles, ts if ts is not None else state.timestamp), info

    def save(self, state: LocalizationState, path) -> None:
        """Write ``state`` to ``.npz`` (arrays, config, version, checksum; no pickle)."""
        arrays = {
            "particles": state.particles.particles,
            "log_weights": state.particles.log_weights,
        }
        cfg = self._checkpoint_config(np.shape(state.particles.log_weights)[0])
        save_arrays(
            path, arrays, _FORMAT, cfg, {"timestamp": state.timestamp}, neg_inf=["log_weights"]
        )

    def load(self, path) -> LocalizationState:
        """Read a state written by :meth:`save`; a damaged or foreign file, one saved under
        another configuration, or NaN/inf inside is a :class:`~dbn.errors.CheckpointError`."""
        shape = jax.eval_shape(self._pf.init, jax.random.key(0)).log_weights.shape
        cfg = self._checkpoint_config(shape[0])
        arrays, header = load_arrays(
            path, _FORMAT, ("particles", "log_weights"), cfg, neg_inf=["log_weights"]
        )
        ts = header.get("timestamp")
        if ts is not None and not (isinstance(ts, (int, float)) and math.isfinite(ts)):
            raise CheckpointError(path, f"timestamp = {ts!r} is not a finite number or null")
        with precision_scope(self.dtype):
            cloud = ParticleState(
                jnp.asarray(arrays["particles"]), jnp.asarray(arrays["log_weights"])
            )
        return LocalizationState(cloud, ts)

    def _checkpoint_config(self, num_particles: int) -> dict:
        return {"model": type(self.model).__name__, "num_particles": int(num_particles),
                "filter": self._pf.step.__qualname__, "dtype": np.dtype(self.dtype).name}  # fmt: skip


def make(
    model: RobotModel, num_particles: int, algorithm: str = "apf", **options
) -> LocalizationTracker:
    """The adapter for ``model`` (k-NN or range-bearing), ``algorithm`` 'apf' or 'sir'."""
    return LocalizationTracker(model, num_particles, algorithm, **options)


def example(key: jax.Array) -> Example:
    """A SIMULATED robot driving an arc among 3 landmarks, range-bearing sensor, 5 steps,
    200 particles; bad: a NaN range."""
    rng = np.random.default_rng(seed_from_key(key))
    landmarks = np.array([[0.0, 0.0], [4.0, 0.0], [2.0, 3.0]])
    model = RangeBearingLocalizationModel(landmarks, [1.0, 1.0, 0.0], [0.1, 0.1, 0.05])
    pose = np.array([1.0, 1.0, 0.0])
    steps = []
    for t in range(5):
        odo = np.array([0.2, 0.0, 0.1, 0.1])
        c, s = np.cos(pose[2]), np.sin(pose[2])
        pose = pose + np.array([c * odo[0], s * odo[0], odo[2]])
        obs = measure_landmarks(rng, landmarks, pose[None], 0.05, 0.02)  # one pose: (1, 3)
        obs = RangeBearingObservation(*(a[0] for a in obs))
        steps.append(LocalizationStep(odo, obs, 0.1 * (t + 1)))
    bad_obs = steps[1].observation._replace(range=np.array([1.0, np.nan, 2.0]))
    return Example(make(model, 200), steps, steps[1]._replace(observation=bad_obs))
