"""The localisation noise measured against ground truth (``models.localization.fit``):
residuals computed apart, a SIMULATED robot's noise recovered, the settings it writes."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dbn.errors import InputError
from models.localization.fit import (
    FLOORS,
    NoiseResiduals,
    noise_residuals,
    noise_settings,
    pool_residuals,
    robust_noise,
)
from models.localization.landmarks import measure_landmarks
from models.localization.mrclam import MRCLAM_NOISE, MRCLAMSequence


def _sequence(rng, steps: int, *, sr: float, sb: float, bias: float, sxy: float,
              sth: float) -> MRCLAMSequence:
    """A SIMULATED run of ``steps`` steps of 0.1 s on a random walk among 3 landmarks, each
    measured every step with range noise ``sr`` and ``bias``, bearing noise ``sb``;
    odometry steps with noise ``sxy`` (x and y) and ``sth``."""
    landmarks = np.array([[0.0, 0.0], [4.0, 0.0], [0.0, 4.0]])
    truth = np.cumsum(np.column_stack([rng.normal(0.03, 0.01, (steps + 1, 2)),
                                       rng.normal(0.0, 0.05, steps + 1)]), axis=0)  # fmt: skip
    truth[:, :2] += 2.0
    c, s = np.cos(truth[:-1, 2]), np.sin(truth[:-1, 2])
    d = np.diff(truth, axis=0)
    rel = np.column_stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1], d[:, 2]])
    odo = rel - rng.normal(0.0, 1.0, rel.shape) * [sxy, sxy, sth]
    obs = measure_landmarks(rng, landmarks, truth[1:], sr, sb, bias)
    times = 0.1 * np.arange(steps + 1)
    return MRCLAMSequence(times, np.column_stack([odo, np.full(steps, 0.1)]), obs, truth,
                          landmarks, np.ones(steps, bool))  # fmt: skip


def test_residuals_are_the_errors_against_the_truth():
    seq = _sequence(np.random.default_rng(0), 5, sr=0.1, sb=0.05, bias=0.0, sxy=0.01, sth=0.02)
    true_turn = math.remainder(seq.truth[1, 2] - seq.truth[0, 2], 2 * math.pi)
    seq.odometry[0, 2] = true_turn - 2 * math.pi + 0.01  # a turn read as a turn less a circle
    res = noise_residuals(seq)
    assert res.odometry[0, 2] == pytest.approx(-0.01)  # wrapped, not 2 pi - 0.01
    assert res.range.shape == res.bearing.shape == (15,) and res.odometry.shape == (5, 3)
    assert res.dt == pytest.approx(0.1)
    for n, (k, j) in enumerate(np.ndindex(5, 3)):  # every measurement, step by step
        x, y, th = seq.truth[k + 1]
        lx, ly = seq.landmarks[j]
        assert res.range[n] == pytest.approx(seq.observations.range[k, j] - math.hypot(lx - x,
                                                                                      ly - y))
        b = seq.observations.bearing[k, j] - (math.atan2(ly - y, lx - x) - th)
        assert res.bearing[n] == pytest.approx(math.remainder(b, 2 * math.pi))
    for k in range(5):
        x0, y0, t0 = seq.truth[k]
        x1, y1, t1 = seq.truth[k + 1]
        true = [math.cos(t0) * (x1 - x0) + math.sin(t0) * (y1 - y0),
                -math.sin(t0) * (x1 - x0) + math.cos(t0) * (y1 - y0),
                math.remainder(t1 - t0, 2 * math.pi)]  # fmt: skip
        np.testing.assert_allclose(res.odometry[k, :2], np.subtract(true[:2], seq.odometry[k, :2]),
                                   atol=1e-12)  # fmt: skip
        assert res.odometry[k, 2] == pytest.approx(
            math.remainder(true[2] - seq.odometry[k, 2], 2 * math.pi), abs=1e-12)


def test_a_simulated_robots_noise_is_recovered():
    """4000 steps of SIMULATED noise: each scale within 5 % (the median absolute deviation
    of 12000 Gaussian errors has a relative sd near 1 %), the bias within 3 mm."""
    truth = {"sigma_range": 0.07, "sigma_bearing": 0.02, "range_bias": 0.04,
             "a_xy": 0.004 / math.sqrt(0.1), "a_theta": 0.01 / math.sqrt(0.1)}  # fmt: skip
    seq = _sequence(np.random.default_rng(1), 4000, sr=0.07, sb=0.02, bias=0.04, sxy=0.004,
                    sth=0.01)  # fmt: skip
    got = robust_noise(noise_residuals(seq))
    assert got["num_measurements"] == 12000 and got["num_steps"] == 4000
    for key, want in truth.items():
        tol = 0.003 if key == "range_bias" else 0.05 * want
        assert abs(got[key] - want) < tol, (key, got[key], want)


def test_pooled_runs_are_measured_as_one():
    rng = np.random.default_rng(2)
    a = noise_residuals(_sequence(rng, 50, sr=0.1, sb=0.05, bias=0.0, sxy=0.01, sth=0.02))
    b = noise_residuals(_sequence(rng, 70, sr=0.3, sb=0.01, bias=0.1, sxy=0.03, sth=0.01))
    both = pool_residuals([a, b])
    np.testing.assert_array_equal(both.range, np.concatenate([a.range, b.range]))
    np.testing.assert_array_equal(both.odometry, np.concatenate([a.odometry, b.odometry]))
    assert robust_noise(both)["num_steps"] == 120
    with pytest.raises(InputError, match="steps differ"):
        pool_residuals([a, b._replace(dt=0.2)])
    with pytest.raises(InputError, match="no run"):
        pool_residuals([])


def test_spreads_by_hand():
    """Medians worked out by hand: range errors 0, 1, 2, 3, 100 (an outlier) have median 2
    and absolute deviations 2, 1, 0, 1, 98 (median 1); the x odometry errors -1, 1, -1, 1
    spread 1.4826, the y errors none: the root mean square of the two is 1.4826 / sqrt(2)
    (pooled, the eight errors' deviations have median 0.5)."""
    odo = np.column_stack([[-1.0, 1.0, -1.0, 1.0], np.zeros(4), [0.0, 0.2, 0.4, 0.6]])
    res = NoiseResiduals(np.array([0.0, 1.0, 2.0, 3.0, 100.0]), np.array([0.1, -0.1, 0.3,
                         -0.3, 0.0]), odo, 0.25)  # fmt: skip
    got = robust_noise(res)
    assert got["sigma_range"] == pytest.approx(1.4826) and got["range_bias"] == 2.0
    assert got["sigma_bearing"] == pytest.approx(1.4826 * 0.1)
    assert got["a_xy"] == pytest.approx(1.4826 / math.sqrt(2) / 0.5)  # over sqrt(0.25)
    assert got["a_theta"] == pytest.approx(1.4826 * 0.2 / 0.5)  # median 0.3, deviations 0.2


def test_floors_and_refusals():
    zero = NoiseResiduals(np.zeros(4), np.zeros(4), np.zeros((3, 3)), 0.1)
    got = robust_noise(zero)  # errors rounded away: each scale its floor, never 0
    assert {k: got[k] for k in FLOORS} == FLOORS
    with pytest.raises(InputError, match="0 landmark measurements"):
        robust_noise(zero._replace(range=np.zeros(0), bearing=np.zeros(0)))


def test_settings_scale_the_measured_noise_and_keep_the_rest():
    measured = {"sigma_range": 0.1, "sigma_bearing": 0.01, "range_bias": 0.05, "a_xy": 0.02,
                "a_theta": 0.03}  # fmt: skip
    base = {**MRCLAM_NOISE, "max_range": 7.0}
    got = noise_settings(base, measured, 2.0, 4.0)
    b_xy, b_theta = MRCLAM_NOISE["motion"][1], MRCLAM_NOISE["motion"][3]
    assert got["motion"] == pytest.approx((0.04, b_xy, 0.06, b_theta))
    assert got["sigma_range"] == pytest.approx(0.4) and got["sigma_bearing"] == pytest.approx(0.04)
    assert got["range_bias"] == 0.05 and got["max_range"] == 7.0
    assert got["outlier_prob"] == base["outlier_prob"]
    assert got["initial_std"] == base["initial_std"]
    with pytest.raises(InputError, match="scales"):
        noise_settings(base, measured, 0.0, 1.0)
