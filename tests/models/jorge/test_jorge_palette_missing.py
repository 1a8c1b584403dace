"""Known colours a stroke's palette lacks (issue 16, thirty-fourth round):
``palette_missing_log_likelihood`` reads ``log p(d | m, b(u))``, the fit's table is add-one
smoothed frequencies, bad tables are refused naming the field, and a label that swaps a
member for someone else, which the gain table cannot tell from the true label, now pays
for the colours the palette lacks."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from dbn.errors import InputError, ModelError
from models.jorge.evidence import palette_missing_log_likelihood
from models.jorge.fit import fit_parameters
from models.jorge.labels import LabelParams
from models.jorge.network import FITTED_PALETTE_MISSING, LabelGraph, NetworkConfig
from models.jorge.strokes import StrokeSet, make_stroke

F = frozenset


def test_missing_likelihood_reads_newcomers_the_bin_of_u_and_d():
    rng = np.random.default_rng(3)
    table = np.log(rng.dirichlet(np.ones(6), size=(3, 3)))  # m = 0..2, u bins 0 / 1-5 / 6+, d = 0..5
    bins = (0, 1, 6)
    missing, known, new = np.array([0, 1, 2, 7, 0]), np.array([0, 3, 6, 9, 12]), np.array([0, 1, 5, 2, 0])
    out = palette_missing_log_likelihood(missing, known, new, table, bins)
    np.testing.assert_array_equal(out, table[[0, 1, 2, 2, 0], [0, 1, 2, 2, 2], [0, 1, 2, 5, 0]])
    empty = palette_missing_log_likelihood(missing, known, new, np.zeros((0, 0, 0)), bins)
    np.testing.assert_array_equal(empty, 0.0)
    with pytest.raises(InputError, match="missing at most known"):
        palette_missing_log_likelihood(np.array([4]), np.array([3]), np.array([0]), table, bins)
    with pytest.raises(InputError):
        palette_missing_log_likelihood(np.array([0, 1]), np.array([3]), np.array([0]), table, bins)
    with pytest.raises(ModelError, match="3-D"):
        palette_missing_log_likelihood(missing, known, new, table[:, 0], bins)
    with pytest.raises(ModelError):  # one entry of axis 1 per bin
        palette_missing_log_likelihood(missing, known, new, table, (0, 1))


def test_the_default_table_is_the_fitted_one_and_bad_tables_are_refused():
    cfg = NetworkConfig()
    assert cfg.palette_missing and cfg.palette_missing_table == FITTED_PALETTE_MISSING
    t = np.exp(np.array(FITTED_PALETTE_MISSING))
    assert t.shape == (6, 5, 13)
    np.testing.assert_allclose(t.sum(axis=2), 1.0)
    positive = tuple(tuple(tuple(-v for v in row) for row in block) for block in FITTED_PALETTE_MISSING)
    for bad in (positive, FITTED_PALETTE_MISSING[0], ((( -0.1, -2.0),),), (((-0.1,), (-0.2, -0.3)),)):
        with pytest.raises(ModelError, match="palette_missing_table"):
            NetworkConfig(palette_missing_table=bad)
    with pytest.raises(ModelError, match="palette_missing must be a bool"):
        NetworkConfig(palette_missing=1)


def _meet_and_leave() -> StrokeSet:
    """Persons 0 and 1 alone, together, and 0 alone again, whose last palette lacks colour 4."""
    strokes = [
        make_stroke(0, 0, 10, (0, 0), (10, 0), [0, 1, 2, 3, 4], {0}),
        make_stroke(1, 0, 10, (40, 0), (30, 0), [5, 6, 7, 8, 9], {1}),
        make_stroke(2, 12, 20, (20, 0), (20, 0), [0, 1, 5, 6, 7], {0, 1}),
        make_stroke(3, 22, 30, (10, 0), (0, 0), [0, 1, 2, 3], {0}),
    ]
    strokes[2] = replace(strokes[2], palette=np.arange(10))
    return StrokeSet.from_strokes(strokes, fps=25.0)


def test_fitted_missing_table_is_smoothed_frequencies():
    base = NetworkConfig(labels=LabelParams(max_group_size=3), gate="pixels")
    p = np.exp(np.array(fit_parameters([_meet_and_leave()], base).palette_missing_table))
    assert p.shape == (4, 5, 13)  # m = 0..3, bin of u (0, 1-5, 6-7, 8-9, 10+), d = 0..12
    np.testing.assert_allclose(p.sum(axis=2), 1.0)
    # two roots: one newcomer each, nothing known, nothing missing
    assert p[1, 0, 0] == pytest.approx((2 + 1) / (2 + 13))
    # the pair knows both palettes (10 colours) and has them all
    assert p[0, 4, 0] == pytest.approx((1 + 1) / (1 + 13))
    # person 0 alone again: 5 known colours, colour 4 missing
    assert p[0, 1, 1] == pytest.approx((1 + 1) / (1 + 13))
    assert p[0, 1, 0] == pytest.approx(1 / 14)
    off = fit_parameters([_meet_and_leave()], replace(base, palette_missing=False))
    assert off.palette_missing_table == ()


def _swap_graph(missing: bool) -> LabelGraph:
    """A (colours 0-4), B (5-9) and C (0, 5, 10, 11) seen alone, then a region of A and C:
    |A u C| = |B u C| = 8, so the label of B and C gains what the true label gains."""
    cfg = NetworkConfig(labels=LabelParams(max_group_size=3), gate="pixels", size_evidence=False,
                        palette_missing_table=NetworkConfig().palette_missing_table if missing else ())
    g = LabelGraph(cfg, fps=25.0)
    for s in [
        make_stroke(0, 0, 10, (0, 0), (10, 0), [0, 1, 2, 3, 4], {0}),
        make_stroke(1, 0, 10, (300, 0), (310, 0), [5, 6, 7, 8, 9], {1}),
        make_stroke(2, 0, 10, (600, 0), (610, 0), [0, 5, 10, 11], {2}),
        make_stroke(3, 40, 50, (900, 300), (910, 300), [0, 1, 2, 5, 10], {0, 2}),
    ]:
        if s.index == 3:
            s = replace(s, palette=np.array([0, 1, 2, 3, 4, 5, 10, 11]))
        g.add_stroke(s)
    return g


def test_a_swapped_member_pays_for_the_colours_the_palette_lacks():
    true, swapped = F({0, 2}), F({1, 2})
    blind = _swap_graph(missing=False).palette_count_loglik(3, [true, swapped])
    assert blind[0] == blind[1]  # the gain table alone cannot tell them apart
    told = _swap_graph(missing=True).palette_count_loglik(3, [true, swapped])
    table = np.array(FITTED_PALETTE_MISSING)
    # both know 8 colours (bin 8-9); the swap lacks B's 6, 7, 8, 9
    assert told[0] - blind[0] == pytest.approx(table[0, 3, 0])
    assert told[1] - blind[1] == pytest.approx(table[0, 3, 4])
    assert told[0] - told[1] > 4.0


@pytest.mark.parametrize("field", ["palette_count_table", "palette_gain_table", "palette_missing_table"])
def test_a_ragged_palette_table_is_refused_naming_its_field(field):
    with pytest.raises(ModelError, match=field):
        NetworkConfig(**{field: ((-0.1,), (-0.2, -0.3))})
