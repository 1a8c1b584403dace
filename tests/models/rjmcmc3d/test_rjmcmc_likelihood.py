"""Likelihood of seed 003, eqs. 8-10: the incremental version equals the full recompute."""

from __future__ import annotations

import math

import numpy as np
import pytest

from models.rjmcmc3d.likelihood import (
    Config,
    IncrementalLikelihood,
    colour_cost,
    full_loglik,
    prepare_frame,
)
from models.rjmcmc3d.model import TrackerParams
from models.rjmcmc3d.scene import Frame, default_scene, render_frame, simulate_walkers
from models.rjmcmc3d.tracker import RJMCMCTracker


def _frame(D: np.ndarray, image: np.ndarray) -> Frame:
    return Frame(D, image, np.zeros(0, np.int64), np.zeros((0, 2)), np.zeros((0, 2)))


def test_foreground_term_closed_form() -> None:
    """One box on a known D map: c1 * sum over the box of (D - c2) (eq. 9)."""
    p = TrackerParams()
    rng = np.random.default_rng(0)
    D = rng.random((1, 20, 30)).astype(np.float32)
    img = rng.random((1, 20, 30, 3)).astype(np.float32)
    data = prepare_frame(p, _frame(D, img))
    boxes = np.zeros((1, 2, 3, 4), dtype=np.int64)
    boxes[0, 0, 0] = (3, 10, 9, 18)
    boxes[0, 0, 1] = (2, 4, 10, 11)  # overlaps the first box by one row
    cfg = Config(
        boxes, np.array([[[2, 4, 10, 18], [0, 0, 0, 0]]]), np.zeros((1, 2)), np.array([True, False])
    )
    nref = np.zeros((2, 3), dtype=np.int64)
    sref = np.zeros((2, 3, 2, data.num_bins))
    mask = np.zeros((20, 30), bool)
    mask[10:18, 3:9] = True
    mask[4:11, 2:10] = True
    expected = p.c1 * float((D[0][mask].astype(np.float64) - p.c2).sum())
    assert full_loglik(p, data, cfg, sref, nref) == pytest.approx(expected, rel=1e-12)
    inc = IncrementalLikelihood(p, data, cfg, sref, nref)
    assert inc.total == pytest.approx(expected, rel=1e-12)


def test_colour_term_bhattacharyya() -> None:
    """A region whose histogram equals a reference has D_c = 0 (eq. 10)."""
    p = TrackerParams()
    nb = 4
    counts = np.zeros((3, 2, nb))
    counts[0, 1] = [10, 0, 5, 5]  # all foreground pixels
    ref = counts[:, 0] + counts[:, 1]
    ref = ref / np.maximum(ref.sum(-1, keepdims=True), 1)
    sref = np.sqrt(ref)[:, None, :]
    nref = np.array([1, 0, 0])
    got = colour_cost(p, counts, sref, nref)
    assert got == pytest.approx(-p.lambda_im * 20 * (0.0 - p.d_min))
    # an orthogonal histogram: Bhattacharyya coefficient 0, D_c = 1
    counts2 = np.zeros((3, 2, nb))
    counts2[0, 1] = [0, 7, 0, 0]
    assert colour_cost(p, counts2, sref, nref) == pytest.approx(-p.lambda_im * 7 * (1 - p.d_min))


@pytest.fixture(scope="module")
def chain_setup():
    scene = default_scene(0, width=192, height=144)
    truth = simulate_walkers(3, scene, 6, 7)
    params = TrackerParams(num_moves=300, burn_in=50)
    tracker = RJMCMCTracker(scene, params)
    state = tracker.init_state()
    for t in range(5):
        state, _ = tracker.step(t, state, render_frame(4, scene, truth, t))
    assert state.alive.sum() >= 3 and (state.nref.sum(1) > 0).sum() >= 3
    return tracker, state, render_frame(4, scene, truth, 5)


def test_incremental_equals_full_over_random_moves(chain_setup) -> None:
    """Every proposal's incremental delta equals the change of the full recompute."""
    tracker, state, frame = chain_setup
    chain = tracker.frame_chain(state, frame, "incremental")
    rng = np.random.default_rng(11)
    checked = 0
    for it in range(400):
        move = it % 6
        prop = chain.propose(rng, move)
        if prop is None or prop[4] == -math.inf:
            continue
        S_new, pr_new, changed, _, _ = prop
        delta, commit = chain._evaluate(S_new, pr_new, changed)
        if commit is None:
            continue
        before = full_loglik(
            chain.p, chain.data, chain._config(chain.S, chain.present), chain.sref, chain.nref
        )
        after = full_loglik(
            chain.p, chain.data, chain._config(S_new, pr_new), chain.sref, chain.nref
        )
        d_lik = commit[-1]
        assert d_lik == pytest.approx(after - before, abs=1e-7), (move, changed)
        checked += 1
        if rng.random() < 0.5:
            chain._commit(commit)
            assert chain.lik.total == pytest.approx(after, abs=1e-6)
    assert checked > 100


def test_full_and_incremental_chains_coincide(chain_setup) -> None:
    tracker, state, frame = chain_setup
    a = tracker.frame_chain(state, frame, "incremental")
    b = tracker.frame_chain(state, frame, "full")
    ra = a.run(np.random.default_rng(5))
    rb = b.run(np.random.default_rng(5))
    assert np.array_equal(a.present, b.present)
    assert np.allclose(a.S, b.S)
    assert np.allclose(ra["presence"], rb["presence"])
    assert a.loglik == pytest.approx(b.loglik, abs=1e-6)


def _two_people(dx_back: int, dx_front: int) -> Config:
    """One view, person 0 in front (depth 1) of person 1 (depth 2), boxes shifted by dx."""
    boxes = np.zeros((1, 2, 3, 4), dtype=np.int64)
    for j, dx in ((0, dx_front), (1, dx_back)):
        boxes[0, j] = [
            (8 + dx, 30, 16 + dx, 40),
            (6 + dx, 14, 18 + dx, 31),
            (9 + dx, 8, 15 + dx, 15),
        ]
    bbox = np.concatenate([boxes[0, :, :, :2].min(1), boxes[0, :, :, 2:].max(1)], axis=-1)[None]
    return Config(boxes, bbox, np.array([[1.0, 2.0]]), np.array([True, True]))


@pytest.mark.parametrize("who", [0, 1])
def test_incremental_occlusion_front_and_back(who: int) -> None:
    """Moving the person behind leaves the front one's colour term; moving the front one
    changes the hidden pixels of the one behind; both deltas equal the full recompute."""
    p = TrackerParams()
    rng = np.random.default_rng(3)
    D = rng.random((1, 48, 40)).astype(np.float32)
    img = rng.random((1, 48, 40, 3)).astype(np.float32)
    data = prepare_frame(p, _frame(D, img))
    refs = rng.random((2, 3, 1, data.num_bins))
    sref = np.sqrt(refs / refs.sum(-1, keepdims=True))
    nref = np.ones((2, 3), dtype=np.int64)
    before = _two_people(dx_back=4, dx_front=0)
    inc = IncrementalLikelihood(p, data, before, sref, nref)
    assert inc.total == pytest.approx(full_loglik(p, data, before, sref, nref), abs=1e-9)
    after = _two_people(dx_back=4 + 3 * (who == 1), dx_front=3 * (who == 0))
    ov = {
        who: (
            True,
            after.boxes[:, who].tolist(),
            after.bbox[:, who].tolist(),
            [after.depth[0, who]],
        )
    }
    delta, pending = inc.propose(ov)
    want = full_loglik(p, data, after, sref, nref) - full_loglik(p, data, before, sref, nref)
    assert delta == pytest.approx(want, abs=1e-9)
    recoloured = sorted(j for _, j, _ in pending.colour)
    # the person in front (0) keeps its visible pixels when the one behind (1) moves
    assert recoloured == ([0, 1] if who == 0 else [1])
    inc.commit(pending)
    assert inc.total == pytest.approx(full_loglik(p, data, after, sref, nref), abs=1e-9)
