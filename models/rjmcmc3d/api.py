"""The multi-camera RJ-MCMC 3-D tracker (seed 003) under the tracker protocol.

:meth:`RJMCMCTracker.step` is already pure (an explicit int seed, the previous
:class:`TrackState` not mutated); the adapter derives the seed from the key
(:func:`models.protocol.seed_from_key`) and offers ``save`` / ``load`` of the state as
``.npz`` (no pickle). Info is :class:`FrameResult`; its ``log_target`` is the log target
of the chain's last state (seed 003, eq. 11, up to a constant).
"""

from __future__ import annotations

import jax
import numpy as np

from dbn.errors import CheckpointError, InputError
from inference.checkpoint import load_arrays, save_arrays
from models.protocol import Example, StepTracker, check_key, seed_from_key
from models.rjmcmc3d.model import TrackerParams
from models.rjmcmc3d.scene import Frame, Scene
from models.rjmcmc3d.tracker import FrameResult, RJMCMCTracker, TrackState

__all__ = ["RJMCMC3DTracker", "make", "example"]

_FORMAT = "dbntrack-rjmcmc3d-state-2"  # 2: TrackState.frame (the last frame index)


class RJMCMC3DTracker(StepTracker):
    """Protocol adapter over :class:`RJMCMCTracker` (``step(key, state, frame)``)."""

    name = "rjmcmc3d"
    score_field = "log_target"
    can_save = True

    def __init__(self, tracker: RJMCMCTracker) -> None:
        self.tracker = tracker

    def init(self, key: jax.Array) -> TrackState:
        """No one tracked yet (deterministic: the key is checked, not used)."""
        check_key(key)
        return self.tracker.init_state()

    def step(self, key: jax.Array, state: TrackState, obs: Frame) -> tuple[TrackState, FrameResult]:
        """One frame's RJ-MCMC chain, seeded from ``key``."""
        if not isinstance(obs, Frame):
            raise InputError(f"obs must be a rjmcmc3d Frame, got {type(obs).__name__}")
        return self.tracker.step(seed_from_key(key), state, obs)

    def save(self, state: TrackState, path) -> None:
        """Write ``state`` to an ``.npz`` file (arrays, config, version, checksum)."""
        arrays = {f: getattr(state, f) for f in TrackState._fields}
        save_arrays(path, arrays, _FORMAT, self.tracker.params)

    def load(self, path) -> TrackState:
        """Read a state written by :meth:`save`; a damaged or foreign file, one saved under
        other :class:`TrackerParams`, or NaN/inf inside is a
        :class:`~dbn.errors.CheckpointError`."""
        arrays, _ = load_arrays(path, _FORMAT, TrackState._fields, self.tracker.params)
        values = [arrays[name] for name in TrackState._fields]
        m = self.tracker.params.max_objects
        if np.shape(arrays["alive"]) != (m,) or np.ndim(values[-1]) or np.ndim(values[-2]):
            raise CheckpointError(path, f"arrays do not fit max_objects = {m}")
        values[-2], values[-1] = int(values[-2]), int(values[-1])  # next_label, frame
        if values[-1] < -1:
            raise CheckpointError(path, f"frame = {values[-1]} is not a frame index >= -1")
        return TrackState(*values)


def make(scene: Scene, params: TrackerParams | None = None, **options) -> RJMCMC3DTracker:
    """The adapter over ``RJMCMCTracker(scene, params, **options)``."""
    return RJMCMC3DTracker(RJMCMCTracker(scene, params, **options))


def example(key: jax.Array) -> Example:
    """A small SIMULATED 3-camera hall (192 x 144 px), 2 walkers, 3 frames, 200 moves/frame;
    bad: a frame with NaN in its foreground maps. The frames carry their index ``t``. (At
    96 x 72 px a walker covers a few pixels and the chain found nobody on most seeds: a log
    target of 0 every frame.)"""
    from models.rjmcmc3d.scene import default_scene, render_frame, simulate_walkers

    seed = seed_from_key(key)
    scene = default_scene(0, width=192, height=144)
    truth = simulate_walkers(seed, scene, 3, 2)
    frames = [render_frame(seed + 1, scene, truth, t)._replace(t=t) for t in range(3)]
    bad = frames[1]._replace(D=np.where(np.ones_like(frames[1].D, bool), np.nan, frames[1].D))
    tracker = make(scene, TrackerParams(num_moves=200, burn_in=60))
    return Example(tracker, frames, bad)
