"""Conversions to and from pgmpy (the one adapter module)."""

from __future__ import annotations

import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dbn import pgmpy_adapter as pa
from dbn.errors import EvidenceError, FileFormatError, InputError, ModelError


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**31 - 1))
def test_bn_round_trip_keeps_every_table(factories, seed: int) -> None:
    bn = factories.random_bn(seed)
    back = pa.from_pgmpy(pa.to_pgmpy(bn))
    assert set(back.nodes) == set(bn.nodes)
    for n in bn.nodes:
        assert back.parents(n) == bn.parents(n)
        np.testing.assert_array_equal(back.table(n), bn.table(n))
        assert back.variable(n).state_names == bn.variable(n).state_names


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 2**31 - 1))
def test_dbn_round_trip_keeps_both_slices(factories, seed: int) -> None:
    dbn = factories.random_dbn(seed)
    back = pa.dbn_from_pgmpy(pa.dbn_to_pgmpy(dbn))
    # the model's node order, not pgmpy's CPD order (which follows string hashing)
    assert [v.name for v in back.variables] == list(dbn.names)
    assert set(back.interface) == set(dbn.interface)
    for n in dbn.names:
        for mine, theirs in [(dbn.initial_net, back.initial_net), (dbn.transition_net, back.transition_net)]:
            assert set(theirs.parents(n)) == set(mine.parents(n))
            order = [theirs.parents(n).index(p) for p in mine.parents(n)]
            np.testing.assert_allclose(
                np.moveaxis(theirs.table(n), order + [len(order)], list(range(len(order) + 1))),
                mine.table(n),
                atol=1e-15,
            )


def test_dbn_from_pgmpy_keeps_the_node_order() -> None:
    """pgmpy's DBN keeps its CPDs in an order that follows string hashing (it changed with
    PYTHONHASHSEED); the declaration follows the order the nodes were added instead."""
    from dbn.examples import coupled_chains

    model = pa.dbn_to_pgmpy(coupled_chains(4))
    back = pa.dbn_from_pgmpy(model)
    assert [v.name for v in back.variables] == ["x0", "y0", "x1", "y1", "x2", "y2", "x3", "y3"]
    assert list(back.interface) == ["x0", "x1", "x2", "x3"]


def test_example_networks_read_offline() -> None:
    bn = pa.example_network("asia")
    assert len(bn) == 8 and bn.is_discrete
    sachs = pa.example_network("sachs")  # rows rounded in the file: renormalised
    for n in sachs.nodes:
        np.testing.assert_allclose(sachs.table(n).sum(-1), 1.0, atol=1e-12)


def test_read_bif_gz(tmp_path) -> None:
    from importlib import resources

    ref = resources.files("pgmpy") / "utils" / "example_models" / "cancer.bif.gz"
    if not ref.is_file():
        pytest.skip("pgmpy does not bundle cancer.bif.gz here")
    with resources.as_file(ref) as path:
        bn = pa.read_bif(path)
    assert set(bn.nodes) == {"Pollution", "Smoker", "Cancer", "Xray", "Dyspnoea"}
    assert bn.parents("Cancer") == ("Pollution", "Smoker") or set(bn.parents("Cancer")) == {"Pollution", "Smoker"}


def _asia():
    return pa.to_pgmpy(pa.bundled_network("asia"))


def _half_declared():
    """A pgmpy Bayes net a -> b with a CPD for a only."""
    from pgmpy.factors.discrete import TabularCPD as PgmpyCPD
    from pgmpy.models import DiscreteBayesianNetwork

    model = DiscreteBayesianNetwork([("a", "b")])
    model.add_cpds(PgmpyCPD("a", 2, [[0.5], [0.5]]))
    return model


@pytest.mark.parametrize(
    ("call", "error", "needle"),
    [
        (lambda: pa.from_pgmpy(_half_declared()), ModelError, "no CPD for node(s) ['b']"),
        (lambda: pa.from_pgmpy(None), ModelError, "expected a pgmpy DiscreteBayesianNetwork"),
        (lambda: pa.dbn_from_pgmpy("x"), ModelError, "expected a pgmpy DynamicBayesianNetwork"),
        (lambda: pa.to_pgmpy(None), ModelError, "to_pgmpy needs a dbn BayesNet, got NoneType"),
        (lambda: pa.dbn_to_pgmpy(None), ModelError, "dbn_to_pgmpy needs a TwoSliceDBN, got NoneType"),
        (lambda: pa.parse_bif(None), InputError, "text of a BIF file"),
        (lambda: pa.parse_bif("network x {}", renormalize_tol=-1), ModelError, "renormalize_tol"),
        (lambda: pa.read_bif(None), InputError, "path must be a file name"),
        (lambda: pa.pgmpy_marginals(_asia(), ["asia"], {"nosuch": "yes"}), EvidenceError,
         "no node 'nosuch'"),
        (lambda: pa.pgmpy_map(_asia(), {"asia": "maybe"}), EvidenceError, "no state 'maybe'"),
    ],
)
def test_bad_arguments_are_library_errors(call, error, needle) -> None:
    """A node without a CPD was dropped silently; the rest raised AttributeError,
    TypeError, networkx's or numpy's errors, or (a negative tolerance) were accepted."""
    with pytest.raises(error, match=re.escape(needle)):
        call()


def test_a_subclass_of_a_pgmpy_model_is_taken() -> None:
    """Your own subclass of pgmpy's Bayes net was refused ('expected a pgmpy
    DiscreteBayesianNetwork, got MyNet'); a class of that name outside pgmpy still is."""
    from pgmpy.factors.discrete import TabularCPD as PgmpyCPD
    from pgmpy.models import DiscreteBayesianNetwork

    class MyNet(DiscreteBayesianNetwork):
        pass

    model = MyNet([("a", "b")])
    model.add_cpds(PgmpyCPD("a", 2, [[0.3], [0.7]]),
                   PgmpyCPD("b", 2, [[0.9, 0.2], [0.1, 0.8]], evidence=["a"], evidence_card=[2]))
    bn = pa.from_pgmpy(model)
    assert bn.parents("b") == ("a",)
    assert pa.pgmpy_marginals(model, ["b"], {})["b"] == pytest.approx([0.3 * 0.9 + 0.7 * 0.2,
                                                                         0.3 * 0.1 + 0.7 * 0.8])

    class DiscreteBayesianNetwork:  # noqa: F811 - a look-alike that is not pgmpy's
        pass

    with pytest.raises(ModelError, match="expected a pgmpy DiscreteBayesianNetwork"):
        pa.from_pgmpy(DiscreteBayesianNetwork())


def _weather_dbn(slice1_rain=("dry", "wet"), parent_rain=("dry", "wet")):
    """A pgmpy DBN Rain -> Rain' with named states; the slice-1 CPD may list Rain's states
    (as its child, and for its parent Rain at slice 0) in other orders."""
    from pgmpy.factors.discrete import TabularCPD as PgmpyCPD
    from pgmpy.models import DynamicBayesianNetwork

    model = DynamicBayesianNetwork([(("Rain", 0), ("Rain", 1))])
    model.add_cpds(
        PgmpyCPD(("Rain", 0), 2, [[0.9], [0.1]], state_names={("Rain", 0): ["dry", "wet"]}),
        PgmpyCPD(("Rain", 1), 2, [[0.8, 0.3], [0.2, 0.7]], evidence=[("Rain", 0)],
                 evidence_card=[2],
                 state_names={("Rain", 1): list(slice1_rain), ("Rain", 0): list(parent_rain)}),
    )
    return model


def test_states_listed_in_another_order_are_refused() -> None:
    """A CPD that lists a variable's states in another order than the variable's own CPD
    was read as if they were in that order: its probabilities silently meant others
    (pgmpy's own check_model refuses the Bayes-net case; its DBN check does not)."""
    from pgmpy.factors.discrete import TabularCPD as PgmpyCPD
    from pgmpy.models import DiscreteBayesianNetwork

    model = DiscreteBayesianNetwork([("a", "b")])
    model.add_cpds(PgmpyCPD("a", 2, [[0.3], [0.7]], state_names={"a": ["x", "y"]}),
                   PgmpyCPD("b", 2, [[0.9, 0.2], [0.1, 0.8]], evidence=["a"], evidence_card=[2],
                            state_names={"b": ["u", "v"], "a": ["y", "x"]}))
    with pytest.raises(ModelError, match=r"the CPD of b lists the states of a as \['y', 'x'\]"):
        pa.from_pgmpy(model)
    tdbn = pa.dbn_from_pgmpy(_weather_dbn())  # one order: taken
    assert tdbn.variables[0].state_names == ("dry", "wet")
    for kwargs in ({"slice1_rain": ("wet", "dry")}, {"parent_rain": ("wet", "dry")}):
        needle = r"lists the states of \('Rain', [01]\) as \['wet', 'dry'\]"
        with pytest.raises(ModelError, match=needle):
            pa.dbn_from_pgmpy(_weather_dbn(**kwargs))


_BIF_HEAD = """network t { }
variable A { type discrete [ 2 ] { a0, a1 }; }
variable C { type discrete [ 2 ] { c0, c1 }; }
probability ( A ) { table 0.3, 0.7; }
"""


@pytest.mark.parametrize(
    ("block", "needle"),
    [
        # the last of two rows silently won
        ("( C | A ) { (a0) 0.2, 0.8; (a1) 0.5, 0.5; (a0) 0.4, 0.6; }",
         "row ('a0',) is given twice"),
        ("( C | A ) { (a0) 0.2, 0.8; table 0.2, 0.5, 0.8, 0.5; }", "a table besides other rows"),
        # a missing row was a row of zeros, refused as not summing to 1
        ("( C | A ) { (a1) 0.5, 0.5; }", "no row for parents ('a0',)"),
        ("( C ) { }", "no table"),
    ],
)
def test_a_bif_probability_block_gives_each_row_once(block: str, needle: str) -> None:
    message = re.escape(f"<BIF text>:5: probability of 'C': {needle}")
    with pytest.raises(FileFormatError, match=message):
        pa.parse_bif(_BIF_HEAD + f"probability {block}\n")
    ok = pa.parse_bif(_BIF_HEAD + "probability ( C | A ) { (a1) 0.5, 0.5; (a0) 0.2, 0.8; }\n")
    assert ok.table("C").tolist() == [[0.2, 0.8], [0.5, 0.5]]  # rows in any order, by name
