"""The path-recovery filter (seed 001, first phase) under the tracker protocol.

``step(key, state, obs)`` is :func:`models.pathrecovery.filter.step` with a numpy
``Generator`` seeded from the key (:func:`models.protocol.seed_from_key`); the state is
the filter's own immutable :class:`inference.particle.ParticleState` plus the time step.
``save`` / ``load`` write the state to ``.npz``. The second phase (dynamic programming
over the k-best lists, :func:`recover_path`) is offline and stays outside the protocol. Info is :class:`StepInfo`; its ``log_score`` is
the step's log mean unnormalised particle weight.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import numpy as np

from dbn.checks import check_type
from dbn.errors import CheckpointError, InputError
from inference.checkpoint import load_arrays, save_arrays
from inference.particle import ParticleState
from models.pathrecovery.filter import (
    FilterConfig,
    PathFilterModel,
    PathParticles,
    StepInfo,
    init,
    make_model,
    step,
)
from models.protocol import Example, StepTracker, check_key, next_frame_index, seed_from_key

_FORMAT = "dbntrack-pathrecovery-state-1"

__all__ = ["PathObservation", "PathState", "PathRecoveryTracker", "make", "example"]


class PathObservation(NamedTuple):
    """One time step's observations: ``cam`` (n,) sorted, ``feat`` (n, d), index offset
    and time step ``t`` (``None``: the step after the state's; given, it must be exactly
    ``state.t + 1``: a replayed, repeated or skipped step is a
    :class:`~dbn.errors.TimeOrderError` naming ``obs.t``)."""

    cam: np.ndarray
    feat: np.ndarray
    offset: int = 0
    t: int | None = None


class PathState(NamedTuple):
    """The particle set after step ``t`` (``t = 0``: the initial state)."""

    particles: ParticleState
    t: int


class PathRecoveryTracker(StepTracker):
    """Protocol adapter of the first phase of seed 001 for one :class:`PathFilterModel`."""

    name = "pathrecovery"
    score_field = "log_score"
    can_save = True

    def __init__(self, model: PathFilterModel) -> None:
        self.model = check_type("model", model, PathFilterModel)  # (from make_model)

    def init(self, key: jax.Array) -> PathState:
        """All particles at ``C_0`` with ``f_0`` (deterministic: the key is checked, not used)."""
        check_key(key)
        return PathState(init(self.model), 0)

    def step(self, key: jax.Array, state: PathState, obs) -> tuple[PathState, StepInfo]:
        """One filter step on ``obs`` (a :class:`PathObservation` or ``(cam, feat)``)."""
        if not isinstance(obs, tuple) or len(obs) not in (2, 3, 4):
            raise InputError(f"obs must be (cam, feat[, offset[, t]]), got {type(obs).__name__}")
        obs = PathObservation(*obs)
        t = next_frame_index(state.t, obs.t, "obs.t")
        rng = np.random.default_rng(seed_from_key(key))
        particles, info = step(rng, self.model, state.particles, obs.cam, obs.feat, obs.offset)
        return PathState(particles, t), info

    def save(self, state: PathState, path) -> None:
        """Write ``state`` to an ``.npz`` file (arrays, config, version, checksum; no pickle)."""
        arrays = {f: getattr(state.particles.particles, f) for f in PathParticles._fields}
        arrays["log_weights"] = state.particles.log_weights
        cfg, extra = self._checkpoint_config(), {"t": int(state.t)}
        save_arrays(path, arrays, _FORMAT, cfg, extra, neg_inf=["log_weights"])

    def load(self, path) -> PathState:
        """Read a state written by :meth:`save`; a damaged or foreign file, one saved under
        another configuration or for other sizes, or NaN/inf inside is a
        :class:`~dbn.errors.CheckpointError`."""
        names = (*PathParticles._fields, "log_weights")
        arrays, header = load_arrays(
            path, _FORMAT, names, self._checkpoint_config(), neg_inf=["log_weights"]
        )
        parts = PathParticles(*(arrays[name] for name in PathParticles._fields))
        lw = arrays["log_weights"]
        n, d = self.model.config.num_particles, self.model.f0.size
        if parts.cam.shape != (n,) or parts.feat.shape != (n, d) or lw.shape != (n,):
            raise CheckpointError(path, f"arrays do not fit num_particles={n}, feature_dim={d}")
        t = header.get("t")
        if not isinstance(t, int) or isinstance(t, bool) or t < 0:
            raise CheckpointError(path, f"t = {t!r} is not a step count >= 0")
        return PathState(ParticleState(parts, lw), t)

    def _checkpoint_config(self) -> dict:
        return {"config": self.model.config, "feature_dim": int(self.model.f0.size)}


def make(model: PathFilterModel) -> PathRecoveryTracker:
    """The tracker for a model from :func:`models.pathrecovery.make_model`."""
    return PathRecoveryTracker(model)


def example(key: jax.Array) -> Example:
    """A 4 x 4 grid, 60 SIMULATED walkers, 8 steps, 60 particles; bad: cameras unsorted."""
    from models.pathrecovery.simulate import manhattan_grid, simulate_scene

    seed = seed_from_key(key)
    net = manhattan_grid(seed, 4, 4)
    sc = simulate_scene(seed + 1, net, num_objects=60, num_timesteps=9, cm=0.2)
    model = make_model(net, sc.c0, sc.f0, sc.sigma, FilterConfig(num_particles=60, k=5))
    ptr = np.asarray(sc.odb.time_ptr)
    obs = [
        PathObservation(
            np.asarray(sc.odb.cam[ptr[t] : ptr[t + 1]]),
            np.asarray(sc.odb.feat[ptr[t] : ptr[t + 1]]),
            int(ptr[t]),
            t,
        )
        for t in range(1, ptr.size - 1)
    ]
    bad = obs[1]._replace(cam=obs[1].cam[::-1].copy())
    return Example(PathRecoveryTracker(model), obs, bad)
