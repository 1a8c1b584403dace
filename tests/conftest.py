"""Shared fixtures: the real-data folder (skipping with a reason when absent)."""

from __future__ import annotations

import os

import pytest

os.environ.setdefault("JAX_PLATFORMS", "cpu")

from hypothesis import settings  # noqa: E402

from models import datasets  # noqa: E402

# CI draws the same examples every run (a failure there is reproducible, not luck);
# developers' runs keep exploring (hypothesis's default random draws): HYPOTHESIS_PROFILE=ci
settings.register_profile("ci", derandomize=True, print_blob=True)
if os.environ.get("HYPOTHESIS_PROFILE"):
    settings.load_profile(os.environ["HYPOTHESIS_PROFILE"])


@pytest.fixture(scope="session")
def shared_data():
    """The ``../shared/data`` folder (or ``$DBNTRACK_DATA``); skip the test when absent."""
    path = datasets.data_dir()
    if not path.is_dir():
        pytest.skip(f"real data folder {path} is absent (set DBNTRACK_DATA)")
    return path


# --- seeded random-model factories (used with hypothesis-drawn seeds) ----------------------
import numpy as np  # noqa: E402

from dbn.bayesnet import BayesNet  # noqa: E402
from dbn.cpds import TabularCPD  # noqa: E402
from dbn.dbn import TwoSliceDBN, prev  # noqa: E402
from dbn.variables import DiscreteVariable  # noqa: E402


def random_table(rng: np.random.Generator, shape: tuple[int, ...], zeros: bool = True) -> np.ndarray:
    """Random CPD table ``(*parent_cards, card)``; with ``zeros``, some entries are exactly 0."""
    alpha = rng.choice([0.3, 1.0, 5.0])
    rows = rng.dirichlet(np.full(shape[-1], alpha), size=int(np.prod(shape[:-1])))
    if zeros and shape[-1] > 1:
        mask = rng.random(rows.shape) < 0.15
        mask[np.arange(rows.shape[0]), rng.integers(shape[-1], size=rows.shape[0])] = False
        rows = np.where(mask, 0.0, rows)
        rows /= rows.sum(axis=1, keepdims=True)
    return rows.reshape(shape)


def random_bn(seed: int, max_nodes: int = 8, max_card: int = 4, max_parents: int = 3) -> BayesNet:
    """A random discrete Bayes net (random DAG, cardinalities, tables with some zeros)."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, max_nodes + 1))
    cards = rng.integers(1, max_card + 1, size=n)
    names = [f"v{i}" for i in range(n)]
    cpds = []
    for i in range(n):
        candidates = [j for j in range(i) if rng.random() < 0.5]
        parents = [names[j] for j in candidates[:max_parents]]
        shape = (*(int(cards[j]) for j in candidates[:max_parents]), int(cards[i]))
        cpds.append(TabularCPD(names[i], parents, random_table(rng, shape)))
    order = rng.permutation(n)
    return BayesNet(
        [DiscreteVariable(names[i], int(cards[i])) for i in order], [cpds[i] for i in rng.permutation(n)]
    )


def random_evidence(seed: int, bn: BayesNet, p_hard: float = 0.3, p_soft: float = 0.3):
    """Random hard evidence (a state of positive probability is not guaranteed) and soft
    evidence (positive likelihood vectors)."""
    rng = np.random.default_rng(seed)
    hard = {n: int(rng.integers(bn.cardinality(n))) for n in bn.nodes if rng.random() < p_hard}
    soft = {n: rng.random(bn.cardinality(n)) + 0.05 for n in bn.nodes if rng.random() < p_soft}
    return hard, soft


def random_dbn(seed: int, max_card: int = 3) -> TwoSliceDBN:
    """A random two-slice DBN: hidden a, b (b also in the interface when drawn), a
    non-interface hidden h and an observation o, with random intra/inter-slice edges."""
    rng = np.random.default_rng(seed)
    ka, kb, kh, ko = (int(k) for k in rng.integers(1, max_card + 1, size=4))
    ka = max(ka, 2)
    variables = [
        DiscreteVariable("a", ka),
        DiscreteVariable("b", kb),
        DiscreteVariable("h", kh),
        DiscreteVariable("o", ko),
    ]
    b_parents = ["a"] if rng.random() < 0.7 else []
    o_parents = ["a", "h"] if rng.random() < 0.5 else ["a"]
    a_prev = [prev("a")] + ([prev("b")] if rng.random() < 0.5 else [])
    cards = {"a": ka, "b": kb, "h": kh, "o": ko, prev("a"): ka, prev("b"): kb}

    def cpd(name, parents):
        return TabularCPD(name, parents, random_table(rng, (*(cards[p] for p in parents), cards[name])))

    initial = [cpd("a", []), cpd("b", b_parents), cpd("h", ["b"]), cpd("o", o_parents)]
    transition = [cpd("a", a_prev), cpd("b", b_parents), cpd("h", ["b"]), cpd("o", o_parents)]
    return TwoSliceDBN(variables, initial, transition)


@pytest.fixture(scope="session")
def factories():
    """The random-model factories of this file, for tests that draw seeds with hypothesis."""
    from types import SimpleNamespace

    return SimpleNamespace(
        random_table=random_table, random_bn=random_bn, random_evidence=random_evidence, random_dbn=random_dbn
    )


# --- jax precision (13c): no module switches jax to 64-bit at import any more ---------------
import jax  # noqa: E402


def pytest_configure(config):
    config.addinivalue_line(
        "markers", "x32: run the test with jax in its default 32-bit mode (no x64 fixture)"
    )


@pytest.fixture(autouse=True)
def _jax_x64(request):
    """Run every test inside ``jax.enable_x64(True)`` (a per-test, thread-local context).

    The library never switches jax to 64-bit globally; engines that promise float64 enter
    the mode themselves (``inference.precision``). Tests keep float64 arithmetic in their
    own oracle code through this fixture; tests marked ``x32`` run without it, which is
    how the engines' own choice of dtype is checked.
    """
    if request.node.get_closest_marker("x32") is not None:
        yield
        return
    with jax.enable_x64(True):
        yield
