"""Compacting a sparse hypothesis table by posterior mass (inference.adf.compact)
against brute-force oracles: which rows are dropped, where their mass goes, and that
threshold 0 changes nothing."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dbn.errors import InputError
from inference.adf.compact import compact_rows, prune_rows_by_mass, row_capacity


def table(seed: int, S: int = 12, W: int = 3, N: int = 7):
    rng = np.random.default_rng(seed)
    scale = rng.choice([1e-4, 1e-2, 0.3, 1.0], size=(S, 1)) * rng.uniform(0.5, 1.0, (S, 1))
    w = rng.dirichlet(np.ones(W), size=S) * scale  # row masses without (float32) ties
    w[rng.random((S, W)) < 0.2] = 0.0
    owners = rng.integers(0, N, (S, W))
    valid = rng.random(S) < 0.8
    w[~valid] = 0.0
    sink = rng.random(N)
    return w, owners, valid, sink


def owner_totals(w, owners, sink):
    tot = np.array(sink, float)
    np.add.at(tot, owners.ravel(), w.ravel())
    return tot


def oracle_drop(w, valid, eps, max_rows):
    """Rows a brute force drops: valid, 0 < mass < eps, the max_rows lightest."""
    mass = w.sum(1)
    below = [s for s in range(len(mass)) if valid[s] and 0 < mass[s] < eps]
    below.sort(key=lambda s: mass[s])
    return set(below if max_rows is None else below[:max_rows])


def run(w, owners, valid, sink, eps, max_rows):
    with jax.enable_x64(True):
        out = prune_rows_by_mass(
            jnp.asarray(w),
            jnp.asarray(owners),
            jnp.asarray(valid),
            jnp.asarray(sink),
            eps,
            max_rows,
        )
    return [np.asarray(a) for a in out]


@settings(max_examples=25, deadline=None)
@given(
    seed=st.integers(0, 10_000),
    eps=st.sampled_from([1e-3, 0.02, 0.5]),
    max_rows=st.sampled_from([None, 1, 3]),
)
def test_prune_matches_brute_force_and_moves_mass_to_the_sink(seed, eps, max_rows):
    w, owners, valid, sink = table(seed)
    w2, valid2, sink2, pruned = run(w, owners, valid, sink, eps, max_rows)
    dropped = set(np.flatnonzero(valid & ~valid2))
    assert dropped == oracle_drop(w, valid, eps, max_rows)
    assert not (valid2 & ~valid).any()
    np.testing.assert_array_equal(w2[sorted(dropped)], 0.0)
    keep = [s for s in range(len(w)) if s not in dropped]
    np.testing.assert_array_equal(w2[keep], w[keep])
    # every owner's total mass (table + sink) is unchanged
    np.testing.assert_allclose(owner_totals(w2, owners, sink2), owner_totals(w, owners, sink))
    assert pruned == pytest.approx(w[sorted(dropped)].sum(), abs=1e-15)
    assert pruned <= eps * len(dropped) + 1e-15


@settings(max_examples=10, deadline=None)
@given(seed=st.integers(0, 10_000), max_rows=st.sampled_from([None, 2]))
def test_threshold_zero_changes_nothing_bit_for_bit(seed, max_rows):
    w, owners, valid, sink = table(seed)
    w2, valid2, sink2, pruned = run(w, owners, valid, sink, 0.0, max_rows)
    np.testing.assert_array_equal(w2, w)
    np.testing.assert_array_equal(valid2, valid)
    np.testing.assert_array_equal(sink2, sink)
    assert pruned == 0.0


def test_compact_rows_keeps_valid_rows_in_order_and_pads():
    rows = {"a": np.arange(6.0), "b": np.arange(12).reshape(6, 2)}
    valid = np.array([False, True, False, True, True, False])
    blank = {"a": -1.0, "b": np.array([7, 7])}
    with jax.enable_x64(True):
        out, v = compact_rows(rows, valid, 5, blank)
    np.testing.assert_array_equal(np.asarray(out["a"]), [1, 3, 4, -1, -1])
    np.testing.assert_array_equal(np.asarray(out["b"]), [[2, 3], [6, 7], [8, 9], [7, 7], [7, 7]])
    np.testing.assert_array_equal(np.asarray(v), [True, True, True, False, False])
    assert np.asarray(out["b"]).dtype == rows["b"].dtype
    with pytest.raises(InputError):
        compact_rows(rows, valid, 2, blank)


def test_row_capacity_is_the_smallest_grid_size_up_to_the_cap():
    assert row_capacity(10, 1024, 64) == 64
    assert row_capacity(65, 1024, 64) == 128
    assert row_capacity(300, 1024, 64) == 512
    assert row_capacity(2000, 1024, 64) == 1024
    assert row_capacity(300, 256, 64) == 256
    assert row_capacity(5, 48, 64) == 48
    with pytest.raises(InputError):
        row_capacity(5, 0, 64)
