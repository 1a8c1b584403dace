"""The compiled per-move loops equal their numpy references (projection, eq. 10 term)."""

from __future__ import annotations

import numpy as np
import pytest

from models.rjmcmc3d import compiled
from models.rjmcmc3d.likelihood import IncrementalLikelihood, prepare_frame
from models.rjmcmc3d.model import TrackerParams
from models.rjmcmc3d.projection import BoxProjector
from models.rjmcmc3d.scene import default_scene, render_frame, simulate_walkers
from models.rjmcmc3d.tracker import RJMCMCTracker

pytestmark = pytest.mark.skipif(not compiled.AVAILABLE, reason="numba not installed")


@pytest.fixture(scope="module")
def scene():
    return default_scene(0, width=192, height=144)


def test_projection_equals_numpy(scene) -> None:
    proj = BoxProjector(scene)
    rng = np.random.default_rng(0)
    fl = scene.floor
    for _ in range(300):
        x, y = rng.uniform(fl[0] - 2, fl[1] + 2), rng.uniform(fl[2] - 2, fl[3] + 2)
        h, a = rng.uniform(1.4, 2.0), rng.uniform(-np.pi, np.pi)
        fast, ref = proj.one(x, y, h, a), proj.one_numpy(x, y, h, a)
        assert fast[0] == ref[0] and fast[1] == ref[1]
        np.testing.assert_allclose(fast[2], ref[2], rtol=1e-12)


def test_colour_cost_equals_numpy(scene) -> None:
    """Colour terms with occluders, on a chain state carrying reference histograms."""
    truth = simulate_walkers(3, scene, 6, 7)
    params = TrackerParams(num_moves=300, burn_in=50)
    tracker = RJMCMCTracker(scene, params)
    state = tracker.init_state()
    for t in range(4):
        state, _ = tracker.step(t, state, render_frame(4, scene, truth, t))
    chain = tracker.frame_chain(state, render_frame(4, scene, truth, 4))
    lik = chain.lik
    assert isinstance(lik, IncrementalLikelihood)
    rng = np.random.default_rng(1)
    checked = 0
    for _ in range(200):
        j = int(rng.integers(params.max_objects))
        s = chain.S[j].copy()
        s[:2] += rng.normal(0, 0.5, 2)
        boxes, bbox, depth = chain.proj.one(*s.tolist())
        for v in range(scene.num_views):
            occ = [
                (k, lik.boxes_l[v][k], lik.bbox_l[v][k], lik.depth_l[v][k])
                for k in lik.alive
                if k != j
            ]
            args = (v, j, boxes[v], bbox[v], depth[v], occ)
            ref = lik._slot_cost_numpy(*args)
            assert lik._slot_cost(*args) == pytest.approx(ref, rel=1e-10, abs=1e-10)
            checked += ref != 0.0
    assert checked > 50
    assert prepare_frame(params, render_frame(4, scene, truth, 4)).code.dtype == np.int64


def test_update_density_equals_python(scene, monkeypatch) -> None:
    truth = simulate_walkers(3, scene, 2, 7)
    tracker = RJMCMCTracker(scene, TrackerParams(num_moves=300, burn_in=50))
    chain = tracker.frame_chain(tracker.init_state(), render_frame(4, scene, truth, 1))
    assert chain.det.shape[0] >= 3
    rng = np.random.default_rng(2)
    p = tracker.params
    near_seen = 0
    for _ in range(300):
        d = chain.det[int(rng.integers(chain.det.shape[0]))]
        x0, y0 = (d + rng.normal(0, 0.3, 2)).tolist()
        x1, y1 = (d + rng.normal(0, 0.3, 2)).tolist()
        L, near = chain._kernel_at(x0, y0)
        near_seen += bool(near)
        with monkeypatch.context() as m:
            m.setattr(compiled, "AVAILABLE", False)
            ref = chain._log_q_update(x1, y1, x0, y0)
        got = compiled.update_log_q(x1, y1, x0, y0, *L, chain.det, p.det_gate**2, p.p_det_update)
        assert got == pytest.approx(ref, rel=1e-12, abs=1e-12)
    assert near_seen > 100


def test_compiled_and_numpy_chains_coincide(scene, monkeypatch) -> None:
    """The whole tracker with and without the compiled loops: the same tracks."""
    truth = simulate_walkers(3, scene, 5, 7)
    tracker = RJMCMCTracker(scene, TrackerParams(num_moves=400, burn_in=100))
    frames = [render_frame(4, scene, truth, t) for t in range(5)]
    fast = tracker.run(11, frames)
    monkeypatch.setattr(compiled, "AVAILABLE", False)
    ref = tracker.run(11, frames)
    for a, b in zip(fast, ref, strict=True):
        assert np.array_equal(a.ids, b.ids)
        np.testing.assert_allclose(a.X, b.X, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(a.accept_rate, b.accept_rate, equal_nan=True)
    assert sum(len(a.ids) for a in fast) >= 10


def test_frame_codes_equal_numpy(scene, monkeypatch) -> None:
    truth = simulate_walkers(3, scene, 2, 7)
    frame = render_frame(4, scene, truth, 1)
    params = TrackerParams()
    fast = prepare_frame(params, frame)
    monkeypatch.setattr(compiled, "AVAILABLE", False)
    ref = prepare_frame(params, frame)
    for a, b in zip(fast, ref, strict=True):
        assert np.array_equal(a, b)
