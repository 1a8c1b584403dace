"""``models.pathrecovery.fit``: the network's W^p and gap means counted from the objects'
observed moves, against moves counted by hand and a SIMULATED scene's own network."""

from __future__ import annotations

import numpy as np
import pytest

from dbn.errors import InputError
from models.pathrecovery.fit import count_moves, fitted_network, pool_moves
from models.pathrecovery.model import CameraNetwork
from models.pathrecovery.simulate import manhattan_grid, simulate_scene


def _net() -> CameraNetwork:
    """Three cameras: 0 -> {0, 1, 2 (gap 3)}, 1 -> {0, 1}, 2 -> {0 (gap 2), 2}."""
    indptr = np.array([0, 3, 5, 7])
    indices = np.array([0, 1, 2, 0, 1, 0, 2])
    probs = np.array([0.5, 0.3, 0.2, 0.4, 0.6, 0.1, 0.9])
    gap = np.array([0, 0, 3.0, 0, 0, 2.0, 0])
    return CameraNetwork(indptr, indices, probs, gap, np.zeros((3, 2)))


# (t, camera, object), in no particular order
OBS = np.array([
    [0, 0, 7], [1, 1, 7], [2, 0, 7], [5, 2, 7],  # 0->1 (1), 1->0 (1), 0->2 (3, a gap edge)
    [4, 0, 8], [0, 2, 8], [1, 2, 8],             # 2->2 (1), 2->0 (3, a gap edge)
    [0, 1, 9], [2, 1, 9],                        # 1->1 in 2 steps: no gap on a self loop
    [1, 2, 10], [0, 1, 10],                      # 1->2: not an edge
    [3, 0, 11],                                  # one observation: no move
])  # fmt: skip


def test_moves_counted_by_hand():
    c = count_moves(_net(), *OBS.T)
    np.testing.assert_array_equal(c.edge_moves, [0, 1, 1, 1, 0, 1, 1])
    np.testing.assert_array_equal(c.delay_sums, [0, 1, 3, 1, 0, 3, 1])
    assert c.unexplained == 2


def test_an_object_twice_in_a_step_is_refused():
    with pytest.raises(InputError, match="object 7 is observed twice at t = 1"):
        count_moves(_net(), *np.vstack([OBS, [[1, 2, 7]]]).T)


def test_fitted_network_by_hand():
    """W^p = (n_e + lambda p_e) / (n_a + lambda), gap mean (D_e + lambda mu_e) / (n_e +
    lambda) on gap edges, 0 elsewhere; pooled runs add their counts."""
    net = _net()
    c = count_moves(net, *OBS.T)
    fit = fitted_network(net, pool_moves([c, c]), strength=2.0)  # n doubled
    n = 2 * np.array([0, 1, 1, 1, 0, 1, 1])
    leaving = np.array([4, 4, 4, 2, 2, 4, 4])
    np.testing.assert_allclose(fit.probs, (n + 2 * net.probs) / (leaving + 2), rtol=1e-12)
    np.testing.assert_allclose(fit.gap_mean, [0, 0, (6 + 2 * 3) / 4, 0, 0, (6 + 2 * 2) / 4, 0],
                               rtol=1e-12)  # fmt: skip
    np.testing.assert_allclose(np.add.reduceat(fit.probs, net.indptr[:-1]), 1.0, rtol=1e-12)
    nothing = count_moves(net, [0], [1], [5])  # camera 1's object never moves
    np.testing.assert_allclose(fitted_network(net, nothing).probs, net.probs, rtol=1e-12)
    with pytest.raises(InputError, match="strength"):
        fitted_network(net, c, strength=0.0)


def test_a_simulated_scene_gives_its_network_back():
    """Every object's moves of a SIMULATED scene (2000 walkers, 60 steps on 490 cameras)
    give the simulator's network back within sampling error: each W^p of a camera left 100
    times or more within 5 binomial standard errors, each gap mean of an edge crossed 10
    times or more within 5 standard errors of a mean delay (sd 0.2 mu, rounding's 1/12),
    and the gap means' mean relative error within 2 % (gaps open at the end are unseen)."""
    net = manhattan_grid(0)
    scene = simulate_scene(4, net, num_objects=2000, num_timesteps=60, cm=0.17)
    odb = scene.odb
    steps = np.repeat(np.arange(odb.num_timesteps), np.diff(odb.time_ptr))
    c = count_moves(net, steps, odb.cam, odb.obj)
    assert c.unexplained == 0
    fit = fitted_network(net, c)
    src = np.repeat(np.arange(net.num_cameras), np.diff(net.indptr))
    left = np.bincount(src, weights=c.edge_moves, minlength=net.num_cameras)[src]
    busy = left >= 100
    assert busy.sum() > 1000
    se = np.sqrt(net.probs * (1 - net.probs) / np.maximum(left, 1))
    assert np.abs((fit.probs - net.probs) / se)[busy].max() < 5
    gap = (net.gap_mean > 0) & (c.edge_moves >= 10)
    assert gap.sum() > 100
    mu, n = net.gap_mean[gap], c.edge_moves[gap]
    assert np.abs((fit.gap_mean[gap] - mu) / np.sqrt((0.04 * mu**2 + 1 / 12) / n)).max() < 5
    assert abs(np.mean(fit.gap_mean[gap] / mu - 1)) < 0.02
