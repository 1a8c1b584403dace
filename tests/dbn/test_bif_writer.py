"""``dbn.bif_writer.format_bif``: a discrete Bayes net as BIF text, read back by this
library's parser and by pgmpy's (the oracle)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dbn.bayesnet import BayesNet
from dbn.bif_writer import format_bif
from dbn.cpds import DeterministicCPD, TabularCPD
from dbn.errors import FileFormatError, InputError, ModelError
from dbn.pgmpy_adapter import bundled_network, parse_bif, read_bif
from dbn.variables import ContinuousVariable, DiscreteVariable

# state names beyond identifiers, as BIF holds them (pgmpy's "child" network has "<7.5")
_STATE = st.text(st.sampled_from("ab9_.-<>=%+*/ é"), min_size=1, max_size=6).filter(
    lambda s: s == s.strip() and "//" not in s and "/*" not in s)


def assert_same_net(back: BayesNet, bn: BayesNet) -> None:
    """``back`` is ``bn`` with its nodes sorted: parents, states and tables (to rounding of
    the reader's renormalisation, at most a last bit)."""
    assert back.nodes == tuple(sorted(bn.nodes))
    for n in bn.nodes:
        assert back.parents(n) == bn.parents(n)
        assert back.variable(n).state_names == bn.variable(n).state_names
        np.testing.assert_allclose(back.table(n), bn.table(n), rtol=1e-14, atol=0)


def _named_net(factories, seed: int, data) -> BayesNet:
    """A random net of the shared factory with state names drawn from :data:`_STATE`."""
    bn = factories.random_bn(seed, max_nodes=5, max_card=3)
    variables = []
    for n in bn.nodes:
        k = bn.cardinality(n)
        names = data.draw(st.lists(_STATE, min_size=k, max_size=k, unique=True))
        names = [n.replace(" ", "") for n in names] if k == 1 else names  # refused: below
        variables.append(DiscreteVariable(n, k, tuple(names)))
    cpds = [TabularCPD(n, bn.parents(n), bn.table(n)) for n in bn.nodes]
    return BayesNet(variables, cpds)


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), data=st.data())
def test_the_text_reads_back_as_the_net(factories, seed: int, data) -> None:
    bn = _named_net(factories, seed, data)
    assert_same_net(parse_bif(format_bif(bn)), bn)


@settings(max_examples=2, deadline=None)  # pgmpy parses ~1 s a net
@given(seed=st.integers(0, 2**31 - 1), data=st.data())
def test_pgmpy_reads_the_same_net(factories, tmp_path_factory, seed: int, data) -> None:
    bn = _named_net(factories, seed, data)
    path = tmp_path_factory.mktemp("bif") / "net.bif"
    path.write_text(format_bif(bn), encoding="utf-8")
    assert_same_net(read_bif(path), bn)


def test_a_bundled_network_with_odd_states_round_trips() -> None:
    """pgmpy's "child" net has states such as "<7.5"; its 20 nodes and tables come back."""
    bn = bundled_network("child")
    assert "<7.5" in bn.variable("CO2Report").state_names
    assert_same_net(parse_bif(format_bif(bn)), bn)


def test_probabilities_keep_every_bit_and_deterministic_cpds_are_tables() -> None:
    third = 1.0 / 3.0
    bn = BayesNet(
        [DiscreteVariable("A", 3, ("x", "y", "z")), DiscreteVariable("B", 2, ("u", "v"))],
        [TabularCPD("A", [], [third, third, 1.0 - 2 * third]),
         DeterministicCPD("B", ["A"], lambda a: (a == 2).astype(int))],
    )  # fmt: skip
    text = format_bif(bn)
    assert repr(third) in text and "(z) 0.0, 1.0 ;" in text
    back = parse_bif(text)
    np.testing.assert_array_equal(back.table("A"), bn.table("A"))
    np.testing.assert_array_equal(back.table("B"), [[1, 0], [1, 0], [0, 1]])


def _one(state: str = "ok", variable: str = "A") -> BayesNet:
    return BayesNet([DiscreteVariable(variable, 2, ("s0", state))],
                    [TabularCPD(variable, [], [0.5, 0.5])])  # fmt: skip


@pytest.mark.parametrize("state", ["a,b", "x;y", "(x)", "a|b", "{a}", "a//b", "a/*b", " a", "a\tb",
                                   "my variable", "default"])  # fmt: skip
def test_a_state_bif_cannot_hold_is_refused_by_name(state: str) -> None:
    with pytest.raises(ModelError, match=r"state 1 of 'A' is .*rename it"):
        format_bif(_one(state))


def test_a_lone_state_with_whitespace_is_refused_where_pgmpy_misreads_it(tmp_path) -> None:
    """pgmpy's reader splits ``{ no rain }`` in two states (no comma), but reads ``no rain``
    beside another state: the first is refused, the second written and read back."""
    lone = BayesNet([DiscreteVariable("A", 1, ("no rain",))], [TabularCPD("A", [], [1.0])])
    path = tmp_path / "lone.bif"
    path.write_text("variable A {\n type discrete [ 1 ] { no rain };\n}\n"
                    "probability ( A ) {\n table 1.0 ;\n}\n")  # fmt: skip
    with pytest.raises(FileFormatError, match="'A': its only state 'no rain' holds whitespace"):
        read_bif(path)  # pgmpy's own error was "cannot reshape array of size 1 ..."
    assert parse_bif(path.read_text()).variable("A").state_names == ("no rain",)
    with pytest.raises(ModelError, match="only state"):
        format_bif(lone)
    two = _one("no rain")
    path.write_text(format_bif(two))
    assert_same_net(read_bif(path), two)


@pytest.mark.parametrize("variable", ["rain fall", "x/y", "p(a)", "variable", "default.x", "é"])
def test_a_variable_name_bif_cannot_hold_is_refused(variable: str) -> None:
    if variable == "é":  # a letter: held
        assert parse_bif(format_bif(_one(variable=variable))).nodes == ("é",)
        return
    with pytest.raises(ModelError, match=r"a variable name is .*rename it"):
        format_bif(_one(variable=variable))


@pytest.mark.parametrize(("state", "variable"), [("variable", "A"), ("s1", "default.x")])
def test_the_keywords_refused_do_break_the_readers(tmp_path, state: str, variable: str) -> None:
    """Why a keyword as a word is refused: written anyway, pgmpy's reader fails (and this
    library's on ``variable``)."""
    text = f"variable {variable} {{\n type discrete [ 2 ] {{ s0, {state} }};\n}}\n" \
           f"probability ( {variable} ) {{\n table 0.5, 0.5 ;\n}}\n"
    path = tmp_path / "net.bif"
    path.write_text(text)
    with pytest.raises(FileFormatError):
        read_bif(path)
    if state == "variable":
        with pytest.raises(FileFormatError):
            parse_bif(text)
    with pytest.raises(ModelError, match="keyword"):
        format_bif(_one(state, variable.replace("default.x", "A")) if state == "variable"
                   else _one(variable=variable))


def test_not_a_discrete_net_or_bad_name_is_refused() -> None:
    with pytest.raises(ModelError, match="discrete"):
        format_bif(BayesNet([ContinuousVariable("x", 1)], [_gaussian("x")]))
    with pytest.raises(ModelError, match="BayesNet"):
        format_bif("net")
    with pytest.raises(InputError, match="name must be a str"):
        format_bif(_one(), name=3)
    with pytest.raises(ModelError, match="network name"):
        format_bif(_one(), name="my net")


def _gaussian(name: str):
    from dbn.cpds import LinearGaussianCPD

    return LinearGaussianCPD(name, [], [], np.zeros(1), np.eye(1))
