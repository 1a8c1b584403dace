r"""Noise scales of the range-bearing localisation model measured against ground truth.

With the robot's true poses known, every landmark measurement has a range error
:math:`r_m - \hat r_m` and a bearing error :math:`\mathrm{wrap}(b_m - \hat b_m)`
(:math:`\hat r_m, \hat b_m` from the true pose, seed 002 eq. 1.13), and every filter step
an odometry error, the true relative pose less the integrated odometry (eq. 1.12). Their
robust spreads (1.4826 times the median absolute deviation, which the heavy tails the
model's outlier term absorbs do not inflate) and the median range error are the
measurement noise, the range bias and the ``a * sqrt(dt)`` part of
:class:`~models.localization.model.MotionNoise` (the ``b`` parts, proportional to the
motion, are not measured: they are kept). :func:`noise_settings` scales them for a filter
(the step's quantisation and the truth's own error make a filter with the bare spreads
overconfident: :mod:`models.track.localization_fit` searches the scales).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from dbn.errors import InputError
from models.localization.model import relative_pose, wrap_angle

__all__ = ["NoiseResiduals", "noise_residuals", "pool_residuals", "robust_noise",
           "noise_settings", "FLOORS"]  # fmt: skip

FLOORS = {"sigma_range": 1e-3, "sigma_bearing": 1e-3, "a_xy": 1e-4, "a_theta": 1e-4}
"""The least scale :func:`robust_noise` returns (m, rad, m / sqrt(s), rad / sqrt(s)): data
rounded to fewer digits than its noise can have a median absolute deviation of 0."""


class NoiseResiduals(NamedTuple):
    """The errors of one run (or several pooled) against its ground truth.

    Attributes
    ----------
    range : (M,) measured less true range of every landmark measurement [m]
    bearing : (M,) measured less true bearing, wrapped to [-pi, pi) [rad]
    odometry : (T, 3) true relative pose less the odometry step ``(dx, dy, dtheta)``
    dt : float, the filter's step [s]
    """

    range: np.ndarray
    bearing: np.ndarray
    odometry: np.ndarray
    dt: float


def noise_residuals(seq) -> NoiseResiduals:
    """The residuals of a :class:`~models.localization.mrclam.MRCLAMSequence` (its
    ``truth`` the true poses ``(T + 1, 3)`` at the step times)."""
    obs = seq.observations
    k, j = np.nonzero(np.asarray(obs.mask))
    pose = seq.truth[k + 1]
    lm = seq.landmarks[np.asarray(obs.landmark)[k, j]]
    r_hat = np.hypot(lm[:, 0] - pose[:, 0], lm[:, 1] - pose[:, 1])
    b_hat = np.arctan2(lm[:, 1] - pose[:, 1], lm[:, 0] - pose[:, 0]) - pose[:, 2]
    er = np.asarray(obs.range)[k, j] - r_hat
    eb = np.asarray(wrap_angle(np.asarray(obs.bearing)[k, j] - b_hat))
    odo = relative_pose(seq.truth[:-1], seq.truth[1:]) - seq.odometry[:, :3]
    odo[:, 2] = wrap_angle(odo[:, 2])
    dt = float(np.median(seq.odometry[:, 3]))
    return NoiseResiduals(er, eb, odo, dt)


def pool_residuals(runs: Sequence[NoiseResiduals]) -> NoiseResiduals:
    """Several runs' residuals as one (their steps must have the same ``dt``)."""
    if not runs:
        raise InputError("pool_residuals: no run to pool")
    steps = sorted({r.dt for r in runs})
    if not np.allclose(steps, steps[0]):
        raise InputError(f"pool_residuals: the runs' steps differ ({steps} s)")
    return NoiseResiduals(np.concatenate([r.range for r in runs]),
                          np.concatenate([r.bearing for r in runs]),
                          np.concatenate([r.odometry for r in runs]), steps[0])  # fmt: skip


def _spread(e: np.ndarray) -> float:
    """1.4826 x the median absolute deviation (the sd of a Gaussian's sample)."""
    return 1.4826 * float(np.median(np.abs(e - np.median(e))))


def robust_noise(res: NoiseResiduals) -> dict:
    """The measured noise: ``sigma_range``, ``sigma_bearing``, ``range_bias`` (the median
    range error), ``a_xy`` (the root mean square of the spreads of the odometry's x and y
    errors, over ``sqrt(dt)``: the model's one ``sigma_xy`` for both axes, whose
    maximum-likelihood variance is the mean of the two; pooling the errors instead would
    give the lesser axis's spread where the two differ, as a robot's along-track and
    lateral errors do), ``a_theta``, each scale at least its :data:`FLOORS` entry, with
    ``num_measurements`` and ``num_steps``.

    Raises
    ------
    InputError
        No landmark measurement or no step to measure on.
    """
    if res.range.size == 0 or len(res.odometry) == 0:
        raise InputError(f"{res.range.size} landmark measurements and {len(res.odometry)} "
                         "steps: the noise needs some of each")  # fmt: skip
    root = math.sqrt(res.dt)
    out = {"sigma_range": _spread(res.range), "sigma_bearing": _spread(res.bearing),
           "a_xy": math.hypot(_spread(res.odometry[:, 0]), _spread(res.odometry[:, 1]))
           / math.sqrt(2.0) / root,
           "a_theta": _spread(res.odometry[:, 2]) / root}  # fmt: skip
    out = {k: max(v, FLOORS[k]) for k, v in out.items()}
    return {**out, "range_bias": float(np.median(res.range)),
            "num_measurements": int(res.range.size), "num_steps": int(len(res.odometry))}


def noise_settings(base: dict, measured: dict, motion_scale: float, sensor_scale: float) -> dict:
    """``base`` (settings as :data:`~models.localization.mrclam.MRCLAM_NOISE`: ``motion``
    ``(a_xy, b_xy, a_theta, b_theta)``, ``sigma_range``, ``sigma_bearing``, ...) with the
    ``measured`` noise (:func:`robust_noise`) written over it: ``a_xy`` and ``a_theta``
    times ``motion_scale``, ``sigma_range`` and ``sigma_bearing`` times ``sensor_scale``,
    ``range_bias`` as measured; ``b_xy``, ``b_theta`` and the other keys kept."""
    if not (motion_scale > 0 and sensor_scale > 0):
        raise InputError(f"noise scales must be > 0, got {motion_scale!r}, {sensor_scale!r}")
    _, b_xy, _, b_theta = base["motion"]
    motion = (measured["a_xy"] * motion_scale, b_xy, measured["a_theta"] * motion_scale, b_theta)
    return {**base, "motion": tuple(float(v) for v in motion),
            "sigma_range": measured["sigma_range"] * sensor_scale,
            "sigma_bearing": measured["sigma_bearing"] * sensor_scale,
            "range_bias": measured["range_bias"]}  # fmt: skip
