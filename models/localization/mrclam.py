r"""The real UTIAS MRCLAM dataset 6 (robots 1 and 2): loader and step sequences for the filter.

Data: ``../shared/data/mrclam6`` (found through :func:`models.datasets.require`; see its
README: UTIAS Multi-Robot Cooperative Localization and Mapping, K. Leung et al. 2011).
Odometry ``(t, v, w)`` is the action, range-bearing measurements to the 15 known landmarks
are the observation (measurements of other robots, whose barcodes map to subjects 1-5,
and unknown barcodes are ignored), motion-capture poses are the truth.

The filter runs on a fixed time grid (``dt`` seconds): the action of a step is the
odometry integrated over the step, as a relative pose; the observations of a step are the
landmark measurements whose time is nearest to the step's end (padded to the largest count per step, with a mask).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from dbn.errors import InputError
from models import datasets
from models.localization.model import RangeBearingObservation, relative_pose, wrap_angle

__all__ = [
    "MRCLAMRobot",
    "MRCLAMSequence",
    "load_robot",
    "build_sequence",
    "integrate_odometry",
    "estimate_noise",
    "mrclam_model",
    "MRCLAM_NOISE",
]


class MRCLAMRobot(NamedTuple):
    """Raw data of one robot.

    Attributes
    ----------
    odometry : (num_odometry, 3) time [s], forward velocity [m/s], angular velocity [rad/s]
    measurements : (num_measurements, 4) time, barcode, range [m], bearing [rad]
    groundtruth : (num_poses, 4) time, x, y, theta
    landmarks : (15, 2) landmark positions, rows for subjects 6..20
    landmark_subjects : (15,) their subject numbers
    barcode_to_subject : dict
    """

    odometry: np.ndarray
    measurements: np.ndarray
    groundtruth: np.ndarray
    landmarks: np.ndarray
    landmark_subjects: np.ndarray
    barcode_to_subject: dict


def load_robot(robot: int = 1) -> MRCLAMRobot:
    """Load robot ``robot`` (1 or 2) of MRCLAM dataset 6 from the shared data folder, with
    the checks of any MRCLAM folder (:func:`models.io.localization.read_mrclam_folder`).

    Raises
    ------
    FileNotFoundError
        When the data folder is absent (tests skip, the demo falls back to simulation).
    InputError
        A robot other than 1 and 2; a file that is missing, not numeric, ragged, or with
        an id that is not an integer (naming the file and line).
    TimeOrderError
        When a file's timestamps go backwards.
    """
    # imported here: models.io.localization reads into this module's MRCLAMRobot
    from models.io.localization import read_mrclam_folder

    if robot not in (1, 2):
        raise InputError(f"robot = {robot!r}: only robots 1 and 2 are in the shared data")
    return read_mrclam_folder(datasets.require("mrclam6"), robot)


def integrate_odometry(odometry: np.ndarray, times: np.ndarray) -> np.ndarray:
    """Dead-reckoned poses ``(len(times), 3)`` in the frame of the first odometry sample.

    Each sample's velocities hold until the next sample (Euler integration), vectorised
    with cumulative sums; poses are interpolated linearly (unwrapped angle) at ``times``.
    """
    t, v, w = odometry[:, 0], odometry[:, 1], odometry[:, 2]
    dt = np.diff(t)
    th = np.concatenate([[0.0], np.cumsum(w[:-1] * dt)])
    x = np.concatenate([[0.0], np.cumsum(v[:-1] * np.cos(th[:-1]) * dt)])
    y = np.concatenate([[0.0], np.cumsum(v[:-1] * np.sin(th[:-1]) * dt)])
    return np.column_stack(
        [np.interp(times, t, x), np.interp(times, t, y), np.interp(times, t, th)]
    )


class MRCLAMSequence(NamedTuple):
    """A robot's run on a fixed time grid, ready for the filter.

    Attributes
    ----------
    times : (num_timesteps + 1,) grid times [s]
    odometry : (num_timesteps, 4) ``(dx, dy, dtheta, dt)`` per step, robot frame
    observations : RangeBearingObservation, leaves (num_timesteps, max_meas)
    truth : (num_timesteps + 1, 3) motion-capture poses at the step times
    landmarks : (15, 2)
    on_grid : (num_timesteps,) bool, which steps end on the regular ``dt`` grid (errors are
        averaged over these, so that extra measurement-time steps do not weigh in)
    """

    times: np.ndarray
    odometry: np.ndarray
    observations: RangeBearingObservation
    truth: np.ndarray
    landmarks: np.ndarray
    on_grid: np.ndarray


def _check_span(t: np.ndarray, t0: float, t_end: float, duration: float) -> None:
    """Refuse a run that starts outside the odometry's times ``t`` or ends after them
    (the dead reckoning would hold the last pose: steps of no data, scored as data)."""
    if not t[0] <= t0 < t[-1]:
        raise InputError(f"start t = {t0:.6g}: outside the odometry's times [{t[0]:.6g}, "
                         f"{t[-1]:.6g}]")  # fmt: skip
    if t_end > t[-1]:
        raise InputError(f"duration = {duration:g} s from t = {t0:.6g} runs past the "
                         f"odometry's end (t = {t[-1]:.6g}, {t[-1] - t0:.6g} s in)")  # fmt: skip


def build_sequence(
    data: MRCLAMRobot,
    *,
    duration: float = 300.0,
    dt: float = 0.1,
    start: float | None = None,
    align: str = "grid",
) -> MRCLAMSequence:
    """Cut the first ``duration`` seconds (from the first odometry sample) into filter steps.

    Parameters
    ----------
    data : MRCLAMRobot
    duration, dt : float, seconds
    start : float, optional
        Start time; default the later of the first odometry and ground-truth samples.
    align : 'grid' or 'events'
        'grid' (default): a plain ``dt`` grid, each measurement attached to the nearest grid
        time; 'events': the step ends are the grid plus every landmark-measurement time, so
        each measurement is applied at its own time (steps of variable length). On robot 2
        (held out) both gave the same accuracy (0.275 vs 0.273 m), so the simpler grid is
        the default.
    """
    if not (dt > 0 and duration > dt):
        raise InputError(f"need 0 < dt < duration, got dt={dt!r}, duration={duration!r}")
    if align not in ("events", "grid"):
        raise InputError(f"align = {align!r}, expected 'events' or 'grid'")
    t0 = max(data.odometry[0, 0], data.groundtruth[0, 0]) if start is None else float(start)
    grid = t0 + dt * np.arange(int(math.floor(duration / dt)) + 1)
    _check_span(data.odometry[:, 0], t0, grid[-1], duration)
    # landmark measurements (robots and unknown barcodes dropped)
    meas = data.measurements
    index = {int(s): i for i, s in enumerate(data.landmark_subjects)}
    subj = np.array([data.barcode_to_subject.get(int(b), -1) for b in meas[:, 1]], dtype=int)
    keep = np.isin(subj, list(index)) & (meas[:, 0] > grid[0]) & (meas[:, 0] <= grid[-1])
    meas, subj = meas[keep], subj[keep]
    if align == "events":
        times = np.union1d(grid, meas[:, 0])
        step = np.searchsorted(times, meas[:, 0]) - 1  # the step ending at the measurement
    else:
        times = grid
        step = np.rint((meas[:, 0] - times[0]) / dt).astype(int) - 1  # nearest grid time
    n = len(times) - 1
    step = np.clip(step, 0, n - 1)
    dead = integrate_odometry(data.odometry, times)
    rel = relative_pose(dead[:-1], dead[1:])
    odo = np.column_stack([rel, np.diff(times)])
    gt = data.groundtruth
    th = np.unwrap(gt[:, 3])
    truth = np.column_stack(
        [
            np.interp(times, gt[:, 0], gt[:, 1]),
            np.interp(times, gt[:, 0], gt[:, 2]),
            wrap_angle(np.interp(times, gt[:, 0], th)),
        ]
    )
    counts = np.bincount(step, minlength=n)
    width = max(1, int(counts.max()) if counts.size else 1)
    order = np.argsort(step, kind="stable")
    step, meas, subj = step[order], meas[order], subj[order]
    slot = np.arange(len(step)) - np.concatenate([[0], np.cumsum(counts)])[step]
    lm = np.zeros((n, width), dtype=np.int32)
    rng = np.zeros((n, width))
    brg = np.zeros((n, width))
    mask = np.zeros((n, width), dtype=bool)
    lm[step, slot] = [index[int(s)] for s in subj]
    rng[step, slot] = meas[:, 2]
    brg[step, slot] = meas[:, 3]
    mask[step, slot] = True
    on_grid = np.isin(times[1:], grid)
    obs = RangeBearingObservation(lm, rng, brg, mask)
    return MRCLAMSequence(times, odo, obs, truth, data.landmarks, on_grid)


def estimate_noise(data: MRCLAMRobot, *, duration: float = 600.0, dt: float = 0.1) -> dict:
    """Noise scales estimated against motion capture (use a robot other than the test one).

    Returns robust (median absolute deviation) standard deviations of the range and
    bearing errors of landmark measurements, and per-step odometry errors over ``dt`` steps
    split into the ``a * sqrt(dt)`` form of :class:`~models.localization.model.MotionNoise`.
    """
    from models.localization.fit import noise_residuals, robust_noise

    noise = robust_noise(noise_residuals(build_sequence(data, duration=duration, dt=dt)))
    return {k: noise[k] for k in ("sigma_range", "sigma_bearing", "range_bias", "a_xy",
                                  "a_theta", "num_measurements")}  # fmt: skip


#: Noise settings of the MRCLAM model, chosen on robot 2 (held out; robot 1 is the test
#: robot): :func:`estimate_noise` as a guide (range sd ~0.17 m with heavy tails and a 5 cm
#: bias, bearing sd ~0.01 rad, widened for the 0.1 s step quantisation), then a small grid
#: of filter runs there (N = 2,000, first 5 minutes, 2 seeds): position RMSE 0.275 m for
#: (motion 0.02/0.1/0.05/0.1, range sd 0.2) and 0.229 m for the values below.
MRCLAM_NOISE = {
    "motion": (0.01, 0.1, 0.1, 0.1),
    "sigma_range": 0.4,
    "sigma_bearing": 0.05,
    "outlier_prob": 0.05,
    "initial_std": (0.05, 0.05, 0.05),
}


def mrclam_model(seq: MRCLAMSequence, settings: dict | None = None):
    """The range-bearing :class:`RangeBearingLocalizationModel` for a sequence (initial belief
    around the true first pose) with the noise ``settings`` (keys of ``MRCLAM_NOISE``, and
    optionally ``range_bias`` and ``max_range``; default ``MRCLAM_NOISE``)."""
    from models.localization.model import MotionNoise, RangeBearingLocalizationModel

    cfg = MRCLAM_NOISE if settings is None else settings
    extra = {k: float(cfg[k]) for k in ("range_bias", "max_range") if k in cfg}
    return RangeBearingLocalizationModel(
        seq.landmarks,
        seq.truth[0],
        np.asarray(cfg["initial_std"]),
        MotionNoise(*cfg["motion"]),
        sigma_range=cfg["sigma_range"],
        sigma_bearing=cfg["sigma_bearing"],
        outlier_prob=cfg["outlier_prob"],
        **extra,
    )
