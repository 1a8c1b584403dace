"""Fixed-lag learn-search on streams (issue 17, deliverable 3): equal to the plain search
when the window covers the stream, bounded work per observation on longer streams, valid
partitions for every window, bad input (SIMULATED data)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import inference  # noqa: F401
from dbn.errors import InputError, ModelError
from models.zajdel.data import take
from models.zajdel.learnsearch import (
    LearnSearchConfig,
    initial_params,
    learn_search,
    params_from_zajdel,
    partition_log_scores,
)
from models.zajdel.learnsearch_stream import stream_learn_search
from models.zajdel.metrics import partition_accuracy
from models.zajdel.scores import canonical_labels
from models.zajdel.simulate import OfficeConfig, simulate_office
from models.zajdel.simulate_stream import stream_config


def _start(sc):
    return initial_params(take(sc.obs, slice(0, 6)), sc.params.path, sc.params.p_new)


@pytest.mark.parametrize("seed, T, batch", [(0, 1, 2), (0, 5, 2), (1, 10, 3)])
def test_whole_window_equals_plain_search_with_learning(seed, T, batch):
    sc = simulate_office(seed)
    p0 = _start(sc)
    cfg = LearnSearchConfig(num_hypotheses=T, batch=batch)
    a = learn_search(sc.obs, p0, cfg)
    b = stream_learn_search(sc.obs, p0, cfg, window=sc.obs.num_obs, close_z=None)
    np.testing.assert_array_equal(a.labels, b.labels)
    np.testing.assert_allclose(b.log_scores, a.log_scores, rtol=0, atol=1e-8)
    for x, y in zip(a.params[:4], b.params[:4]):
        np.testing.assert_allclose(y, x, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(b.params.path.travel_mean, a.params.path.travel_mean, rtol=1e-12)


@settings(max_examples=8, deadline=None)
@given(
    seed=st.integers(0, 10_000),
    n=st.integers(2, 24),
    T=st.integers(1, 6),
    p_new=st.sampled_from([None, 0.2]),
)
def test_whole_window_equals_plain_search_fixed_params(seed, n, T, p_new):
    sc = simulate_office(seed, OfficeConfig(num_people=2, num_obs=n))
    pt = params_from_zajdel(sc.params)._replace(p_new=p_new)
    cfg = LearnSearchConfig(num_hypotheses=T, learn=False, n0=min(4, n))
    a = learn_search(sc.obs, pt, cfg)
    b = stream_learn_search(sc.obs, pt, cfg, window=n + 3, close_z=None)
    np.testing.assert_array_equal(a.labels, b.labels)
    np.testing.assert_allclose(b.log_scores, a.log_scores, rtol=0, atol=1e-8)
    # and the scores are the from-scratch posterior of the kept partitions
    best = partition_log_scores(a.labels, sc.obs, pt)
    assert abs(float(best) - b.log_scores[0]) < 1e-8


@settings(max_examples=8, deadline=None)
@given(
    seed=st.integers(0, 10_000),
    window=st.integers(1, 12),
    T=st.integers(1, 5),
    close=st.sampled_from([None, 1.0, 5.0]),
)
def test_any_window_gives_a_valid_partition(seed, window, T, close):
    sc = simulate_office(seed, OfficeConfig(num_people=3, num_obs=30))
    cfg = LearnSearchConfig(num_hypotheses=T, n0=3)
    b = stream_learn_search(sc.obs, _start(sc), cfg, window=window, close_z=close)
    assert b.labels.shape == (30,)
    np.testing.assert_array_equal(b.labels, canonical_labels(b.labels))
    assert b.max_window <= max(window + 1, 3)
    assert b.max_candidates <= T * (b.max_open_tracks + 1)


def test_work_per_observation_does_not_grow_with_the_stream():
    """Count work, not time: children scored per observation and open tracks held stay
    bounded when the stream is 3 times longer (people keep entering and leaving)."""
    cfg = LearnSearchConfig(num_hypotheses=4, learn=False)
    out = {}
    for n in (140, 420):
        sc = simulate_office(3, stream_config(n))
        out[n] = stream_learn_search(sc.obs, params_from_zajdel(sc.params), cfg, window=10)
    people_long = 420 // 14
    assert out[420].max_window == 11
    assert out[420].max_open_tracks < people_long / 2  # without closing: every person
    assert out[420].max_open_tracks <= out[140].max_open_tracks + 6
    assert out[420].max_candidates <= 4 * (out[420].max_open_tracks + 1)
    # closing never fires when disabled: every track stays open
    sc = simulate_office(3, stream_config(140))
    keep_all = stream_learn_search(
        sc.obs, params_from_zajdel(sc.params), cfg, window=10, close_z=None
    )
    assert keep_all.max_open_tracks >= keep_all.labels.max() + 1


@pytest.mark.parametrize(
    "kw",
    [
        dict(window=0),
        dict(window=-3),
        dict(window=2.5),
        dict(window=True),
        dict(window=5, close_z=0.0),
        dict(window=5, close_z=float("nan")),
        dict(window=5, close_z=-1.0),
    ],
)
def test_bad_window_or_close_raises(kw):
    sc = simulate_office(0, OfficeConfig(num_people=2, num_obs=10))
    with pytest.raises(InputError):
        stream_learn_search(sc.obs, _start(sc), LearnSearchConfig(), **kw)


@pytest.mark.parametrize(
    "cfg",
    [
        LearnSearchConfig(num_hypotheses=0),
        LearnSearchConfig(batch=0),
        LearnSearchConfig(n0=9),
        LearnSearchConfig(shrinkage=-1.0),
    ],
)
def test_bad_config_raises(cfg):
    sc = simulate_office(0, OfficeConfig(num_people=2, num_obs=10))
    with pytest.raises(InputError):
        stream_learn_search(sc.obs, _start(sc), cfg, window=4)


def test_stream_config_people_enter_and_leave():
    sc = simulate_office(0, stream_config(280))
    assert sc.obs.num_obs == 280 and sc.labels.max() + 1 == 20
    assert sc.peak_concurrent < 20  # not everyone is inside at once
    with pytest.raises(ModelError):
        stream_config(5, passes=14)


@pytest.mark.slow
def test_accuracy_does_not_fall_with_stream_length():
    """Partition accuracy on 1,400-observation streams is not below that on 280-observation
    streams (same generator, seeds 10-14), up to three standard errors of the difference."""
    cfg = LearnSearchConfig(num_hypotheses=20, batch=4)
    q = {280: [], 1400: []}
    for n in q:
        for s in range(10, 15):
            sc = simulate_office(s, stream_config(n))
            res = stream_learn_search(sc.obs, _start(sc), cfg, window=20)
            q[n].append(partition_accuracy(res.labels, sc.labels))
    d = np.asarray(q[1400]) - np.asarray(q[280])
    se = d.std(ddof=1) / np.sqrt(d.size)
    assert d.mean() >= -max(3.0 * se, 0.02), q
