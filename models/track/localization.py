"""``dbntrack track localization``: the robot's pose track from an MRCLAM folder or
generic CSVs (formats in :mod:`models.io.localization`), with the range-bearing model and
MRCLAM noise settings (:data:`models.localization.mrclam.MRCLAM_NOISE`), through the
registry's protocol adapter (auxiliary particle filter by default).

Config keys: ``robot`` (1), ``duration`` (s, default: the whole odometry), ``dt`` (0.1),
``num_particles`` (2000), ``algorithm`` ('apf' or 'sir'), ``initial_pose`` ([x, y, theta];
default: the first ground-truth pose, required without ground truth); the noise of your
robot (default :data:`~models.localization.mrclam.MRCLAM_NOISE`, chosen on MRCLAM's robot
2): ``motion`` ``[a_xy, b_xy, a_theta, b_theta]``
(:class:`~models.localization.model.MotionNoise`), ``sigma_range`` (m), ``sigma_bearing``
(rad), ``outlier_prob``, ``initial_std`` ``[sx, sy, stheta]``, ``range_bias`` (m, 0) and
``max_range`` (m, 10).
``dbntrack fit localization`` measures them on your runs with ground truth
(:mod:`models.track.localization_fit`).
"""

from __future__ import annotations

from pathlib import Path

import jax
import numpy as np

from dbn.errors import ConfigError, InputError
from models.io.localization import (
    mrclam_file,
    read_generic,
    read_mrclam_folder,
    read_poses,
    write_poses,
)
from models.track.context import RunContext
from models.track.options import array, check_keys, integer, number, text

INPUTS = ("an MRCLAM dataset folder (RobotN_Odometry.dat, ...), or",
          "odometry.csv measurements.csv landmarks.csv [groundtruth.csv]")  # fmt: skip
NOISE_KEYS = ("motion", "sigma_range", "sigma_bearing", "outlier_prob", "initial_std",
              "range_bias", "max_range")  # fmt: skip
_KEYS = {"robot", "duration", "dt", "num_particles", "algorithm", "initial_pose", "start",
         *NOISE_KEYS}  # fmt: skip
_MAX_STEPS = 1e8  # filter steps of one run (a duration beyond it is a unit mistake)


def _read(inputs: list[str], robot: int):
    """The robot's data and the odometry file's path (for errors)."""
    if len(inputs) == 1 and Path(inputs[0]).is_dir():
        return read_mrclam_folder(inputs[0], robot), mrclam_file(inputs[0], f"Robot{robot}_Odometry")
    if len(inputs) in (3, 4):
        return read_generic(*inputs), Path(inputs[0])
    raise InputError(
        f"localization needs an MRCLAM folder or 3-4 CSV files, got {len(inputs)} input(s)"
    )


def run_options(config: dict) -> dict:
    """The config's options, checked before any file is read (``noise``:
    :func:`config_noise`)."""
    check_keys(config, _KEYS)
    initial = array(config, "initial_pose") if "initial_pose" in config else None
    if initial is not None and initial.shape != (3,):
        raise ConfigError(f"config initial_pose = {config['initial_pose']!r}: need [x, y, theta]")
    if initial is not None:
        _check_magnitude(config, "initial_pose", initial)
    opts = {"robot": integer(config, "robot", 1), "initial_pose": initial, "dt": number(config, "dt", 0.1),
            "duration": number(config, "duration") if config.get("duration") is not None else None,
            "start": number(config, "start") if config.get("start") is not None else None,
            "num_particles": integer(config, "num_particles", 2000),
            "algorithm": text(config, "algorithm", "apf")}  # fmt: skip
    if not opts["dt"] > 0:
        raise ConfigError(f"config dt = {opts['dt']!r}: expected a step > 0 s")
    if opts["duration"] is not None and not opts["duration"] > opts["dt"]:
        raise ConfigError(f"config duration = {opts['duration']!r}: expected more than one step "
                          f"(dt = {opts['dt']!r})")  # fmt: skip
    if opts["duration"] is not None and not opts["duration"] / opts["dt"] <= _MAX_STEPS:
        raise ConfigError(f"config duration = {opts['duration']!r}: more than {_MAX_STEPS:g} steps "
                          f"of dt = {opts['dt']!r}")  # fmt: skip
    opts["noise"] = config_noise(config)
    return opts


def config_noise(config: dict) -> dict:
    """The model's noise: :data:`~models.localization.mrclam.MRCLAM_NOISE` with the
    config's noise keys (:data:`NOISE_KEYS`) written over it, each checked (scales > 0
    where the likelihood divides by them, >= 0 for the motion and the initial spread,
    ``outlier_prob`` in (0, 1))."""
    from models.localization.mrclam import MRCLAM_NOISE

    out = {**MRCLAM_NOISE, "range_bias": 0.0, "max_range": 10.0}
    for key, size in (("motion", 4), ("initial_std", 3)):
        if key in config:
            v = array(config, key, ndim=1)
            if v.shape != (size,) or not np.all(v >= 0):
                raise ConfigError(f"config {key} = {config[key]!r}: expected {size} numbers >= 0")
            out[key] = tuple(float(x) for x in v)
    for key in ("sigma_range", "sigma_bearing", "max_range"):
        if key in config and not number(config, key) > 0:
            raise ConfigError(f"config {key} = {config[key]!r}: expected a number > 0")
    if "outlier_prob" in config and not 0 < number(config, "outlier_prob") < 1:
        raise ConfigError(f"config outlier_prob = {config['outlier_prob']!r}: expected a "
                          "probability in (0, 1)")  # fmt: skip
    out.update({k: number(config, k) for k in ("sigma_range", "sigma_bearing", "max_range",
                                               "outlier_prob", "range_bias") if k in config})
    for key in NOISE_KEYS:
        if key in config:
            _check_magnitude(config, key, np.asarray(out[key], float))
    return out


def _check_magnitude(config: dict, key: str, value: np.ndarray) -> None:
    """A :class:`ConfigError` for a value of ``key`` beyond
    :data:`~models.io.localization.MAX_MAGNITUDE` (1e7, the files' bound): an initial pose
    or a motion noise of 1e200 ran to rc 0."""
    from models.io.localization import MAX_MAGNITUDE

    if np.any(np.abs(value) > MAX_MAGNITUDE):
        raise ConfigError(f"config {key} = {config[key]!r}: beyond {MAX_MAGNITUDE:g} "
                          "(m, rad, or a noise scale): a unit mistake?")  # fmt: skip


def run_sequence(data, odometry: Path, opts: dict, end: float | None = None):
    """The filter's steps of a run (:func:`~models.localization.mrclam.build_sequence` with
    the options' ``dt``, ``duration``, ``start``) and its data, with the options' initial
    pose (required without ground truth). Without a ``duration`` the run ends at ``end``
    (default: the odometry's last time)."""
    from models.localization.mrclam import build_sequence

    initial = opts["initial_pose"]
    if data.groundtruth is None:
        if initial is None:
            raise InputError("no ground truth to start from: give initial_pose in --config")
        data = data._replace(groundtruth=np.array([[data.odometry[0, 0], *initial]]))
    dt, duration, start = opts["dt"], opts["duration"], opts["start"]
    t0 = max(data.odometry[0, 0], data.groundtruth[0, 0]) if start is None else start
    if duration is None:
        last = data.odometry[-1, 0] if end is None else end
        duration = float(last - t0 - 1e-9)
        if not duration > dt:
            what = f"the start (t = {t0:.6g})" if start is None else f"config start t = {t0:.6g}"
            data_end = "odometry ends" if end is None else "run's data end"
            raise InputError(f"{odometry}: the {data_end} at t = {last:.6g}, less than one step "
                             f"(dt = {dt:g}) after {what}")  # fmt: skip
        if not duration / dt <= _MAX_STEPS:  # dt = 1e-9 asked for 59 GiB of step indices
            raise ConfigError(f"config dt = {dt:g}: the run's {duration:.6g} s would be "
                              f"{duration / dt:.3g} steps, more than {_MAX_STEPS:g}")  # fmt: skip
    try:
        seq = build_sequence(data, duration=duration, dt=dt, start=start)
    except InputError as exc:  # a span outside the odometry's
        raise InputError(f"{odometry}: config {exc}") from None
    if initial is not None:
        seq = seq._replace(truth=np.vstack([initial, seq.truth[1:]]))
    return seq, data


def track(ctx: RunContext, inputs: list[str], config: dict) -> dict:
    """Filter the robot's run; write ``poses.csv`` and ``trajectory.png``."""
    opts = run_options(config)
    with ctx.timed("read"):
        data, odometry = _read(inputs, opts["robot"])
        seq, data = run_sequence(data, odometry, opts)
    with ctx.timed("filter"):
        means = filter_means(seq, opts, ctx.key(), lambda steps, n: ctx.progress(steps, n, "steps"))
    write_poses(ctx.outdir / "poses.csv", seq.times[1:], means)
    _plot(ctx, seq, means, data.groundtruth if len(data.groundtruth) > 1 else None)
    params = {"num_particles": opts["num_particles"], "algorithm": opts["algorithm"],
              "dt": opts["dt"], "num_steps": len(means),
              "initial_pose": [float(x) for x in seq.truth[0]],
              "noise": {k: opts["noise"][k] for k in NOISE_KEYS}}  # fmt: skip
    return {"parameters": params, "outputs": ["poses.csv", "trajectory.png"]}


def filter_means(seq, opts: dict, key, progress=None) -> np.ndarray:
    """The filter's mean pose after each step, ``(T, 3)``: the registry's tracker on the
    model of ``opts["noise"]`` (:func:`~models.localization.mrclam.mrclam_model`), run
    through the protocol from ``key`` (``progress(steps, total)`` wraps the steps)."""
    import models
    from inference.precision import precision_scope
    from models.localization.api import LocalizationStep
    from models.localization.model import circular_mean
    from models.localization.mrclam import mrclam_model
    from models.protocol import split_run_keys

    try:
        tracker = models.get("localization").make(
            model=mrclam_model(seq, opts["noise"]), num_particles=opts["num_particles"],
            algorithm=opts["algorithm"])  # fmt: skip
    except InputError as exc:  # num_particles or algorithm
        raise ConfigError(str(exc)) from None
    obs, T = seq.observations, len(seq.odometry)
    k_init, keys = split_run_keys(key, T)  # the protocol's run
    means = np.zeros((T, 3))
    mean_fn = jax.jit(circular_mean)
    state = tracker.init(k_init)
    for k in range(T) if progress is None else progress(range(T), T):
        y = jax.tree_util.tree_map(lambda a, k=k: a[k], obs)
        step = LocalizationStep(seq.odometry[k], y, float(seq.times[k + 1]))
        state, _ = tracker.step(keys[k], state, step)
        p = state.particles
        with precision_scope(tracker.dtype):
            means[k] = np.asarray(mean_fn(p.particles, p.log_weights))
    return means


def scan_means(seq, opts: dict, key) -> np.ndarray:
    """:func:`filter_means` without its per-step bar, in one ``lax.scan``
    (:func:`~models.localization.tracker.localize`): the same filter from the same keys
    (``localize`` splits ``key`` as the protocol's ``run`` does), so the same poses ``(T, 3)``
    to rounding (tested), and with the noise traced, not compiled in
    (:func:`~inference.particle.filters.run_model`), one compilation for every noise setting
    of a run (``python -m benchmarks localization``: ``speedup_vs_recompiled_run``). The
    fit's many runs take it."""
    from models.localization.mrclam import mrclam_model
    from models.localization.tracker import localize, make_filter

    model = mrclam_model(seq, opts["noise"])
    try:  # num_particles or algorithm, as filter_means names them
        make_filter(model, opts["num_particles"], opts["algorithm"])
    except InputError as exc:
        raise ConfigError(str(exc)) from None
    res = localize(key, model, seq.odometry, seq.observations, opts["num_particles"],
                   opts["algorithm"])  # fmt: skip
    return np.asarray(res.means)


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


def fit(ctx: RunContext, train: list[str], validate: list[str], config: dict, seeds: int = 1,
        prior_strength=(0.0,), folds: int = 0, fold_by: str | None = None) -> dict:
    """``dbntrack fit``: the robot's noise measured on runs with ground truth, and the
    filter's widening of it searched (:mod:`models.track.localization_fit`)."""
    from models.track.localization_fit import fit as fit_runs

    return fit_runs(ctx, train, validate, config, seeds, prior_strength, folds, fold_by)


def fit_report(summary: dict) -> list[str]:
    """The lines ``dbntrack fit localization`` prints
    (:func:`models.track.localization_fit.fit_report`)."""
    from models.track.localization_fit import fit_report as report

    return report(summary)


__all__ = ["INPUTS", "NOISE_KEYS", "track", "evaluate", "fit", "fit_report", "filter_means",
           "scan_means",
           "config_noise", "run_options", "run_sequence"]
