"""models.zajdel.learnsearch_checkpoint: the learn-search (plain and fixed-lag) saved part
way and resumed goes on exactly as the one that never stopped (SIMULATED office)."""

from __future__ import annotations

import jax
import numpy as np
import pytest

from dbn.errors import CheckpointError
from inference.checkpoint import load_arrays, save_arrays
from models.zajdel.api_learnsearch import make
from models.zajdel.data import take
from models.zajdel.learnsearch import LearnSearchConfig, params_from_zajdel
from models.zajdel.learnsearch_checkpoint import _config, load_stream, params_digest, save_stream
from models.zajdel.learnsearch_stream import StreamSearch
from models.zajdel.simulate import OfficeConfig, simulate_office

CONFIG = LearnSearchConfig(num_hypotheses=5, n0=3, batch=4)  # EM every 4 observations


@pytest.fixture(scope="module")
def office():
    sc = simulate_office(3, OfficeConfig(num_people=4, num_cameras=3, num_obs=24))
    return params_from_zajdel(sc.params), [take(sc.obs, slice(i, i + 1)) for i in range(24)]


def _same(a, b) -> None:
    la, lb = jax.tree_util.tree_leaves(a), jax.tree_util.tree_leaves(b)
    assert len(la) == len(lb)
    for x, y in zip(la, lb):
        np.testing.assert_array_equal(np.asarray(x), np.asarray(y))


def _resume(tracker, steps, cut, tmp_path) -> None:
    """Save after ``cut`` steps, load, and step both to the end: the same states and infos."""
    key = jax.random.key(0)
    state = tracker.init(key)
    for obs in steps[:cut]:
        state, _ = tracker.step(key, state, obs)
    tracker.save(state, tmp_path / "search.npz")
    loaded = tracker.load(tmp_path / "search.npz")
    _same(tracker.fingerprint(loaded), tracker.fingerprint(state))
    for obs in steps[cut:]:
        state, a = tracker.step(key, state, obs)
        loaded, b = tracker.step(key, loaded, obs)
        _same(a, b)
    _same(tracker.fingerprint(loaded), tracker.fingerprint(state))


@pytest.mark.parametrize("cut", [0, 2, 9, 17])  # before n0, EM and commits between
def test_the_fixed_lag_search_resumes_exactly(office, tmp_path, cut):
    params, steps = office
    _resume(make(params, CONFIG, window=6), steps, cut, tmp_path)


@pytest.mark.parametrize("cut", [0, 5])
def test_the_plain_search_resumes_exactly(office, tmp_path, cut):
    params, steps = office
    _resume(make(params, CONFIG), steps[:10], cut, tmp_path)


def test_a_learned_state_keeps_its_parameters(office, tmp_path):
    params, steps = office
    tracker = make(params, CONFIG, window=6)
    state, _ = tracker.run(jax.random.key(0), steps[:12])
    state = state[-1]
    assert not np.array_equal(state.theta.mean, params.mean)  # EM moved them
    tracker.save(state, tmp_path / "s.npz")
    loaded = tracker.load(tmp_path / "s.npz")
    np.testing.assert_array_equal(loaded.theta.path.travel_std, state.theta.path.travel_std)
    np.testing.assert_array_equal(loaded.theta.noise_cov, state.theta.noise_cov)


def _saved(office, num_steps: int, path):
    """The fixed-lag tracker (window 6) after ``num_steps`` steps, saved to ``path``."""
    params, steps = office
    tracker = make(params, CONFIG, window=6)
    states, _ = tracker.run(jax.random.key(0), steps[:num_steps])
    tracker.save(states[-1], path)
    return tracker, states[-1]


def test_another_tracker_or_a_bad_file_is_refused(office, tmp_path):
    params, steps = office
    path = tmp_path / "s.npz"
    tracker, last = _saved(office, 8, path)
    others = [make(params._replace(mean=params.mean + 1.0), CONFIG, window=6),
              make(params, CONFIG, window=7), make(params, CONFIG._replace(batch=5), window=6),
              make(params, CONFIG, window=6, close_z=None), make(params, CONFIG)]
    for other in others:
        with pytest.raises(CheckpointError, match="s.npz"):
            other.load(path)
    # parameters that differ from the tracker's beyond what EM learns are not saved
    moved = last.copy()
    moved.theta = moved.theta._replace(path=moved.theta.path._replace(window=np.float64(1.0)))
    with pytest.raises(CheckpointError, match="beyond what EM learns"):
        tracker.save(moved, tmp_path / "moved.npz")
    assert not (tmp_path / "moved.npz").exists()
    # a plain search state whose labels do not fit its observations
    plain = make(params, CONFIG)
    s, _ = plain.run(jax.random.key(0), steps[:5])
    plain.save(s[-1], tmp_path / "p.npz")
    with np.load(tmp_path / "p.npz") as f:
        names = [n for n in f.files if n != "__header__"]
    config = _config(CONFIG, params)
    arrays, _ = load_arrays(tmp_path / "p.npz", "zajdel-learnsearch", names, config)
    save_arrays(tmp_path / "bad.npz", dict(arrays, labels=arrays["labels"][:-1]),
                "zajdel-learnsearch", config, neg_inf=("log_scores",))
    with pytest.raises(CheckpointError, match="bad.npz.*do not fit 5 observations"):
        plain.load(tmp_path / "bad.npz")


def test_labels_committed_and_not_handed_out_are_kept(office, tmp_path):
    """Outside the protocol (which hands them out at every step) a search may hold labels
    it committed and has not handed out yet."""
    params, steps = office
    search = StreamSearch(params, CONFIG, window=4)
    for obs in steps[:14]:
        search.push(obs)
    assert len(search.committed) == 10 and search.st["win_start"] > 0
    save_stream(tmp_path / "s.npz", search)
    back = load_stream(tmp_path / "s.npz", params, CONFIG, window=4)
    for obs in steps[14:]:
        search.push(obs)
        back.push(obs)
    search.finish()
    back.finish()
    np.testing.assert_array_equal(back.pop_committed(), search.pop_committed())
    np.testing.assert_array_equal(back.window_labels(), search.window_labels())
    assert (back.num_seen, back.em_iterations, back.max_window) == \
        (search.num_seen, search.em_iterations, search.max_window)


def test_the_parameters_digest_sees_values_not_types(office):
    params, _ = office
    digest = params_digest(params._replace(p_new=0.25))
    assert params_digest(params._replace(p_new=np.float64(0.25))) == digest
    assert params_digest(params._replace(p_new=None)) != digest
    moved = params.path._replace(log_entry=params.path.log_entry.astype(np.float32))
    assert params_digest(params._replace(path=moved)) != params_digest(params)  # rounded
    path = params.path._replace(travel_std=params.path.travel_std * 1.5)
    assert params_digest(params._replace(path=path)) != params_digest(params)


def test_arrays_that_do_not_fit_each_other_are_refused(office, tmp_path):
    params, _ = office
    good = tmp_path / "good.npz"
    tracker, _ = _saved(office, 10, good)
    with np.load(good) as f:
        names = [n for n in f.files if n != "__header__"]
    config = {"config": CONFIG._asdict(), "params_sha256": params_digest(params), "window": 6,
              "close_z": 5.0}
    arrays, header = load_arrays(good, "zajdel-learnsearch-stream", names, config,
                                 neg_inf=[n for n in names if n.startswith("st_")])
    extra = {k: v for k, v in header.items() if k not in ("format", "version", "config",
                                                           "checksum")}
    cases = {"st_lab": arrays["st_lab"][:, :-1], "st_ncol": arrays["st_ncol"][:-1],
             "theta_mean": arrays["theta_mean"][:-1], "buf_camera": arrays["buf_camera"][:-1],
             "buf_appearance": arrays["buf_appearance"][:, :-1]}
    for name, value in cases.items():
        bad = tmp_path / f"{name}.npz"
        save_arrays(bad, dict(arrays, **{name: value}), "zajdel-learnsearch-stream", config, extra,
                    neg_inf=[n for n in names if n.startswith("st_")])
        with pytest.raises(CheckpointError, match=f"{name}.npz"):
            tracker.load(bad)
