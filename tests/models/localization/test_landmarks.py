"""The SIMULATED range-bearing measurements against their closed form."""

import math

import numpy as np
import pytest

from models.localization.landmarks import measure_landmarks


def test_noise_free_measurements_are_the_geometry():
    landmarks = np.array([[3.0, 4.0], [-1.0, 0.0]])
    poses = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 3.0], [3.0, 0.0, -math.pi / 2]])
    obs = measure_landmarks(np.random.default_rng(0), landmarks, poses, 0.0, 0.0, bias=0.5)
    assert obs.range.shape == obs.bearing.shape == obs.mask.shape == (3, 2) and obs.mask.all()
    np.testing.assert_allclose(obs.range, [[5.5, 1.5], [5.5, 1.5], [4.5, 4.5]])
    wrap = math.remainder  # the robot's frame, in [-pi, pi]
    expected = [[math.atan2(4, 3), math.pi], [wrap(math.atan2(4, 3) - 3.0, 2 * math.pi),
                wrap(math.pi - 3.0, 2 * math.pi)], [math.pi, -math.pi / 2]]  # fmt: skip
    np.testing.assert_allclose(np.cos(obs.bearing), np.cos(expected), atol=1e-12)
    np.testing.assert_allclose(np.sin(obs.bearing), np.sin(expected), atol=1e-12)
    assert np.all((obs.bearing >= -math.pi) & (obs.bearing < math.pi))
    np.testing.assert_array_equal(obs.landmark, [[0, 1]] * 3)


def test_the_noise_has_the_asked_spread():
    poses = np.zeros((20000, 3))
    obs = measure_landmarks(np.random.default_rng(1), np.array([[10.0, 0.0]]), poses, 0.3, 0.01)
    assert np.mean(obs.range) == pytest.approx(10.0, abs=0.01)
    assert np.std(obs.range) == pytest.approx(0.3, rel=0.03)
    assert np.std(obs.bearing) == pytest.approx(0.01, rel=0.03)
