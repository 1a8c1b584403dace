"""The vectorised evidence and merge paths against their plain definitions.

``label_objects`` / ``union_rows`` (one pass over a domain's objects, then palette unions in
numpy) must give what :func:`known_objects`, :meth:`LabelGraph.palette_stroke` and a
per-label union give; the bit-mask merge of :func:`child_table` must give the loop's sums
to the last bit, and so must its inherited and joined mass (set per entry, moved in one
step) give the per-entry loop's.
"""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from models.jorge.labels import (
    NEW_STRIDE,
    LabelParams,
    _merge_mass,
    _merge_mass_loop,
    _new_column,
    _new_mass,
    _piece_law,
    admissible_labels,
    birth_stroke,
    child_table,
    known_objects,
    label_objects,
    new_objects,
    union_rows,
)

# objects born at strokes 0-7: lone newcomers and members of new groups of 2 and 3
_OBJECTS = sorted({o for k in range(8) for m in (1, 2, 3) for o in new_objects(k, m)})
labels_strategy = st.frozensets(st.sampled_from(_OBJECTS), min_size=1, max_size=5)


@settings(max_examples=80, deadline=None)
@given(domain=st.lists(labels_strategy, min_size=1, max_size=8), k=st.integers(0, 7),
       own_items=st.dictionaries(st.sampled_from(_OBJECTS), st.integers(0, 7), max_size=3),
       joined_items=st.dictionaries(st.sampled_from([o for o in _OBJECTS if o < NEW_STRIDE]),
                                    labels_strategy, max_size=3))
def test_label_objects_matches_the_definitions(domain, k, own_items, joined_items):
    """``own``: members of new groups or joiners with a palette of their own; ``joined``:
    lone newcomers that joined an inherited label, mapped to their birth label."""
    own = {o: s for o, s in own_items.items() if o >= NEW_STRIDE or o in joined_items}
    joined = {o: lab | {o} for o, lab in joined_items.items()}
    obj = label_objects(domain, k, own, joined)
    start = known_start = 0
    for i, lab in enumerate(domain):
        strokes = obj.palette_strokes[start:start + obj.sizes[i]]
        assert sorted(strokes.tolist()) == sorted(own.get(o, birth_stroke(o)) for o in lab)
        known = obj.known_strokes[known_start:known_start + obj.known_counts[i]]
        expected = known_objects(lab, k, own=own, joined=joined)
        assert sorted(known.tolist()) == sorted(own.get(o, birth_stroke(o)) for o in expected)
        assert obj.is_new[i] == any(birth_stroke(o) == k for o in lab)
        start += obj.sizes[i]
        known_start += obj.known_counts[i]
    assert start == obj.palette_strokes.size and known_start == obj.known_strokes.size


@settings(max_examples=60, deadline=None)
@given(counts=st.lists(st.integers(0, 4), min_size=1, max_size=6), seed=st.integers(0, 2**16))
def test_union_rows_is_the_union_per_group(counts, seed):
    rng = np.random.default_rng(seed)
    palettes = rng.random((9, 12)) < 0.2
    strokes = rng.integers(0, 9, size=sum(counts))
    rows = union_rows(palettes, strokes, np.array(counts))
    start = 0
    for i, c in enumerate(counts):
        expected = palettes[strokes[start:start + c]].any(axis=0) if c else np.zeros(12, dtype=bool)
        np.testing.assert_array_equal(rows[i], expected)
        start += c


def _laws(domains, shared, params):
    return [[_piece_law(lab, sh, params) for lab in dom] for dom, sh in zip(domains, shared)]


@settings(max_examples=60, deadline=None)
@given(a=st.lists(st.frozensets(st.integers(0, 9), min_size=1, max_size=3), min_size=1, max_size=4, unique=True),
       b=st.lists(st.frozensets(st.integers(0, 9), min_size=1, max_size=3), min_size=1, max_size=4, unique=True),
       shared=st.tuples(st.booleans(), st.booleans()), gmax=st.integers(2, 5))
def test_vectorised_merge_equals_the_loop_bit_for_bit(a, b, shared, gmax):
    params = LabelParams(p_split=0.7, p_part=0.3, max_group_size=gmax)
    domain = admissible_labels([a, b], list(shared), frozenset({99}), gmax, partial=True)
    index = {lab: i for i, lab in enumerate(domain[: max(1, len(domain) // 2)])}  # a pruned domain
    laws = _laws([a, b], shared, params)
    out = []
    for merge in (_merge_mass, _merge_mass_loop):
        table, total = np.zeros((len(a), len(b), len(index))), np.zeros((len(a), len(b)))
        merge(table, total, laws, index, 0.4, gmax)
        out.append((table, total))
    np.testing.assert_array_equal(out[0][0], out[1][0])
    np.testing.assert_array_equal(out[0][1], out[1][1])


def test_merge_past_62_objects_falls_back_to_the_loop():
    params = LabelParams(p_merge=0.3, max_group_size=3)
    a = [frozenset({i, i + 1}) for i in range(0, 64, 2)]
    b = [frozenset({i}) for i in range(64, 96)]
    domain = admissible_labels([a, b], [False, False], frozenset({200}), 3)
    table = child_table([a, b], [False, False], domain, frozenset({200}), params)
    assert table.shape == (32, 32, len(domain))
    np.testing.assert_allclose(table.sum(axis=-1), 1.0)
    merged = domain.index(a[3] | b[5])
    assert table[3, 5, merged] > 0 and table[3, 6, merged] == 0


def _child_table_loop(doms, shared, domain, new, params):
    """:func:`child_table` with ``truncate``, its inherited and joined mass entry by entry."""
    kept = len(domain)
    sources = {lab - new for lab in domain if new < lab} - set(domain)
    domain = [*domain, *sorted(sources, key=sorted)]
    index = {lab: i for i, lab in enumerate(domain)}
    n = len(doms)
    p_merge = (params.p_merge, params.p_merge_one_split, params.p_merge_both_split)[sum(shared)] if n == 2 else 0.0
    w_single = (1.0 - params.p_new - p_merge) / n
    laws = _laws(doms, shared, params)
    table = np.zeros(tuple(len(d) for d in doms) + (len(domain),))
    total = np.zeros(table.shape[:-1])
    for p in range(n):
        slab, mass = np.zeros((len(doms[p]), len(domain))), np.zeros(len(doms[p]))
        for i, law in enumerate(laws[p]):
            for piece, w in law:
                mass[i] += w_single * w * (len(piece) <= params.max_group_size)
                if piece in index:
                    slab[i, index[piece]] += w_single * w
        total += mass.reshape([-1 if q == p else 1 for q in range(n)])
        table += slab if n == 1 else (slab[:, None, :] if p == 0 else slab[None, :, :])
    if p_merge > 0:
        _merge_mass(table, total, laws, index, p_merge, params.max_group_size)
    moves = [(c, index.get(lab | new)) for lab, c in index.items()
             if not (lab & new) and len(lab) < params.max_group_size]
    if moves:
        src = [c for c, _ in moves]
        moved = params.p_join * table[..., src]
        table[..., src] *= 1.0 - params.p_join
        for t, (_, d) in enumerate(moves):
            if d is not None:
                table[..., d] += moved[..., t]
    table += params.p_new * _new_column(domain, new, params)
    return table[..., :kept] / (total + params.p_new * _new_mass(new, params))[..., None]


@settings(max_examples=60, deadline=None)
@given(a=st.lists(st.frozensets(st.integers(0, 9), min_size=1, max_size=3), min_size=1, max_size=4, unique=True),
       b=st.lists(st.frozensets(st.integers(0, 9), min_size=1, max_size=3), min_size=1, max_size=4, unique=True),
       shared=st.tuples(st.booleans(), st.booleans()), two=st.booleans(), gmax=st.integers(2, 5),
       keep=st.randoms(use_true_random=False))
def test_inherited_and_joined_mass_equal_the_entrywise_loop_bit_for_bit(a, b, shared, two, gmax, keep):
    params = LabelParams(p_new=0.1, p_merge=0.3, p_split=0.7, p_part=0.3, max_group_size=gmax,
                         new_group_probs=(0.6, 0.3, 0.1), p_join=0.2)
    (doms, flags), new = ([a, b], list(shared)) if two else ([a], [shared[0]]), frozenset({99})
    full = admissible_labels(doms, flags, new, gmax, partial=True, max_new=3, join=True)
    domain = [new] + [lab for lab in full[1:] if keep.random() < 0.6]  # a pruned domain
    np.testing.assert_array_equal(child_table(doms, flags, domain, new, params, truncate=True),
                                  _child_table_loop(doms, flags, domain, new, params))
