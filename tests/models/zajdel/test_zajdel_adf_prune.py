"""The Zajdel ADF's pointer table pruned by mass and sized by its open slots
(models.zajdel.adf_prune): against the fixed table, and its invariants."""

from __future__ import annotations

import numpy as np
import pytest

from models.zajdel.adf_prune import PRUNE_ROWS
from models.zajdel.data import take
from models.zajdel.simulate import simulate_office
from models.zajdel.tracker import ADFConfig, ZajdelADF

CFG = ADFConfig(max_open=32, persons_per_slot=8, init_persons=32, chunk=8, link_out=12)


def pointer_rows(state) -> np.ndarray:
    rows = np.asarray(state.never) + np.asarray(state.closed)
    np.add.at(rows, np.asarray(state.slot_person).ravel(), np.asarray(state.slot_pprob).ravel())
    return rows


@pytest.mark.heavy  # ~16 s: one compile per table size; CI runs it (pytest -m heavy)
def test_table_sized_by_open_slots_at_threshold_zero_equals_the_fixed_table():
    sc = simulate_office(4)
    # min_open = max_open: a fixed table (with the prune hook at threshold 0, which
    # changes nothing bit for bit: tests/inference/adf/test_compact.py)
    _, fixed = ZajdelADF(sc.params, CFG._replace(min_open=CFG.max_open)).run(sc.obs)
    tr = ZajdelADF(sc.params, CFG._replace(min_open=16))
    st, dyn = tr.run(sc.obs)
    assert fixed.num_open.max() == CFG.max_open  # the cap is reached: evictions happen
    assert tr.init().slot_valid.shape[0] == 16 and st.slot_valid.shape[0] == CFG.max_open
    # the table grew from 16 slots (a chunk that filled it was run again), evicting
    # only at the cap: the same posteriors as the fixed 32-slot table
    np.testing.assert_allclose(dyn.link_matrix(), fixed.link_matrix(), atol=1e-12)
    np.testing.assert_allclose(dyn.counter_mean, fixed.counter_mean, atol=1e-12)
    np.testing.assert_array_equal(dyn.pruned_mass, 0.0)


@pytest.mark.slow  # ~10 s idle: one table size compiled per step and per chunk
def test_pruned_mass_is_bounded_and_every_pointer_row_sums_to_one():
    eps = 3e-2
    sc = simulate_office(5)
    obs = take(sc.obs, slice(0, 40))
    tr = ZajdelADF(sc.params, CFG._replace(slot_mass_eps=eps, min_open=16))
    st, res = tr.run(obs)
    np.testing.assert_allclose(pointer_rows(st), 1.0, atol=1e-12)
    assert (res.pruned_mass >= 0).all() and res.pruned_mass.max() > 0
    assert res.pruned_mass.max() <= eps * PRUNE_ROWS
    assert res.num_open.max() < CFG.max_open  # pruned below the cap
    np.testing.assert_allclose(res.link_prob.sum(1) + res.new_prob, 1.0, atol=1e-9)
    # step by step gives the same as the run (the table resized before every step)
    s = tr.init()
    for k in range(6):
        s, info = tr.step(s, take(obs, slice(k, k + 1)))
        assert int(info.num_open) == res.num_open[k]
        assert float(info.new_prob) == pytest.approx(res.new_prob[k], abs=1e-12)
