"""``dbntrack track localization``: the robot's pose track from an MRCLAM folder or
generic CSVs (formats in :mod:`models.io.localization`), with the range-bearing model and
MRCLAM noise settings (:data:`models.localization.mrclam.MRCLAM_NOISE`), through the
registry's protocol adapter (auxiliary particle filter by default).

Config keys: ``robot`` (1), ``duration`` (s, default: the whole odometry), ``dt`` (0.1),
``num_particles`` (2000), ``algorithm`` ('apf' or 'sir'), ``initial_pose`` ([x, y, theta];
default: the first ground-truth pose, required without ground truth).
"""

from __future__ import annotations

from pathlib import Path

import jax
import numpy as np

from dbn.errors import InputError
from models.io.localization import read_generic, read_mrclam_folder, read_poses, write_poses
from models.track.context import RunContext

INPUTS = ("an MRCLAM dataset folder (RobotN_Odometry.dat, ...), or",
          "odometry.csv measurements.csv landmarks.csv [groundtruth.csv]")  # fmt: skip
_KEYS = {"robot", "duration", "dt", "num_particles", "algorithm", "initial_pose", "start"}


def _read(inputs: list[str], config: dict):
    if len(inputs) == 1 and Path(inputs[0]).is_dir():
        return read_mrclam_folder(inputs[0], int(config.get("robot", 1)))
    if len(inputs) in (3, 4):
        return read_generic(*inputs)
    raise InputError(
        f"localization needs an MRCLAM folder or 3-4 CSV files, got {len(inputs)} input(s)"
    )


def _sequence(data, config: dict):
    from models.localization.mrclam import build_sequence

    initial = config.get("initial_pose")
    if initial is not None:
        initial = np.asarray(initial, dtype=np.float64)
        if initial.shape != (3,) or not np.isfinite(initial).all():
            raise InputError(
                f"config initial_pose = {config['initial_pose']!r}: need [x, y, theta]"
            )
    if data.groundtruth is None:
        if initial is None:
            raise InputError("no ground truth to start from: give initial_pose in --config")
        data = data._replace(groundtruth=np.array([[data.odometry[0, 0], *initial]]))
    dt = float(config.get("dt", 0.1))
    t0 = max(data.odometry[0, 0], data.groundtruth[0, 0])
    duration = float(config.get("duration") or (data.odometry[-1, 0] - t0 - 1e-9))
    seq = build_sequence(data, duration=duration, dt=dt, start=config.get("start"))
    if initial is not None:
        seq = seq._replace(truth=np.vstack([initial, seq.truth[1:]]))
    return seq, data


def track(ctx: RunContext, inputs: list[str], config: dict) -> dict:
    """Filter the robot's run; write ``poses.csv`` and ``trajectory.png``."""
    import models
    from inference.precision import precision_scope
    from models.localization.api import LocalizationStep
    from models.localization.model import circular_mean
    from models.localization.mrclam import mrclam_model
    from models.protocol import split_run_keys

    unknown = set(config) - _KEYS
    if unknown:
        raise InputError(f"unknown config key(s) {sorted(unknown)}; valid: {sorted(_KEYS)}")
    with ctx.timed("read"):
        data = _read(inputs, config)
        seq, data = _sequence(data, config)
    n_part = int(config.get("num_particles", 2000))
    tracker = models.get("localization").make(
        model=mrclam_model(seq), num_particles=n_part, algorithm=config.get("algorithm", "apf")
    )
    obs = seq.observations
    T = len(seq.odometry)
    k_init, keys = split_run_keys(ctx.key(), T)  # the protocol's run, with progress
    means = np.zeros((T, 3))
    mean_fn = jax.jit(circular_mean)
    with ctx.timed("filter"):
        state = tracker.init(k_init)
        for k in ctx.progress(range(T), T, "steps"):
            y = jax.tree_util.tree_map(lambda a, k=k: a[k], obs)
            step = LocalizationStep(seq.odometry[k], y, float(seq.times[k + 1]))
            state, _ = tracker.step(keys[k], state, step)
            p = state.particles
            with precision_scope(tracker.dtype):
                means[k] = np.asarray(mean_fn(p.particles, p.log_weights))
    write_poses(ctx.outdir / "poses.csv", seq.times[1:], means)
    _plot(ctx, seq, means, data.groundtruth if len(data.groundtruth) > 1 else None)
    params = {"num_particles": n_part, "algorithm": config.get("algorithm", "apf"),
              "dt": float(config.get("dt", 0.1)), "num_steps": T,
              "initial_pose": [float(x) for x in seq.truth[0]]}  # fmt: skip
    return {"parameters": params, "outputs": ["poses.csv", "trajectory.png"]}


def _plot(ctx: RunContext, seq, means: np.ndarray, gt: np.ndarray | None) -> None:
    ncols = 1 if gt is None else 2
    with ctx.figure("trajectory.png", ncols=ncols, figsize=(6 * ncols, 5), squeeze=False) as (
        _,
        axes,
    ):
        ax = axes[0, 0]
        ax.plot(seq.landmarks[:, 0], seq.landmarks[:, 1], "k^", label="landmarks")
        if gt is not None:
            t = seq.times[1:]
            ax.plot(np.interp(t, gt[:, 0], gt[:, 1]), np.interp(t, gt[:, 0], gt[:, 2]),
                    "g-", lw=1, label="ground truth")  # fmt: skip
        ax.plot(means[:, 0], means[:, 1], "b-", lw=1, label="filter (mean pose)")
        ax.set_aspect("equal")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.legend(fontsize=8)
        if gt is not None:
            t = seq.times[1:]
            err = np.hypot(means[:, 0] - np.interp(t, gt[:, 0], gt[:, 1]),
                           means[:, 1] - np.interp(t, gt[:, 0], gt[:, 2]))  # fmt: skip
            axes[0, 1].plot(t - t[0], err)
            axes[0, 1].set_xlabel("time [s]")
            axes[0, 1].set_ylabel("position error [m]")


def evaluate(result: str, truth: str) -> dict:
    """Position RMSE (and mean, max error, heading RMSE) of a pose CSV against a truth pose
    CSV, MRCLAM ``.dat`` or folder, the truth interpolated at the result's times (as the
    benchmark's ``mrclam_rmse_m``)."""
    from models.localization.model import wrap_angle

    t, est = read_poses(result)
    tt, ref = read_poses(truth)
    inside = (t >= tt[0]) & (t <= tt[-1])
    if not inside.any():
        raise InputError(f"{result}: no time inside the truth's span [{tt[0]}, {tt[-1]}]")
    t, est = t[inside], est[inside]
    x, y = np.interp(t, tt, ref[:, 0]), np.interp(t, tt, ref[:, 1])
    th = wrap_angle(np.interp(t, tt, np.unwrap(ref[:, 2])))
    err = np.hypot(est[:, 0] - x, est[:, 1] - y)
    dth = wrap_angle(est[:, 2] - th)
    return {"rmse_m": float(np.sqrt(np.mean(err**2))), "mean_error_m": float(err.mean()),
            "max_error_m": float(err.max()), "heading_rmse_rad": float(np.sqrt(np.mean(dth**2))),
            "num_compared": int(err.size)}  # fmt: skip


__all__ = ["INPUTS", "track", "evaluate"]
