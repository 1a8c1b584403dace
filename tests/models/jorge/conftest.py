"""Shared checks of the jorge tests."""

from __future__ import annotations

import numpy as np
import pytest

from dbn import pgmpy_adapter
from inference.exact import map_assignment
from models.jorge.network import node_name, solve


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


@pytest.fixture
def assert_window_matches_pgmpy():
    """``check(window, num_nodes)``: MAP log probability and marginals equal pgmpy's."""
    return _assert_window_matches_pgmpy
