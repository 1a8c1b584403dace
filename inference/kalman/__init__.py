"""Kalman filter (float64, Cholesky): the closed-form oracle of the particle filter tests."""

from inference.kalman.filter import (
    KalmanResult,
    LinearGaussianParams,
    kalman_filter,
    lgssm_joint_log_likelihood,
    lgssm_sample,
)

__all__ = [
    "KalmanResult",
    "LinearGaussianParams",
    "kalman_filter",
    "lgssm_joint_log_likelihood",
    "lgssm_sample",
]
