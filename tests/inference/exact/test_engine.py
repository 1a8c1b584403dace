"""ExactInference (pruned VE / pruned junction tree): enumeration and pgmpy as oracles,
the compile cache, the memory guard and bad input."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dbn import pgmpy_adapter as pa
from dbn.bayesnet import BayesNet
from dbn.cpds import TabularCPD
from dbn.errors import EvidenceError, MemoryLimitError, UnknownVariableError
from dbn.variables import DiscreteVariable
from inference.exact.engine import ExactInference
from inference.exact.enumeration import brute_force_marginals, joint_factor

TOL = 1e-9


@settings(max_examples=80, deadline=None)
@given(
    seed=st.integers(0, 2**31 - 1),
    ev_seed=st.integers(0, 2**31 - 1),
    engine=st.sampled_from(["auto", "ve", "jt"]),
    subset=st.booleans(),
    big=st.booleans(),
)
def test_marginals_equal_enumeration(factories, seed, ev_seed, engine, subset, big) -> None:
    bn = factories.random_bn(seed, max_nodes=12, max_card=3) if big else factories.random_bn(seed)
    hard, _ = factories.random_evidence(ev_seed, bn, p_soft=0.0)
    rng = np.random.default_rng(ev_seed)
    hidden = [n for n in bn.nodes if n not in hard]
    nodes = [n for n in bn.nodes if rng.random() < 0.5] if subset else None
    inf = ExactInference(bn)
    if not np.isfinite(joint_factor(bn, hard).log_normalizer()):
        if nodes is None and hidden:  # all marginals: impossible evidence is always caught
            with pytest.raises(EvidenceError):
                inf.marginals(hard, engine=engine)
        return
    expected, _ = brute_force_marginals(bn, hard)
    got = inf.marginals(hard, nodes, engine=engine)
    assert got.engine in ("ve", "jt")
    assert set(got.marginals) == set(bn.nodes if nodes is None else nodes) - (
        set(hard) if nodes is None else set()
    )
    for n, m in got.marginals.items():
        if n in hard:
            assert m[hard[n]] == 1.0
        else:
            np.testing.assert_allclose(m, expected[n], atol=TOL, rtol=0)


def _chain_net(tables: dict[str, np.ndarray] | None = None) -> BayesNet:
    """a -> b -> c, all binary."""
    t = tables or {
        "a": np.array([0.3, 0.7]),
        "b": np.array([[0.9, 0.1], [0.2, 0.8]]),
        "c": np.array([[0.6, 0.4], [0.1, 0.9]]),
    }
    cpds = [TabularCPD("a", [], t["a"]), TabularCPD("b", ["a"], t["b"])]
    cpds.append(TabularCPD("c", ["b"], t["c"]))
    return BayesNet([DiscreteVariable(n, 2) for n in "abc"], cpds)


def test_cache_reused_for_new_values_and_invalidated_by_structure() -> None:
    bn = _chain_net()
    inf = ExactInference(bn)
    inf.marginals({"c": 0})
    assert inf.compiles == 1
    second = inf.marginals({"c": 1})  # same observed variable: no compile
    assert inf.compiles == 1 and not second.compiled
    expected, _ = brute_force_marginals(bn, {"c": 1})
    np.testing.assert_allclose(second.marginals["a"], expected["a"], atol=TOL)
    inf.marginals({"b": 0})  # another observed set: compiles
    assert inf.compiles == 2
    # same structure, other numbers: trees are kept and the new tables are used
    other = _chain_net(
        {
            "a": np.array([0.5, 0.5]),
            "b": np.array([[0.5, 0.5], [0.1, 0.9]]),
            "c": np.array([[0.2, 0.8], [0.7, 0.3]]),
        }
    )
    inf.bn = other
    got = inf.marginals({"c": 1})
    assert not got.compiled
    expected, _ = brute_force_marginals(other, {"c": 1})
    np.testing.assert_allclose(got.marginals["a"], expected["a"], atol=TOL)
    # another structure: the cache is emptied
    inf.bn = pa.bundled_network("asia")
    assert inf.cache_size == 0
    assert inf.marginals({"asia": "yes"}).compiled


def test_engines_both_available_and_choice_reported(monkeypatch) -> None:
    import inference.exact.engine as engine_module

    monkeypatch.setattr(engine_module, "_SMALL_TREE", 0)  # compare costs even on alarm
    bn = pa.bundled_network("alarm")
    inf = ExactInference(bn)
    chosen = inf.marginals({"HR": "HIGH", "SAO2": "LOW"})
    assert chosen.engine in ("ve", "jt")
    ev = {"HR": "HIGH", "SAO2": "LOW"}
    ve = inf.marginals(ev, engine="ve")
    jt = inf.marginals(ev, engine="jt")
    few = inf.marginals(ev, nodes=["LVFAILURE", "HYPOVOLEMIA"])  # a handful: VE
    assert (ve.engine, jt.engine, few.engine) == ("ve", "jt", "ve")
    for n, m in ve.marginals.items():
        np.testing.assert_allclose(m, jt.marginals[n], atol=TOL, rtol=0)
    for n, m in [*few.marginals.items(), *chosen.marginals.items()]:
        np.testing.assert_allclose(m, jt.marginals[n], atol=TOL, rtol=0)
    with pytest.raises(ValueError, match="engine"):
        inf.marginals(ev, engine="bp")


def test_memory_guard_names_the_clique() -> None:
    bn = pa.bundled_network("alarm")
    inf = ExactInference(bn, max_table_size=20)
    with pytest.raises(MemoryLimitError, match=r"clique \[.*\] would hold .* entries"):
        inf.marginals({"HR": "HIGH"}, engine="jt")
    with pytest.raises(MemoryLimitError):
        inf.marginals({"HR": "HIGH"})
    assert ExactInference(bn).marginals({"HR": "HIGH"}).max_table_size > 20


def test_bad_input_raises_clear_errors() -> None:
    bn = _chain_net()
    inf = ExactInference(bn)
    with pytest.raises(EvidenceError, match="unknown variable 'z'"):
        inf.marginals({"z": 0})
    with pytest.raises(EvidenceError):
        inf.marginals({"a": 5})
    asia = ExactInference(pa.bundled_network("asia"))
    with pytest.raises(EvidenceError, match="no state named"):
        asia.marginals({"asia": "maybe"})
    with pytest.raises(UnknownVariableError, match="nope"):
        inf.marginals({}, nodes=["nope"])
    det = _chain_net(
        {
            "a": np.array([1.0, 0.0]),
            "b": np.array([[1.0, 0.0], [0.0, 1.0]]),
            "c": np.array([[1.0, 0.0], [0.0, 1.0]]),
        }
    )
    for engine in ("ve", "jt", "auto"):
        with pytest.raises(EvidenceError, match="probability zero"):
            ExactInference(det).marginals({"c": 1}, engine=engine)
        with pytest.raises(EvidenceError, match="probability zero"):
            ExactInference(det).marginals({"a": 1}, engine=engine)


@pytest.mark.parametrize("name", ["alarm", "hepar2", "win95pts", "hailfinder"])
def test_medium_networks_equal_pgmpy(name: str) -> None:
    _compare_with_pgmpy(name, seed=12, max_queries=None)


@pytest.mark.slow
@pytest.mark.parametrize("name", pa.bundled_networks())
def test_every_bundled_network_equals_pgmpy(name: str) -> None:
    """Every BIF network pgmpy ships, two random evidence sets; pgmpy (slow on the large
    ones) checks a random sample of 40 queries of each."""
    for seed in (1, 2):
        _compare_with_pgmpy(name, seed=seed, max_queries=40)


def _compare_with_pgmpy(name: str, seed: int, max_queries: int | None) -> None:
    bn = pa.bundled_network(name)
    rng = np.random.default_rng(seed)
    observed = [str(n) for n in rng.choice(list(bn.nodes), size=3, replace=False)]
    x = bn.sample(rng, 1)  # evidence values from a sample: positive probability
    ev = {n: bn.variable(n).state_names[int(x[n][0])] for n in observed}
    ours = ExactInference(bn).marginals(ev)
    hidden = [n for n in bn.nodes if n not in ev]
    if max_queries is not None and len(hidden) > max_queries:
        hidden = [hidden[i] for i in rng.choice(len(hidden), max_queries, replace=False)]
    theirs = pa.pgmpy_marginals(pa.to_pgmpy(bn), hidden, ev)
    for n in hidden:
        np.testing.assert_allclose(ours.marginals[n], theirs[n], atol=TOL, rtol=0)


def test_posterior_marginals_keeps_one_engine_per_net() -> None:
    from inference.exact import posterior_marginals

    bn = _chain_net()
    first = posterior_marginals(bn, {"c": 0})
    again = posterior_marginals(bn, {"c": 1})
    assert first.compiled and not again.compiled
    expected, _ = brute_force_marginals(bn, {"c": 1})
    np.testing.assert_allclose(again.marginals["b"], expected["b"], atol=TOL)
    assert posterior_marginals(_chain_net(), {"c": 1}).compiled  # another net object


def test_a_pgmpy_network_is_taken_and_answers_as_its_conversion() -> None:
    """``ExactInference(pgmpy_model)`` (and ``posterior_marginals``) convert it, as
    ``inference.filter`` converts a pgmpy DBN; it was refused ("needs a dbn BayesNet").
    Oracle: the same query on the converted net, and pgmpy's own variable elimination."""
    from inference.exact import posterior_marginals

    bn = pa.bundled_network("asia")
    theirs = pa.to_pgmpy(bn)
    ev = {"smoke": "yes", "xray": "no"}
    ours = ExactInference(theirs).marginals(ev).marginals
    again = posterior_marginals(theirs, ev).marginals
    oracle = ExactInference(bn).marginals(ev).marginals
    pgmpy_ve = pa.pgmpy_marginals(theirs, ["lung", "bronc"], ev)
    for n in ("lung", "bronc"):
        np.testing.assert_allclose(ours[n], oracle[n], atol=1e-12)
        np.testing.assert_allclose(again[n], oracle[n], atol=1e-12)
        np.testing.assert_allclose(ours[n], pgmpy_ve[n], atol=TOL)


@pytest.mark.parametrize(("kwargs", "needle"), [
    ({"max_table_size": "x"}, "max_table_size must be an integer >= 1, got 'x'"),
    ({"max_table_size": 2.5}, "max_table_size must be an integer >= 1, got 2.5"),
    ({"max_table_size": 0}, "max_table_size must be an integer >= 1, got 0"),
    ({"max_table_size": -3}, "got -3"),
    ({"restarts": "a"}, "restarts must be an integer >= 0, got 'a'"),
    ({"restarts": -1}, "restarts must be an integer >= 0, got -1"),
    ({"restarts": True}, "got True"),
])  # fmt: skip
def test_bad_settings_are_refused_naming_them(kwargs, needle) -> None:
    """They raised int()'s ValueError ('x', 'a'), were truncated (2.5 ran as 2), or ran
    as something else (0 as the default limit, -3 refused every clique, -1 restarts)."""
    from dbn.errors import InputError

    with pytest.raises(InputError) as exc:
        ExactInference(_chain_net(), **kwargs)
    assert needle in str(exc.value)
    assert ExactInference(_chain_net(), restarts=0).restarts == 0


def test_one_node_by_name_and_bad_nodes_or_engine() -> None:
    """``nodes="lung"`` was read letter by letter ("query of unknown variable 'l'"),
    ``nodes=5`` raised Python's TypeError and ``engine="xx"`` a bare ValueError."""
    from dbn.errors import InputError

    inf = ExactInference(pa.bundled_network("asia"))
    one = inf.marginals({"smoke": "yes"}, "lung").marginals
    assert list(one) == ["lung"]
    np.testing.assert_allclose(one["lung"], inf.marginals({"smoke": "yes"}, ["lung"])
                               .marginals["lung"])  # fmt: skip
    with pytest.raises(InputError, match="nodes must be a variable name or a sequence"):
        inf.marginals({}, 5)
    with pytest.raises(InputError, match="engine must be one of"):
        inf.marginals({}, ["lung"], engine="xx")


def test_a_case_reads_as_a_dbn_slice_does() -> None:
    """A DataFrame row of cases (pandas Series; a gap makes the row's numbers floats and
    NaN) and None / -1 / NaN for unobserved read as in a DBN slice; they were refused
    ("state must be an int or a name, got 1.0"; a Series "must be a mapping"). Oracle:
    the same query with only the observed states, and brute-force enumeration."""
    import pandas as pd

    bn = _chain_net()
    rows = pd.DataFrame({"a": [1, None], "c": [0, 1]}, dtype="Int64").astype(float)
    inf = ExactInference(bn)
    for (_, row), seen in zip(rows.iterrows(), ({"a": 1, "c": 0}, {"c": 1}), strict=True):
        assert isinstance(row["c"], float)
        expected, _ = brute_force_marginals(bn, seen)
        got = inf.marginals(row, ["b"]).marginals["b"]
        np.testing.assert_allclose(got, expected["b"], atol=TOL)
    for unobserved in (None, -1, float("nan")):
        np.testing.assert_allclose(inf.marginals({"a": unobserved, "c": 0}, ["b"]).marginals["b"],
                                   inf.marginals({"c": 0}, ["b"]).marginals["b"])  # fmt: skip
    with pytest.raises(EvidenceError, match="got 0.5"):
        inf.marginals({"a": 0.5})
