"""Learn-search over partitions (seed 000, Fig. 4, Appendix A): closed-form track evidence
against a direct Gaussian density, incremental scores against from-scratch scores, the
search against exhaustive enumeration, EM monotonicity, bad input."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.special import logsumexp
from scipy.stats import multivariate_normal

from dbn.errors import InputError, ModelError, NonFiniteError, ShapeError
from models.zajdel.data import Observations, take
from models.zajdel.learnsearch import (
    LearnSearchConfig,
    LSParams,
    em_step,
    initial_params,
    learn_search,
    params_from_zajdel,
    partition_log_scores,
    track_log_evidence,
)
from models.zajdel.metrics import partition_accuracy
from models.zajdel.oracle import enumerate_partitions
from models.zajdel.path import make_path_model, pairwise_path_logprob
from models.zajdel.scores import label_prior_log_prob, path_log_prob
from models.zajdel.simulate import OfficeConfig, simulate_office


def small_problem(seed: int, K: int = 6, r: int = 3, C: int = 3, p_new: float | None = 0.3):
    rng = np.random.default_rng(seed)
    trans = rng.uniform(0.5, 1.5, (C, 1, C, 1))
    trans /= trans.sum((2, 3), keepdims=True)
    path = make_path_model(trans, np.full((C, 1), 1.0 / C), rng.uniform(5, 15, (C, C)),
                           rng.uniform(5, 15, (C, C)), window=50.0)
    te = np.sort(rng.uniform(0, 60, K))
    obs = Observations(rng.normal(size=(K, r)), rng.integers(C, size=K), te, te + 1.0,
                       np.zeros(K, np.int64), np.zeros(K, np.int64))
    A = rng.normal(size=(C, r, r))
    noise = 0.3 * A @ np.swapaxes(A, 1, 2) + 0.5 * np.eye(r)
    B = rng.normal(size=(r, r))
    params = LSParams(rng.normal(size=r), B @ B.T + np.eye(r), 0.3 * rng.normal(size=(C, r)),
                      noise, path, p_new)
    return obs, params


def test_track_evidence_matches_joint_gaussian():
    """Eq. A.2 integrated: a track's appearances are jointly Gaussian with mean
    mu + b(l_i) and covariance R + delta_ij S(l_i)."""
    obs, p = small_problem(0, K=5)
    rng = np.random.default_rng(0)
    masks = rng.random((20, 5)) < 0.6
    masks[:, 0] = True
    got = track_log_evidence(obs.appearance, obs.camera, masks, p)
    r = p.obs_dim
    for m, g in zip(masks, got):
        idx = np.nonzero(m)[0]
        n = idx.size
        mean = (p.mean + p.bias[obs.camera[idx]]).ravel()
        cov = np.kron(np.ones((n, n)), p.prior_cov)
        for a, i in enumerate(idx):
            cov[a * r:(a + 1) * r, a * r:(a + 1) * r] += p.noise_cov[obs.camera[i]]
        want = multivariate_normal(mean, cov).logpdf(obs.appearance[idx].ravel())
        assert g == pytest.approx(want, abs=1e-9)


def test_partition_score_is_sum_of_tracks_and_relabel_invariant():
    obs, p = small_problem(1)
    parts = enumerate_partitions(6)[::7]
    got = partition_log_scores(parts, obs, p)
    logp0, logpd = pairwise_path_logprob(obs, p.path)
    for lab, g in zip(parts, got):
        masks = lab[None, :] == np.unique(lab)[:, None]
        want = (track_log_evidence(obs.appearance, obs.camera, masks, p).sum()
                + path_log_prob(logp0, logpd, masks).sum() + label_prior_log_prob(lab, p.p_new))
        assert g == pytest.approx(want, abs=1e-9)
    perm = np.random.default_rng(0).permutation(6)
    np.testing.assert_allclose(partition_log_scores(perm[parts], obs, p), got, atol=1e-9)


@pytest.mark.parametrize("p_new", [0.2, None])
def test_exhaustive_search_finds_exact_map(p_new):
    """With T >= Bell(K) the search keeps every partition: its MAP is the enumeration's,
    and its incrementally updated scores equal the from-scratch scores."""
    obs, p = small_problem(2, K=7, p_new=p_new)
    parts = enumerate_partitions(7)
    ls = partition_log_scores(parts, obs, p)
    res = learn_search(obs, p, LearnSearchConfig(num_hypotheses=len(parts), n0=1, learn=False))
    assert res.hypotheses.shape == parts.shape
    np.testing.assert_array_equal(res.labels, parts[np.argmax(ls)])
    np.testing.assert_allclose(res.log_scores, partition_log_scores(res.hypotheses, obs, p), atol=1e-8)
    np.testing.assert_allclose(np.sort(res.log_scores), np.sort(ls), atol=1e-8)


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 10_000), K=st.integers(1, 6), T=st.integers(1, 12),
       p_new=st.sampled_from([None, 0.1, 0.5]))
def test_kept_partitions_are_the_best_children_property(seed, K, T, p_new):
    """For random small models: the kept scores equal the from-scratch scores, and after
    the last observation they are the T best scores among the children of the
    partitions kept one step earlier (checked by enumerating those children)."""
    obs, p = small_problem(seed, K=K, p_new=p_new)
    cfg = LearnSearchConfig(num_hypotheses=T, n0=1, learn=False)
    res = learn_search(obs, p, cfg)
    np.testing.assert_allclose(res.log_scores, partition_log_scores(res.hypotheses, obs, p), atol=1e-8)
    if K >= 2:
        prev = learn_search(take(obs, slice(0, K - 1)), p, cfg).hypotheses
        kids = np.concatenate([np.concatenate([np.repeat(h[None], h.max() + 2, 0),
                                               np.arange(h.max() + 2)[:, None]], 1) for h in prev])
        best = np.sort(partition_log_scores(kids, obs, p))[::-1][:T]
        np.testing.assert_allclose(res.log_scores, best, atol=1e-8)


def test_beam_scores_are_incremental_and_exact_on_simulated_data():
    sc = simulate_office(3)
    p = params_from_zajdel(sc.params)
    res = learn_search(sc.obs, p, LearnSearchConfig(num_hypotheses=8, learn=False))
    np.testing.assert_allclose(res.log_scores, partition_log_scores(res.hypotheses, sc.obs, p), atol=1e-7)
    assert np.all(np.diff(res.log_scores) <= 0)
    assert len({tuple(h) for h in res.hypotheses}) == res.hypotheses.shape[0]  # distinct


def test_more_hypotheses_never_lower_the_final_map_score_given_params():
    """Given parameters, the kept MAP's score cannot be worse with T = 20 than with T = 1
    on the first few observations, where T = 20 is exhaustive."""
    sc = simulate_office(1)
    obs = take(sc.obs, slice(0, 5))
    p = params_from_zajdel(sc.params)
    s1 = learn_search(obs, p, LearnSearchConfig(num_hypotheses=1, n0=1, learn=False)).log_scores[0]
    s52 = learn_search(obs, p, LearnSearchConfig(num_hypotheses=52, n0=1, learn=False)).log_scores[0]
    assert s52 >= s1 - 1e-9
    assert s52 == pytest.approx(partition_log_scores(enumerate_partitions(5), obs, p).max())


@pytest.mark.parametrize("biased", [False, True])
def test_em_never_decreases_the_marginal_likelihood(biased):
    """Exact EM (shrinkage 0, appearance parameters) over every partition of 6 observations:
    log sum_omega p(Y, omega | Theta) is non-decreasing (Dempster et al.)."""
    obs, p = small_problem(4, K=6, r=2, C=2)
    parts = enumerate_partitions(6)
    cfg = LearnSearchConfig(shrinkage=0.0, travel_shrinkage=0.0, learn_travel=False, biased=biased)
    theta = p._replace(bias=np.zeros_like(p.bias)) if not biased else p
    prev = -np.inf
    for _ in range(15):
        ls = partition_log_scores(parts, obs, theta)
        L = float(logsumexp(ls))
        assert L >= prev - 1e-9
        prev = L
        theta = em_step(obs, parts, ls, theta, cfg, theta)
    assert np.abs(theta.bias).max() > 0 if biased else np.abs(theta.bias).max() == 0


def test_em_recovers_travel_time_of_a_known_partition():
    """M step of the travel times (shrinkage 0) on one partition with weight 1: the
    per-pair mean and std of the travel times of its links."""
    obs, p = small_problem(5, K=6, C=1)
    lab = np.array([[0, 0, 0, 1, 1, 1]])
    cfg = LearnSearchConfig(shrinkage=0.0, travel_shrinkage=0.0)
    th = em_step(obs, lab, np.zeros(1), p, cfg, p)
    x = np.array([obs.t_enter[k] - obs.t_quit[k - 1] for k in (1, 2, 4, 5)])
    assert th.path.travel_mean[0, 0] == pytest.approx(x.mean())
    assert th.path.travel_std[0, 0] == pytest.approx(x.std())


def test_learned_search_beats_single_hypothesis_on_simulated_office():
    """SIMULATED office scenario (20 observations): learning from data, T = 10 finds a
    partition at least as accurate as T = 1 and the number of people close to the truth."""
    cfg = OfficeConfig(num_obs=30)
    qs = {1: [], 10: []}
    for seed in range(3):
        sc = simulate_office(seed, cfg)
        p0 = initial_params(take(sc.obs, slice(0, 6)), sc.params.path, sc.params.p_new)
        for T in qs:
            res = learn_search(sc.obs, p0, LearnSearchConfig(num_hypotheses=T))
            qs[T].append(partition_accuracy(res.labels, sc.labels))
            assert res.labels.shape == (30,)
            assert len(res.map_history) == 1 + 12
    assert np.mean(qs[10]) >= np.mean(qs[1])


def test_deterministic():
    sc = simulate_office(2, OfficeConfig(num_obs=20))
    p0 = initial_params(take(sc.obs, slice(0, 6)), sc.params.path, sc.params.p_new)
    a = learn_search(sc.obs, p0, LearnSearchConfig(num_hypotheses=5, biased=True))
    b = learn_search(sc.obs, p0, LearnSearchConfig(num_hypotheses=5, biased=True))
    np.testing.assert_array_equal(a.hypotheses, b.hypotheses)
    np.testing.assert_array_equal(a.params.noise_cov, b.params.noise_cov)


def test_bad_input_raises():
    obs, p = small_problem(0)
    with pytest.raises(InputError):
        learn_search(obs, p, LearnSearchConfig(num_hypotheses=0))
    with pytest.raises(InputError):
        learn_search(obs, p, LearnSearchConfig(n0=9))
    with pytest.raises(InputError):
        learn_search(obs, p, LearnSearchConfig(batch=0))
    with pytest.raises(ModelError):
        learn_search(obs, p._replace(prior_cov=-np.eye(3)), LearnSearchConfig())
    with pytest.raises(ModelError):
        learn_search(obs, p._replace(bias=np.zeros((2, 3))), LearnSearchConfig())
    bad = obs._replace(appearance=np.where(np.arange(3) == 1, np.nan, obs.appearance))
    with pytest.raises(NonFiniteError):
        learn_search(bad, p)
    with pytest.raises(ShapeError):
        learn_search(obs._replace(appearance=obs.appearance[:, :2]), p)
    with pytest.raises(ShapeError):
        learn_search(obs._replace(camera=obs.camera + 5), p)


@pytest.mark.parametrize(("change", "needle"), [
    ({"mean": np.zeros(3) + 0j}, "mean holds complex numbers"),
    ({"mean": ["a", "b", "c"]}, "mean is not an array of numbers"),
    ({"bias": np.full((3, 3), "x")}, "bias is not an array of numbers"),
    ({"p_new": "a"}, "p_new = 'a': must be None or a number in (0, 1)"),
    ({"p_new": float("nan")}, "p_new = nan"),
])  # fmt: skip
def test_learn_search_names_parameters_that_are_not_real_numbers(change, needle):
    """Complex parameters passed the check (and ran in complex arithmetic), text raised
    numpy's TypeError from isfinite, and a text p_new Python's TypeError."""
    obs, params = small_problem(0)
    with pytest.raises(ModelError) as exc:
        learn_search(obs, params._replace(**change))
    assert needle in str(exc.value)
