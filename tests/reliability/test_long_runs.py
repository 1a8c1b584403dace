"""Long runs of the on-line trackers that are slow per step (issue 14, deliverable 5):
RJ-MCMC 3-D (100,000 frames, bounded: tiny images, few moves) and the Jorge on-line
labeller (a proportional run: its per-stroke cost is an exact window inference).

Memory is measured twice: the state's own size, and :mod:`tracemalloc` over a tail of
the run (a leak outside the state -- a cache, a log -- would show there). All ``slow``;
``DBNTRACK_LONG_STEPS`` shortens a trial run (the checks scale with it).
"""

from __future__ import annotations

import dataclasses
import gc
import os
import pickle
import tracemalloc

import jax
import numpy as np
import pytest

LONG = int(os.environ.get("DBNTRACK_LONG_STEPS", 100_000))


def _traced_growth(step, state, start: int, num_steps: int):
    """Run ``num_steps`` steps from index ``start`` under tracemalloc; the state and the
    bytes still allocated (traced) per step over the second half of them (the first half
    lets caches fill)."""
    half = num_steps // 2
    tracemalloc.start(1)
    try:
        for i in range(start, start + half):
            state = step(i, state)
        gc.collect()
        mid = tracemalloc.get_traced_memory()[0]
        for i in range(start + half, start + num_steps):
            state = step(i, state)
        gc.collect()
        end = tracemalloc.get_traced_memory()[0]
    finally:
        tracemalloc.stop()
    return state, (end - mid) / (num_steps - half)


# --- RJ-MCMC 3-D: 100,000 frames ----------------------------------------------------------
def _state_bytes(state) -> int:
    return sum(int(np.asarray(v).nbytes) for v in state)


@pytest.mark.slow
def test_long_run_rjmcmc3d_bounded() -> None:
    """100,000 frames of a 64 x 48 px 3-camera hall with 2 simulated walkers (20 rendered
    frames cycled, each carrying its index), 2 moves per frame: the chain's per-frame
    machinery (proposals, likelihood, posterior, reference histograms) runs 100,000
    times at ~6 ms of CPU a frame (20,000 frames: 155 s on a loaded 2-core machine, 4 B
    per frame still allocated over the traced tail) instead of ~0.2 s at full size. The state (fixed by
    max_objects) stays the same size and finite; the tracemalloc tail holds no growth."""
    from models.rjmcmc3d import TrackerParams
    from models.rjmcmc3d.scene import default_scene, render_frame, simulate_walkers

    scene = default_scene(0, width=64, height=48)
    truth = simulate_walkers(1, scene, 20, 2)
    frames = [render_frame(2, scene, truth, t) for t in range(20)]
    tr = models_make("rjmcmc3d", scene=scene, params=TrackerParams(num_moves=2, burn_in=0))
    keys = jax.random.split(jax.random.key(5), 100)

    def step(i, s):
        return tr.step(keys[i % 100], s, frames[i % 20]._replace(t=i))[0]

    state = tr.init(jax.random.key(1))
    size0 = _state_bytes(state)
    tail = min(2_000, LONG // 5)
    check = max(1, (LONG - tail) // 10)
    for i in range(LONG - tail):
        state = step(i, state)
        if (i + 1) % check == 0:
            assert all(np.isfinite(np.asarray(v, float)).all() for v in state), i
            assert _state_bytes(state) == size0
    state, per_step = _traced_growth(step, state, LONG - tail, tail)
    assert state.frame == LONG - 1 and _state_bytes(state) == size0
    assert all(np.isfinite(np.asarray(v, float)).all() for v in state)
    print(f"rjmcmc3d: {LONG} frames, state {size0} B, {per_step:.1f} B/frame traced (tail)")
    assert per_step < 64, f"{per_step:.0f} bytes still allocated per frame"


def models_make(name: str, **kwargs):
    import models

    return models.get(name).make(**kwargs)


# --- Jorge on-line labeller: proportional run ---------------------------------------------
#: strokes of the Jorge run: ~30-75 ms each (a loaded 2-core machine), so 100,000 would
#: take 1-2 h; the cost per stroke is flat in the run length (the exact inference over the
#: max_active-node window every period_s), so a run of 2,000 checks the same steady state
JORGE_STROKES = min(LONG, 2_000)


def _stroke_stream():
    """Stroke ``i`` of an endless stream: a simulated 900-frame, 3-person block of
    strokes repeated, each repetition shifted past the previous one (new people)."""
    from models.jorge.simulate import simulate_ground_truth
    from models.jorge.strokes import build_strokes

    block = build_strokes(0, simulate_ground_truth(0, num_people=3, num_frames=900))
    base = list(block.strokes)
    span = max(s.end for s in base) + 1

    def stroke(i):
        c, o = divmod(i, len(base))
        s, f = base[o], c * span
        return dataclasses.replace(
            s, index=i, start=s.start + f, end=s.end + f, frames=np.asarray(s.frames) + f
        )

    return stroke, block.fps


@pytest.mark.slow
def test_long_run_jorge_proportional() -> None:
    """The labeller the protocol wraps, stepped in place as the protocol's ``fold`` steps it
    (``run`` copies it at every step, quadratic: :mod:`models.jorge.api`), 2,000 strokes. The labeller keeps its whole
    label graph by design (every stroke is a node with its positions, domain, belief;
    one inference record per period): it grows linearly, measured 0.5-0.65 kB pickled
    and ~4.5 kB allocated (tracemalloc, last 400; 1.6 kB when first written) per stroke;
    2,000 strokes ran in 109 s on a loaded 2-core machine (~50 ms a stroke). Asserted: beliefs finite and normalised, every stroke
    labelled, growth per stroke flat (last block <= 1.5 x the second) and bounded."""
    stroke, fps = _stroke_stream()
    lab = models_make("jorge", fps=fps).init(jax.random.key(0)).labeller
    n, blocks = JORGE_STROKES, 5
    tail = n // blocks
    sizes = []
    for i in range(n - tail):
        lab.add_stroke(stroke(i))
        if (i + 1) % tail == 0:
            sizes.append(len(pickle.dumps(lab)))

    def step(i, lab):
        lab.add_stroke(stroke(i))
        return lab

    lab, per_stroke = _traced_growth(step, lab, n - tail, tail)
    sizes.append(len(pickle.dumps(lab)))
    growth = np.diff(sizes) / tail
    print(f"jorge: {n} strokes, pickled {sizes} B, {per_stroke:.0f} B/stroke traced (tail)")
    assert growth[-1] <= 1.5 * growth[0] + 64, sizes
    assert growth.max() < 2_000, growth  # bytes of state per stroke
    assert per_stroke < 16_000, per_stroke  # bytes allocated per stroke (tracemalloc)
    assert len(lab.graph.nodes) == n and len(lab.labels) >= n - lab.config.max_active
    for b in lab.beliefs.values():
        assert np.isfinite(b).all() and abs(b.sum() - 1.0) < 1e-9
    assert all(np.isfinite(r.log_prob) for r in lab.records)
