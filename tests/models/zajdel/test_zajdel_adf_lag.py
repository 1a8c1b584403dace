"""The fixed-lag revision's window hypotheses against a brute-force score.

:func:`models.zajdel.adf_lag._score_hypotheses` scores every joint choice of parents of
the window observations at once: chains through earlier window members get their
appearance predictive from one closed-form batch NIW update, computed once per distinct
(origin, members). The oracle here walks each hypothesis alone: the chain's NIW is
updated one member at a time (:func:`inference.adf.niw.niw_update_np`) and every term
is added in a plain loop.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from inference.adf.niw import NIW, niw_predictive_logpdf_np, niw_update_np
from models.zajdel.adf_lag import _enumerate_parents, _score_hypotheses
from models.zajdel.data import take
from models.zajdel.path import log_p_delta
from models.zajdel.simulate import simulate_office
from models.zajdel.tracker import ADFConfig, ZajdelADF

CFG = ADFConfig(
    max_open=12, persons_per_slot=8, init_persons=32, chunk=8, link_out=12, label_out=12
)


@pytest.fixture(scope="module")
def belief():
    """A belief after 6 observations of an office scenario, and the scenario."""
    sc = simulate_office(3)
    state, _ = ZajdelADF(sc.params, CFG).run(take(sc.obs, slice(0, 6)))
    return sc, state


def _slot_niw(state, s: int) -> NIW:
    fields = ("slot_a", "slot_kappa", "slot_eta", "slot_C")
    return NIW(*(np.asarray(getattr(state, f))[s] for f in fields))


def _brute_force(params, state, o, idx, combos, logw, logw0, lp_win) -> np.ndarray:
    S = logw.shape[1]
    app = o.appearance[idx]
    out = np.zeros(len(combos))
    for h, row in enumerate(combos):
        chain: list[NIW] = []  # the NIW of each window position's chain, after it
        for i, par in enumerate(row):
            if par < 0:
                out[h] += logw0[i]
                chain.append(niw_update_np(params.prior, app[i]))
            elif par < S:
                out[h] += logw[i, par]
                chain.append(niw_update_np(_slot_niw(state, par), app[i]))
            else:
                j, k = idx[par - S], idx[i]
                out[h] += lp_win + log_p_delta(
                    params.path, o.camera[j], o.border_quit[j], o.t_quit[j],
                    o.camera[k], o.border_enter[k], o.t_enter[k],
                )  # fmt: skip
                out[h] += niw_predictive_logpdf_np(app[i], chain[par - S])
                chain.append(niw_update_np(chain[par - S], app[i]))
    return out


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), n=st.integers(2, 4), branch=st.integers(1, 3))
def test_window_scores_equal_brute_force(belief, seed: int, n: int, branch: int) -> None:
    sc, state = belief
    rng = np.random.default_rng(seed)
    S = np.asarray(state.slot_a).shape[0]
    idx = np.arange(6, 6 + n)
    logw = rng.normal(-3.0, 2.0, size=(n, S))
    logw[rng.random((n, S)) < 0.3] = -np.inf  # impossible links are left out of the candidates
    logw0 = rng.normal(-3.0, 1.0, size=n)
    lp_win = float(rng.normal(-2.0, 0.5))
    cand = np.argsort(-logw, axis=1)[:, :branch]
    cand_ok = np.take_along_axis(np.isfinite(logw), cand, 1)
    combos = _enumerate_parents(cand, cand_ok, n, S)
    got = _score_hypotheses(sc.params, state, sc.obs, idx, combos, np.where(cand_ok, cand, 0),
                            logw, logw0, lp_win)  # fmt: skip
    want = _brute_force(sc.params, state, sc.obs, idx, combos, logw, logw0, lp_win)
    assert np.isfinite(got).all() == np.isfinite(want).all()
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9)
    # a chain through a window member is among the hypotheses (the test reaches that branch)
    assert (combos >= S).any()


@pytest.mark.parametrize("lag", [-1, 1.5, True, "2"])
def test_a_lag_that_is_no_count_is_refused(belief, lag) -> None:
    from dbn.errors import InputError

    sc, state = belief
    with pytest.raises(InputError, match="lag must be an integer >= 0"):
        ZajdelADF(sc.params, CFG).run(take(sc.obs, slice(6, 8)), state, lag=lag)
