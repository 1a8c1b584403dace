"""The birth-leave filtering form of the Zajdel ADF (issue 17, ``birth_leave="filter"``):
new people at a (time-varying) rate lambda, a returning person's hazard
(1 - rho) p_delta / g_j, the appearance prior fitted by empirical Bayes."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import truncnorm

from dbn.errors import ModelError
from inference.adf.niw import NIW, niw_log_evidence_masked_np, niw_log_evidence_stats_np
from models.zajdel.birth_leave import (
    estimate_arrival_profile,
    fit_appearance_prior,
    with_birth_leave,
)
from models.zajdel.data import take
from models.zajdel.path import log_p_delta, log_stay_prob, stay_table
from models.zajdel.simulate import simulate_office
from models.zajdel.tracker import ADFConfig, ZajdelADF

CFG = ADFConfig(
    max_open=12,
    persons_per_slot=4,
    init_persons=32,
    chunk=8,
    link_out=12,
    label_out=12,
    birth_leave="filter",
)


RATE = [0.05, 0.05, 0.05]  # every test's rate has this shape: one compilation for all


def test_stay_probability_is_the_truncated_normal_survival():
    path = with_birth_leave(simulate_office(7).params, 0.05, 0.1).path
    trans = np.exp(np.asarray(path.log_trans)).sum(-1)
    mu, sd = np.asarray(path.travel_mean), np.asarray(path.travel_std)
    for c, b, d in [(0, 0, 0.0), (3, 1, 40.0), (6, 0, 150.0)]:
        s = sum(
            trans[c, b, c2] * truncnorm.sf(d, -mu[c, c2] / sd[c, c2], np.inf, mu[c, c2], sd[c, c2])
            for c2 in range(mu.shape[0])
        )
        assert np.exp(log_stay_prob(path, c, b, d)) == pytest.approx(0.1 + 0.9 * s, rel=1e-10)
    table, step = stay_table(path, 300.0, 64)
    assert np.allclose(table[..., 0], 0.0) and np.all(np.diff(table, axis=-1) <= 1e-12)


def test_two_observations_equal_the_model():
    # the second observation: new (lambda(te) entry t0) against the first continued,
    # (1 - rho) p_delta / g(te - tq) t(o | o_0); lambda from a two-bin profile
    sc = simulate_office(3)
    obs = take(sc.obs, slice(0, 2))
    te1 = float(obs.t_enter[1])
    params = with_birth_leave(sc.params, [0.5, 0.02, 0.3], 0.1, rate_bin=te1 * 0.9)
    _, res = ZajdelADF(params, CFG).run(obs)
    path, pr = params.path, params.prior
    x = obs.appearance
    ev = lambda m: niw_log_evidence_masked_np(x, np.array([m]), pr)[0]  # noqa: E731
    new = np.log(0.02) + path.log_entry[obs.camera[1], obs.border_enter[1]] + ev([0, 1])
    lk = (
        np.log(0.9)
        + log_p_delta(
            path,
            obs.camera[0],
            obs.border_quit[0],
            obs.t_quit[0],
            obs.camera[1],
            obs.border_enter[1],
            te1,
        )
        - log_stay_prob(path, obs.camera[0], obs.border_quit[0], te1 - obs.t_quit[0])
        + ev([1, 1])
        - ev([1, 0])
    )
    p_new = 1.0 / (1.0 + np.exp(lk - new))
    assert float(res.new_prob[1]) == pytest.approx(p_new, rel=1e-4)
    assert float(res.new_prob[0]) == 1.0


def test_rescaling_time_and_rates_leaves_posteriors_unchanged():
    sc = simulate_office(4)
    obs = take(sc.obs, slice(0, 30))
    params = with_birth_leave(sc.params, [0.05, 0.02, 0.01], 0.1, rate_bin=200.0)
    _, a = ZajdelADF(params, CFG).run(obs)
    f = 60.0
    obs2 = obs._replace(t_enter=obs.t_enter * f, t_quit=obs.t_quit * f)
    _, b = ZajdelADF(params._replace(path=params.path.rescale_time(f)), CFG).run(obs2)
    np.testing.assert_allclose(a.link_matrix(), b.link_matrix(), atol=1e-9)
    np.testing.assert_allclose(a.counter_mean, b.counter_mean, atol=1e-9)


def test_new_end_keeps_its_mass_and_the_counter_sums_the_births():
    # 4 persons per slot: the label posterior spreads over more, yet the newest end is
    # surely someone's latest (mass 1: the persons left out do not take it to 'closed'); no slot holds
    # more than 1; the counter's mean is the summed P(new)
    sc = simulate_office(5)
    params = with_birth_leave(sc.params, RATE, 0.1)
    st, res = ZajdelADF(params, CFG).run(take(sc.obs, slice(0, 40)))
    pp = np.asarray(st.slot_pprob).sum(1)
    newest = int(np.argmax(np.where(np.asarray(st.slot_valid), np.asarray(st.slot_obs), -1)))
    assert pp[newest] == pytest.approx(1.0, abs=1e-9)
    assert pp.max() <= 1.0 + 1e-9
    assert int(res.num_open.max()) == CFG.max_open  # the cap was reached
    np.testing.assert_allclose(res.counter_mean, np.cumsum(res.new_prob), atol=1e-9)


def test_ends_that_cannot_be_continued_leave_the_table():
    sc = simulate_office(4)
    obs = take(sc.obs, slice(0, 30))
    tr = ZajdelADF(with_birth_leave(sc.params, RATE, 0.1), CFG)
    st, res = tr.run(obs)
    late = take(obs, slice(29, None))
    late = late._replace(t_enter=late.t_enter + 86_400.0, t_quit=late.t_quit + 86_400.0)
    _, res2 = tr.run(late, state=st)
    assert float(res2.new_prob[0]) == 1.0
    assert int(res2.num_open[0]) == 1


def test_arrival_profile_counts_first_entries():
    sc = simulate_office(0)
    prof = estimate_arrival_profile([sc, sc], 20.0)
    _, first = np.unique(sc.labels, return_index=True)
    assert prof.size == int(np.ceil(sc.obs.t_quit.max() / 20.0))
    # 2 copies of P people over 2 x 20 s per bin, half a person per bin added
    assert prof.sum() * 40.0 == pytest.approx(2 * first.size + 0.5 * prof.size)
    assert np.all(prof > 0)
    with pytest.raises(ModelError, match="bin_width"):
        estimate_arrival_profile([sc], 0.0)
    with pytest.raises(ModelError, match="new_rate"):
        with_birth_leave(sc.params, [0.1, -1.0], 0.1, 10.0)
    with pytest.raises(ModelError, match="birth_leave"):
        ZajdelADF(with_birth_leave(sc.params, 0.1, 0.1), CFG._replace(birth_leave="smooth"))


def test_fitted_prior_moves_towards_the_generating_one():
    # people drawn from a NIW with eta = r + 1 + 40; the fit starts at r + 1 + 4
    rng = np.random.default_rng(0)
    r, P, n, k_true, extra = 3, 300, 8, 2.0, 40.0
    V0 = 0.5 * np.eye(r)
    labels = np.repeat(np.arange(P), n)
    from scipy.stats import invwishart

    Vs = invwishart.rvs(df=r + 1 + extra, scale=extra * V0, size=P, random_state=rng)
    ms = np.array([rng.multivariate_normal(np.zeros(r), V / k_true) for V in Vs])
    X = ms[labels] + np.einsum(
        "kij,kj->ki", np.linalg.cholesky(Vs)[labels], rng.normal(size=(P * n, r))
    )
    sc = type("S", (), {"labels": labels, "obs": type("O", (), {"appearance": X})()})()
    start = NIW(np.zeros(r), 1.0, r + 1 + 4.0, 4.0 * V0)
    fit = fit_appearance_prior([sc], start)
    assert r + 1 + 20 < fit.eta < r + 1 + 80
    assert fit.kappa == pytest.approx(k_true, rel=0.3)
    np.testing.assert_allclose(fit.C / (fit.eta - r - 1), V0)  # E[V] kept
    masks = labels[None, :] == np.arange(P)[:, None]
    assert (
        niw_log_evidence_masked_np(X, masks, fit).sum()
        > niw_log_evidence_masked_np(X, masks, start).sum()
    )


def test_evidence_from_statistics_equals_the_masked_form():
    rng = np.random.default_rng(1)
    X = rng.normal(size=(12, 3))
    masks = rng.uniform(size=(5, 12)) < 0.5
    pr = NIW(np.zeros(3), 0.7, 6.0, 2.0 * np.eye(3))
    M = masks.astype(float)
    got = niw_log_evidence_stats_np(M.sum(1), M @ X, np.einsum("sk,ki,kj->sij", M, X, X), pr)
    np.testing.assert_array_equal(got, niw_log_evidence_masked_np(X, masks, pr))
