"""Particle filtering of declared DBNs against exact filtering (discrete) and Kalman."""

from __future__ import annotations

import jax
import numpy as np
import pytest

from dbn.cpds import LinearGaussianCPD, TabularCPD
from dbn.dbn import TwoSliceDBN, prev
from dbn.errors import EvidenceError, InputError, ShapeError, UnknownVariableError
from dbn.examples import coupled_chains, sample_coupled_chains
from dbn.variables import ContinuousVariable, DiscreteVariable
from inference.exact.dbn_filter import DBNFilter
from inference.kalman import LinearGaussianParams, kalman_filter, lgssm_sample
from inference.particle import bootstrap_filter, run
from inference.particle.dbn_adapter import DBNStateSpaceModel, particle_filter_dbn

RUNS = 8


def _z_scores(estimates: np.ndarray, exact: np.ndarray) -> np.ndarray:
    """|mean of independent runs - exact| in standard errors of that mean."""
    se = estimates.std(axis=0, ddof=1) / np.sqrt(estimates.shape[0])
    return np.abs(estimates.mean(axis=0) - exact) / np.maximum(se, 1e-12)


def test_bootstrap_marginals_within_standard_errors_of_exact() -> None:
    n, T = 3, 12
    dbn = coupled_chains(n)
    _, ys = sample_coupled_chains(np.random.default_rng(0), n, T)
    ev = {f"y{i}": ys[:, i] for i in range(n)}
    flt = DBNFilter(dbn)
    res = flt.filter(ev)
    exact = np.stack([flt.marginals_of(res.beliefs, f"x{i}")[:, 1] for i in range(n)], axis=1)
    model = DBNStateSpaceModel(dbn)
    inp = model.inputs(ev)
    pf = bootstrap_filter(model, 2000)
    summary = model.summary([f"x{i}" for i in range(n)])
    est, lls = [], []
    for r in range(RUNS):  # one compiled filter, independent keys
        _, infos, outs = run(jax.random.key(r), pf, inp, inp, summary=summary)
        est.append(np.stack([np.asarray(outs[f"x{i}"])[:, 1] for i in range(n)], axis=1))
        lls.append(np.asarray(infos.log_likelihood))
    est = np.array(est)  # (RUNS, T, n)
    assert est.std(axis=0).max() > 0  # the runs are independent
    assert _z_scores(est, exact).max() < 5.0
    # log-likelihood estimate: exp is unbiased, its log close for 2000 particles
    assert _z_scores(np.array(lls).sum(axis=1)[:, None], np.array([res.log_likelihood]))[0] < 5


@pytest.mark.parametrize("method", ["bootstrap", pytest.param("auxiliary", marks=pytest.mark.slow)])
def test_particle_filter_dbn_result(method: str) -> None:
    n, T = 3, 10
    dbn = coupled_chains(n)
    _, ys = sample_coupled_chains(np.random.default_rng(1), n, T)
    ev = {f"y{i}": ys[:, i] for i in range(n)}
    ev["y1"][3] = -1  # a missing observation
    flt = DBNFilter(dbn)
    res = flt.filter(ev)
    out = particle_filter_dbn(jax.random.key(7), dbn, ev, num_particles=20000, method=method)
    assert out.method == "particle" and out.info["filter"] == method
    assert set(out.marginals) == {f"x{i}" for i in range(n)}
    for i in range(n):
        m = out.marginals[f"x{i}"]
        assert m.shape == (T, 2)
        np.testing.assert_allclose(m.sum(axis=1), 1.0, atol=1e-12)
        p = flt.marginals_of(res.beliefs, f"x{i}")
        # one run: within 5 binomial standard errors at the weights' effective sample size
        se = np.sqrt(p * (1 - p) / out.info["ess"][:, None])
        assert np.all(np.abs(m - p) <= 5 * se + 1e-9)
    assert abs(out.log_likelihood - res.log_likelihood) < 0.1


class NumpyGaussianCPD:
    """A continuous CPD of the protocol kind, written in numpy (runs eagerly)."""

    def __init__(self, variable, parents, a, q) -> None:
        self.variable, self.parents, self.a, self.q = variable, tuple(parents), a, q

    def _mean(self, pv):
        return self.a * np.asarray(pv[self.parents[0]]) if self.parents else 0.0

    def sample(self, key, parent_values):
        m = self._mean(parent_values)
        z = np.asarray(jax.random.normal(key, np.shape(np.asarray(parent_values[self.parents[0]]))))
        return m + np.sqrt(self.q) * z

    def log_prob(self, value, parent_values):
        r = np.asarray(value) - self._mean(parent_values)
        return -0.5 * (r[..., 0] ** 2 / self.q + np.log(2 * np.pi * self.q))


def _lg_dbn(custom: bool):
    a, q, r = 0.9, 0.5, 0.8
    x, y = ContinuousVariable("x"), ContinuousVariable("y")
    init_x = LinearGaussianCPD("x", [], [], [0.0], [[a * a + q]])
    if custom:
        trans_x = NumpyGaussianCPD("x", [prev("x")], a, q)
    else:
        trans_x = LinearGaussianCPD("x", [prev("x")], [[[a]]], [0.0], [[q]])
    obs = LinearGaussianCPD("y", ["x"], [[[1.0]]], [0.0], [[r]])
    dbn = TwoSliceDBN([x, y], [init_x, obs], [trans_x, obs])
    params = LinearGaussianParams(
        np.array([[a]]), np.array([[q]]), np.eye(1), np.array([[r]]), np.zeros(1), np.eye(1)
    )
    return dbn, params


@pytest.mark.parametrize("custom", [False, True], ids=["linear_gaussian", "protocol_cpd"])
def test_continuous_dbn_matches_kalman(custom: bool) -> None:
    dbn, params = _lg_dbn(custom)
    _, ys = lgssm_sample(3, params, 4 if custom else 8)  # simulated from the model
    kf = kalman_filter(params, ys)
    N = 20000 if not custom else 5000  # the protocol CPD runs eagerly: fewer particles
    out = particle_filter_dbn(jax.random.key(2), dbn, {"y": ys}, num_particles=N)
    assert out.info["num_particles"] == N
    m, v = out.means["x"][:, 0], out.covariances["x"][:, 0, 0]
    se = np.sqrt(kf.filtered_covs[:, 0, 0] / out.info["ess"])
    assert np.all(np.abs(m - kf.filtered_means[:, 0]) < 5 * se)
    np.testing.assert_allclose(v, kf.filtered_covs[:, 0, 0], rtol=0.1)
    assert abs(out.log_likelihood - kf.log_likelihood) < 0.1


def test_bad_inputs() -> None:
    dbn = coupled_chains(2)
    ev = {"y0": np.zeros(4, int), "y1": np.zeros(4, int)}
    key = jax.random.key(0)
    with pytest.raises(UnknownVariableError, match="zz"):
        particle_filter_dbn(key, dbn, {**ev, "zz": np.zeros(4, int)})
    with pytest.raises(ShapeError, match="y1"):
        particle_filter_dbn(key, dbn, {"y0": ev["y0"], "y1": np.zeros(3, int)})
    with pytest.raises(InputError, match="method"):
        particle_filter_dbn(key, dbn, ev, method="magic")
    with pytest.raises(InputError, match="num_particles"):
        particle_filter_dbn(key, dbn, ev, num_particles=0)
    with pytest.raises(UnknownVariableError, match="q"):
        particle_filter_dbn(key, dbn, ev, query=["q"])
    # a discrete parent table fits; layout documented
    s = DiscreteVariable("s", 2)
    d = TwoSliceDBN(
        [s], [TabularCPD("s", [], [0.5, 0.5])], [TabularCPD("s", [prev("s")], np.eye(2))]
    )
    assert DBNStateSpaceModel(d).state_dim == 2


def test_random_dbn_with_hidden_non_interface_variable(factories) -> None:
    """Intra-slice edges, a hidden variable outside the interface, missing observations:
    marginals of every hidden variable within standard errors of exact filtering."""
    dbn = factories.random_dbn(12)
    T = 6
    rng = np.random.default_rng(5)
    ev = {"o": rng.integers(-1, dbn.initial_net.cardinality("o"), size=T)}
    flt = DBNFilter(dbn)
    exact, state = {q: [] for q in ("a", "b", "h")}, None
    for t in range(T):
        slice_ev = {"o": int(ev["o"][t])} if ev["o"][t] >= 0 else {}
        m = flt.slice_marginals(state, slice_ev)
        state = flt.init(slice_ev) if t == 0 else flt.step(state, slice_ev)
        for q in exact:
            exact[q].append(m[q])
    model = DBNStateSpaceModel(dbn)
    inp = model.inputs(ev)
    pf = bootstrap_filter(model, 2000)
    summary = model.summary(("a", "b", "h"))
    runs = [run(jax.random.key(r), pf, inp, inp, summary=summary)[2] for r in range(RUNS)]
    for q in exact:
        est = np.array([np.asarray(o[q]) for o in runs])  # (RUNS, T, K)
        z = _z_scores(est, np.array(exact[q]))
        spread = est.std(axis=0) > 0
        assert z[spread].max() < 5.0
        # where every run agrees, they agree with exact (up to a 1-in-2000 resolution)
        assert np.all(np.abs(est.mean(axis=0) - np.array(exact[q]))[~spread] <= 1e-3)
        # states the exact filter rules out are never held by a particle
        assert np.all(est[:, np.array(exact[q]) == 0] == 0)


@pytest.mark.parametrize("engine", ["bootstrap", "rbpf"])  # auxiliary: the same check
def test_a_slice_no_particle_can_explain_is_an_error_not_a_posterior(engine) -> None:
    """The switch never changes (stay = 1) and is seen to change at slice 2. Every
    particle got weight zero there: the result held ``-inf`` at slice 2 and, from there
    on, the resampler's uniform fallback as if it were a posterior. The exact engines and
    Boyen-Koller raise at that slice; the particle filters now do too."""
    from dbn.examples import switching_lds
    from inference.particle.rbpf import rbpf_filter_dbn

    dbn = switching_lds(stay=1.0)
    ev = {"s": np.array([0, 0, 1, 1]), "y": np.zeros((4, 1))}
    def run_it(evidence):
        key = jax.random.key(0)
        if engine == "rbpf":
            return rbpf_filter_dbn(key, dbn, evidence, num_particles=16)
        return particle_filter_dbn(key, dbn, evidence, num_particles=16, method=engine)

    with pytest.raises(EvidenceError, match="slice 2: every one of the 16 particles"):
        run_it(ev)  # (possible evidence passes the check in every other test here)
