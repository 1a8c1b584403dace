"""The Zajdel ADF tracker's birth-leave link prior (issue 17): new people arrive at a
rate, a pass is a person's last with a probability, ends that can no longer be
continued leave the pointer table."""

from __future__ import annotations

import numpy as np
import pytest

from dbn.errors import ModelError
from models.zajdel.birth_leave import estimate_birth_leave, with_birth_leave
from models.zajdel.data import Observations, concat_observations, take
from models.zajdel.oracle import exact_filtering
from models.zajdel.simulate import large_config, simulate_office
from models.zajdel.tracker import ADFConfig, ADFState, ZajdelADF

CFG = ADFConfig(
    max_open=12,
    persons_per_slot=8,
    init_persons=32,
    chunk=8,
    link_out=12,
    label_out=12,
    birth_leave=True,
)


def pointer_rows(state: ADFState) -> np.ndarray:
    rows = np.asarray(state.never) + np.asarray(state.closed)
    np.add.at(rows, np.asarray(state.slot_person).ravel(), np.asarray(state.slot_pprob).ravel())
    return rows


def office(seed: int, k: int, rate: float = 0.05, leave: float = 0.1):
    sc = simulate_office(seed)
    return take(sc.obs, slice(0, k)), with_birth_leave(sc.params, rate, leave)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_equals_oracle_at_two_observations(seed):
    # with rho = 1/2 and lambda = p_new / (W (1 - p_new)), "new" vs "link" of the second
    # observation has the same prior odds as the spec's p_new prior the oracle scores
    sc = simulate_office(seed)
    obs = take(sc.obs, slice(0, 2))
    p_new, W = sc.params.p_new, float(sc.params.path.window)
    params = with_birth_leave(sc.params, p_new / (W * (1.0 - p_new)), 0.5)
    _, res = ZajdelADF(params, CFG).run(obs)
    ora = exact_filtering(obs, sc.params)
    np.testing.assert_allclose(res.link_matrix(), ora.link_post, atol=1e-12)


def test_rescaling_time_and_rate_leaves_posteriors_unchanged():
    obs, params = office(3, 30)
    _, a = ZajdelADF(params, CFG).run(obs)
    f = 60.0
    obs2 = obs._replace(t_enter=obs.t_enter * f, t_quit=obs.t_quit * f)
    params2 = params._replace(path=params.path.rescale_time(f))
    _, b = ZajdelADF(params2, CFG).run(obs2)
    np.testing.assert_allclose(a.link_matrix(), b.link_matrix(), atol=1e-9)
    np.testing.assert_allclose(a.counter_mean, b.counter_mean, atol=1e-9)


def test_ends_that_cannot_be_continued_leave_the_table():
    obs, params = office(4, 30)
    tr = ZajdelADF(params, CFG)
    st, res = tr.run(obs)
    assert int(res.num_open[-1]) > 1
    # one more pass a day later: no earlier end can be continued any more
    late = take(obs, slice(len(obs.t_quit) - 1, None))
    late = late._replace(t_enter=late.t_enter + 86_400.0, t_quit=late.t_quit + 86_400.0)
    st2, res2 = tr.run(late, state=st)
    assert float(res2.new_prob[0]) == 1.0
    assert int(res2.num_open[0]) == 1  # only the new slot is open
    np.testing.assert_allclose(
        float(res2.counter_mean[0]), float(res.counter_mean[-1]) + 1, atol=1e-9
    )
    np.testing.assert_allclose(pointer_rows(st2), 1.0, atol=1e-9)
    np.testing.assert_allclose(pointer_rows(st), 1.0, atol=1e-9)


def test_default_is_the_spec_prior():
    # the switch is off by default; setting the rates alone changes nothing
    sc = simulate_office(5)
    obs = take(sc.obs, slice(0, 20))
    cfg = CFG._replace(birth_leave=False)
    _, a = ZajdelADF(sc.params, cfg).run(obs)
    _, b = ZajdelADF(with_birth_leave(sc.params, 0.05, 0.1), cfg).run(obs)
    np.testing.assert_array_equal(a.link_matrix(), b.link_matrix())
    assert ADFConfig().birth_leave is False


def test_estimates_match_the_simulator():
    cfg = large_config(2000)._replace(arrival_window=600.0)
    scs = [simulate_office(s, cfg) for s in (1, 2)]
    rate, leave = estimate_birth_leave(scs)
    assert leave == pytest.approx(1.0 / 20.0)
    # 100 people uniform over 600 s per scenario: the span of first entries is
    # 600 (P - 1) / (P + 1) on average; the rate within 15 % of 100 / 600
    assert rate == pytest.approx(100.0 / 600.0, rel=0.15)


def test_bad_parameters_raise():
    sc = simulate_office(0)
    with pytest.raises(ModelError, match="new_rate"):
        with_birth_leave(sc.params, -1.0, 0.1)
    with pytest.raises(ModelError, match="leave_prob"):
        with_birth_leave(sc.params, 0.1, 1.0)
    with pytest.raises(ModelError, match="birth_leave"):
        ZajdelADF(sc.params, CFG)  # rates not set
    one = Observations(*(np.asarray(x)[:1] for x in sc.obs))
    with pytest.raises(ModelError):
        estimate_birth_leave([type("S", (), {"obs": one, "labels": np.zeros(1, int)})()])


def test_concat_keeps_pointer_rows():
    obs, params = office(6, 24)
    tr = ZajdelADF(params, CFG)
    st, _ = tr.run(take(obs, slice(0, 12)))
    st, _ = tr.run(take(obs, slice(12, 24)), state=st)
    st_all, _ = tr.run(concat_observations([take(obs, slice(0, 12)), take(obs, slice(12, 24))]))
    np.testing.assert_allclose(pointer_rows(st), 1.0, atol=1e-9)
    np.testing.assert_allclose(np.asarray(st.counter), np.asarray(st_all.counter), atol=1e-12)


def test_continuation_horizon_solves_the_closing_rule():
    from scipy.stats import truncnorm

    from models.zajdel.path import continuation_horizon

    params = with_birth_leave(simulate_office(7).params, 0.05, 0.1)
    path, eps, rho = params.path, 1e-6, 0.1
    h = continuation_horizon(path, eps)
    trans = np.exp(np.asarray(path.log_trans)).sum(-1)
    mu, sd = np.asarray(path.travel_mean), np.asarray(path.travel_std)

    def cont(c, b, d):
        s = sum(
            trans[c, b, c2] * truncnorm.sf(d, -mu[c, c2] / sd[c, c2], np.inf, mu[c, c2], sd[c, c2])
            for c2 in range(mu.shape[0])
        )
        return (1 - rho) * s / (rho + (1 - rho) * s)

    for c, b in [(0, 0), (3, 1), (6, 0)]:
        assert cont(c, b, h[c, b] * (1 - 1e-3)) > eps > cont(c, b, h[c, b] * (1 + 1e-3))
    unset = continuation_horizon(simulate_office(7).params.path, eps)
    assert np.isinf(unset).all()
