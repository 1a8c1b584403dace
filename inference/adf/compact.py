r"""Compacting an ADF's sparse hypothesis table by posterior mass (issue 17).

Many ADF beliefs keep a table of hypotheses (rows), each holding probability mass
spread over a few owners: in seed 002's tracker a row is an open track end and its
entries :math:`q(z^{(n)} = j)` the probability that it is person n's latest pass. The
per-observation cost is set by the table's *capacity*; most of it may hold rows whose
mass is negligible. This module keeps the capacity near the number of rows that carry
mass:

* :func:`prune_rows_by_mass` (jit-able, one step): rows whose total mass is below a
  threshold ``eps`` are dropped and their mass moved to a per-owner ``sink`` (e.g.
  "closed track end"), so that every owner's total (table + sink) is unchanged; the
  mass moved is reported, at most ``eps`` times the number of rows dropped (optionally
  at most ``max_rows`` rows per step, the lightest, to keep the scatter small);
* :func:`compact_rows` (between chunks): the valid rows gathered to the front (their
  order kept) and the table resized to a new capacity, padded with a blank row;
* :func:`row_capacity`: the capacity for a number of rows, on a doubling grid (each
  new capacity is one more compiled shape), between a floor and the cap.

With ``eps = 0`` nothing is pruned (bit for bit); compaction only reorders rows.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from dbn.errors import InputError

__all__ = ["prune_rows_by_mass", "compact_rows", "row_capacity"]


def prune_rows_by_mass(weights, owners, valid, sink, eps: float, max_rows: int | None = None):
    """Drop the rows of a sparse table whose total mass is below ``eps``.

    Parameters
    ----------
    weights : (S, W) nonnegative masses (row s, entry w)
    owners : (S, W) int, owner of each entry (index into ``sink``)
    valid : (S,) bool, rows in use
    sink : (N,) per-owner mass outside the table
    eps : threshold (static or traced float); 0 drops nothing
    max_rows : drop at most this many rows per call, the lightest first (static; the
        scatter into ``sink`` then touches ``max_rows * W`` entries instead of
        ``S * W``; rows left over are dropped by later calls); ``None``: all

    Returns
    -------
    (weights, valid, sink, pruned): the dropped rows' entries zeroed and invalid, their
    mass added to ``sink`` at their owners, and ``pruned`` () the total mass moved
    (``<= eps * number of dropped rows``).
    """
    mass = jnp.sum(weights, axis=1)
    below = valid & (mass < eps) & (mass > 0)
    S = mass.shape[0]
    if max_rows is None or max_rows >= S:
        rows = jnp.arange(S)
        drop_rows = below
    else:  # the max_rows lightest rows below eps (float32 ranking: an order, not a value)
        key = jnp.where(below, -mass, -jnp.inf).astype(jnp.float32)
        _, rows = jax.lax.top_k(key, max_rows)
        drop_rows = below[rows]
    moved = jnp.where(drop_rows[:, None], weights[rows], 0.0)

    def add(sk):
        return sk.at[owners[rows].reshape(-1)].add(moved.reshape(-1))

    sink = jax.lax.cond(jnp.any(drop_rows), add, lambda sk: sk, sink)
    drop = jnp.zeros(S, bool).at[rows].set(drop_rows)
    weights = jnp.where(drop[:, None], 0.0, weights)
    return weights, valid & ~drop, sink, jnp.sum(jnp.where(drop_rows, mass[rows], 0.0))


def compact_rows(rows, valid, size: int, blank):
    """Gather the valid rows to the front (order kept) and resize the table to ``size``.

    Parameters
    ----------
    rows : pytree of arrays with leading axis S (the table's fields)
    valid : (S,) bool
    size : new capacity (>= number of valid rows)
    blank : pytree like one row of ``rows`` (no leading axis): the padding row

    Returns
    -------
    (rows, valid) with leading axis ``size``: the valid rows first, then blank rows.
    """
    keep = np.flatnonzero(np.asarray(valid))
    if keep.size > size:
        raise InputError(f"compact_rows: {keep.size} valid rows do not fit size {size}")
    pad = size - keep.size

    def one(a, b):  # on the host: the kept rows' count changes every call, and each
        a = np.asarray(a)  # count would compile a gather of its own
        fill = np.broadcast_to(np.asarray(b, a.dtype), (pad,) + a.shape[1:])
        return jnp.asarray(np.concatenate([a[keep], fill]))

    new_valid = jnp.asarray(np.concatenate([np.ones(keep.size, bool), np.zeros(pad, bool)]))
    return jax.tree_util.tree_map(one, rows, blank), new_valid


def row_capacity(needed: int, cap: int, floor: int) -> int:
    """The smallest capacity ``floor * 2^i`` holding ``needed`` rows, at most ``cap``
    (the cap itself when the doubling passes it). A coarse grid: each capacity is one
    more compiled shape."""
    if floor < 1 or cap < 1:
        raise InputError(f"row_capacity: floor = {floor}, cap = {cap}: must be >= 1")
    size = min(floor, cap)
    while size < needed and size < cap:
        size = min(2 * size, cap)
    return size
