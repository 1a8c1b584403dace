"""The streaming learn-search under the tracker protocol (``make(..., window=W)``): steps
give the batch stream search's labels, are pure, reject bad input with the state intact,
and hold only the window (SIMULATED data)."""

from __future__ import annotations

import jax
import numpy as np
import pytest

import models
from dbn.errors import InputError
from models.zajdel.data import take
from models.zajdel.learnsearch import LearnSearchConfig, initial_params
from models.zajdel.learnsearch_stream import stream_learn_search
from models.zajdel.scores import canonical_labels
from models.zajdel.simulate import simulate_office
from models.zajdel.simulate_stream import stream_config


def _setup(seed: int, num_obs: int, learn: bool):
    sc = simulate_office(seed, stream_config(num_obs))
    p0 = initial_params(take(sc.obs, slice(0, 6)), sc.params.path, sc.params.p_new)
    cfg = LearnSearchConfig(num_hypotheses=6, n0=4, batch=3, learn=learn)
    return sc, p0, cfg


def _stream_labels(tracker, obs) -> tuple[np.ndarray, object]:
    state = tracker.init(jax.random.key(0))
    committed = []
    for i in range(obs.num_obs):
        state, info = tracker.step(jax.random.key(i), state, take(obs, slice(i, i + 1)))
        committed.append(info.committed)
    return canonical_labels(np.concatenate(committed + [info.window_labels])), state


@pytest.mark.parametrize("learn, num_obs", [(False, 56), (True, 70)])
def test_steps_give_the_batch_stream_search(learn: bool, num_obs: int) -> None:
    # learn=True: 70 - n0 is a multiple of the batch, so the batch search's extra EM
    # after its last observation does not happen there either
    sc, p0, cfg = _setup(3, num_obs, learn)
    assert sc.obs.num_obs == num_obs
    tracker = models.get("zajdel_learnsearch").make(params=p0, config=cfg, window=8)
    labels, state = _stream_labels(tracker, sc.obs)
    batch = stream_learn_search(sc.obs, p0, cfg, window=8)
    np.testing.assert_array_equal(labels, batch.labels)
    assert state.buf.num_obs <= 8 and state.committed == []  # only the window is held


def test_step_is_pure_and_rejects_time_going_backwards() -> None:
    sc, p0, cfg = _setup(4, 28, True)
    tracker = models.get("zajdel_learnsearch").make(params=p0, config=cfg, window=5)
    state = tracker.init(jax.random.key(0))
    for i in range(12):
        state, _ = tracker.step(jax.random.key(i), state, take(sc.obs, slice(i, i + 1)))
    before = tracker.fingerprint(state)
    one = take(sc.obs, slice(12, 13))
    a, ia = tracker.step(jax.random.key(1), state, one)
    b, ib = tracker.step(jax.random.key(2), state, one)
    np.testing.assert_array_equal(ia.window_labels, ib.window_labels)
    assert ia.log_score == ib.log_score
    with pytest.raises(InputError, match="t_quit"):
        tracker.step(jax.random.key(3), state, take(sc.obs, slice(2, 3)))
    after = tracker.fingerprint(state)
    _same(before, after)


def _same(a, b) -> None:
    la, lb = jax.tree_util.tree_leaves(a), jax.tree_util.tree_leaves(b)
    assert len(la) == len(lb)
    for u, v in zip(la, lb, strict=True):
        np.testing.assert_array_equal(np.asarray(u), np.asarray(v))


def test_bad_window_is_refused_at_construction() -> None:
    sc, p0, cfg = _setup(0, 14, False)
    with pytest.raises(InputError, match="window"):
        models.get("zajdel_learnsearch").make(params=p0, config=cfg, window=0)
