"""Conformance of every registered tracker to the protocol of :mod:`models.protocol`.

Parametrised over ``models.available()``: each entry's tiny SIMULATED example is run
through ``init`` / ``step`` / ``run`` / ``fold``; same key, same result; a rejected observation
raises a :mod:`dbn.errors` class and leaves the state exactly as before; save/load round
trip where offered; Info carries the one-step score where the model has one.
"""

from __future__ import annotations

import copy
import dataclasses
import subprocess
import sys

import jax
import numpy as np
import pytest

import models
from dbn.errors import DBNError, InputError
from models.protocol import StepTracker, Tracker, split_run_keys, step_key_list

NAMES = models.available()


def _leaves(x, depth: int = 0) -> list:
    """Flatten a state/info (NamedTuples, containers, dataclasses, arrays) to numpy leaves."""
    if depth > 12:
        raise AssertionError("structure too deep to compare")
    if isinstance(x, dict):
        return [("k", repr(k)) for k in sorted(x, key=repr)] + [
            leaf for k in sorted(x, key=repr) for leaf in _leaves(x[k], depth + 1)
        ]
    if isinstance(x, tuple | list):
        return [("len", len(x))] + [leaf for v in x for leaf in _leaves(v, depth + 1)]
    if isinstance(x, frozenset | set):
        return [("set", tuple(sorted(map(repr, x))))]
    if dataclasses.is_dataclass(x) and not isinstance(x, type):
        return _leaves(dataclasses.astuple(x), depth + 1)
    if x is None or isinstance(x, str | bool | int | float | np.generic):
        return [np.asarray(x)]
    if isinstance(x, np.ndarray | jax.Array):
        if jax.dtypes.issubdtype(x.dtype, jax.dtypes.prng_key):
            x = jax.random.key_data(x)
        return [np.asarray(x)]
    raise AssertionError(f"cannot compare a {type(x).__name__}")


def _assert_same(a, b) -> None:
    la, lb = _leaves(a), _leaves(b)
    assert len(la) == len(lb)
    for u, v in zip(la, lb, strict=True):
        if isinstance(u, tuple):
            assert u == v
            continue
        assert u.shape == v.shape and u.dtype == v.dtype
        assert np.array_equal(u, v, equal_nan=u.dtype.kind in "fc"), (u, v)


_EXAMPLES: dict = {}


def _example(name: str):
    if name not in _EXAMPLES:
        _EXAMPLES[name] = models.get(name).example(jax.random.key(0))
    return _EXAMPLES[name]


def test_registry_lists_the_six_trackers_with_their_metadata() -> None:
    assert set(NAMES) == {
        "zajdel_adf",
        "zajdel_learnsearch",
        "jorge",
        "localization",
        "pathrecovery",
        "rjmcmc3d",
    }
    for name in NAMES:
        e = models.get(name)
        assert e.name == name and e.seed_paper and e.tracks and e.input_formats
    with pytest.raises(InputError, match="available: zajdel_adf"):
        models.get("kalman")


def test_importing_models_imports_no_tracker() -> None:
    code = "import sys, models; models.available(); print(sorted(m for m in sys.modules if m.startswith(('jax', 'models.'))))"
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120
    )
    assert out.stdout.strip() == "['models.registry']", out.stdout


@pytest.mark.parametrize("name", NAMES)
def test_same_key_same_result_and_run_equals_steps(name: str) -> None:
    ex = _example(name)
    tr = ex.tracker
    assert isinstance(tr, Tracker) and isinstance(tr, StepTracker) and tr.name == name
    obs = ex.observations[:3]
    before = copy.deepcopy(tr.fingerprint(tr.init(jax.random.key(5))))
    states, infos = tr.run(jax.random.key(1), obs)
    states2, infos2 = tr.run(jax.random.key(1), obs)
    assert len(states) == len(infos) == len(obs)
    _assert_same([tr.fingerprint(s) for s in states], [tr.fingerprint(s) for s in states2])
    _assert_same(infos, infos2)
    # run is init + one step per observation with the split keys
    k_init, keys = split_run_keys(jax.random.key(1), len(obs))
    state = tr.init(k_init)
    for i, o in enumerate(obs):
        state, info = tr.step(keys[i], state, o)
        _assert_same(tr.fingerprint(state), tr.fingerprint(states[i]))
        _assert_same(info, infos[i])
    # running did not change the tracker: init gives what it gave before
    _assert_same(tr.fingerprint(tr.init(jax.random.key(5))), before)


@pytest.mark.parametrize("name", NAMES)
def test_rejected_observation_leaves_the_state_unchanged(name: str) -> None:
    ex = _example(name)
    tr = ex.tracker
    state, _ = tr.step(jax.random.key(2), tr.init(jax.random.key(1)), ex.observations[0])
    snapshot = copy.deepcopy(tr.fingerprint(state))
    with pytest.raises(DBNError):
        tr.step(jax.random.key(3), state, ex.bad_observation)
    _assert_same(tr.fingerprint(state), snapshot)
    # and the state still steps as if nothing had happened; a good step does not mutate it
    a = tr.step(jax.random.key(4), state, ex.observations[1])
    _assert_same(tr.fingerprint(state), snapshot)
    fresh, _ = tr.step(jax.random.key(2), tr.init(jax.random.key(1)), ex.observations[0])
    b = tr.step(jax.random.key(4), fresh, ex.observations[1])
    _assert_same(tr.fingerprint(a[0]), tr.fingerprint(b[0]))
    _assert_same(a[1], b[1])


@pytest.mark.parametrize("name", NAMES)
def test_info_carries_the_one_step_score(name: str) -> None:
    ex = _example(name)
    tr = ex.tracker
    _, infos = tr.run(jax.random.key(7), ex.observations[:2])
    if tr.score_field is None:
        pytest.skip(f"{name} has no one-step score")
    for info in infos:
        s = tr.score(info)
        assert isinstance(s, float) and not np.isnan(s) and s < np.inf


def _arrays(x, depth: int = 0) -> list:
    """The numpy arrays inside an observation (NamedTuples, containers, plain objects)."""
    if isinstance(x, np.ndarray):
        return [x]
    if isinstance(x, dict):
        x = list(x.values())
    elif not isinstance(x, tuple | list) and hasattr(x, "__dict__") and depth < 6:
        x = list(vars(x).values())
    if isinstance(x, tuple | list):
        return [a for v in x for a in _arrays(v, depth + 1)]
    return []


@pytest.mark.parametrize("name", NAMES)
def test_running_leaves_the_callers_observations_as_they_were(name: str) -> None:
    """A tracker reads its observations: it neither changes them nor freezes the caller's
    arrays (CPDs and camera networks once set the caller's arrays read-only)."""
    ex = _example(name)
    obs = list(ex.observations[:3])
    snapshot = copy.deepcopy(obs)
    arrays = _arrays(obs)
    writeable = [a.flags.writeable for a in arrays]
    assert arrays, f"{name}: no numpy arrays found in its observations"
    ex.tracker.run(jax.random.key(1), obs)
    _assert_same(obs, snapshot)
    assert [a.flags.writeable for a in arrays] == writeable


@pytest.mark.parametrize("name", NAMES)
def test_save_load_round_trip(name: str, tmp_path) -> None:
    ex = _example(name)
    tr = ex.tracker
    if not tr.can_save:
        pytest.skip(f"{name} offers no save/load")
    state, _ = tr.step(jax.random.key(2), tr.init(jax.random.key(1)), ex.observations[0])
    path = tmp_path / "state.npz"
    tr.save(state, path)
    loaded = tr.load(path)
    _assert_same(tr.fingerprint(loaded), tr.fingerprint(state))
    a = tr.step(jax.random.key(3), loaded, ex.observations[1])
    b = tr.step(jax.random.key(3), state, ex.observations[1])
    _assert_same(tr.fingerprint(a[0]), tr.fingerprint(b[0]))
    _assert_same(a[1], b[1])


@pytest.mark.slow  # compiles the scanned filter (~10-20 s)
def test_localization_protocol_run_equals_the_batch_filter() -> None:
    """The adapter's step-by-step run is the library's scanned filter (same keys)."""
    from models.localization.tracker import localize

    ex = _example("localization")
    tr = ex.tracker
    states, infos = tr.run(jax.random.key(3), ex.observations)
    odo = np.stack([o.odometry for o in ex.observations])
    obs = jax.tree_util.tree_map(lambda *a: np.stack(a), *[o.observation for o in ex.observations])
    obs = obs._replace(landmark=obs.landmark.astype(np.int32))
    res = localize(jax.random.key(3), tr.model, odo, obs, 200, "apf")
    np.testing.assert_allclose(
        [float(i.log_likelihood) for i in infos], np.asarray(res.infos.log_likelihood), rtol=1e-9
    )
    np.testing.assert_allclose(
        np.asarray(states[-1].particles.particles), np.asarray(res.final_state.particles), atol=1e-9
    )


@pytest.mark.x32
@pytest.mark.parametrize(
    "name", [pytest.param("zajdel_adf", marks=pytest.mark.slow), "localization"]
)  # zajdel_adf: a fresh compile of the ADF step in this mode (~15 s)
def test_float64_trackers_need_no_global_x64(name: str) -> None:
    """With jax in its default 32-bit mode the adapters still compute in float64."""
    ex = _example(name)
    tr = ex.tracker
    state, info = tr.step(jax.random.key(2), tr.init(jax.random.key(1)), ex.observations[0])
    floats = [
        x
        for x in jax.tree_util.tree_leaves((state, info))
        if getattr(x, "dtype", np.dtype(int)).kind == "f"
    ]
    assert floats and all(x.dtype == np.float64 for x in floats)
    assert not jax.config.jax_enable_x64


@pytest.mark.parametrize("name", NAMES)
def test_fold_is_run_keeping_the_last_state(name: str) -> None:
    ex = _example(name)
    tr = ex.tracker
    obs = ex.observations[:3]
    states, infos = tr.run(jax.random.key(1), obs)
    totals: list = []

    def bar(steps, total):
        totals.append(total)
        return steps

    state, fold_infos = tr.fold(jax.random.key(1), obs, bar)
    assert totals == [len(obs)]
    _assert_same(tr.fingerprint(state), tr.fingerprint(states[-1]))
    _assert_same(fold_infos, infos)
    # no observations: the init state of run's key split
    empty, none = tr.fold(jax.random.key(1), [])
    assert none == []
    _assert_same(tr.fingerprint(empty), tr.fingerprint(tr.init(split_run_keys(jax.random.key(1), 0)[0])))


@pytest.mark.parametrize(
    "make",
    [
        lambda: jax.random.key(7),
        lambda: jax.random.key(7, impl="rbg"),
        lambda: jax.random.PRNGKey(7),
    ],
    ids=["threefry", "rbg", "raw"],
)
def test_step_key_list_is_list_of_the_split_keys(make) -> None:
    """The host route gives the keys ``list()`` gives: same bits, same kind of key; and
    split_run_keys' step keys are exactly those of the split."""
    k_init, k_steps = jax.random.split(make())
    keys = jax.random.split(k_steps, 5)
    got, want = step_key_list(keys), list(keys)
    assert len(got) == len(want) == 5
    run_init, run_keys = split_run_keys(make(), 5)
    assert len(run_keys) == 5
    for a, b in zip([run_init, *run_keys], [k_init, *got]):
        assert a.dtype == b.dtype and a.shape == b.shape
        typed = jax.dtypes.issubdtype(a.dtype, jax.dtypes.prng_key)
        bits = (lambda k: np.asarray(jax.random.key_data(k))) if typed else np.asarray
        np.testing.assert_array_equal(bits(a), bits(b))
    for g, w in zip(got, want):
        assert g.dtype == w.dtype and g.shape == w.shape
        typed = jax.dtypes.issubdtype(w.dtype, jax.dtypes.prng_key)
        if typed:
            assert jax.random.key_impl(g) == jax.random.key_impl(w)
        bits = (lambda k: np.asarray(jax.random.key_data(k))) if typed else np.asarray
        np.testing.assert_array_equal(bits(g), bits(w))
        # a step draws the same numbers from either
        draws = [np.asarray(jax.random.uniform(k, (3,))) for k in (g, w)]
        np.testing.assert_array_equal(*draws)


@pytest.mark.parametrize("name", NAMES)
def test_anything_but_an_observation_or_a_key_is_refused_naming_it(name: str) -> None:
    """``step`` on None, an int, a str, a list or a dict, ``run`` / ``fold`` on a non-
    sequence and a key that is not a PRNG key raised Python's or jax's own errors
    (AttributeError: 'NoneType' object has no attribute 'appearance'; a str passed the
    jorge stroke check through its ``.index`` method; TypeError: 'int' object is not
    iterable; jax's invalid PRNG key data). Each is now a dbn.errors class and the state
    is left as it was. ``init`` and ``step`` refuse a bad key on every tracker, the
    deterministic ones too (they took any value; localization's init raised jax's
    TypeError)."""
    ex = _example(name)
    tr = ex.tracker
    state = tr.init(jax.random.key(1))
    snapshot = copy.deepcopy(tr.fingerprint(state))
    for obs in (None, 5, "abc", [], {}):
        with pytest.raises(DBNError):
            tr.step(jax.random.key(2), state, obs)
    for observations in (None, 5, "ab"):
        for method in (tr.run, tr.fold):
            with pytest.raises(InputError, match="observations must be a sequence"):
                method(jax.random.key(2), observations)
    for key in (0, None, np.zeros(3), "abc"):
        for call in (lambda k: tr.run(k, ex.observations[:1]), tr.init,
                     lambda k: tr.step(k, state, ex.observations[0])):  # fmt: skip
            with pytest.raises(InputError, match="key must be one jax PRNG key"):
                call(key)
    _assert_same(tr.fingerprint(state), snapshot)


@pytest.mark.parametrize("name", NAMES)
def test_make_refuses_the_wrong_object_naming_the_argument(name: str) -> None:
    """``models.get(name).make`` given None, an int, a str or a dict where its model,
    parameters, scene or config belong raised ``AttributeError`` ('NoneType' object has no
    attribute 'prior' / 'network' / 'floor'), or, for the learn-search and path-recovery
    trackers, built a tracker that failed at its first step. Each is now a dbn.errors
    class naming the argument and the class it needs."""
    entry = models.get(name)
    more = (10,) if name == "localization" else (7.0,) if name == "jorge" else ()
    for bad in (None, 5, "abc", {}):
        if name == "jorge" and bad is None:
            continue  # None is the default OnlineConfig
        with pytest.raises(DBNError, match=r"^(params|config|model|scene) must be an instance"):
            entry.make(bad, *more)
