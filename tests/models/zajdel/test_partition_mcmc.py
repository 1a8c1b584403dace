"""Partition Metropolis-Hastings (seed 000 section 5.4 + split / merge / move) against the
exact posterior by enumeration of every partition (K <= 6 observations)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats
from scipy.special import logsumexp

from dbn.errors import InputError
from models.zajdel.data import Observations
from models.zajdel.learnsearch import LSParams, _canonical, _terms, partition_log_scores
from models.zajdel.mcmc import MCMCConfig, chain_init, chain_step, partition_mcmc
from models.zajdel.oracle import enumerate_partitions
from models.zajdel.path import make_path_model

P_FAIL = 1e-4  # significance level of every statistical test below (fixed seeds)


def small_problem(seed: int, K: int = 6, r: int = 2, C: int = 3, p_new: float | None = 0.3):
    """A small model with a broad posterior over the partitions of K observations."""
    rng = np.random.default_rng(seed)
    trans = rng.uniform(0.5, 1.5, (C, 1, C, 1))
    trans /= trans.sum((2, 3), keepdims=True)
    path = make_path_model(trans, np.full((C, 1), 1.0 / C), rng.uniform(5, 15, (C, C)),
                           rng.uniform(5, 15, (C, C)), window=50.0)
    te = np.sort(rng.uniform(0, 40, K))
    obs = Observations(rng.normal(size=(K, r)), rng.integers(C, size=K), te, te + 1.0,
                       np.zeros(K, np.int64), np.zeros(K, np.int64))
    noise = np.broadcast_to(0.8 * np.eye(r) + 0.1, (C, r, r)).copy()
    params = LSParams(np.zeros(r), np.eye(r), 0.3 * rng.normal(size=(C, r)), noise, path, p_new)
    return obs, params


def exact(obs, params):
    parts = enumerate_partitions(obs.num_obs)
    ls = partition_log_scores(parts, obs, params)
    return parts, np.exp(ls - logsumexp(ls)), ls


def index_of(parts: np.ndarray, labels: np.ndarray) -> np.ndarray:
    K = parts.shape[1]
    base = (K + 1) ** np.arange(K)
    table = {int(c): i for i, c in enumerate(parts @ base)}
    return np.array([table[int(c)] for c in _canonical(labels) @ base])


def test_chain_scores_match_from_scratch():
    obs, params = small_problem(0)
    parts, _, ls = exact(obs, params)
    st = chain_init(parts, obs, params)
    np.testing.assert_allclose(st.score, ls, rtol=0, atol=1e-9)
    t = _terms(obs, params)
    rng = np.random.default_rng(1)
    for _ in range(5):  # bookkeeping after accepted and rejected moves of every type
        st, _, _ = chain_step(rng, st, t, params.p_new)
        np.testing.assert_allclose(st.score, partition_log_scores(st.labels, obs, params), atol=1e-8)


@pytest.mark.parametrize("K", [2, 3, 4, 5, 6])
@pytest.mark.parametrize("p_new", [0.3, None])
def test_detailed_balance_one_step(K, p_new):
    """From exact posterior draws, one step of the mixture kernel: the count of a -> b
    transitions must equal that of b -> a in expectation (detailed balance); given
    N_ab + N_ba, N_ab ~ Binomial(., 1/2), summed as a chi-square over all pairs."""
    obs, params = small_problem(K, K=K, p_new=p_new)
    parts, pi, _ = exact(obs, params)
    rng = np.random.default_rng(100 + K)
    M = 40_000
    a = rng.choice(len(parts), size=M, p=pi)
    st, moves, acc = chain_step(rng, chain_init(parts[a], obs, params), _terms(obs, params), p_new)
    assert acc.any() and np.bincount(moves, minlength=4).min() > 0
    b = index_of(parts, st.labels)
    N = np.zeros((len(parts), len(parts)))
    np.add.at(N, (a, b), 1)
    iu = np.triu_indices(len(parts), 1)
    x, y = N[iu], N.T[iu]
    keep = x + y > 0
    chi2 = float(((x - y)[keep] ** 2 / (x + y)[keep]).sum())
    assert stats.chi2.sf(chi2, keep.sum()) > P_FAIL, (chi2, keep.sum())


def test_invariance_from_exact_draws():
    """Chains started at exact posterior draws stay exactly posterior-distributed after
    any number of steps: multinomial chi-square of the final states (independent chains)."""
    obs, params = small_problem(7)
    parts, pi, _ = exact(obs, params)
    rng = np.random.default_rng(7)
    M = 20_000
    st = chain_init(parts[rng.choice(len(parts), size=M, p=pi)], obs, params)
    t = _terms(obs, params)
    for _ in range(15):
        st, _, _ = chain_step(rng, st, t, params.p_new)
    cnt = np.bincount(index_of(parts, st.labels), minlength=len(parts))
    E = M * pi
    big = E >= 5
    chi2 = ((cnt[big] - E[big]) ** 2 / E[big]).sum() + (cnt[~big].sum() - E[~big].sum()) ** 2 / max(
        E[~big].sum(), 1e-12)
    assert stats.chi2.sf(chi2, big.sum()) > P_FAIL


def test_visit_frequencies_match_exact_posterior():
    """Visit frequencies of independent chains from random starts (after burn-in) match the
    exact posterior on every one of the Bell(6) = 203 partitions, within Monte-Carlo error:
    per-cell standard error from the spread between chains (floored by the i.i.d. one)."""
    obs, params = small_problem(3)
    parts, pi, _ = exact(obs, params)
    rng = np.random.default_rng(11)
    C, steps, burn = 64, 3000, 300
    st = chain_init(rng.integers(6, size=(C, 6)), obs, params)
    t = _terms(obs, params)
    visits = np.zeros((C, len(parts)))
    rows = np.arange(C)
    for s in range(steps):
        st, _, _ = chain_step(rng, st, t, params.p_new)
        if s >= burn:
            np.add.at(visits, (rows, index_of(parts, st.labels)), 1)
    f = visits / (steps - burn)
    mean = f.mean(0)
    se = np.maximum(f.std(0, ddof=1) / np.sqrt(C), np.sqrt(pi * (1 - pi) / (C * (steps - burn))))
    z = np.abs(mean - pi) / np.maximum(se, 1e-300)
    bound = stats.norm.isf(P_FAIL / 2 / len(parts))  # Bonferroni over the cells
    assert np.abs(mean.sum() - 1) < 1e-12
    assert z.max() < bound, (z.max(), bound, int(np.argmax(z)))


def test_swap_only_keeps_track_sizes():
    obs, params = small_problem(2)
    rng = np.random.default_rng(2)
    lab0 = np.array([[0, 0, 1, 1, 1, 2]] * 50)
    st = chain_init(lab0, obs, params)
    t = _terms(obs, params)
    for _ in range(20):
        st, _, _ = chain_step(rng, st, t, params.p_new, move=0)
    sizes = np.sort(np.stack([np.bincount(r, minlength=6) for r in st.labels]), axis=1)
    assert (sizes == np.sort(np.bincount(lab0[0], minlength=6))).all()


def test_partition_mcmc_result_and_reproducibility():
    obs, params = small_problem(4)
    parts, pi, ls = exact(obs, params)
    cfg = MCMCConfig(init="random", burn_in=50)
    r1 = partition_mcmc(5, obs, params, 400, cfg, num_chains=4, checkpoints=(100,))
    r2 = partition_mcmc(5, obs, params, 400, cfg, num_chains=4)
    r3 = partition_mcmc(5, obs, params, 100, cfg, num_chains=4)
    np.testing.assert_array_equal(r1.best_at[100][0], r3.best_labels)  # a shorter run
    np.testing.assert_array_equal(r1.best_labels, r2.best_labels)
    np.testing.assert_array_equal(r1.coassign, r2.coassign)
    assert r1.best_score == pytest.approx(float(partition_log_scores(r1.best_labels, obs, params)))
    assert r1.best_score == pytest.approx(float(ls.max()))  # 1600 draws find the MAP of 203
    np.testing.assert_allclose(np.diag(r1.coassign), 1.0)
    np.testing.assert_allclose(r1.coassign, r1.coassign.T)
    g = partition_mcmc(0, obs, params, 10, MCMCConfig(init="greedy"))
    assert g.score_trace.shape == (10, 1)


def test_bad_config_raises():
    obs, params = small_problem(0)
    with pytest.raises(InputError):
        partition_mcmc(0, obs, params, 10, MCMCConfig(move_probs=(0.5, 0.5, 0.5, 0.0)))
    with pytest.raises(InputError):
        partition_mcmc(0, obs, params, 10, MCMCConfig(move_probs=(0.5, 0.0, 0.5, 0.0)))
    with pytest.raises(InputError):
        partition_mcmc(0, obs, params, 10, MCMCConfig(init="nope"))
    with pytest.raises(InputError):
        partition_mcmc(0, obs, params, 0)
    for value in (np.nan, 2.5, -1):  # all three ran
        with pytest.raises(InputError, match="burn_in"):
            partition_mcmc(0, obs, params, 10, MCMCConfig(burn_in=value))
