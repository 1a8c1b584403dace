"""Seed 001 simulator: topologies, delays, propagation, scenes and the confusion measure."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import chi2

from dbn.errors import InputError, ModelError, NonFiniteError, NotNormalizedError, ShapeError
from models.pathrecovery import (
    CameraNetwork,
    confusion_measure,
    manhattan_grid,
    propagate,
    similarity,
    simulate_scene,
    street,
)
from models.pathrecovery.model import whiten


def test_grid_size_and_degree():
    net = manhattan_grid(0, 7, 7, (4, 3))
    assert net.num_cameras == 4 * 49 + 4 * 7 * 6 + 3 * 7 * 6
    deg = net.degrees()
    # clique cameras: self + 3 clique + 1 street (4 at the border); chain cameras: 3
    n_border = 4 * 7
    want = (5 * 196 - n_border + 3 * (net.num_cameras - 196)) / net.num_cameras
    assert deg.mean() == pytest.approx(want)
    assert 3.6 < deg.mean() < 3.8
    big = manhattan_grid(0, 22, 21)
    assert 4800 < big.num_cameras < 5100


def test_street_degrees():
    net = street(0, n_per_side=250)
    deg = net.degrees()
    assert net.num_cameras == 500
    # interior cameras have 4 neighbours + self, the four end cameras 2 + self
    assert np.sum(deg == 5) == 496 and np.sum(deg == 3) == 4


@pytest.mark.parametrize("make", [manhattan_grid, street])
def test_transitions_self_loop_bias_and_gaps(make):
    net = make(3)
    rows = net.rows
    self_edge = rows == net.indices
    assert np.allclose(net.probs[self_edge], 0.5)
    row_sum = np.bincount(rows, weights=net.probs)
    assert np.allclose(row_sum, 1.0)
    # directional bias: in every row with both kinds, favoured edges weigh 1.2x the others
    ratios = []
    for i in range(0, net.num_cameras, 7):
        p = net.probs[net.indptr[i] : net.indptr[i + 1]][~self_edge[net.indptr[i] : net.indptr[i + 1]]]
        if p.min() < p.max() - 1e-12:
            ratios.append(p.max() / p.min())
    assert ratios and np.allclose(ratios, 1.2)
    # gaps on 20 % of the undirected edges, half of mean 7, half of mean 3; symmetric
    und = (rows < net.indices)
    gaps = net.gap_mean[und]
    assert np.mean(gaps > 0) == pytest.approx(0.2, abs=1.0 / und.sum())
    assert abs(np.sum(gaps == 7.0) - np.sum(gaps == 3.0)) <= 1
    back = net.edge_index(net.indices, rows)
    assert np.array_equal(net.gap_mean, net.gap_mean[back])


def test_delay_pmf_and_sampling_agree():
    net = manhattan_grid(1)
    assert np.allclose(net.delay_pmf.sum(axis=1), 1.0)
    gap_edges = np.flatnonzero(net.gap_mean == 7.0)[:1]
    rng = np.random.default_rng(0)
    n = 20000
    d = net.sample_delays(rng, np.repeat(gap_edges, n))
    counts = np.bincount(d, minlength=net.delay_pmf.shape[1])
    expected = n * net.delay_pmf[gap_edges[0]]
    keep = expected > 5
    stat = np.sum((counts[keep] - expected[keep]) ** 2 / expected[keep])
    assert stat < chi2.ppf(0.999, keep.sum() - 1)
    assert np.all(net.sample_delays(rng, np.flatnonzero(net.gap_mean == 0)) == 1)


def test_propagate_walks_edges_and_counts_down():
    net = manhattan_grid(2)
    rng = np.random.default_rng(1)
    cam = np.full(30000, 10)
    ta = np.zeros(30000, dtype=np.int64)
    new_cam, new_ta, moved = propagate(rng, net, cam, ta)
    row = slice(net.indptr[10], net.indptr[11])
    assert set(np.unique(new_cam)) <= set(net.indices[row])
    assert np.all(moved == 10)
    # empirical next-camera frequencies match W^p (chi-square at 0.1 %)
    counts = np.array([np.sum(new_cam == j) for j in net.indices[row]])
    expected = cam.size * net.probs[row]
    stat = np.sum((counts - expected) ** 2 / expected)
    assert stat < chi2.ppf(0.999, counts.size - 1)
    # hidden objects only count down, visible again at their destination
    h_cam, h_ta, h_moved = propagate(rng, net, np.array([5, 6]), np.array([3, 1]))
    assert h_cam.tolist() == [5, 6] and h_ta.tolist() == [2, 0] and h_moved.tolist() == [-1, -1]
    # without gaps nobody becomes hidden
    _, ta2, _ = propagate(rng, net, cam, ta, gaps=False)
    assert np.all(ta2 == 0)


def test_network_rejects_bad_declarations():
    ok = dict(
        indptr=np.array([0, 2, 4]),
        indices=np.array([0, 1, 0, 1]),
        probs=np.array([0.5, 0.5, 0.5, 0.5]),
        gap_mean=np.zeros(4),
        coords=np.zeros((2, 2)),
    )
    CameraNetwork(**ok)
    with pytest.raises(NotNormalizedError, match="camera 0"):
        CameraNetwork(**{**ok, "probs": np.array([0.5, 0.6, 0.5, 0.5])})
    with pytest.raises(ModelError, match="self loop"):
        CameraNetwork(
            **{
                **ok,
                "indptr": np.array([0, 1, 3]),
                "indices": np.array([1, 0, 1]),
                "probs": np.array([1.0, 0.5, 0.5]),
                "gap_mean": np.zeros(3),
            }
        )
    with pytest.raises(ModelError, match="gap"):
        CameraNetwork(**{**ok, "gap_mean": np.array([3.0, 0, 0, 0])})
    with pytest.raises(ModelError, match="coords"):
        CameraNetwork(**{**ok, "coords": np.zeros((3, 2))})
    with pytest.raises(ModelError):
        manhattan_grid(0, p_self=1.5)


_NET = dict(indptr=[0, 2, 4], indices=[0, 1, 0, 1], probs=[0.5, 0.5, 0.5, 0.5],
            gap_mean=[0.0, 1.0, 1.0, 0.0], coords=[[0.0, 0.0], [1.0, 0.0]])


@pytest.mark.parametrize(("field", "value", "needle"), [
    ("probs", np.array([0.5, 0.5, 0.5, 0.5]) + 0j, "probs holds complex numbers"),
    ("coords", [["a", "b"], ["c", "d"]], "coords is not an array of numbers"),
    ("indices", [0, 1.7, 0, 1], "indices must be whole numbers, got [1.7]"),
    ("indptr", [0, 2, np.nan], "indptr must be whole numbers"),
])  # fmt: skip
def test_network_arrays_that_are_not_numbers_are_refused_naming_the_field(field, value, needle):
    """Complex probabilities lost their imaginary parts (a ComplexWarning), an index of 1.7
    became 1, and strings raised numpy's ValueError."""
    with pytest.raises(ModelError) as exc:
        CameraNetwork(**{**_NET, field: value})
    assert needle in str(exc.value)


def test_a_network_copies_the_callers_arrays():
    """The network froze the caller's own arrays (their next assignment raised numpy's
    read-only error); it keeps copies, frozen."""
    arrays = {k: np.array(v) for k, v in _NET.items()}
    net = CameraNetwork(**arrays)
    for name, a in arrays.items():
        assert a.flags.writeable, name
        assert not getattr(net, name).flags.writeable, name
    arrays["probs"][:] = 9.0
    assert net.probs.tolist() == _NET["probs"]


@pytest.mark.parametrize("gap", [1e7, 1e200])
def test_a_gap_whose_delay_table_would_not_fit_is_refused_naming_the_edge(gap, monkeypatch):
    """gap_mean 1e7 (steps) on one edge asked for a 96 x 18,000,001 table (12.9 GiB; it
    ran out of memory, or took it where it was there); 1e200 wrapped in the int cast and
    ran as a one-step edge. At the limit the table is built."""
    from models.pathrecovery import model

    ok = dict(indptr=np.array([0, 2, 4]), indices=np.array([0, 1, 0, 1]),
              probs=np.array([0.5, 0.5, 0.5, 0.5]), coords=np.zeros((2, 2)))  # fmt: skip
    with pytest.raises(ModelError, match=r"gap_mean .* on edge 1 -> 0: its delay pmf table"):
        CameraNetwork(**ok, gap_mean=np.array([0, 5.0, gap, 0]))
    mu = 1000.0  # at the limit the table is built; one step beyond, refused
    monkeypatch.setattr(model, "MAX_DELAY_TABLE", 4 * (int(np.ceil(mu * 1.8)) + 1))
    net = CameraNetwork(**ok, gap_mean=np.array([0, 5.0, mu, 0]))
    assert net.delay_pmf.shape == (4, int(np.ceil(mu * 1.8)) + 1)
    with pytest.raises(ModelError, match="1 -> 0"):
        CameraNetwork(**ok, gap_mean=np.array([0, 5.0, mu + 1, 0]))
    with pytest.raises(ModelError, match="too long a gap"):
        model.delay_support(np.array([gap * 1e15]))


def test_confusion_measure_by_hand():
    # GT similarities 0.9, 0.5 -> a = 0.5; others 0.6, 0.95 inside Omega, 0.4 outside
    s = np.array([0.9, 0.5, 0.6, 0.4, 0.95])
    gt = np.array([True, True, False, False, False])
    assert confusion_measure(s, gt) == pytest.approx((0.6 + 0.95) / (0.9 + 0.5 + 0.6 + 0.95))
    with pytest.raises(InputError):
        confusion_measure(s, np.zeros(5, dtype=bool))
    with pytest.raises(ShapeError):
        confusion_measure(s, gt[:3])


def test_similarity_is_mahalanobis_kernel():
    sigma = np.array([[2.0, 0.3], [0.3, 1.0]])
    chol = np.linalg.cholesky(sigma)
    f1, f2 = np.array([0.3, -1.0]), np.array([1.0, 0.5])
    d = f1 - f2
    assert similarity(f1, f2, chol) == pytest.approx(np.exp(-0.5 * d @ np.linalg.solve(sigma, d)))
    x = np.random.default_rng(0).standard_normal((5, 2))
    assert np.allclose(chol @ whiten(chol, x).T, x.T)


@pytest.fixture(scope="module")
def grid():
    return manhattan_grid(0)


def test_scene_hits_requested_cm_and_is_reproducible(grid):
    for cm in (0.17, 0.4):
        scene = simulate_scene(5, grid, num_objects=800, num_timesteps=60, cm=cm)
        assert abs(scene.cm - cm) < 0.02
        # the reported CM is the CM of the data (recomputed independently)
        sim = similarity(scene.odb.feat, scene.f0, np.linalg.cholesky(scene.sigma))
        assert confusion_measure(sim, scene.odb.obj == scene.target) == pytest.approx(scene.cm)
    a = simulate_scene(7, grid, num_objects=300, num_timesteps=30, cm=0.2)
    b = simulate_scene(7, grid, num_objects=300, num_timesteps=30, cm=0.2)
    c = simulate_scene(8, grid, num_objects=300, num_timesteps=30, cm=0.2)
    assert np.array_equal(a.odb.feat, b.odb.feat) and np.array_equal(a.true_cam, b.true_cam)
    assert not np.array_equal(a.true_cam, c.true_cam)


def test_scene_ground_truth_is_consistent(grid):
    scene = simulate_scene(3, grid, num_objects=500, num_timesteps=80, cm=0.2)
    odb = scene.odb
    for t in range(odb.num_timesteps):
        lo, hi = odb.time_ptr[t], odb.time_ptr[t + 1]
        assert np.all(np.diff(odb.cam[lo:hi]) >= 0)
        mine = np.flatnonzero(odb.obj[lo:hi] == scene.target)
        if scene.true_ta[t] > 0:
            assert mine.size == 0 and scene.true_obs[t] == -1
        else:
            assert mine.size == 1 and scene.true_obs[t] == lo + mine[0]
            assert odb.cam[scene.true_obs[t]] == scene.true_cam[t]
    # a visible object's count of visible objects equals the number of observations
    assert odb.cam.size == np.sum(scene.obj_ta == 0)
    # the target's path is legal: consecutive visible cameras are joined by an edge
    for t in range(1, odb.num_timesteps):
        if scene.true_ta[t - 1] == 0:
            assert grid.edge_index(np.array([scene.true_cam[t - 1]]), np.array([scene.true_cam[t]]))[0] >= 0


def test_feature_drift_has_mean_f0(grid):
    """Eq. 11: E f_t = f_0; the drift's stationary variance is (1-g)^2/(1-(1-g)^2) Sigma."""
    scene = simulate_scene(4, grid, num_objects=2000, num_timesteps=40, spread=1.0, cm=None)
    odb = scene.odb
    late = odb.time_ptr[20]
    # e_0 = 0: the features at t = 0 are the object means
    f_obj = np.full((2000, scene.f0.size), np.nan)
    f_obj[odb.obj[: odb.time_ptr[1]]] = odb.feat[: odb.time_ptr[1]]
    dev = odb.feat[late:] - f_obj[odb.obj[late:]]
    dev = dev[~np.isnan(dev[:, 0])]
    var = 0.2**2 / (1 - 0.2**2)
    # lag-1 autocorrelation 0.2 (geometric): variance of the mean inflated by (1+r)/(1-r) = 1.5
    se = np.sqrt(1.5 * var / dev.shape[0])
    assert np.all(np.abs(dev.mean(axis=0)) < 4 * se)
    assert dev.var(axis=0) == pytest.approx(np.full(scene.f0.size, var), rel=0.05)


def test_scene_bad_input(grid):
    with pytest.raises(InputError):
        simulate_scene(0, grid, num_objects=50, num_timesteps=20, cm=1.5)
    with pytest.raises(InputError):
        simulate_scene(0, grid, num_objects=50, num_timesteps=20, cm=0.2, spread=1.0)
    with pytest.raises(InputError):
        simulate_scene(0, grid, num_objects=50, num_timesteps=20, cm=0.2, gamma=1.0)
    with pytest.raises(ShapeError):
        simulate_scene(0, grid, num_objects=50, num_timesteps=20, cm=0.2, sigma=np.eye(3))
    with pytest.raises(NonFiniteError, match="sigma"):  # was scipy's ValueError
        simulate_scene(0, grid, num_objects=50, num_timesteps=20, cm=0.2,
                       sigma=np.full((4, 4), np.nan))  # fmt: skip
