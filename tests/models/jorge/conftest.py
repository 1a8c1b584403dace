"""Shared checks of the jorge tests."""

from __future__ import annotations

import numpy as np
import pytest

from dbn import pgmpy_adapter
from inference.exact import map_assignment
from models.jorge.labels import LabelParams
from models.jorge.network import LabelGraph, NetworkConfig, node_name, solve
from models.jorge.strokes import make_stroke


def _assert_window_matches_pgmpy(win, num_nodes: int) -> None:
    """The window's MAP log probability and marginals equal pgmpy's (colours added as
    observed binary children, which the adapter's pgmpy engines can take)."""
    bn, ev = win.with_colour_nodes()
    _, lp = map_assignment(bn, ev)
    res = solve(win)
    assert lp == pytest.approx(res.log_prob, abs=1e-9)
    model = pgmpy_adapter.to_pgmpy(bn)
    names_ev = {n: bn.variable(n).state_names[s] for n, s in ev.items()}
    theirs = pgmpy_adapter.pgmpy_map(model, names_ev)
    theirs_idx = {n: bn.variable(n).index(s) for n, s in theirs.items()}
    assert bn.log_joint({**theirs_idx, **ev}) == pytest.approx(lp, abs=1e-9)
    marg = pgmpy_adapter.pgmpy_marginals(model, [node_name(k) for k in range(num_nodes)], names_ev)
    for k in range(num_nodes):
        np.testing.assert_allclose(res.marginals[k], marg[node_name(k)], atol=1e-9)


@pytest.fixture(scope="session")
def assert_window_matches_pgmpy():
    """``check(window, num_nodes)``: MAP log probability and marginals equal pgmpy's."""
    return _assert_window_matches_pgmpy


def _random_window(data, with_sizes: bool = False, max_configs: int = 20000):
    """A window over 3-6 random strokes (start gaps, lengths, positions, colours and,
    with ``with_sizes``, region sizes drawn by hypothesis), groups of at most 2; examples
    whose joint exceeds ``max_configs`` labellings are rejected (``assume``)."""
    from hypothesis import assume
    from hypothesis import strategies as st

    n = data.draw(st.integers(3, 6))
    g = LabelGraph(NetworkConfig(labels=LabelParams(max_group_size=2)), fps=25.0)
    start = 0
    for k in range(n):
        start += data.draw(st.integers(0, 4))
        length = data.draw(st.integers(0, 3))
        x0 = data.draw(st.floats(0, 30))
        colours = data.draw(st.lists(st.integers(0, 11), min_size=2, max_size=5, unique=True))
        size = (data.draw(st.floats(10, 120)), data.draw(st.floats(20, 120))) if with_sizes else None
        g.add_stroke(make_stroke(k, start, start + length, (x0, 0.0), (x0 + 1, 0.0), colours, size=size))
    win = g.window(range(n))
    assume(np.prod([win.bn.cardinality(node_name(k)) for k in range(n)]) <= max_configs)
    return win


@pytest.fixture(scope="session")
def random_window():
    """``draw(data, with_sizes=False)``: a random small label window (see above)."""
    return _random_window
