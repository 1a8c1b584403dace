"""``models.io.dbn.write_two_slice_bif``: a DBN declared in Python (or built in pgmpy) as a
two-slice BIF file that ``read_two_slice_bif`` and ``dbntrack track dbn`` read back."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dbn.dbn import TwoSliceDBN
from dbn.errors import InputError, ModelError
from inference.exact.enumeration import brute_force_marginals
from models.cli import main
from models.io.dbn import read_marginals, read_two_slice_bif, write_two_slice_bif


def assert_same_dbn(back: TwoSliceDBN, dbn: TwoSliceDBN) -> None:
    """Both slices of every variable: parents, states and tables (variables sorted)."""
    assert back.names == tuple(sorted(dbn.names))
    for n in dbn.names:
        assert back.initial_net.variable(n).state_names == dbn.initial_net.variable(n).state_names
        for mine, theirs in ((dbn.initial_net, back.initial_net),
                             (dbn.transition_net, back.transition_net)):  # fmt: skip
            assert theirs.parents(n) == mine.parents(n)
            np.testing.assert_allclose(theirs.table(n), mine.table(n), rtol=1e-14, atol=0)


@settings(max_examples=3, deadline=None)  # pgmpy's BIF parser: ~1 s a file
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
    names = dbn.initial_net.variable("o").state_names
    evidence = tmp_path / "evidence.csv"
    evidence.write_text("o\n" + "".join(f"{names[r]}\n" for r in rows))
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
    evidence = tmp_path / "readings.csv"
    evidence.write_text(",".join(f"y{i}" for i in range(n)) + "\n"
                        + "".join(",".join(str(int(v)) for v in y) + "\n" for y in ys))  # fmt: skip
    out = tmp_path / "out"
    assert main(["track", "dbn", str(bif), str(evidence), "-o", str(out), "--quiet"]) == 0
    got = read_marginals(out / "marginals.csv")
    for t in range(T):
        seen = {f"y{i}_{s}": int(ys[s, i]) for i in range(n) for s in range(t + 1)}
        want = marginals(dbn.unroll(t + 1), seen)
        for i in range(n):
            np.testing.assert_allclose(got[f"x{i}"][1][t], want[f"x{i}_{t}"], atol=1e-12)
