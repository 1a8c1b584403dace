"""Palette colour count as soft evidence on a label's number of people (issue 16):
``palette_count_log_likelihood`` reads its table, the fit's table is add-one smoothed
frequencies, and the evidence tells a new group from a new person."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from dbn.errors import InputError, ModelError
from models.jorge.evidence import palette_count_log_likelihood
from models.jorge.fit import fit_parameters
from models.jorge.labels import LabelParams, new_objects
from models.jorge.network import LabelGraph, NetworkConfig
from models.jorge.online import OnlineConfig, OnlineLabeller
from models.jorge.strokes import StrokeSet, make_stroke


def test_palette_likelihood_reads_rows_by_size_and_clips():
    rng = np.random.default_rng(0)
    table = np.log(rng.dirichlet(np.ones(7), size=3))  # sizes 1..3, counts 0..6
    out = palette_count_log_likelihood(4, np.array([1, 2, 3, 5]), table)
    np.testing.assert_array_equal(out, table[[0, 1, 2, 2], 4])  # size 5 uses the last row
    np.testing.assert_array_equal(
        palette_count_log_likelihood(9, np.array([2]), table), table[[1], 6]
    )
    np.testing.assert_array_equal(
        palette_count_log_likelihood(4, np.array([1, 2]), np.zeros((0, 0))), 0.0
    )
    with pytest.raises(InputError):
        palette_count_log_likelihood(4, np.array([0, 1]), table)
    with pytest.raises(ModelError):
        palette_count_log_likelihood(4, np.array([1]), table[0])
    with pytest.raises(ModelError):  # not log probabilities
        NetworkConfig(palette_count_table=tuple(map(tuple, -table)))


def test_fitted_palette_table_is_smoothed_frequencies():
    ss = StrokeSet.from_strokes(
        [
            make_stroke(0, 0, 10, (0, 0), (10, 0), [0, 1, 2], {0}, size=(20, 50)),
            make_stroke(1, 0, 10, (40, 0), (30, 0), [3, 4, 5], {1}, size=(20, 50)),
            make_stroke(2, 12, 20, (20, 0), (20, 0), [0, 1, 3, 4], {0, 1}, size=(40, 50)),
            make_stroke(3, 22, 30, (10, 0), (0, 0), [0, 1, 2], {0}, size=(20, 50)),
        ],
        fps=25.0,
    )
    cfg = fit_parameters([ss], NetworkConfig(labels=LabelParams(max_group_size=3), gate="pixels"))
    p = np.exp(np.array(cfg.palette_count_table))
    assert p.shape == (3, 13)
    np.testing.assert_allclose(p.sum(axis=1), 1.0)
    assert p[0, 3] == pytest.approx((3 + 1) / (3 + 13))  # three single strokes of 3 colours
    assert p[1, 4] == pytest.approx((1 + 1) / (1 + 13))  # one pair stroke of 4 colours
    np.testing.assert_allclose(p[2], 1 / 13)  # no group of three: uniform


def _root_label(num_palette: int, table: np.ndarray) -> frozenset:
    labels = LabelParams(max_group_size=3, new_group_probs=(0.5, 0.5))
    cfg = NetworkConfig(
        labels=labels, palette_count_table=tuple(map(tuple, table)), size_evidence=False,
        palette_gain_table=(), palette_missing_table=(),
    )
    stroke = make_stroke(0, 0, 10, (0, 0), (10, 0), [0, 1, 2])
    stroke = replace(stroke, palette=np.arange(num_palette))
    lab = OnlineLabeller(OnlineConfig(network=cfg), fps=25.0)
    return lab.add_stroke(stroke)


def test_palette_count_tells_a_new_group_from_a_new_person():
    table = np.full((3, 13), 1e-3)
    table[0, 3], table[1, 6], table[2, 9] = 1.0, 1.0, 1.0
    table = np.log(table / table.sum(axis=1, keepdims=True))
    assert _root_label(3, table) == new_objects(0, 1)
    assert _root_label(6, table) == new_objects(0, 2)
    # without a table: no palette evidence
    graph = LabelGraph(
        NetworkConfig(
            labels=LabelParams(max_group_size=3, new_group_probs=(0.5, 0.5)),
            palette_count_table=(),
            palette_gain_table=(),
            palette_missing_table=(),
            size_evidence=False,
        ),
        fps=25.0,
    )
    stroke = replace(make_stroke(0, 0, 10, (0, 0), (10, 0), [0, 1, 2]), palette=np.arange(6))
    graph.add_stroke(stroke)
    np.testing.assert_array_equal(graph.palette_count_loglik(0), 0.0)
    np.testing.assert_array_equal(graph.evidence_loglik(0), graph.colour_loglik(0))
