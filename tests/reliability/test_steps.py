"""Fuzz of every public step (issue 14): one bad field at a time, never garbage.

For every registry tracker (``models.get(name).example(key)``), every bad version of one
field of an observation (NaN, inf, huge, negative, wrong dtype, wrong shape, out-of-range
id; :mod:`tests.reliability.conftest_steps`) and time going backwards must either

* raise a :mod:`dbn.errors` class, leaving the state handed in exactly as it was, or
* be accepted and give a state without NaN (beyond the NaN a valid step leaves),

and never raise another exception. The default run tries one bad value per kind and
tracker; ``slow`` tries every field of every observation and hypothesis-drawn mixes.
Also: the regressions of issue 14 and the DBN filters (``inference.filter``,
``DBNFilter.step``).
"""

from __future__ import annotations

import dataclasses
import functools
import os
import sys

import jax
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import models
from dbn.errors import DBNError, InputError, NonFiniteError

sys.path.insert(0, os.path.dirname(__file__))
from conftest_steps import KINDS, mutants, nan_leaves, same, snapshot  # noqa: E402

TRACKERS = models.available()
#: trackers whose observations carry a time (a replayed earlier one must be rejected)
TIMED = {"zajdel_adf", "zajdel_learnsearch", "jorge", "localization", "pathrecovery", "rjmcmc3d"}


@functools.cache
def _setup(name: str):
    """The example, the state after ``obs[0]``, and the NaN paths a valid step leaves."""
    ex = models.get(name).example(jax.random.key(0))
    tr, obs = ex.tracker, ex.observations
    s1, _ = tr.step(jax.random.key(2), tr.init(jax.random.key(1)), obs[0])
    good, _ = tr.step(jax.random.key(3), s1, obs[1])
    return ex, s1, good, frozenset(nan_leaves(good))


def _check_one(tr, state, bad, allowed_nan: frozenset, label: str) -> str:
    """Step ``bad`` on ``state``; assert the contract; 'rejected' or 'accepted'."""
    before = snapshot(state)
    try:
        new, _ = tr.step(jax.random.key(3), state, bad)
    except DBNError:
        assert same(before, state), f"{label}: rejected, but the state changed"
        return "rejected"
    except Exception as exc:  # noqa: BLE001 - the point: no other exception
        pytest.fail(f"{label}: raised {type(exc).__name__}: {exc}")
    assert same(before, state), f"{label}: accepted, but the state handed in was mutated"
    extra = set(nan_leaves(new)) - allowed_nan
    assert not extra, f"{label}: accepted and put NaN into {sorted(extra)[:3]}"
    return "accepted"


def _one_per_kind(obs) -> list[tuple[str, object]]:
    seen, out = set(), []
    for label, bad in mutants(obs):
        kind = label.rsplit(":", 1)[1]
        if kind not in seen:
            seen.add(kind)
            out.append((label, bad))
    return out


@pytest.mark.parametrize("name", TRACKERS)
def test_one_bad_field_per_kind(name):
    ex, s1, _, allowed = _setup(name)
    cases = _one_per_kind(ex.observations[1]) + [("example bad", ex.bad_observation)]
    assert len(cases) >= 4
    outcomes = {label: _check_one(ex.tracker, s1, bad, allowed, f"{name} {label}")
                for label, bad in cases}  # fmt: skip
    assert outcomes["example bad"] == "rejected"
    assert any(o == "rejected" for o in outcomes.values())


@pytest.mark.parametrize("name", TRACKERS)
def test_time_going_backwards(name):
    ex, _, good, allowed = _setup(name)
    outcome = _check_one(ex.tracker, good, ex.observations[0], allowed, f"{name} replay")
    if name in TIMED:
        assert outcome == "rejected"


@pytest.mark.slow
@pytest.mark.parametrize("name", TRACKERS)
def test_every_bad_field_of_every_observation(name):
    ex, s1, _, allowed = _setup(name)
    tr, state = ex.tracker, s1
    for t, obs in enumerate(ex.observations[1:], start=1):
        for label, bad in mutants(obs):
            _check_one(tr, state, bad, allowed, f"{name} obs[{t}] {label}")
        state, _ = tr.step(jax.random.key(10 + t), state, obs)


@pytest.mark.slow
@settings(max_examples=60, deadline=None, suppress_health_check=list(HealthCheck))
@given(data=st.data())
def test_hypothesis_bad_fields(data):
    name = data.draw(st.sampled_from(TRACKERS))
    ex, s1, _, allowed = _setup(name)
    cases = list(mutants(ex.observations[1]))
    label, bad = data.draw(st.sampled_from(cases))
    # a second bad field on top of the first (validation must still come first)
    more = list(mutants(bad))
    if more and data.draw(st.booleans()):
        label, bad = data.draw(st.sampled_from(more))
    _check_one(ex.tracker, s1, bad, allowed, f"{name} {label}")


def test_kinds_are_covered():
    """Across the trackers' observations every kind of bad value is produced."""
    kinds = set()
    for name in TRACKERS:
        ex, *_ = _setup(name)
        kinds |= {label.rsplit(":", 1)[1] for label, _ in mutants(ex.observations[1])}
    assert kinds == set(KINDS)


# --- the regressions of issue 14 ------------------------------------------------------------
def test_rjmcmc3d_image_in_0_255_is_rejected_uint8_converted_explicitly():
    from models.rjmcmc3d import unit_image

    ex, s1, _, _ = _setup("rjmcmc3d")
    frame = ex.observations[1]
    before = snapshot(s1)
    for bad in (frame._replace(D=frame.D * 255), frame._replace(image=frame.image * 255),
                frame._replace(image=(frame.image * 255).astype(np.uint8))):  # fmt: skip
        with pytest.raises(InputError, match=r"\[0, 1\]"):
            ex.tracker.step(jax.random.key(3), s1, bad)
    assert same(before, s1)
    u8 = (np.asarray(frame.image) * 255).round().astype(np.uint8)
    img = unit_image(u8)
    assert img.dtype == np.float32 and img.min() >= 0 and img.max() <= 1
    np.testing.assert_allclose(img, frame.image, atol=0.5 / 255 + 1e-6)
    with pytest.raises(InputError):
        unit_image(frame.image)


def test_zajdel_huge_appearance_rejected_state_intact():
    ex, s1, _, _ = _setup("zajdel_adf")
    obs = ex.observations[1]
    before = snapshot(s1)
    with pytest.raises(InputError, match="appearance"):
        ex.tracker.step(jax.random.key(3), s1, obs._replace(appearance=obs.appearance * 0 + 1e50))
    assert same(before, s1)


def test_pathrecovery_nan_features_and_time_pointer_past_the_end():
    from models.pathrecovery.filter import run_filter
    from models.pathrecovery.recover import recover_path
    from models.pathrecovery.simulate import ObservationDB

    ex, *_ = _setup("pathrecovery")
    model = ex.tracker.model
    odb = _example_odb(ex)
    ptr = odb.time_ptr.copy()
    ptr[-1] += 5  # points past the end of the data
    with pytest.raises(InputError, match="time_ptr"):
        run_filter(0, model, ObservationDB(ptr, odb.cam, odb.feat, odb.obj))
    lists = run_filter(0, model, odb)
    feat = np.array(odb.feat, dtype=np.float64)
    feat[0, 0] = np.nan
    with pytest.raises(NonFiniteError):
        recover_path(model, lists, feat, k=model.config.k)


def _example_odb(ex):
    from models.pathrecovery.simulate import ObservationDB

    obs = ex.observations
    cam = np.concatenate([o.cam for o in obs])
    feat = np.concatenate([o.feat for o in obs])
    # an empty step 0 (the filter starts at t = 1), then one step per observation
    ptr = np.concatenate([[0, 0], np.cumsum([o.cam.size for o in obs])]).astype(np.int64)
    return ObservationDB(ptr, cam, feat, np.zeros(cam.size, np.int64))


@pytest.mark.parametrize("n", [0, -1, 2.5, True])
def test_zero_or_bad_particle_counts_rejected_at_construction(n):
    from models.localization.tracker import make_filter

    ex, *_ = _setup("localization")
    with pytest.raises(InputError, match="num_particles"):
        make_filter(ex.tracker.model, n)


def test_localize_checks_on_the_host_before_tracing():
    from models.localization.model import RangeBearingObservation
    from models.localization.tracker import localize

    ex, *_ = _setup("localization")
    steps = ex.observations
    odo = np.stack([s.odometry for s in steps])
    fields = RangeBearingObservation._fields
    obs = RangeBearingObservation(
        *(np.stack([np.asarray(getattr(s.observation, f)) for s in steps]) for f in fields)
    )
    raw = np.zeros((len(steps), 7))  # a raw array where observations are expected
    for bad in (raw, obs._replace(range=obs.range[:2]), obs._replace(range=obs.range * np.nan)):
        with pytest.raises(DBNError):
            localize(jax.random.key(0), ex.tracker.model, odo, bad, 50)
    res = localize(jax.random.key(0), ex.tracker.model, odo, obs, 50)
    assert np.isfinite(res.means).all()


def test_localization_refuses_bearings_in_degrees():
    """A bearing beyond one turn (degrees given for radians) was taken; a masked-out slot
    may hold anything finite."""
    from models.localization.model import RangeBearingObservation
    from models.localization.tracker import localize

    ex, *_ = _setup("localization")
    steps = ex.observations
    odo = np.stack([s.odometry for s in steps])
    fields = RangeBearingObservation._fields
    obs = RangeBearingObservation(
        *(np.stack([np.asarray(getattr(s.observation, f)) for s in steps]) for f in fields)
    )
    degrees = obs._replace(bearing=np.where(obs.mask, 7.0, obs.bearing))
    with pytest.raises(InputError, match="beyond one turn: bearings are radians"):
        localize(jax.random.key(0), ex.tracker.model, odo, degrees, 50)
    one = steps[0].observation
    bad = one._replace(bearing=np.where(np.asarray(one.mask), 90.0, np.asarray(one.bearing)))
    state = ex.tracker.init(jax.random.key(0))
    with pytest.raises(InputError, match=r"observation.bearing\[\d+\] = 90.0 is beyond one turn"):
        ex.tracker.step(jax.random.key(1), state, steps[0]._replace(observation=bad))
    padded = one._replace(bearing=np.where(np.asarray(one.mask), np.asarray(one.bearing), 99.0))
    ex.tracker.step(jax.random.key(1), state, steps[0]._replace(observation=padded))


def test_jorge_bad_palette_rejected_before_the_periodic_inference():
    from models.jorge.online import OnlineLabeller

    ex, *_ = _setup("jorge")
    tr = ex.tracker
    lab = OnlineLabeller(tr.config, tr.fps)
    strokes = ex.observations
    for s in strokes[:-1]:
        lab.add_stroke(s)
    last = strokes[-1]
    # make the periodic inference due at the next stroke
    lab._next_inference = last.start
    for palette in (np.array([10**6]), np.array([-1]), np.array([0.5])):
        before = snapshot(tr.fingerprint(models.jorge.api.JorgeState(lab)))
        with pytest.raises(InputError, match="palette"):
            lab.add_stroke(dataclasses.replace(last, palette=palette))
        assert same(before, tr.fingerprint(models.jorge.api.JorgeState(lab)))
    lab.add_stroke(last)
    assert len(lab.records) >= 1


# --- DBN filters -----------------------------------------------------------------------------
def _dbn_case():
    from dbn.examples import coupled_chains

    dbn = coupled_chains(2)
    rng = np.random.default_rng(0)
    ev = {"y0": rng.integers(0, 2, 6), "y1": rng.integers(0, 2, 6)}
    return dbn, ev


@pytest.mark.parametrize(
    "bad",
    [
        {"y0": np.array([0, 1, 5, 0, 1, 0])},  # out-of-range state
        {"y0": np.array([0, 1, -2, 0, 1, 0])},  # negative (-1 is 'unobserved')
        {"y0": np.array([0.0, 1.0, 0.5, 0.0, 1.0, 0.0])},  # not a whole number
        {"y0": np.array([0.0, 1.0, np.inf, 0.0, 1.0, 0.0])},  # infinite
        {"y0": np.array([True, False, True, False, True, False])},  # wrong dtype
        {"y0": np.zeros((6, 2), np.int64)},  # wrong shape
        {"y0": np.zeros(4, np.int64)},  # wrong length
        {"nope": np.zeros(6, np.int64)},  # unknown variable
    ],
)
@pytest.mark.parametrize("method", ["exact", "bk"])
def test_inference_filter_rejects_bad_evidence(bad, method):
    import inference

    dbn, ev = _dbn_case()
    with pytest.raises(DBNError):
        inference.filter(dbn, {**ev, **bad}, method=method)


@pytest.mark.parametrize("method", ["exact", "bk"])
def test_a_float_column_of_whole_numbers_and_nan_is_the_integer_column(method):
    """pandas writes an integer column with a missing value as floats with NaN: read as
    the integers with -1 (they were refused as 'wrong dtype', NaN as bad)."""
    import inference

    dbn, ev = _dbn_case()
    ints = np.array([0, 1, -1, 0, 1, 0])
    floats = np.array([0.0, 1.0, np.nan, 0.0, 1.0, 0.0])
    a = inference.filter(dbn, {**ev, "y0": ints}, method=method)
    b = inference.filter(dbn, {**ev, "y0": floats}, method=method)
    np.testing.assert_array_equal(a.log_likelihoods, b.log_likelihoods)


@pytest.mark.parametrize(
    "evidence, soft",
    [
        ({"y0": 7}, None),
        ({"y0": -2}, None),  # -1 is unobserved, as in a column (test_api)
        ({"y0": True}, None),
        ({"zz": 0}, None),
        (None, {"y0": np.array([np.nan, 1.0])}),
        (None, {"y0": np.array([-1.0, 1.0])}),
        (None, {"y0": np.array([1.0, 1.0, 1.0])}),
        (None, {"y0": np.array([np.inf, 1.0])}),
    ],
)
def test_dbn_filter_step_rejects_bad_evidence_state_intact(evidence, soft):
    from inference.exact.dbn_filter import DBNFilter

    dbn, _ = _dbn_case()
    f = DBNFilter(dbn)
    state = f.step(f.init({"y0": 0, "y1": 1}), {"y0": 1})
    before = snapshot(state)
    try:
        new = f.step(state, evidence, soft)
    except DBNError:
        assert same(before, state)
        return
    pytest.fail(f"accepted bad evidence {evidence} {soft}: {new}")


# --- long runs (deliverable 5) ---------------------------------------------------------------
#: length of the long runs (the issue's 100,000; ``DBNTRACK_LONG_STEPS`` shortens a trial run)
LONG = int(os.environ.get("DBNTRACK_LONG_STEPS", 100_000))
CHECK = max(1, min(10_000, LONG // 10))  # steps between checks of a long run


def _state_bytes(state) -> int:
    """Bytes held by the arrays of a state (named tuples, lists, dicts, arrays)."""
    if isinstance(state, (np.ndarray, jax.Array)):
        return int(np.asarray(state).nbytes)
    if isinstance(state, dict):
        return sum(_state_bytes(v) for v in state.values())
    if isinstance(state, (list, tuple)):
        return sum(_state_bytes(v) for v in state)
    return 8


def _bounded_run(step, state, num_steps, check_every=CHECK, bytes_per_step=0):
    """Run ``num_steps`` steps: no NaN, and the state does not grow after the first block
    (beyond ``bytes_per_step`` per step, for a state that grows by design)."""
    sizes = []
    for i in range(num_steps):
        state = step(i, state)
        if (i + 1) % check_every == 0:
            assert not nan_leaves(state), f"NaN after {i + 1} steps"
            sizes.append(_state_bytes(state))
    assert max(sizes) <= 2 * sizes[0] + bytes_per_step * num_steps, sizes
    return state


@pytest.mark.slow
def test_long_run_localization():
    ex, *_ = _setup("localization")
    tr, steps = ex.tracker, ex.observations
    keys = jax.random.split(jax.random.key(5), 1000)

    def step(i, s):
        o = steps[i % len(steps)]
        return tr.step(keys[i % 1000], s, o._replace(timestamp=0.1 * (i + 1)))[0]

    state = _bounded_run(step, tr.init(jax.random.key(1)), LONG)
    assert np.isfinite(np.asarray(state.particles.particles)).all()


@pytest.mark.slow
def test_long_run_dbn_filter():
    from inference.exact.dbn_filter import DBNFilter

    dbn, _ = _dbn_case()
    f = DBNFilter(dbn)
    rng = np.random.default_rng(0)
    ys = rng.integers(0, 2, (LONG, 2))

    def step(i, s):
        return f.step(s, {"y0": int(ys[i, 0]), "y1": int(ys[i, 1])})

    state = _bounded_run(step, f.init({"y0": 0}), LONG)
    assert np.isfinite(state.log_likelihood)


@pytest.mark.slow
def test_long_run_zajdel_adf():
    ex, *_ = _setup("zajdel_adf")
    tr, steps = ex.tracker, ex.observations
    span = float(max(np.max(o.t_quit) for o in steps)) + 1.0

    def step(i, s):
        c, o = divmod(i, len(steps))
        o = steps[o]
        o = o._replace(t_enter=o.t_enter + c * span, t_quit=o.t_quit + c * span)
        return tr.step(jax.random.key(0), s, o)[0]

    # What grows, and only that: the three person arrays counter q(c) (N + 1,), never (N,)
    # and closed (N,), float64 = 24 bytes per unit of the person capacity N. N doubles
    # while the counter's support (c with q(c) > 0, up to one more person per observation)
    # comes near it, so N <= 2 (k + 2) and they hold <= 48 bytes per observation (~32
    # measured): per-person state by design (labels are person indices, and each
    # repetition of the block brings new people: E[c] grows ~0.6 per observation, 357
    # after 600; the support's top, 412, is where q(c) > 0 exactly, 406 where > 1e-12).
    # Everything else (the slot table) is fixed by max_open, checked exactly below.
    fixed = []

    def checked(i, s):
        s = step(i, s)
        if (i + 1) % CHECK == 0:
            n, k = s.never.shape[0], int(s.k)
            assert s.counter.shape == (n + 1,) and s.closed.shape == (n,)
            assert n <= max(2 * (k + 2), tr.adf.config.init_persons), (n, k)
            fixed.append(_state_bytes(s) - 8 * (3 * n + 1))
        return s

    _bounded_run(checked, tr.init(jax.random.key(1)), LONG, bytes_per_step=48)
    assert len(set(fixed)) == 1, fixed


@pytest.mark.slow
def test_long_run_pathrecovery():
    ex, *_ = _setup("pathrecovery")
    tr, steps = ex.tracker, ex.observations
    keys = jax.random.split(jax.random.key(5), 100)

    def step(i, s):  # the example's observations again, at the next time step
        return tr.step(keys[i % 100], s, steps[i % len(steps)]._replace(t=i + 1))[0]

    _bounded_run(step, tr.init(jax.random.key(1)), LONG)


def _bad_constructions():
    from models.jorge.online import OnlineConfig
    from models.localization.tracker import make_filter
    from models.pathrecovery.filter import FilterConfig
    from models.rjmcmc3d import TrackerParams

    model = _setup("localization")[0].tracker.model
    yield "make_filter(num_particles=0)", lambda: make_filter(model, 0)
    yield "TrackerParams(num_moves=2.5)", TrackerParams(num_moves=2.5).validate
    yield "TrackerParams(h_mean=-1)", TrackerParams(h_mean=-1.0).validate
    yield "TrackerParams(p_det_update=2)", TrackerParams(p_det_update=2.0).validate
    yield "OnlineConfig(max_active=nan)", lambda: OnlineConfig(max_active=float("nan"))
    yield "FilterConfig(num_particles=0)", FilterConfig(num_particles=0).validate


def test_parameters_validated_at_construction():
    for label, make in _bad_constructions():
        with pytest.raises(DBNError):
            make()
            pytest.fail(f"{label} accepted")


def test_localization_mask_and_timestamp_must_be_what_they_say():
    """A mask of 0/2 ints or of text was read as booleans, and a timestamp "1" as 1.0."""
    ex, s1, _, allowed = _setup("localization")
    obs = ex.observations[1]
    ints = obs._replace(observation=obs.observation._replace(
        mask=np.asarray(obs.observation.mask, int) * 2))  # fmt: skip
    with pytest.raises(InputError, match="observation.mask must hold booleans"):
        ex.tracker.step(jax.random.key(3), s1, ints)
    with pytest.raises(InputError, match="timestamp must be a number"):
        ex.tracker.step(jax.random.key(3), s1, obs._replace(timestamp=str(obs.timestamp)))
    assert _check_one(ex.tracker, s1, obs, allowed, "localization good") == "accepted"
