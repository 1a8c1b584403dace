"""Rao-Blackwellised particle filter: against switch-path enumeration, Kalman, and the
bootstrap filter; the conditional linear-Gaussian CPD it relies on."""

from __future__ import annotations

import jax
import numpy as np
import pytest
from scipy.stats import multivariate_normal

from benchmarks._dbn_scale_approx import slds_exact_means
from dbn.cpds import ConditionalLinearGaussianCPD, LinearGaussianCPD
from dbn.dbn import TwoSliceDBN, prev
from dbn.errors import CPDShapeError, InputError, ModelError
from dbn.examples import sample_switching_lds, switching_lds
from dbn.variables import ContinuousVariable, DiscreteVariable
from inference.kalman import LinearGaussianParams, kalman_filter, lgssm_sample
from inference.particle.dbn_adapter import particle_filter_dbn
from inference.particle.rbpf import rbpf_filter_dbn


def test_rbpf_means_match_switch_path_enumeration() -> None:
    dbn = switching_lds()
    _, _, ys = sample_switching_lds(np.random.default_rng(4), 6)
    exact = slds_exact_means(ys)
    runs = 16
    est = np.array(
        [
            rbpf_filter_dbn(jax.random.key(r), dbn, {"y": ys}, num_particles=300).means["x"]
            for r in range(runs)
        ]
    )
    assert est.shape == (runs, 6, 2)
    se = est.std(axis=0, ddof=1) / np.sqrt(runs)
    z = np.abs(est.mean(axis=0) - exact) / np.maximum(se, 1e-12)
    assert z.max() <= 4.0
    assert se.max() > 0  # the runs differ: z is not a division by a floor


@pytest.mark.parametrize("switch", [False, True], ids=["no_switch", "inert_prev_switch"])
def test_rbpf_without_effective_switches_is_the_kalman_filter(switch: bool) -> None:
    """No discrete variable, or a switch of the previous slice whose states select equal
    parameters: either way the RBPF is the Kalman filter, whatever the particles."""
    a, q, r = 0.9, 0.5, 0.8
    x, y = ContinuousVariable("x"), ContinuousVariable("y")
    obs = LinearGaussianCPD("y", ["x"], [[[1.0]]], [0.0], [[r]])
    x0 = LinearGaussianCPD("x", [], [], [0.0], [[a * a + q]])
    if switch:
        sw = switching_lds()
        xt = ConditionalLinearGaussianCPD(
            "x", [prev("s")], [prev("x")], [[[[a]], [[a]]]], [[0.0], [0.0]], [[[q]], [[q]]]
        )
        variables = [DiscreteVariable("s", 2), x, y]
        dbn = TwoSliceDBN(
            variables, [sw.initial_cpds[0], x0, obs], [sw.transition_cpds[0], xt, obs]
        )
    else:
        xt = LinearGaussianCPD("x", [prev("x")], [[[a]]], [0.0], [[q]])
        dbn = TwoSliceDBN([x, y], [x0, obs], [xt, obs])
    params = LinearGaussianParams(
        np.array([[a]]), np.array([[q]]), np.eye(1), np.array([[r]]), np.zeros(1), np.eye(1)
    )
    _, ys = lgssm_sample(0, params, 12)
    ys[5] = np.nan  # a missing observation: predict only
    out = rbpf_filter_dbn(jax.random.key(0), dbn, {"y": ys}, num_particles=4)
    kf_a = kalman_filter(params, ys[:5])
    np.testing.assert_allclose(out.means["x"][:5], kf_a.filtered_means, atol=1e-9)
    np.testing.assert_allclose(out.covariances["x"][:5], kf_a.filtered_covs, atol=1e-9)
    np.testing.assert_allclose(out.log_likelihoods[:5], kf_a.log_likelihoods, atol=1e-9)
    assert out.log_likelihoods[5] == 0.0 and out.method == "rbpf"
    # after the gap: slice 5 is a pure prediction, then filtering resumes
    m5 = a * out.means["x"][4, 0]
    assert abs(out.means["x"][5, 0] - m5) < 1e-9


@pytest.mark.heavy  # ~9 s: a comparison over seeds; the enumeration oracle stays; CI runs it
def test_rbpf_beats_bootstrap_with_the_same_particles() -> None:
    dbn = switching_lds()
    rng = np.random.default_rng(11)
    err_rb, err_pf = [], []
    for seed in range(3):
        _, xs, ys = sample_switching_lds(rng, 40)
        key = jax.random.key(seed)
        rb = rbpf_filter_dbn(key, dbn, {"y": ys}, num_particles=50)
        pf = particle_filter_dbn(key, dbn, {"y": ys}, num_particles=50)
        assert pf.means["x"].shape == rb.means["x"].shape == (40, 2)
        np.testing.assert_allclose(rb.marginals["s"].sum(axis=1), 1.0, atol=1e-12)
        err_rb.append((rb.means["x"] - xs) ** 2)
        err_pf.append((pf.means["x"] - xs) ** 2)
    assert np.sqrt(np.mean(err_rb)) < np.sqrt(np.mean(err_pf))


def test_conditional_linear_gaussian_cpd() -> None:
    W = np.array([[[1.0, 0.5]], [[-1.0, 2.0]]])  # (K=2, d=1, parent dim 2)
    b = np.array([[0.1], [-0.3]])
    S = np.array([[[0.5]], [[2.0]]])
    cpd = ConditionalLinearGaussianCPD("y", ["s"], ["x"], [W], b, S)
    assert cpd.parents == ("s", "x") and cpd.dim == 1 and cpd.discrete_cardinalities == (2,)
    s = np.array([0, 1, 1])
    x = np.array([[0.2, 1.0], [1.0, -1.0], [0.0, 0.0]])
    v = np.array([[0.3], [-2.0], [1.0]])
    lp = cpd.log_prob(v, {"s": s, "x": x})
    for i in range(3):
        mean = W[s[i]] @ x[i] + b[s[i]]
        assert abs(lp[i] - multivariate_normal(mean, S[s[i]]).logpdf(v[i])) < 1e-12
    draw = cpd.sample(jax.random.key(0), {"s": s, "x": x})
    assert draw.shape == (3, 1)
    renamed = cpd.renamed("y_1", ["s_1", "x_1"])
    assert renamed.discrete_parents == ("s_1",) and renamed.continuous_parents == ("x_1",)
    with pytest.raises(CPDShapeError, match="cov"):
        ConditionalLinearGaussianCPD("y", ["s"], ["x"], [W], b, S[:1])
    with pytest.raises(CPDShapeError, match="weight"):
        ConditionalLinearGaussianCPD("y", ["s"], ["x"], [W[:, :, :1].T], b, S)
    with pytest.raises(ModelError, match="positive definite"):
        ConditionalLinearGaussianCPD("y", ["s"], ["x"], [W], b, -S)
    with pytest.raises(ModelError, match="integer states"):
        cpd.log_prob(v, {"s": np.array([0, 2, 1]), "x": x})
    # unrolling keeps it
    assert switching_lds().unroll(3).cpd("x_2").discrete_parents == ("s_2",)


class _NotLinear:
    def __init__(self, variable, parents):
        self.variable, self.parents = variable, tuple(parents)

    def sample(self, key, parent_values):
        raise NotImplementedError

    def log_prob(self, value, parent_values):
        raise NotImplementedError


def test_bad_inputs() -> None:
    dbn = switching_lds()
    ys = np.zeros((5, 1))
    key = jax.random.key(0)
    with pytest.raises(InputError, match="num_particles"):
        rbpf_filter_dbn(key, dbn, {"y": ys}, num_particles=0)
    with pytest.raises(InputError, match="observed continuous"):
        rbpf_filter_dbn(key, dbn, {"y": ys}, query=["y"])
    s, x = DiscreteVariable("s", 2), ContinuousVariable("x")
    bad = TwoSliceDBN(
        [s, x],
        [dbn.initial_cpds[0], LinearGaussianCPD("x", [], [], [0.0], [[1.0]])],
        [dbn.transition_cpds[0], _NotLinear("x", [prev("x")])],
    )
    with pytest.raises(ModelError, match="LinearGaussianCPD or ConditionalLinearGaussianCPD"):
        rbpf_filter_dbn(key, bad, {"s": np.zeros(3, int)})
