"""The Zajdel ADF tracker against the exact oracle, and its invariants."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from benchmarks._zajdel_numpy_loop import NumpyLoopADF
from dbn.errors import InputError, NonFiniteError, ShapeError, TimeOrderError
from models.zajdel.data import Observations, take
from models.zajdel.oracle import exact_filtering
from models.zajdel.simulate import simulate_office
from models.zajdel.tracker import ADFConfig, ADFState, ZajdelADF, chain_decode

CFG = ADFConfig(
    max_open=12, persons_per_slot=8, init_persons=32, chunk=8, link_out=12, label_out=12
)


def scenario(seed: int, k: int, p_new="sparse"):
    sc = simulate_office(seed)
    params = sc.params if p_new == "sparse" else sc.params._replace(p_new=None)
    return take(sc.obs, slice(0, k)), params


def pointer_rows(state: ADFState) -> np.ndarray:
    rows = np.asarray(state.never) + np.asarray(state.closed)
    np.add.at(rows, np.asarray(state.slot_person).ravel(), np.asarray(state.slot_pprob).ravel())
    return rows


def assert_state_equal(a: ADFState, b: ADFState) -> None:
    for f in ADFState._fields:
        np.testing.assert_array_equal(
            np.asarray(getattr(a, f)), np.asarray(getattr(b, f)), err_msg=f
        )


@pytest.mark.parametrize("prior", ["sparse", "uniform"])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_adf_equals_oracle_at_two_observations(prior, seed):
    obs, params = scenario(seed, 2, prior)
    tr = ZajdelADF(params, CFG)
    _, res = tr.run(obs)
    ora = exact_filtering(obs, params)
    np.testing.assert_allclose(res.link_matrix(), ora.link_post, atol=1e-12)
    lab = res.label_matrix()
    np.testing.assert_allclose(lab, ora.label_post[:, : lab.shape[1]], atol=1e-12)
    np.testing.assert_allclose(res.loglik.cumsum(), ora.log_evidence, rtol=1e-10)


@pytest.mark.parametrize("old_update", ["seed", "keep"])
def test_adf_close_to_oracle_at_eight_observations(old_update):
    gaps, agree = [], []
    for seed in range(4):
        obs, params = scenario(seed, 8)
        _, res = ZajdelADF(params, CFG._replace(old_update=old_update)).run(obs)
        A, O = res.link_matrix(), exact_filtering(obs, params).link_post
        gaps.append(np.abs(A - O).sum(1).mean() / 2)
        agree.append((A.argmax(1) == O.argmax(1)).mean())
    assert np.mean(gaps) < 0.05 and np.mean(agree) >= 0.9


def test_time_rescaling_leaves_posteriors_unchanged():
    obs, params = scenario(5, 20)
    _, res = ZajdelADF(params, CFG).run(obs)
    f = 1.0 / 60.0  # seconds -> minutes
    obs2 = obs._replace(t_enter=obs.t_enter * f, t_quit=obs.t_quit * f)
    params2 = params._replace(path=params.path.rescale_time(f))
    _, res2 = ZajdelADF(params2, CFG).run(obs2)
    np.testing.assert_allclose(res.link_matrix(), res2.link_matrix(), atol=1e-8)
    np.testing.assert_allclose(res.counter_mean, res2.counter_mean, atol=1e-8)


@settings(max_examples=8, deadline=None)
@given(seed=st.integers(0, 1000), k=st.integers(5, 40))
def test_pointer_rows_sum_to_one(seed, k):
    obs, params = scenario(seed, k)
    tr = ZajdelADF(params, CFG._replace(prune_eps=1e-4))  # pruning and the 12-slot cap active
    state = tr.init()
    _, res = tr.run(obs, state=state)
    state, _ = tr.run(obs)
    rows = pointer_rows(state)
    np.testing.assert_allclose(rows, 1.0, atol=1e-12)
    assert (np.asarray(state.slot_pprob) >= 0).all()
    assert int(np.asarray(state.slot_valid).sum()) <= CFG.max_open
    assert np.asarray(state.counter).sum() == pytest.approx(1.0, abs=1e-12)
    np.testing.assert_allclose(res.link_prob.sum(1) + res.new_prob, 1.0, atol=1e-9)


def test_link_posterior_rows_sum_to_one_without_truncation():
    obs, params = scenario(3, 10)
    _, res = ZajdelADF(params, CFG).run(obs)
    np.testing.assert_allclose(res.link_matrix().sum(1), 1.0, atol=1e-12)


def _bad_inputs(obs: Observations):
    one = take(obs, slice(5, 6))
    yield TimeOrderError, take(obs, slice(0, 1))  # earlier than the last quit time
    yield ShapeError, one._replace(appearance=one.appearance[:, :5])
    app = one.appearance.copy()
    app[0, 2] = np.nan
    yield NonFiniteError, one._replace(appearance=app)
    yield NonFiniteError, one._replace(t_enter=np.array([np.inf]))
    yield ShapeError, one._replace(camera=np.array([99]))
    yield ShapeError, one._replace(border_enter=np.array([-1]))
    yield TimeOrderError, one._replace(t_enter=one.t_quit + 5.0)  # quit before enter


def test_bad_input_raises_and_leaves_state_unchanged(tmp_path):
    obs, params = scenario(0, 8)
    tr = ZajdelADF(params, CFG)
    state, _ = tr.run(take(obs, slice(0, 5)))
    before = ADFState(*(np.array(x) for x in state))
    for err, bad in _bad_inputs(obs):
        with pytest.raises(err):
            tr.step(state, bad)
        with pytest.raises(err):
            tr.run(bad, state=state)
        assert_state_equal(state, before)
    with pytest.raises(InputError):
        tr.run(take(obs, slice(5, 8)), state=state, lag=-1)
    # and the tracker continues exactly as if nothing had happened
    s1, r1 = tr.run(take(obs, slice(5, 8)), state=state)
    s2, r2 = tr.run(take(obs, slice(5, 8)), state=ADFState(*before))
    assert_state_equal(s1, s2)


def test_save_load_resume_is_bit_identical(tmp_path):
    obs, params = scenario(4, 30)
    tr = ZajdelADF(params, CFG)
    full_state, full = tr.run(obs)
    s, first = tr.run(take(obs, slice(0, 13)))
    tr.save(s, tmp_path / "state.npz")
    s2 = ZajdelADF(params, CFG).load(tmp_path / "state.npz")
    s3, second = tr.run(take(obs, slice(13, 30)), state=s2)
    assert_state_equal(full_state, s3)
    for f in (
        "link_obs",
        "link_prob",
        "new_prob",
        "label_person",
        "label_prob",
        "counter_mean",
        "loglik",
    ):
        a = getattr(full, f)
        b = np.concatenate([getattr(first, f), getattr(second, f)])
        np.testing.assert_array_equal(a, b, err_msg=f)


def test_step_matches_run_and_lag_zero_is_plain_filter():
    obs, params = scenario(6, 6)
    tr = ZajdelADF(params, CFG)
    _, res = tr.run(obs)
    _, res0 = tr.run(obs, lag=0)
    np.testing.assert_array_equal(res.link_prob, res0.link_prob)
    state = tr.init()
    for k in range(6):
        state, info = tr.step(state, take(obs, slice(k, k + 1)))
        np.testing.assert_allclose(np.asarray(info.link_prob), res.link_prob[k], atol=1e-12)


def test_fixed_lag_gives_valid_posteriors():
    obs, params = scenario(2, 12)
    _, res = ZajdelADF(params, CFG).run(obs, lag=2)
    np.testing.assert_allclose(res.link_matrix().sum(1), 1.0, atol=1e-9)
    assert (res.link_prob >= 0).all()


def test_chain_decoding_continues_each_observation_at_most_once():
    link_obs = np.array([[-1, -1], [0, -1], [0, 1], [0, 2]])
    link_prob = np.array([[0, 0], [0.9, 0], [0.8, 0.1], [0.7, 0.2]])
    new_prob = np.array([1.0, 0.1, 0.1, 0.1])
    lab = chain_decode(link_obs, link_prob, new_prob)
    # 1 takes 0 (0.9); 2 cannot take 0 any more -> 1 (0.1 ties new 0.1) ; 3 -> 2 (0.2)
    assert lab[1] == lab[0]
    assert lab[3] == lab[2]


@pytest.mark.heavy  # ~14 s: the projection run op by op; CI runs it (pytest -m heavy)
def test_step_eager_equals_jitted():
    import jax

    from inference.adf.driver import adf_step

    obs, params = scenario(7, 6)
    tr = ZajdelADF(params, CFG)
    state, _ = tr.run(take(obs, slice(0, 5)))
    x = tuple(np.asarray(v)[5] for v in tr._xs(obs))
    s1, i1 = adf_step(tr._hooks, tr._model, state, x)
    h, m = tr._hooks, tr._model
    with jax.disable_jit(), jax.enable_x64(True):
        s2, i2 = h.project(m, state, x, h.condition(m, state, x, h.predict(m, state, x)))
    for f in ADFState._fields:
        np.testing.assert_allclose(
            np.asarray(getattr(s1, f)), np.asarray(getattr(s2, f)), rtol=1e-9, atol=1e-12, err_msg=f
        )
    np.testing.assert_allclose(np.asarray(i1.link_prob), np.asarray(i2.link_prob), atol=1e-12)


@pytest.mark.parametrize(
    "old_update,prior", [("keep", "sparse"), ("seed", "sparse"), ("keep", "uniform")]
)
def test_tracker_equals_numpy_loop_reference(old_update, prior):
    """Regression: the tracker on the generic driver gives what the tracker gave before
    the move (the frozen plain-loop twin ``benchmarks._zajdel_numpy_loop``, equal to the
    old tracker to 1e-12): link posteriors, P(new), one-step log-likelihoods, label
    posteriors and counter means, with eviction and pruning active."""
    K = 25
    obs, params = scenario(8, K, prior)  # 25 observations > 12 slots
    cfg = CFG._replace(old_update=old_update, prune_eps=1e-6, mix_top=6, label_out=32)
    _, res = ZajdelADF(params, cfg).run(obs)
    lo, lp, npr, lz, qlab, cmean = NumpyLoopADF(params, cfg, cfg.init_persons).run(obs, full=True)
    B = np.zeros((K, K))
    kk = np.repeat(np.arange(K), lo.shape[1])
    m = lo.reshape(-1) >= 0
    np.add.at(B, (kk[m], lo.reshape(-1)[m]), lp.reshape(-1)[m])
    B[np.arange(K), np.arange(K)] += npr
    np.testing.assert_allclose(res.link_matrix(), B, atol=1e-10)
    np.testing.assert_allclose(res.new_prob, npr, atol=1e-10)
    np.testing.assert_allclose(res.loglik, lz, rtol=1e-10)
    np.testing.assert_allclose(res.counter_mean, cmean, rtol=1e-10)
    lab = res.label_matrix()
    np.testing.assert_allclose(lab, qlab[:, : lab.shape[1]], atol=1e-10)
    assert np.abs(qlab[:, lab.shape[1] :]).max(initial=0.0) < 1e-10


def test_float64_without_global_x64(tmp_path):
    """The tracker computes in float64 whatever jax's global setting (it enters
    ``jax.enable_x64`` itself): the same results with x64 switched off around it."""
    import jax

    obs, params = scenario(3, 10)
    tr = ZajdelADF(params, CFG)
    ref_state, ref = tr.run(obs)
    with jax.enable_x64(False):
        tr32 = ZajdelADF(params, CFG)
        state, res = tr32.run(take(obs, slice(0, 6)))
        tr32.save(state, tmp_path / "s.npz")
        state = tr32.load(tmp_path / "s.npz")
        state, info = tr32.step(state, take(obs, slice(6, 7)))
        state, res2 = tr32.run(take(obs, slice(7, 10)), state=state)
    for f in ADFState._fields:
        assert np.asarray(getattr(state, f)).dtype == np.asarray(getattr(ref_state, f)).dtype, f
    assert np.asarray(state.counter).dtype == np.float64 and res.link_prob.dtype == np.float64
    np.testing.assert_array_equal(res.link_prob, ref.link_prob[:6])
    np.testing.assert_allclose(np.asarray(info.link_prob), ref.link_prob[6], atol=1e-12)
    np.testing.assert_allclose(res2.link_prob, ref.link_prob[7:], atol=1e-12)
