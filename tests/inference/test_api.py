"""``inference.filter``: one entry point, dispatch, ``auto``'s choice, pgmpy models in,
bad input out. The approximate engines are stubbed here (they have their own tests)."""

from __future__ import annotations

import re
import sys
import types

import jax
import numpy as np
import pytest

import inference
from dbn import pgmpy_adapter as pa
from dbn.cpds import LinearGaussianCPD, TabularCPD
from dbn.dbn import TwoSliceDBN, prev
from dbn.errors import (
    EvidenceError,
    FrontierTooLargeError,
    InputError,
    MemoryLimitError,
    ModelError,
    NonFiniteError,
    ShapeError,
    UnknownEvidenceError,
    UnknownVariableError,
)
from dbn.examples import coupled_chains, sample_coupled_chains
from dbn.variables import ContinuousVariable, DiscreteVariable
from inference import api
from inference.exact.dbn_filter import DBNFilter
from inference.results import DBNFilterResult


def _chains(n: int, T: int, seed: int = 0):
    _, ys = sample_coupled_chains(np.random.default_rng(seed), n, T)
    return coupled_chains(n), {f"y{i}": ys[:, i] for i in range(n)}


def _stub(monkeypatch, module: str, fn: str, calls: list) -> None:
    def engine(*args, **kwargs):
        calls.append((args, kwargs))
        T = len(next(iter(args[-2 if fn == "bk_filter" else -2].values())))
        return DBNFilterResult({}, np.zeros(T), fn, info={"stub": True})

    mod = types.ModuleType(module)
    setattr(mod, fn, engine)
    monkeypatch.setitem(sys.modules, module, mod)


def test_exact_is_lazily_exported_and_equals_the_dense_engine() -> None:
    assert inference.filter is api.filter
    dbn, ev = _chains(4, 30)
    res = inference.filter(dbn, ev, method="exact")
    dense = DBNFilter(dbn)
    ref = dense.filter(ev)
    assert res.method == "exact" and res.num_timesteps == 30
    assert abs(res.log_likelihood - ref.log_likelihood) < 1e-9
    for i in range(4):
        np.testing.assert_allclose(
            res.marginals[f"x{i}"], dense.marginals_of(ref.beliefs, f"x{i}"), atol=1e-9
        )
    auto = inference.filter(dbn, ev)
    assert (
        auto.method == "exact"
        and "exact" in auto.info["auto"]
        and auto.info["predicted_size"] == 16
    )
    np.testing.assert_allclose(auto.marginals["x3"], res.marginals["x3"], atol=0)


def test_pgmpy_dbn_in_gives_the_same_result() -> None:
    dbn, ev = _chains(2, 12)
    ours = inference.filter(dbn, ev, query=["x1", "y0"])
    theirs = inference.filter(pa.dbn_to_pgmpy(dbn), ev, query=["x1", "y0"])
    for name in ("x1", "y0"):
        np.testing.assert_allclose(theirs.marginals[name], ours.marginals[name], atol=1e-12)
    assert abs(theirs.log_likelihood - ours.log_likelihood) < 1e-12


def test_pgmpy_dbn_without_all_cpds_is_refused() -> None:
    model = pa.dbn_to_pgmpy(coupled_chains(2))
    model.remove_cpds(model.get_cpds(("x1", 1)))
    with pytest.raises(ModelError, match=r"no CPD for node\(s\) \[\('x1', 1\)\]"):
        inference.filter(model, {"y0": np.zeros(3, int)})


def _weather() -> TwoSliceDBN:
    """A two-state chain ``x`` seen through ``y``, states named as pgmpy users name them."""
    x = DiscreteVariable("x", 2, ("sun", "rain"))
    y = DiscreteVariable("y", 3, ("dry", "damp", "wet"))
    obs = np.array([[0.7, 0.2, 0.1], [0.1, 0.3, 0.6]])
    return TwoSliceDBN(
        [x, y],
        [TabularCPD("x", [], [0.5, 0.5]), TabularCPD("y", ["x"], obs)],
        [TabularCPD("x", [prev("x")], [[0.9, 0.1], [0.2, 0.8]]), TabularCPD("y", ["x"], obs)],
    )


def test_evidence_by_state_name_equals_evidence_by_index_on_every_engine() -> None:
    """Columns of state names (None = unobserved) were refused by every engine ("must hold
    integer states"); pgmpy's own inference takes names. They now give the same results as
    the indices of those names, a pgmpy model in too."""
    from inference.exact.dbn_filter import DBNFilter

    dbn = _weather()
    by_index = {"y": np.array([0, 2, -1, 1, 2, 2])}
    by_name = {"y": ["dry", "wet", None, "damp", "wet", "wet"]}
    runs = [
        lambda ev: inference.filter(dbn, ev, "exact"),
        lambda ev: inference.filter(pa.dbn_to_pgmpy(dbn), ev, "exact"),
        lambda ev: inference.filter(dbn, ev, "bk"),
        lambda ev: inference.filter(dbn, ev, "particle", key=jax.random.key(3), num_particles=64),
    ]
    for run in runs:
        a, b = run(by_index), run(by_name)
        np.testing.assert_array_equal(a.marginals["x"], b.marginals["x"])
        np.testing.assert_array_equal(a.log_likelihoods, b.log_likelihoods)
    dense = DBNFilter(dbn)
    assert dense.filter(by_name).log_likelihood == dense.filter(by_index).log_likelihood


def test_pgmpy_evidence_by_slice_equals_pgmpy_dbn_inference() -> None:
    """pgmpy's evidence, ``{(name, t): state}``, was refused ("unknown variable ('y', 0)").
    It now gives pgmpy's own ``DBNInference`` marginals at every slice (oracle), by name
    or by index, a slice without evidence included."""
    dbn = _weather()
    model = pa.dbn_to_pgmpy(dbn)
    names = {("y", 0): "dry", ("y", 1): "wet", ("y", 3): "damp", ("y", 4): "wet"}
    index = {k: ("dry", "damp", "wet").index(v) for k, v in names.items()}
    res = inference.filter(model, names)
    assert res.num_timesteps == 5
    ours = inference.filter(dbn, index).marginals["x"]
    np.testing.assert_allclose(ours, res.marginals["x"], atol=1e-12)
    for t in range(5):
        seen = {k: v for k, v in names.items() if k[1] <= t}
        theirs = pa.pgmpy_dbn_forward(model, [("x", t)], seen)[("x", t)]
        np.testing.assert_allclose(res.marginals["x"][t], theirs, atol=1e-12)
    assert inference.filter(dbn, names, "bk", num_timesteps=7).num_timesteps == 7


def test_pgmpy_integer_state_names_read_as_pgmpy_reads_them() -> None:
    """A pgmpy variable with integer states ``[1, 2, 3]``: pgmpy reads the evidence
    ``2`` as the state named 2 (the second); as an index it would be the third."""
    from pgmpy.factors.discrete import TabularCPD as PgmpyCPD
    from pgmpy.models import DynamicBayesianNetwork

    model = DynamicBayesianNetwork([(("x", 0), ("y", 0)), (("x", 0), ("x", 1))])
    x0, x1, y0 = ("x", 0), ("x", 1), ("y", 0)
    model.add_cpds(
        PgmpyCPD(x0, 2, [[0.5], [0.5]]),
        PgmpyCPD(y0, 3, [[0.7, 0.1], [0.2, 0.3], [0.1, 0.6]], evidence=[x0], evidence_card=[2],
                 state_names={y0: [1, 2, 3], x0: [0, 1]}),
        PgmpyCPD(x1, 2, [[0.9, 0.2], [0.1, 0.8]], evidence=[x0], evidence_card=[2]),
    )
    model.initialize_initial_state()
    for ev in ({("y", 0): 2, ("y", 1): 3}, {("y", 0): 1, ("y", 2): 2}):
        res = inference.filter(model, ev)
        for t in range(res.num_timesteps):
            seen = {k: v for k, v in ev.items() if k[1] <= t}
            theirs = pa.pgmpy_dbn_forward(model, [("x", t)], seen)[("x", t)]
            np.testing.assert_allclose(res.marginals["x"][t], theirs, atol=1e-12)
    with pytest.raises(EvidenceError, match=r"evidence \('y', 0\): 0 is not a state of 'y'"):
        inference.filter(model, {("y", 0): 0})


@pytest.mark.parametrize(
    ("evidence", "needle"),
    [
        ({("y", -1): "dry"}, "key ('y', -1) is not (variable name, slice >= 0)"),
        ({("y", 0): "dry", "y": [0]}, "key 'y' is not (variable name, slice >= 0)"),
        ({("y", 0): 1.5}, "('y', 0): state 1.5 is not an index or a name"),
        ({("y", 0): "dry", ("y", 1): 2}, "slice 1: 2 is not a state name"),
        ({("y", 3): "dry"}, "slice 3 is beyond num_timesteps = 3"),
        ({("z", 0): 1}, "evidence ('z', 0): no discrete variable 'z' (discrete: ['x', 'y'])"),
    ],
)
def test_bad_pgmpy_evidence_names_the_key(evidence, needle) -> None:
    with pytest.raises(EvidenceError, match=re.escape(needle)):
        inference.filter(_weather(), evidence, num_timesteps=3)


def test_one_slice_of_evidence_reads_alike_on_every_on_line_engine() -> None:
    """``init`` / ``step`` took -1 as unobserved under Boyen-Koller only; the exact
    engines refused it ("state -1 out of range") and None, as a column does not. Now
    ``-1`` and None are unobserved, and a name is its index, on all three."""
    from inference.adf.boyen_koller import BoyenKoller
    from inference.exact.dbn_filter import DBNFilter
    from inference.exact.structured_filter import StructuredFilter

    dbn = _weather()
    for flt in (StructuredFilter(dbn), DBNFilter(dbn), BoyenKoller(dbn)):
        for ev in ({"y": -1}, {"y": None}, {"y": np.int64(-1)}):
            np.testing.assert_equal(flt.step(flt.init(ev), ev), flt.step(flt.init({}), {}))
        np.testing.assert_equal(flt.step(flt.init({"y": "wet"}), {"y": "dry"}),
                                flt.step(flt.init({"y": 2}), {"y": 0}))
        with pytest.raises(UnknownEvidenceError, match=r"'z' \(known: \['x', 'y'\]\)"):
            flt.init({"z": 0})
        with pytest.raises(EvidenceError, match="state -2 out of range"):
            flt.init({"y": -2})


def test_auto_falls_back_to_boyen_koller_and_says_why(monkeypatch) -> None:
    calls: list = []
    _stub(monkeypatch, "inference.adf.boyen_koller", "bk_filter", calls)
    dbn, ev = _chains(26, 5)
    with pytest.raises(FrontierTooLargeError, match="bk"):
        inference.filter(dbn, ev, method="exact")
    res = inference.filter(dbn, ev, clusters=[["x0"]])
    assert res.method == "bk_filter" and res.info["stub"]
    assert res.info["auto"].startswith("bk") and "67,108,864" in res.info["auto"]
    ((args, kwargs),) = calls
    assert args[0] is dbn and _same_columns(args[1], ev) and kwargs["clusters"] == [["x0"]]
    wide = inference.filter(*_chains(64, 3))  # too wide to even plan exactly
    assert wide.method == "bk_filter" and "approximate" in wide.info["auto"]
    small = inference.filter(*_chains(3, 5), max_size=4)  # the limit decides
    assert small.method == "bk_filter" and small.info["predicted_size"] == 8


def test_particle_and_rbpf_dispatch_with_the_key_first(monkeypatch) -> None:
    calls: list = []
    _stub(monkeypatch, "inference.particle.dbn_adapter", "particle_filter_dbn", calls)
    _stub(monkeypatch, "inference.particle.rbpf", "rbpf_filter_dbn", calls)
    dbn, ev = _chains(2, 4)
    with pytest.raises(InputError, match="key"):
        inference.filter(dbn, ev, method="particle")
    inference.filter(
        dbn, ev, method="particle", key="K", num_particles=50, particle_method="auxiliary"
    )
    inference.filter(dbn, ev, method="rbpf", key="K", query=["x0"], num_particles=7)
    (a1, k1), (a2, k2) = calls
    assert a1[:2] == ("K", dbn) and _same_columns(a1[2], ev)
    assert k1 == {"num_particles": 50, "method": "auxiliary"}
    assert a2[:2] == ("K", dbn) and _same_columns(a2[2], ev) and a2[3] == ["x0"]
    assert k2 == {"num_particles": 7}


def test_the_engine_gets_the_checked_columns_not_the_callers(monkeypatch) -> None:
    """inference.filter reads the caller's columns once (check_columns) and hands the
    engine what it read: a column of state names arrives as indices (-1 = unobserved);
    the engines read the caller's columns a second time before."""
    calls: list = []
    _stub(monkeypatch, "inference.adf.boyen_koller", "bk_filter", calls)
    dbn, ev = _chains(2, 4)
    names = {v.name: v for v in dbn.variables}["y0"].state_names
    given = {"y0": [names[int(s)] for s in ev["y0"][:3]] + [None], "y1": ev["y1"]}
    inference.filter(dbn, given, method="bk")
    ((args, _),) = calls
    assert list(args[1]) == ["y0", "y1"]
    np.testing.assert_array_equal(args[1]["y0"], [*ev["y0"][:3], -1])
    assert args[1]["y0"].dtype == np.int64


def _same_columns(got, ev) -> bool:
    """The engine got the checked columns (inference.filter reads the caller's once): the
    same names in the same order, the same states."""
    return list(got) == list(ev) and all(np.array_equal(got[n], ev[n]) for n in ev)


def _switching_lg() -> TwoSliceDBN:
    x, y = ContinuousVariable("x", 1), ContinuousVariable("y", 1)
    return TwoSliceDBN(
        [x, y],
        [
            LinearGaussianCPD("x", [], [], [0.0], [[1.0]]),
            LinearGaussianCPD("y", ["x"], [[[1.0]]], [0.0], [[0.5]]),
        ],
        [
            LinearGaussianCPD("x", [prev("x")], [[[0.9]]], [0.0], [[0.1]]),
            LinearGaussianCPD("y", ["x"], [[[1.0]]], [0.0], [[0.5]]),
        ],
    )


def test_continuous_models_go_to_the_particle_filter_and_evidence_is_checked(monkeypatch) -> None:
    calls: list = []
    _stub(monkeypatch, "inference.particle.dbn_adapter", "particle_filter_dbn", calls)
    dbn = _switching_lg()
    ys = np.array([[0.1], [np.nan], [0.3]])
    res = inference.filter(dbn, {"y": ys}, key="K")
    assert res.method == "particle_filter_dbn" and "continuous" in res.info["auto"]
    with pytest.raises(NonFiniteError, match="slice 1"):
        inference.filter(dbn, {"y": np.array([[0.1], [np.inf], [0.2]])}, key="K")
    with pytest.raises(ShapeError, match=r"'y' must have shape \(num_timesteps, 1\)"):
        inference.filter(dbn, {"y": np.zeros((3, 2))}, key="K")
    # a 1-D column of a 1-D variable, as every engine reads it (it was refused here alone)
    inference.filter(dbn, {"y": np.zeros(3)}, key="K")
    with pytest.raises(ModelError, match="continuous"):
        inference.filter(dbn, {"y": ys}, method="exact")
    assert len(calls) == 2


def test_bad_input_raises_before_any_engine_runs(monkeypatch) -> None:
    calls: list = []
    _stub(monkeypatch, "inference.adf.boyen_koller", "bk_filter", calls)
    dbn, ev = _chains(2, 5)
    with pytest.raises(InputError, match="method"):
        inference.filter(dbn, ev, method="magic")
    with pytest.raises(EvidenceError, match="unknown variable 'z'"):
        inference.filter(dbn, {"z": np.zeros(5, int)}, method="bk")
    with pytest.raises(ShapeError, match="'y1' has length 4, expected 5"):
        inference.filter(dbn, {"y0": np.zeros(5, int), "y1": np.zeros(4, int)}, method="bk")
    with pytest.raises(InputError, match="num_particles"):
        inference.filter(dbn, ev, method="bk", num_particles=3)
    with pytest.raises(ModelError, match="TwoSliceDBN"):
        inference.filter(dbn.unroll(2), ev)
    with pytest.raises(InputError, match="soft"):
        inference.filter(dbn, ev, method="particle", key="K", soft_evidence={"y0": np.ones((5, 2))})
    assert calls == []


def test_online_filter_steps_equal_the_batch_run() -> None:
    dbn, ev = _chains(3, 6)
    res = inference.filter(dbn, ev, method="exact")
    flt = inference.online_filter(dbn)
    state = None
    for t in range(6):
        row = {n: int(c[t]) for n, c in ev.items()}
        state = flt.init(row) if state is None else flt.step(state, row)
    assert abs(state.log_likelihood - res.log_likelihood) < 1e-12
    np.testing.assert_allclose(flt.marginals(state)["x2"], res.marginals["x2"][-1], atol=1e-12)


def test_evidence_on_an_unknown_variable_is_one_error_everywhere() -> None:
    """Every engine's own entry point raises UnknownEvidenceError (an EvidenceError and an
    UnknownVariableError at once) for a column the DBN does not have."""
    from inference.adf.boyen_koller import bk_filter
    from inference.exact.dbn_filter import DBNFilter
    from inference.exact.structured_filter import StructuredFilter
    from inference.particle.dbn_adapter import particle_filter_dbn

    dbn, ev = _chains(2, 4)
    bad = {**ev, "zz": np.zeros(4, int)}
    calls = [
        lambda: DBNFilter(dbn).filter(bad),
        lambda: StructuredFilter(dbn).filter(bad),
        lambda: bk_filter(dbn, bad),
        lambda: particle_filter_dbn(jax.random.key(0), dbn, bad, num_particles=4),
        lambda: inference.filter(dbn, bad, method="exact"),
    ]
    for call in calls:
        with pytest.raises(UnknownEvidenceError, match="'zz'") as exc:
            call()
        assert isinstance(exc.value, EvidenceError) and isinstance(exc.value, UnknownVariableError)


_BAD_ARGUMENTS = [  # (method, arguments beyond the model and good evidence, error, needle)
    ("exact", {"evidence": {"y0": [[0], [1, 0]]}}, EvidenceError, "'y0' is not an array"),
    ("bk", {"evidence": {"y0": [[0], [1, 0]]}}, EvidenceError, "'y0' is not an array"),
    ("exact", {"soft_evidence": {"x0": [["a", "b"]] * 5}}, EvidenceError, "'x0' is not an array"),
    ("exact", {"evidence": None, "num_timesteps": "5"}, ShapeError, "num_timesteps"),
    ("exact", {"evidence": None, "num_timesteps": 2.5}, ShapeError, "num_timesteps"),
    ("exact", {"evidence": None, "num_timesteps": True}, ShapeError, "num_timesteps"),
    ("exact", {"evidence": None, "num_timesteps": 10**15}, MemoryLimitError, "10**15"),
    ("exact", {"max_size": "big"}, InputError, "max_size"),
    ("auto", {"max_size": 2.5}, InputError, "max_size"),
    ("bk", {"max_size": 100}, InputError, "do not apply to method 'bk'"),
    ("particle", {"key": 0, "num_particles": 10}, InputError, "key must be one jax PRNG key"),
    ("rbpf", {"key": np.zeros(3), "num_particles": 10}, InputError, "jax PRNG key"),
    ("particle", {"key": jax.random.key(0), "num_particles": 2.5}, InputError, "num_particles"),
    ("rbpf", {"key": jax.random.key(0), "num_particles": 10**13}, InputError, "2**31 - 1"),
]


@pytest.mark.parametrize(("method", "kwargs", "error", "needle"), _BAD_ARGUMENTS)
def test_bad_arguments_raise_the_library_error_naming_them(method, kwargs, error, needle) -> None:
    """Each of these reached numpy or jax (a raw ValueError, TypeError, MemoryError,
    OverflowError or jax's key error), or was taken silently (2.5 particles ran 2, True
    slices ran 1, max_size with method='bk' was ignored)."""
    dbn, ev = _chains(2, 5)
    kwargs = dict(kwargs)
    evidence = kwargs.pop("evidence", ev)
    if evidence is not None and evidence is not ev:
        evidence = {**ev, **evidence}
    needle = needle.replace("10**15", f"{10**15:,}")
    with pytest.raises(error, match=re.escape(needle)):
        inference.filter(dbn, evidence, method, **kwargs)


_ONE_VALUE = {"max_size": 2**20, "clusters": [["x0"], ["x1"]], "num_particles": 16,
              "particle_method": "auxiliary"}


@pytest.mark.parametrize("method", sorted(api.METHOD_OPTIONS))
def test_method_options_is_what_each_method_takes_and_is_read_only(method) -> None:
    """Every option :data:`inference.api.METHOD_OPTIONS` lists for a method (the table
    ``dbntrack track dbn`` checks a config file against) runs; the table cannot be changed
    by a caller (it held mutable sets)."""
    dbn, ev = _chains(2, 3)
    opts = {k: _ONE_VALUE[k] for k in api.METHOD_OPTIONS[method]}
    res = inference.filter(dbn, ev, method, key=jax.random.key(0), **opts)
    assert res.method == method and res.num_timesteps == 3
    with pytest.raises(AttributeError):
        api.METHOD_OPTIONS[method].add("bogus")  # type: ignore[attr-defined]
    with pytest.raises(TypeError):
        api.METHOD_OPTIONS[method] = frozenset()  # type: ignore[index]
    assert set(api.METHOD_OPTIONS) == set(api.METHODS) - {"auto"}


@pytest.mark.parametrize("method", ["bk", "particle"])
def test_num_timesteps_is_never_ignored(method) -> None:
    """``num_timesteps=9`` with 5 slices of evidence ran 5 slices under bk and particle
    (exact refused it), and without evidence they said "filtering needs num_timesteps >= 1"
    though it was given."""
    dbn, ev = _chains(2, 5)
    key = jax.random.key(0)
    with pytest.raises(ShapeError, match="'y0' has length 5, expected 9"):
        inference.filter(dbn, ev, method, key=key, num_timesteps=9)
    with pytest.raises(InputError, match=f"method '{method}' takes the number of slices"):
        inference.filter(dbn, None, method, key=key, num_timesteps=4)
    assert inference.filter(dbn, ev, method, key=key, num_timesteps=5).num_timesteps == 5
    assert inference.filter(dbn, None, "exact", num_timesteps=4).num_timesteps == 4


def test_one_query_name_is_one_variable_everywhere() -> None:
    """``query="x0"`` was split into the letters 'x', '0' by the exact engine, and read as
    one name by the others."""
    dbn, ev = _chains(2, 5)
    for method in ("exact", "bk"):
        assert list(inference.filter(dbn, ev, method, "x0").marginals) == ["x0"]
    assert inference.online_filter(dbn, "x0").query == ("x0",)
    with pytest.raises(EvidenceError, match="mapping"):
        inference.online_filter(dbn).init([0, 1])


def _failing(monkeypatch, module: str, fn: str, exc: BaseException) -> None:
    def engine(*args, **kwargs):
        raise exc

    mod = types.ModuleType(module)
    setattr(mod, fn, engine)
    monkeypatch.setitem(sys.modules, module, mod)


def test_running_out_of_memory_is_a_memory_limit_error(monkeypatch) -> None:
    """jax's RESOURCE_EXHAUSTED (a million-fold num_particles) was a raw JaxRuntimeError;
    now a MemoryLimitError saying what to shrink. Other engine errors pass unchanged."""
    dbn, ev = _chains(2, 4)
    oom = jax.errors.JaxRuntimeError("RESOURCE_EXHAUSTED: Out of memory allocating 8 bytes.")
    _failing(monkeypatch, "inference.particle.dbn_adapter", "particle_filter_dbn", oom)
    with pytest.raises(MemoryLimitError, match=r"fewer particles \(num_particles = 2,000,000\)"):
        inference.filter(dbn, ev, method="particle", key=jax.random.key(0), num_particles=2 * 10**6)
    _failing(monkeypatch, "inference.adf.boyen_koller", "bk_filter", MemoryError())
    with pytest.raises(MemoryLimitError, match="'bk' ran out of memory .*a shorter sequence"):
        inference.filter(dbn, ev, method="bk")
    other = RuntimeError("a bug")
    _failing(monkeypatch, "inference.particle.rbpf", "rbpf_filter_dbn", other)
    with pytest.raises(RuntimeError) as info:
        inference.filter(dbn, ev, method="rbpf", key=jax.random.key(0))
    assert info.value is other


def _bn_entries(pgmpy_taken: bool = True):
    """The Bayes-net entry points; without those that take a pgmpy model as it is
    (``ExactInference``, ``posterior_marginals``) unless ``pgmpy_taken``."""
    from inference.exact import (
        ExactInference,
        JunctionTree,
        log_evidence,
        map_assignment,
        posterior_marginals,
        variable_elimination,
    )
    from inference.exact.enumeration import brute_force_marginals

    taking = [ExactInference, posterior_marginals] if pgmpy_taken else []
    return [lambda m: variable_elimination(m, ["x"]), lambda m: log_evidence(m, {}),
            map_assignment, JunctionTree, *taking, brute_force_marginals]  # fmt: skip


def _dbn_entries():
    from inference.adf.boyen_koller import BoyenKoller, bk_filter
    from inference.exact.dbn_filter import DBNFilter
    from inference.exact.structured_filter import StructuredFilter
    from inference.particle.dbn_adapter import particle_filter_dbn
    from inference.particle.rbpf import rbpf_filter_dbn

    key = jax.random.key(0)
    return [StructuredFilter, DBNFilter, BoyenKoller, lambda m: bk_filter(m, {"y0": [0]}),
            lambda m: particle_filter_dbn(key, m, {"y0": [0]}),
            lambda m: rbpf_filter_dbn(key, m, {"y0": [0]})]  # fmt: skip


def test_every_engine_refuses_a_model_of_another_kind_by_name() -> None:
    """A pgmpy model, a Bayes net where a DBN is needed (or the reverse), or None gave
    Python's AttributeError ('DynamicBayesianNetwork' object has no attribute 'variables')
    in every engine but the structured filter; each now says what it needs, and for a
    pgmpy model how to convert it (``ExactInference`` and ``posterior_marginals`` now
    convert a pgmpy Bayes net themselves: tested in ``test_engine``)."""
    dbn = coupled_chains(2)
    bn = dbn.unroll(2)
    for entries, wrong, needs, convert in [
        (_bn_entries(), [dbn, None], "BayesNet", None),
        (_bn_entries(pgmpy_taken=False), [pa.to_pgmpy(bn)], "BayesNet", "from_pgmpy"),
        (_dbn_entries(), [bn, None], "TwoSliceDBN", None),
        (_dbn_entries(), [pa.dbn_to_pgmpy(dbn)], "TwoSliceDBN", "dbn_from_pgmpy"),
    ]:
        for entry in entries:
            for model in wrong:
                with pytest.raises(ModelError, match=f"needs a (dbn )?{needs}, got") as exc:
                    entry(model)
                text = str(exc.value)
                assert (convert in text) if convert else ("pgmpy" not in text)


def test_method_options_under_auto_before_and_after_the_choice() -> None:
    """``auto`` takes ``max_size`` and, before it chooses, any method's options (what
    ``dbntrack track dbn`` checks a config file against); after, those of the method it
    chose. A key no method takes is refused before the size estimate, naming the valid
    keys; one the chosen method does not take is refused naming that method."""
    every = set().union(*api.METHOD_OPTIONS.values())
    assert api.method_options("auto") == every | {"max_size"}
    assert api.method_options("auto", "bk") == {"max_size", "clusters"}
    for method in api.METHOD_OPTIONS:
        assert api.method_options(method) == api.METHOD_OPTIONS[method]
    for bad in (("nope",), ("bk", "exact"), ("auto", "auto"), ("auto", "nope")):
        with pytest.raises(InputError, match="auto|nope"):
            api.method_options(*bad)
    dbn, ev = _chains(2, 3)
    with pytest.raises(InputError, match=r"\['num_particle'\] do not apply to method 'auto'"
                       r".*'num_particles'"):  # fmt: skip
        inference.filter(dbn, ev, "auto", num_particle=10)
    with pytest.raises(InputError, match=r"\['num_particles'\] do not apply to method 'exact'"):
        inference.filter(dbn, ev, "auto", num_particles=10)  # two small chains: exact
    res = inference.filter(dbn, ev, "auto", max_size=1)  # bk: max_size is still taken
    assert res.method == "bk"


def test_the_package_lists_its_lazy_entry_points() -> None:
    """``inference.filter``, ``online_filter`` and ``method_options`` are importable from the
    package, listed by ``dir`` (tab completion) and ``__all__``; other names still raise."""
    star: dict = {}
    exec("from inference import *", star)  # noqa: S102  (a star import needs module level)
    assert star["filter"] is api.filter and star["method_options"] is api.method_options
    for name in ("filter", "online_filter", "method_options"):
        assert name in dir(inference) and getattr(inference, name) is getattr(api, name)
    with pytest.raises(AttributeError, match="no attribute 'filters'"):
        inference.filters  # noqa: B018


@pytest.mark.parametrize("method", ["exact", "bk", "particle", "rbpf"])
def test_a_query_that_is_no_name_nor_sequence_is_refused_naming_it(method) -> None:
    """``query=5`` raised Python's "'int' object is not iterable" from StructuredFilter and
    BoyenKoller; every engine now says what a query is."""
    from inference.adf.boyen_koller import BoyenKoller
    from inference.exact.structured_filter import StructuredFilter

    dbn, ev = _chains(2, 3)
    needle = "query must be a variable name or a sequence of names, got int 5"
    with pytest.raises(InputError, match=needle):
        inference.filter(dbn, ev, method, query=5, key=jax.random.key(0))
    for build in (lambda: StructuredFilter(dbn, 5), lambda: BoyenKoller(dbn, query=5)):
        with pytest.raises(InputError, match=needle):
            build()
    assert StructuredFilter(dbn, ["x0", "x0"]).query == ("x0",)  # repeated: once
