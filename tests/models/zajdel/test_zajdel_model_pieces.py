"""Path model, scores, metrics, simulator and exact oracle of the Zajdel tracker."""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import quad

from dbn.errors import NotNormalizedError, ShapeError, TimeOrderError
from inference.adf.niw import niw_log_evidence_np, niw_predictive_logpdf_np, niw_update_np
from models.zajdel.data import Observations, take, validate_observations
from models.zajdel.greedy import greedy_labels
from models.zajdel.metrics import num_objects, pairwise_prf, partition_accuracy
from models.zajdel.oracle import enumerate_partitions, exact_filtering, exact_posterior
from models.zajdel.path import log_p_delta, log_p_delta_jax, make_path_model, pairwise_path_logprob
from models.zajdel.scores import (
    label_prior_log_prob,
    labels_to_links,
    links_to_labels,
    partition_log_score,
)
from models.zajdel.simulate import default_config, simulate_office

BELL = [1, 1, 2, 5, 15, 52, 203, 877, 4140]


def small(seed: int, k: int, **kw):
    sc = simulate_office(seed, default_config()._replace(**kw))
    return take(sc.obs, slice(0, k)), sc.labels[:k], sc.params


# ------------------------------------------------------------------------- path model
def test_trunc_normal_travel_time_integrates_to_one():
    sc = simulate_office(0)
    p = sc.params.path
    for cj, c in [(0, 1), (2, 2), (3, 5)]:
        f = lambda x, cj=cj, c=c: np.exp(log_p_delta(p, cj, 0, 0.0, c, 0, x) - p.log_trans[cj, 0, c, 0])  # noqa: E731
        if np.isfinite(p.log_trans[cj, 0, c, 0]):
            assert quad(f, 0, np.inf)[0] == pytest.approx(1.0, abs=1e-7)


def test_impossible_moves_are_minus_inf_never_nan():
    sc = simulate_office(1)
    p = sc.params.path._replace(max_travel=np.float64(100.0))
    C, B = p.num_cameras, p.num_borders
    cj, bj, c, b = np.meshgrid(np.arange(C), np.arange(B), np.arange(C), np.arange(B), indexing="ij")
    for dt in (-5.0, 0.0, 50.0, 150.0, 1e6):
        v = log_p_delta(p, cj, bj, 0.0, c, b, dt)
        vj = np.asarray(log_p_delta_jax(p, cj, bj, 0.0, c, b, dt))
        assert not np.isnan(v).any() and not np.isnan(vj).any()
        np.testing.assert_allclose(np.where(np.isfinite(v), v, 0), np.where(np.isfinite(vj), vj, 0), atol=1e-12)
        assert (np.isinf(v) == np.isinf(vj)).all()
        if dt < 0 or dt > 100:
            assert np.isneginf(v).all()
    assert np.isneginf(log_p_delta(p, cj, bj, 0.0, c, b, 10.0)[~np.isfinite(p.log_trans)]).all()


def test_path_model_rejects_unnormalised_table():
    sc = simulate_office(0)
    p = sc.params.path
    trans = np.exp(p.log_trans) * 1.1
    with pytest.raises(NotNormalizedError, match="trans"):
        make_path_model(trans, np.exp(p.log_entry), p.travel_mean, p.travel_std, 10.0)


_C = 2
_PATH = dict(trans=np.full((_C, 2, _C, 2), 0.25), entry=np.full((_C, 2), 0.25),
             travel_mean=np.ones((_C, _C)), travel_std=np.ones((_C, _C)), window=5.0)


@pytest.mark.parametrize(("field", "value", "needle"), [
    ("trans", np.full((_C, 2, _C, 2), 0.25) + 0j, "trans holds complex numbers"),
    ("entry", [["a", "b"], ["c", "d"]], "entry is not an array of numbers"),
    ("travel_mean", np.ones((3, 3)), "travel_mean (3, 3) / travel_std (2, 2): expected (2, 2)"),
    ("travel_std", "x", "travel_std is not an array of numbers"),
    ("window", "a", "window is not an array of numbers"),
    ("window", np.ones(2), "window, max_travel: expected numbers"),
    ("max_travel", 1j, "max_travel holds complex numbers"),
])  # fmt: skip
def test_path_model_names_arrays_that_are_not_real_numbers(field, value, needle):
    """Complex tables lost their imaginary parts; text and unbroadcastable travel times
    raised numpy's ValueError, a text window Python's TypeError."""
    from dbn.errors import DBNError

    with pytest.raises(DBNError) as exc:
        make_path_model(**{**_PATH, field: value})
    assert needle in str(exc.value)


@pytest.mark.parametrize(("field", "value", "needle"), [
    ("a", np.nan, "prior.a: every number must be finite"),
    ("a", 1j, "prior.a holds complex numbers"),
    ("C", np.inf, "prior.C: every number must be finite"),
    ("kappa", "a", "prior.kappa is not an array of numbers"),
    ("eta", np.inf, "prior.eta: every number must be finite"),
])  # fmt: skip
def test_a_prior_that_is_not_finite_real_numbers_is_refused(field, value, needle):
    """A NaN prior mean, or an infinite scale matrix or degrees of freedom, passed the
    check and ran to NaN posteriors; text raised numpy's ValueError."""
    from dbn.errors import ModelError
    from models.zajdel.params import check_params

    params = simulate_office(0).params
    old = np.asarray(getattr(params.prior, field))
    bad = np.full(old.shape, value) if not isinstance(value, str) else value
    if field == "C" and old.ndim == 2:  # keep it symmetric: infinity on the diagonal
        bad = np.diag(np.full(old.shape[0], value))
    with pytest.raises(ModelError) as exc:
        check_params(params._replace(prior=params.prior._replace(**{field: bad})))
    assert needle in str(exc.value)
    for p_new in (float("nan"), "a", True):
        with pytest.raises(ModelError, match="p_new"):
            check_params(params._replace(p_new=p_new))


# ---------------------------------------------------------------------------- scores
@pytest.mark.parametrize("p_new", [None, 0.2])
def test_label_prior_is_a_distribution_over_partitions(p_new):
    for k in range(1, 7):
        lp = label_prior_log_prob(enumerate_partitions(k), p_new)
        assert np.exp(lp).sum() == pytest.approx(1.0, abs=1e-12)


def test_niw_evidence_is_product_of_predictives():
    obs, _, params = small(3, 6)
    ev = niw_log_evidence_np(obs.appearance, params.prior)
    th, s = params.prior, 0.0
    for o in obs.appearance:
        s += niw_predictive_logpdf_np(o, th)
        th = niw_update_np(th, o)
    assert ev == pytest.approx(s, abs=1e-9)


def test_links_labels_roundtrip():
    parts = enumerate_partitions(6)
    links = labels_to_links(parts)
    for lab, lk in zip(parts, links):
        np.testing.assert_array_equal(links_to_labels(lk), lab)


# ---------------------------------------------------------------------------- metrics
def test_metrics_on_hand_examples():
    true = np.array([0, 0, 0, 1, 1])
    assert partition_accuracy(true, true) == 1.0
    assert pairwise_prf(true, true) == (1.0, 1.0, 1.0)
    single = np.arange(5)
    assert partition_accuracy(single, true) == 1.0  # q rewards one track per observation
    assert pairwise_prf(single, true)[2] == 0.0
    pred = np.array([0, 0, 1, 1, 1])  # tracks {0,1}: pure; {2,3,4}: 2/3
    assert partition_accuracy(pred, true) == pytest.approx((1 + 2 / 3) / 2)
    p, r, f = pairwise_prf(pred, true)  # pred pairs 1+3=4, true pairs 3+1=4, tp 1+1=2
    assert (p, r) == (0.5, 0.5) and f == pytest.approx(0.5)
    assert num_objects(pred) == 2 and num_objects(single) == 5


# -------------------------------------------------------------------------- simulator
def test_simulator_is_seeded_ordered_and_canonical():
    a, b = simulate_office(7), simulate_office(7)
    for x, y in zip(a.obs, b.obs):
        np.testing.assert_array_equal(x, y)
    o = a.obs
    assert o.appearance.shape == (70, 9)
    assert (np.diff(o.t_quit) >= 0).all() and (o.t_quit >= o.t_enter).all()
    assert num_objects(a.labels) == 5 and a.labels[0] == 0
    assert (np.maximum.accumulate(a.labels) + 1 >= np.r_[a.labels[1:], 0]).all()
    validate_observations(o, 9, 7, 2)  # valid by construction
    # true paths are possible under the tracker's model
    logp0, logpd = pairwise_path_logprob(o, a.params.path)
    links = labels_to_links(a.labels)
    k = np.arange(70)
    step = np.where(links == k, logp0, logpd[links, k])
    assert np.isfinite(step).all()


def test_default_scenario_is_hard_for_greedy():
    f1 = [pairwise_prf(greedy_labels(s.obs, s.params), s.labels)[2]
          for s in (simulate_office(i) for i in range(10))]
    assert np.mean(f1) <= 0.80


def test_validation_errors_name_field():
    obs, _, _ = small(0, 4)
    bad = obs._replace(t_quit=obs.t_quit[::-1].copy())
    with pytest.raises(TimeOrderError, match="t_quit"):
        validate_observations(bad, 9, 7, 2)
    with pytest.raises(ShapeError, match="camera"):
        validate_observations(obs._replace(camera=obs.camera + 7), 9, 7, 2)
    with pytest.raises(ShapeError, match="appearance"):
        validate_observations(obs._replace(appearance=obs.appearance[:, :8]), 9, 7, 2)


@pytest.mark.parametrize("value", [1e300, -1e30, 2.0**63])
def test_a_huge_float_index_is_named_as_given_not_wrapped(value: float) -> None:
    """A float camera or border index too large for int64 is refused with the value it
    had; casting first wrapped it (numpy's "invalid value encountered in cast") and the
    error named -9223372036854775808 (found by the slow ``test_hypothesis_bad_fields``)."""
    obs, _, _ = small(0, 4)
    for name in ("camera", "border_enter", "border_quit"):
        col = getattr(obs, name).astype(np.float64)
        col[1] = value
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            with pytest.raises(ShapeError, match=rf"{name}\[1\] = {re.escape(str(value))}: unknown"):
                validate_observations(obs._replace(**{name: col}), 9, 7, 2)


# ----------------------------------------------------------------------------- oracle
def test_enumerate_partitions_counts_and_uniqueness():
    for k in range(1, 9):
        parts = enumerate_partitions(k)
        assert parts.shape == (BELL[k], k)
        assert np.unique(parts, axis=0).shape[0] == BELL[k]


@pytest.mark.parametrize("p_new", [None, 0.1])
def test_oracle_table_equals_direct_partition_score(p_new):
    obs, _, params = small(2, 6)
    params = params._replace(p_new=p_new)
    post = exact_posterior(obs, params)
    direct = partition_log_score(post.partitions, obs, params)
    np.testing.assert_allclose(post.log_joint, direct, rtol=1e-10, atol=1e-8)
    assert post.link_post.sum(1) == pytest.approx(np.ones(6))
    assert post.label_post.sum(1) == pytest.approx(np.ones(6))
    assert post.counter_post.sum() == pytest.approx(1.0)


def test_oracle_filtering_last_row_equals_smoothing():
    obs, _, params = small(4, 5)
    filt = exact_filtering(obs, params)
    post = exact_posterior(obs, params)
    np.testing.assert_allclose(filt.link_post[-1], post.link_post[-1], atol=1e-12)
    assert filt.log_evidence[-1] == pytest.approx(post.log_evidence)


@settings(max_examples=10, deadline=None)
@given(seed=st.integers(0, 10_000), factor=st.sampled_from([1 / 60.0, 60.0, 1000.0]))
def test_oracle_posterior_invariant_to_time_unit(seed, factor):
    obs, _, params = small(seed, 5)
    post = exact_posterior(obs, params)
    obs2 = obs._replace(t_enter=obs.t_enter * factor, t_quit=obs.t_quit * factor)
    params2 = params._replace(path=params.path.rescale_time(factor))
    post2 = exact_posterior(obs2, params2)
    np.testing.assert_allclose(post.link_post, post2.link_post, atol=1e-9)


def test_observations_len():
    obs, _, _ = small(0, 3)
    assert obs.num_obs == 3 and len(obs) == 6 and isinstance(obs, Observations)
