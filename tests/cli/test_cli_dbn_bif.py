"""``models.io.dbn.write_two_slice_bif`` and ``write_evidence``: a DBN declared in Python (or
built in pgmpy) and its evidence as the files ``dbntrack track dbn`` reads back."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dbn.dbn import TwoSliceDBN
from dbn.errors import InputError, ModelError
from inference.exact.enumeration import brute_force_marginals
from models.cli import main
from models.io.dbn import (
    read_evidence,
    read_marginals,
    read_two_slice_bif,
    write_evidence,
    write_two_slice_bif,
)


def assert_same_dbn(back: TwoSliceDBN, dbn: TwoSliceDBN) -> None:
    """Both slices of every variable: parents, states and tables (variables sorted)."""
    assert back.names == tuple(sorted(dbn.names))
    for n in dbn.names:
        assert back.initial_net.variable(n).state_names == dbn.initial_net.variable(n).state_names
        for mine, theirs in ((dbn.initial_net, back.initial_net),
                             (dbn.transition_net, back.transition_net)):  # fmt: skip
            assert theirs.parents(n) == mine.parents(n)
            np.testing.assert_allclose(theirs.table(n), mine.table(n), rtol=1e-14, atol=0)


@settings(max_examples=2, deadline=None)  # pgmpy's BIF parser: ~1 s a file
@given(seed=st.integers(0, 2**31 - 1))
def test_a_random_dbn_reads_back(factories, tmp_path_factory, seed: int) -> None:
    dbn = factories.random_dbn(seed)
    path = write_two_slice_bif(tmp_path_factory.mktemp("bif") / "model.bif", dbn)
    assert_same_dbn(read_two_slice_bif(path), dbn)


def _filtered(dbn: TwoSliceDBN, observed: str, rows: list[int]) -> np.ndarray:
    """Oracle: ``P(a_t | o_0..o_t)`` by enumeration of the unrolled net, shape (T, K)."""
    out = []
    for t in range(len(rows)):
        bn = dbn.unroll(t + 1)
        marg, _ = brute_force_marginals(bn, {f"{observed}_{s}": rows[s] for s in range(t + 1)})
        out.append(marg[f"a_{t}"])
    return np.array(out)


def _possible_observations(dbn: TwoSliceDBN, num: int) -> list[int]:
    """A sequence of ``o`` of positive probability: each the likeliest given those before."""
    rows: list[int] = []
    for t in range(num):
        marg, _ = brute_force_marginals(dbn.unroll(t + 1), {f"o_{s}": rows[s] for s in range(t)})
        rows.append(int(np.argmax(marg[f"o_{t}"])))
    return rows


def test_a_pgmpy_dbn_runs_through_dbntrack_as_the_model_itself(factories, tmp_path) -> None:
    """A user's pgmpy DBN -> ``dbn_from_pgmpy`` -> BIF -> ``dbntrack track dbn``: the
    filtered marginals of the hidden chain are the original model's (enumeration)."""
    from dbn.pgmpy_adapter import dbn_from_pgmpy, dbn_to_pgmpy

    dbn = factories.random_dbn(11, max_card=2)
    user = dbn_from_pgmpy(dbn_to_pgmpy(dbn))
    bif = write_two_slice_bif(tmp_path / "model.bif", user)
    rows = _possible_observations(dbn, 3)
    evidence = write_evidence(tmp_path / "evidence.csv", user, {"o": np.array(rows)})
    out = tmp_path / "out"
    assert main(["track", "dbn", str(bif), str(evidence), "-o", str(out), "--quiet"]) == 0
    states, got = read_marginals(out / "marginals.csv")["a"]
    assert states == list(dbn.initial_net.variable("a").state_names)
    np.testing.assert_allclose(got, _filtered(dbn, "o", rows), atol=1e-12)


def test_what_bif_cannot_hold_is_refused_and_nothing_written(factories, tmp_path) -> None:
    from dbn.examples import switching_lds

    path = tmp_path / "m.bif"
    with pytest.raises(ModelError, match="variable 'x' is continuous"):
        write_two_slice_bif(path, switching_lds())
    with pytest.raises(ModelError, match="TwoSliceDBN"):
        write_two_slice_bif(path, factories.random_bn(0))
    with pytest.raises(InputError, match="cannot write the BIF file"):
        write_two_slice_bif(tmp_path / "no" / "such" / "m.bif", factories.random_dbn(0))
    assert not path.exists()


def test_ten_coupled_chains_run_exactly_where_the_dense_filter_refused(tmp_path) -> None:
    """``--method exact`` (the default) is the structured exact filter: ten coupled chains,
    whose dense slice table (2^30 entries) ``DBNFilter`` refuses, give the junction tree's
    filtered marginals of the unrolled net (SIMULATED readings)."""
    from dbn.errors import DBNError
    from dbn.examples import coupled_chains, sample_coupled_chains
    from inference.exact import marginals
    from inference.exact.dbn_filter import DBNFilter

    n, T = 10, 3
    dbn = coupled_chains(n)
    with pytest.raises(DBNError, match="1073741824 entries"):
        DBNFilter(dbn).init({})
    _, ys = sample_coupled_chains(np.random.default_rng(4), n, T)
    bif = write_two_slice_bif(tmp_path / "chains.bif", dbn)
    evidence = write_evidence(tmp_path / "readings.csv", dbn, {f"y{i}": ys[:, i] for i in range(n)})
    out = tmp_path / "out"
    assert main(["track", "dbn", str(bif), str(evidence), "-o", str(out), "--quiet"]) == 0
    got = read_marginals(out / "marginals.csv")
    for t in range(T):
        seen = {f"y{i}_{s}": int(ys[s, i]) for i in range(n) for s in range(t + 1)}
        want = marginals(dbn.unroll(t + 1), seen)
        for i in range(n):
            np.testing.assert_allclose(got[f"x{i}"][1][t], want[f"x{i}_{t}"], atol=1e-12)


def test_a_table_above_max_size_names_the_command_lines_remedies(capsys, tmp_path) -> None:
    """The size guard's message names Python calls; the CLI adds its own ways out, writes
    nothing, and ``--method auto`` under the same limit runs (Boyen-Koller)."""
    import json

    from dbn.examples import coupled_chains, sample_coupled_chains

    dbn = coupled_chains(4)
    _, ys = sample_coupled_chains(np.random.default_rng(1), 4, 3)
    bif = write_two_slice_bif(tmp_path / "chains.bif", dbn)
    evidence = write_evidence(tmp_path / "readings.csv", dbn, {f"y{i}": ys[:, i] for i in range(4)})
    config = tmp_path / "opts.json"
    config.write_text(json.dumps({"max_size": 4}))
    args = ["track", "dbn", str(bif), str(evidence), "--config", str(config), "--quiet"]
    assert main([*args, "-o", str(tmp_path / "exact")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "above the limit of 4 entries" in err, err
    assert "--method bk" in err and '"max_size" in the --config' in err, err
    assert not (tmp_path / "exact" / "marginals.csv").exists()
    assert main([*args, "--method", "auto", "-o", str(tmp_path / "auto")]) == 0
    assert read_marginals(tmp_path / "auto" / "marginals.csv")["x0"][1].shape == (3, 2)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), data=st.data())
def test_evidence_reads_back_slice_for_slice(factories, tmp_path_factory, seed: int, data) -> None:
    """Any columns (unobserved slices anywhere, the last ones included) come back."""
    dbn = factories.random_dbn(seed)
    T = data.draw(st.integers(1, 6))
    names = data.draw(st.lists(st.sampled_from(dbn.names), min_size=1, unique=True))
    cols = {}
    for n in names:
        k = dbn.initial_net.variable(n).cardinality
        cols[n] = np.array(data.draw(st.lists(st.integers(-1, k - 1), min_size=T, max_size=T)))
    path = write_evidence(tmp_path_factory.mktemp("ev") / "ev.csv", dbn, cols)
    back = read_evidence(path, dbn)
    assert set(back) == set(cols)
    for n in cols:
        np.testing.assert_array_equal(back[n], cols[n])


def _dbn_with_states(states: tuple[str, ...]) -> TwoSliceDBN:
    from dbn.cpds import TabularCPD
    from dbn.variables import DiscreteVariable

    k = len(states)
    flat = np.full(k, 1.0 / k)
    return TwoSliceDBN([DiscreteVariable("s", k, states)], [TabularCPD("s", [], flat)],
                       [TabularCPD("s", [], flat)])  # fmt: skip


def test_evidence_with_odd_state_names_reads_back(tmp_path) -> None:
    """A state beginning with ``#`` (a comment line if it came first), one with a comma or a
    quote (CSV quoting), names given as names and None as unobserved."""
    dbn = _dbn_with_states(("#1", 'a,"b"', "c d"))
    path = write_evidence(tmp_path / "ev.csv", dbn, {"s": ["#1", None, 'a,"b"', "c d", None]})
    np.testing.assert_array_equal(read_evidence(path, dbn)["s"], [0, -1, 1, 2, -1])


def test_evidence_the_csv_cannot_hold_is_refused_and_nothing_written(factories, tmp_path) -> None:
    from dbn.errors import DBNError
    from dbn.examples import switching_lds

    path = tmp_path / "ev.csv"
    with pytest.raises(ModelError, match="continuous"):
        write_evidence(path, switching_lds(), {"y": np.zeros((3, 1))})
    with pytest.raises(ModelError, match="would not read back"):
        write_evidence(path, _dbn_with_states(("a", " b")), {"s": [0, 1]})
    with pytest.raises(DBNError, match="nope"):
        write_evidence(path, factories.random_dbn(0), {"nope": [0]})
    with pytest.raises(DBNError):
        write_evidence(path, factories.random_dbn(0), {"a": [0, 7]})
    with pytest.raises(InputError, match="cannot write the evidence CSV"):
        write_evidence(tmp_path / "no" / "ev.csv", factories.random_dbn(0), {"a": [0]})
    assert not path.exists()
