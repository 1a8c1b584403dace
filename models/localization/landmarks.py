"""SIMULATED range-bearing measurements of known landmarks: the one measurement simulator of
the range-bearing examples, tests and benchmarks (each drives its own path)."""

from __future__ import annotations

import numpy as np

from models.localization.model import RangeBearingObservation, wrap_angle

__all__ = ["measure_landmarks"]


def measure_landmarks(rng: np.random.Generator, landmarks: np.ndarray, poses: np.ndarray,
                      sd_range: float, sd_bearing: float, bias: float = 0.0
                      ) -> RangeBearingObservation:  # fmt: skip
    r"""Every landmark measured from every pose (SIMULATED):
    :math:`r = \lVert l - p_{xy} \rVert + b + \sigma_r \varepsilon`,
    :math:`\beta = \mathrm{wrap}(\operatorname{atan2}(l - p_{xy}) - p_\theta + \sigma_\beta
    \varepsilon')`, the range model of :class:`RangeBearingLocalizationModel` (seed 002's
    parametric sensor) with a range ``bias``. The range noise of every pose is drawn
    before the bearing noise.

    Parameters
    ----------
    rng : numpy Generator (the draws: ``(T, L)`` standard normals for ranges, then bearings)
    landmarks : (L, 2) metres
    poses : (T, 3) ``(x, y, theta)``
    sd_range, sd_bearing : metres, radians
    bias : metres added to every range

    Returns
    -------
    RangeBearingObservation of ``(T, L)`` arrays, all masked in.
    """
    landmarks, poses = np.asarray(landmarks, float), np.asarray(poses, float)
    dx = landmarks[None, :, 0] - poses[:, None, 0]
    dy = landmarks[None, :, 1] - poses[:, None, 1]
    ranges = np.hypot(dx, dy) + bias + sd_range * rng.standard_normal(dx.shape)
    noise = sd_bearing * rng.standard_normal(dx.shape)
    bearing = np.asarray(wrap_angle(np.arctan2(dy, dx) - poses[:, None, 2] + noise))
    lm = np.broadcast_to(np.arange(len(landmarks), dtype=np.int32), dx.shape).copy()
    return RangeBearingObservation(lm, ranges, bearing, np.ones(dx.shape, bool))
