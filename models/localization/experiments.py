"""Repeated runs shared by the benchmark, the demo and the tutorial.

:func:`synthetic_trials` filters SIMULATED runs of the aliased world (seed 002, section
1.3: SIR against the auxiliary filter with occlusion outliers); :func:`mrclam_trials`
filters the real MRCLAM robot with several seeds and the dead-reckoning baseline. Both
run all seeds at once with ``jax.vmap`` over one compiled filter.
"""

from __future__ import annotations

import math
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from inference.particle import ParticleState, run
from inference.precision import honours_dtype
from models.localization.model import compose
from models.localization.simulate import (
    TrainedWorld,
    knn_model_for,
    odometry_only,
    simulate_run,
)
from models.localization.tracker import make_filter, pose_summary, position_errors

__all__ = ["synthetic_trials", "mrclam_trials", "dead_reckoning"]


def _initial_states(key, model, starts: np.ndarray, num_particles: int, dtype) -> ParticleState:
    """One Gaussian cloud per start pose ``(num_runs, 3)``: leaves ``(num_runs, num_particles, ...)``."""
    keys = jax.random.split(key, len(starts))

    def one(k, s):
        z = jax.random.normal(k, (num_particles, 3), dtype=dtype)
        x = jnp.asarray(s, dtype) + z * jnp.asarray(model.initial_std, dtype)
        x = x.at[:, 2].set(jnp.mod(x[:, 2] + math.pi, 2 * math.pi) - math.pi)
        return ParticleState(x, jnp.full((num_particles,), -math.log(num_particles), dtype))

    return jax.vmap(one)(keys, jnp.asarray(starts, dtype))


def _vmapped_run(pf, keys, init, obs, steps):
    def one(k, s0, o, a):
        return run(k, pf, o, a, initial_state=s0, summary=pose_summary)[2]

    return jax.vmap(one)(keys, init, obs, steps)


@honours_dtype
def synthetic_trials(
    seed: int,
    trained: TrainedWorld,
    *,
    num_runs: int = 10,
    num_timesteps: int = 120,
    num_particles: int = 1000,
    outlier_rate: float = 0.1,
    algorithms: tuple[str, ...] = ("sir", "apf"),
    dtype: Any = jnp.float64,
    ess_threshold: float = 0.5,
) -> dict:
    """SIR and APF on ``num_runs`` SIMULATED runs (seeds ``seed .. seed + num_runs - 1``).

    Returns
    -------
    dict
        ``runs`` (the SyntheticRun list) and, per algorithm, ``means`` (num_runs, T, 3),
        ``errors`` (num_runs, T) position errors, ``rmse`` (num_runs,) and
        ``final_error`` (num_runs,); plus ``dead_reckoning_rmse`` (num_runs,).
    """
    runs = [
        simulate_run(seed + i, trained.world, num_timesteps, outlier_rate=outlier_rate)
        for i in range(num_runs)
    ]
    model = knn_model_for(trained, runs[0])  # the same law for every run; starts differ
    obs = [trained.sensor.preprocess(r.observations, dtype=dtype) for r in runs]
    obs = jax.tree_util.tree_map(lambda *a: jnp.stack(a), *obs)
    steps = jnp.stack([jnp.asarray(model.prepare_actions(r.actions), dtype) for r in runs])
    truth = np.stack([r.poses[1:] for r in runs])
    starts = np.stack([r.poses[0] for r in runs])
    out: dict = {"runs": runs}
    key = jax.random.key(seed)
    for name in algorithms:
        pf = make_filter(model, num_particles, name, dtype=dtype, ess_threshold=ess_threshold)
        k_init, k_run = jax.random.split(jax.random.fold_in(key, len(name)))
        init = _initial_states(k_init, model, starts, num_particles, dtype)
        keys = jax.random.split(k_run, num_runs)
        means = _vmapped_run(pf, keys, init, obs, steps)
        means = np.asarray(means)
        err = position_errors(means, truth)
        out[name] = {
            "means": means,
            "errors": err,
            "rmse": np.sqrt(np.mean(err**2, axis=1)),
            "final_error": err[:, -1],
        }
    dead = np.stack([odometry_only(r.poses[0], r.actions) for r in runs])
    out["dead_reckoning_rmse"] = np.sqrt(np.mean(position_errors(dead, truth) ** 2, axis=1))
    out["truth"] = truth
    return out


def dead_reckoning(start: np.ndarray, odometry: np.ndarray) -> np.ndarray:
    """Poses ``(num_timesteps, 3)`` from composing the odometry alone (the baseline)."""
    pose = np.asarray(start, dtype=np.float64)
    out = np.empty((len(odometry), 3))
    for k, u in enumerate(odometry):  # a loop over time steps (not particles)
        pose = compose(pose, u[:3])
        out[k] = pose
    return out


@honours_dtype
def mrclam_trials(
    seed: int,
    *,
    num_runs: int = 5,
    num_particles: int = 2000,
    duration: float = 300.0,
    dt: float = 0.1,
    algorithm: str = "apf",
    robot: int = 1,
    dtype: Any = jnp.float64,
) -> dict:
    """Filter the real MRCLAM robot ``num_runs`` times (keys from ``seed``).

    Raises FileNotFoundError when the shared data is absent.

    Returns
    -------
    dict with ``sequence``, ``means`` (num_runs, T, 3), ``errors`` (num_runs, T),
    ``rmse`` (num_runs,), ``dead_reckoning`` (T, 3) and ``dead_reckoning_rmse`` (float).
    """
    from models.localization.mrclam import build_sequence, load_robot, mrclam_model

    seq = build_sequence(load_robot(robot), duration=duration, dt=dt)
    model = mrclam_model(seq)
    obs = jax.tree_util.tree_map(jnp.asarray, seq.observations)
    steps = jnp.asarray(model.prepare_actions(seq.odometry), dtype)
    pf = make_filter(model, num_particles, algorithm, dtype=dtype)
    keys = jax.random.split(jax.random.key(seed), num_runs)
    means = jax.vmap(lambda k: run(k, pf, obs, steps, summary=pose_summary)[2])(keys)
    means = np.asarray(means)
    truth = seq.truth[1:]
    err = position_errors(means, truth)
    dead = dead_reckoning(seq.truth[0], seq.odometry)
    g = seq.on_grid  # average over the regular time grid
    return {
        "sequence": seq,
        "means": means,
        "errors": err,
        "rmse": np.sqrt(np.mean(err[:, g] ** 2, axis=1)),
        "dead_reckoning": dead,
        "dead_reckoning_rmse": float(np.sqrt(np.mean(position_errors(dead, truth)[g] ** 2))),
    }
