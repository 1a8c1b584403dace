"""The one module that touches pgmpy: conversions, BIF reading, and pgmpy's own engines
(wrapped so that tests and benchmarks can compare against them without importing pgmpy).

Table layout: pgmpy stores ``P(child | parents)`` as ``(card, prod(parent_cards))`` with the
first parent varying slowest; this library stores ``(*parent_cards, card)``. A pgmpy
:class:`~pgmpy.models.DynamicBayesianNetwork` names nodes ``(name, 0)`` / ``(name, 1)``;
here slice-1 parents in the previous slice are written ``prev(name)``.

pgmpy 1.1.2 marks ``get_example_model`` deprecated (removed in 1.3.0; its replacement
downloads from a hub and fails offline). :func:`example_network` reads the BIF files
bundled with pgmpy directly instead, offline; the project pins ``pgmpy<1.3`` until that
is checked against the next release.
"""

from __future__ import annotations

import gzip
import re
import warnings
import zlib
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from dbn.bayesnet import BayesNet, check_discrete_net
from dbn.checks import check_nonnegative, instance_of
from dbn.cpds import ROW_TOLERANCE, TabularCPD
from dbn.dbn import TwoSliceDBN, check_two_slice, is_prev, prev, unprev
from dbn.errors import DBNError, EvidenceError, FileFormatError, InputError, ModelError
from dbn.variables import DiscreteVariable

__all__ = [
    "EXAMPLE_NETWORKS",
    "to_pgmpy",
    "from_pgmpy",
    "dbn_to_pgmpy",
    "dbn_from_pgmpy",
    "read_bif",
    "read_bif_text",
    "parse_bif",
    "example_network",
    "pgmpy_marginals",
    "pgmpy_map",
    "pgmpy_dbn_forward",
]

EXAMPLE_NETWORKS = (
    "asia",
    "cancer",
    "earthquake",
    "sachs",
    "survey",
    "alarm",
    "child",
    "insurance",
)
"""Discrete example networks bundled with pgmpy that the tests and benchmarks use."""


@contextmanager
def _quiet() -> Iterator[None]:
    """Silence pgmpy's deprecation and future warnings inside the adapter, and the one its
    import of ``tqdm.auto`` gives in a notebook without ``ipywidgets`` ("IProgress not
    found": the adapter shows none of pgmpy's bars)."""
    with warnings.catch_warnings():
        for category in (DeprecationWarning, FutureWarning, UserWarning):
            warnings.simplefilter("ignore", category)
        warnings.filterwarnings("ignore", message="IProgress not found")
        yield


def _pgmpy_cpd(
    name: Any, parents: Sequence[Any], table: np.ndarray, names: dict[Any, tuple[str, ...]]
):
    from pgmpy.factors.discrete import TabularCPD as PgmpyCPD

    card = table.shape[-1]
    values = table.reshape(-1, card).T
    return PgmpyCPD(
        variable=name,
        variable_card=card,
        values=values,
        evidence=list(parents) or None,
        evidence_card=list(table.shape[:-1]) or None,
        state_names={n: list(names[n]) for n in [name, *parents]},
    )


def to_pgmpy(bn: BayesNet):
    """A ``pgmpy.models.DiscreteBayesianNetwork`` equal to a discrete :class:`BayesNet`
    (deterministic CPDs become 0/1 tables; state names carried over)."""
    with _quiet():
        from pgmpy.models import DiscreteBayesianNetwork

    check_discrete_net(bn, "to_pgmpy")
    names = {n: bn.variable(n).state_names for n in bn.nodes}
    model = DiscreteBayesianNetwork()
    model.add_nodes_from(bn.nodes)
    model.add_edges_from((p, n) for n in bn.nodes for p in bn.parents(n))
    model.add_cpds(*(_pgmpy_cpd(n, bn.parents(n), bn.table(n), names) for n in bn.nodes))
    with _quiet():
        model.check_model()
    return model


def _cpd_table(cpd) -> tuple[Any, list[Any], np.ndarray, list[str]]:
    """(child, parents, table (*parent_cards, card), child state names) of a pgmpy CPD."""
    child = cpd.variable
    parents = list(cpd.variables[1:])
    cards = [int(k) for k in cpd.cardinality]
    values = np.asarray(cpd.get_values(), dtype=np.float64)  # (card, prod parent cards)
    table = values.T.reshape(*cards[1:], cards[0])
    return child, parents, table, list(_own_states(cpd))


def _own_states(cpd) -> tuple[str, ...]:
    """The state names of a pgmpy CPD's own variable (its index where pgmpy has none)."""
    card = int(cpd.cardinality[0])
    return tuple(str(s) for s in cpd.state_names.get(cpd.variable, range(card)))


def _check_state_order(cpd, node: Any, states: tuple[str, ...], whose: str) -> None:
    """A :class:`ModelError` unless the pgmpy ``cpd`` lists the states of ``node`` (its
    child or a parent) as ``states``, ``whose`` own (pgmpy's ``check_model`` rule for
    parents): a table read in another order would silently mean other probabilities."""
    mine = tuple(str(s) for s in cpd.state_names.get(node, ()))
    if mine != states:
        raise ModelError(f"pgmpy model: the CPD of {cpd.variable} lists the states of {node} "
                         f"as {list(mine)}, but {whose} are {list(states)}; use one order")


def _check_pgmpy(model: Any, kind: str) -> None:
    """A :class:`ModelError` unless ``model`` is an instance of pgmpy's class ``kind`` or of
    a subclass (yours included), told by the class's name and module so that pgmpy is not
    imported here."""
    if not instance_of(model, "pgmpy", kind):
        raise ModelError(f"expected a pgmpy {kind}, got {type(model).__name__}")


def _renormalized(name: Any, table: np.ndarray, tol: float) -> np.ndarray:
    """Rows within ``tol`` of summing to 1 divided by their sum (files print ~8 digits)."""
    sums = table.sum(axis=-1, keepdims=True)
    if np.all(np.abs(sums - 1.0) <= ROW_TOLERANCE):
        return table  # already valid: keep every bit
    if tol > 0 and np.all(np.abs(sums - 1.0) <= tol) and np.all(sums > 0):
        return table / sums
    return table  # let TabularCPD report the offending row


def from_pgmpy(model, renormalize_tol: float = 1e-6) -> BayesNet:
    """A :class:`BayesNet` from a pgmpy ``DiscreteBayesianNetwork`` (node names as str).

    Parameters
    ----------
    renormalize_tol : float
        Tables whose rows all sum to 1 within this tolerance are divided by their row sums
        (published BIF files round to a few digits: sachs has rows summing to 0.99999998);
        a row further off raises :class:`~dbn.errors.NotNormalizedError`. 0 disables it.

    Raises
    ------
    ModelError
        Not a pgmpy Bayes net; a node without a CPD (it used to be dropped silently); a
        CPD that lists a parent's states in another order than the parent's own CPD
        (pgmpy's ``check_model`` refuses it too; it used to be read as if in one order).
    """
    _check_pgmpy(model, "DiscreteBayesianNetwork")
    renormalize_tol = check_nonnegative("renormalize_tol", renormalize_tol, ModelError)
    have = {cpd.variable for cpd in model.get_cpds()}
    missing = [n for n in model.nodes() if n not in have]
    if missing:
        raise ModelError(
            f"pgmpy model: no CPD for node(s) {missing}; add them (model.add_cpds) first"
        )
    own = {cpd.variable: _own_states(cpd) for cpd in model.get_cpds()}
    variables, cpds = [], []
    for cpd in model.get_cpds():
        child, parents, table, states = _cpd_table(cpd)
        for p in parents:
            if p in own:  # an unknown parent is BayesNet's error
                _check_state_order(cpd, p, own[p], "its own CPD's")
        table = _renormalized(child, table, renormalize_tol)
        variables.append(DiscreteVariable(str(child), table.shape[-1], tuple(states)))
        cpds.append(TabularCPD(str(child), [str(p) for p in parents], table))
    return BayesNet(variables, cpds)


def read_bif_text(path: str | Path) -> str:
    """The text of a BIF file (``.gz`` decompressed); an unreadable, missing or non-UTF-8
    file is a :class:`~dbn.errors.FileFormatError` naming it."""
    path = Path(path)
    opener = gzip.open if path.suffix == ".gz" else open
    try:
        with opener(path, "rt", encoding="utf-8") as f:
            return f.read()
    except FileNotFoundError:
        raise FileFormatError(path, "no such BIF file") from None
    except (OSError, EOFError, UnicodeDecodeError, zlib.error) as exc:
        raise FileFormatError(path, f"unreadable BIF file ({exc})") from None


def read_bif(path: str | Path) -> BayesNet:
    """Read a BIF file (optionally ``.gz``) through pgmpy's ``BIFReader``.

    The text is first checked by :func:`parse_bif` (whose errors name the file and the
    line), so that pgmpy never sees a truncated or inconsistent file, nor a variable whose
    only state holds whitespace (pgmpy splits it in two); anything pgmpy still rejects
    becomes a :class:`~dbn.errors.FileFormatError`.
    """
    with _quiet():
        from pgmpy.readwrite import BIFReader

    if not isinstance(path, str | Path):
        raise InputError(f"path must be a file name, got {path!r}")
    text = read_bif_text(path)
    _check_lone_states(parse_bif(text, source=str(path)), path)
    try:
        with _quiet():
            model = BIFReader(string=text).get_model()
    except Exception as exc:  # pgmpy's parser raises anything on a malformed file
        msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise FileFormatError(path, f"pgmpy cannot read it ({msg})") from None
    try:
        return from_pgmpy(model)
    except DBNError as exc:
        raise type(exc)(f"{path}: {exc}") from None


def _check_lone_states(bn: BayesNet, path) -> None:
    """A :class:`~dbn.errors.FileFormatError` for a variable whose only state holds
    whitespace: pgmpy's reader splits ``{ no rain }`` in two states and then fails on the
    table (it said "cannot reshape array of size 1")."""
    from dbn.bif_writer import pgmpy_splits_lone_state

    for n in bn.nodes:
        states = bn.variable(n).state_names
        if len(states) == 1 and pgmpy_splits_lone_state(states[0]):
            raise FileFormatError(path, f"variable {n!r}: its only state {states[0]!r} holds "
                                  "whitespace, which pgmpy's reader splits into two states; "
                                  "rename it (parse_bif reads it as one)")  # fmt: skip


def example_network(name: str) -> BayesNet:
    """One of the discrete example networks bundled with pgmpy, read offline.

    Reads ``pgmpy/utils/example_models/<name>.bif.gz`` from the installed package; falls
    back to ``pgmpy.utils.get_example_model`` if the file is not where 1.1.x keeps it.
    """
    ref = resources.files("pgmpy") / "utils" / "example_models" / f"{name}.bif.gz"
    if ref.is_file():
        with resources.as_file(ref) as path:
            return read_bif(path)
    with _quiet():
        from pgmpy.utils import get_example_model

    with _quiet():
        return from_pgmpy(get_example_model(name))


def dbn_to_pgmpy(dbn: TwoSliceDBN):
    """A ``pgmpy.models.DynamicBayesianNetwork`` (nodes ``(name, 0)``, ``(name, 1)``)."""
    with _quiet():
        from pgmpy.models import DynamicBayesianNetwork

    check_two_slice(dbn, "dbn_to_pgmpy")
    names: dict[Any, tuple[str, ...]] = {}
    for v in dbn.variables:
        if not isinstance(v, DiscreteVariable):
            raise ModelError(f"variable {v.name!r} is continuous: pgmpy DBNs are discrete")
        names[(v.name, 0)] = names[(v.name, 1)] = v.state_names
    edges = []
    for c in dbn.initial_cpds:
        edges += [((p, 0), (c.variable, 0)) for p in c.parents]
    for c in dbn.transition_cpds:
        edges += [((unprev(p), 0) if is_prev(p) else (p, 1), (c.variable, 1)) for p in c.parents]
    model = DynamicBayesianNetwork()
    model.add_nodes_from(v.name for v in dbn.variables)
    model.add_edges_from(edges)
    cpds = []
    for n in dbn.names:
        parents = [(p, 0) for p in dbn.initial_net.parents(n)]
        cpds.append(_pgmpy_cpd((n, 0), parents, dbn.initial_net.table(n), names))
        tparents = [(unprev(p), 0) if is_prev(p) else (p, 1) for p in dbn.transition_net.parents(n)]
        cpds.append(_pgmpy_cpd((n, 1), tparents, dbn.transition_net.table(n), names))
    with _quiet():
        model.add_cpds(*cpds)
        model.initialize_initial_state()
    return model


def dbn_from_pgmpy(model) -> TwoSliceDBN:
    """A :class:`TwoSliceDBN` from a pgmpy ``DynamicBayesianNetwork``.

    The variables (and each slice's CPDs) are in the order the model's nodes were added
    (``model.nodes()``), whatever order pgmpy keeps its CPDs in (that order changes from
    one Python process to the next with string hashing), so the same model gives the same
    declaration, state indexing and printout in every run.

    Raises
    ------
    ModelError
        A node of either slice has no CPD (the message lists them), a CPD lists a
        variable's states (its own at slice 1, or a parent's) in another order than the
        variable's slice-0 CPD (read as if in one order before), or the CPDs do not make
        a valid two-slice template (as :class:`TwoSliceDBN`).
    """
    _check_pgmpy(model, "DynamicBayesianNetwork")
    have = {(str(c.variable[0]), int(c.variable[1])) for c in model.get_cpds()}
    nodes = list(dict.fromkeys(str(n[0]) for n in model.nodes()))  # insertion order
    missing = [(n, t) for n in nodes for t in (0, 1) if (n, t) not in have]
    if missing or not nodes:
        raise ModelError(
            f"pgmpy DBN: no CPD for node(s) {missing or 'any'}; add them (model.add_cpds) first"
        )
    variables: dict[str, DiscreteVariable] = {}
    initial, transition = [], []
    rank = {n: i for i, n in enumerate(nodes)}
    own = {str(c.variable[0]): _own_states(c) for c in model.get_cpds() if int(c.variable[1]) == 0}
    for cpd in sorted(model.get_cpds(), key=lambda c: (int(c.variable[1]), rank.get(str(c.variable[0]), len(rank)))):
        child, parents, table, states = _cpd_table(cpd)
        name, t = child
        table = _renormalized(child, table, 1e-6)
        variables.setdefault(str(name), DiscreteVariable(str(name), table.shape[-1], tuple(states)))
        for node in [child, *parents]:  # every slice's states in the order of (name, 0)'s CPD
            if str(node[0]) in own:  # an unknown parent is TwoSliceDBN's error
                _check_state_order(cpd, node, own[str(node[0])], f"({node[0]}, 0)'s CPD's")
        if t == 0:
            initial.append(TabularCPD(str(name), [str(p) for p, _ in parents], table))
        else:
            pnames = [prev(str(p)) if pt == 0 else str(p) for p, pt in parents]
            transition.append(TabularCPD(str(name), pnames, table))
    return TwoSliceDBN(list(variables.values()), initial, transition)


# --- pgmpy's engines, for comparisons ---------------------------------------------------
def _check_pgmpy_evidence(model, evidence, nodes: Sequence[str] = ()) -> None:
    """Evidence names and state names, and query nodes, the pgmpy ``model`` has; else an
    :class:`EvidenceError` (pgmpy raised networkx's or numpy's own errors)."""
    _check_pgmpy(model, "DiscreteBayesianNetwork")
    known = set(model.nodes())
    for n in [*nodes, *(evidence or {})]:
        if n not in known:
            raise EvidenceError(f"pgmpy model has no node {n!r} (nodes: {sorted(map(str, known))})")
    for n, s in (evidence or {}).items():
        states = model.get_cpds(n).state_names[n]
        if s not in states:
            raise EvidenceError(f"pgmpy model: node {n!r} has no state {s!r} (states: {states})")


def pgmpy_marginals(
    model, nodes: Sequence[str], evidence: Mapping[str, str] | None = None
) -> dict[str, np.ndarray]:
    """pgmpy ``VariableElimination`` queried node by node; each result in our state order.

    ``model`` is a pgmpy model (from :func:`to_pgmpy`); ``evidence`` maps names to state names.
    """
    with _quiet():
        from pgmpy.inference import VariableElimination

    _check_pgmpy_evidence(model, evidence, nodes)
    engine = VariableElimination(model)
    out = {}
    with _quiet():
        for n in nodes:
            f = engine.query([n], evidence=dict(evidence or {}), show_progress=False)
            order = [f.state_names[n].index(s) for s in model.get_cpds(n).state_names[n]]
            out[n] = np.asarray(f.values, dtype=np.float64)[order]
    return out


def pgmpy_map(model, evidence: Mapping[str, str] | None = None) -> dict[str, str]:
    """pgmpy's MAP over all unobserved variables (``VariableElimination.map_query``);
    values are state names."""
    with _quiet():
        from pgmpy.inference import VariableElimination

    _check_pgmpy_evidence(model, evidence)
    engine = VariableElimination(model)
    hidden = [n for n in model.nodes() if n not in (evidence or {})]
    with _quiet():
        return dict(engine.map_query(hidden, evidence=dict(evidence or {}), show_progress=False))


def pgmpy_dbn_forward(
    model, query: Sequence[tuple[str, int]], evidence: Mapping[tuple[str, int], str]
) -> dict[tuple[str, int], np.ndarray]:
    """pgmpy ``DBNInference.forward_inference`` (one call, several slices allowed);
    results in our state order."""
    with _quiet():
        from pgmpy.inference import DBNInference

    engine = DBNInference(model)
    with _quiet():
        res = engine.forward_inference(list(query), dict(evidence))
    out = {}
    for q, f in res.items():
        f_names = list(f.state_names[q])
        ours = model.get_cpds(node=(q[0], 0)).state_names[(q[0], 0)]
        values = np.asarray(f.values, dtype=np.float64)
        if all(s in f_names for s in ours):
            values = values[[f_names.index(s) for s in ours]]
        elif f_names != list(range(len(ours))):  # pgmpy 1.1.2 returns positions 0..K-1
            raise ModelError(f"cannot match pgmpy's states {f_names} of {q} to {ours}")
        out[q] = values
    return out


# --- fast offline reading of the bundled BIF files (issue 12) ---------------------------
_BIF_VARIABLE = re.compile(
    r"variable\s+([^\s{]+)\s*\{[^}]*?type\s+discrete\s*\[\s*(\d+)\s*\]\s*\{([^}]*)\}", re.S
)
_BIF_PROBABILITY = re.compile(r"probability\s*\(([^)]*)\)\s*\{([^}]*)\}", re.S)


def bundled_networks() -> tuple[str, ...]:
    """Names of every discrete BIF network shipped with the installed pgmpy (sorted)."""
    folder = resources.files("pgmpy") / "utils" / "example_models"
    names = [p.name[: -len(".bif.gz")] for p in folder.iterdir() if p.name.endswith(".bif.gz")]
    return tuple(sorted(names))


def _line(text: str, pos: int) -> int:
    return text.count("\n", 0, pos) + 1


def _numbers(text: str, source: str, line: int, what: str) -> np.ndarray:
    """Comma/space separated floats of a BIF row, else a FileFormatError at ``line``."""
    fields = [x for x in re.split(r"[,\s]+", text.strip()) if x]
    try:
        return np.array(fields, dtype=np.float64)
    except ValueError:
        raise FileFormatError(source, f"{what}: not numbers {text.strip()[:40]!r}", line) from None


def _check_bif_text(text: str, source: str) -> None:
    """Whole-file checks: not empty, balanced braces (truncation), no stray bytes."""
    if "\x00" in text:
        raise FileFormatError(source, "binary data (NUL byte): not a BIF text file")
    ctrl = re.search(r"[\x01-\x08\x0b\x0c\x0e-\x1f\x7f]", text)
    if ctrl:  # it would end up inside a name or a state (pgmpy keeps it)
        raise FileFormatError(source, f"control character {ctrl.group()!r} (a damaged file?)",
                              _line(text, ctrl.start()))
    if not re.search(r"\bvariable\b", text):
        raise FileFormatError(source, "empty or not a BIF file (no variable declaration)")
    depth, opened = 0, []
    for m in re.finditer(r"[{}]", text):
        if m.group() == "{":
            opened.append(m.start())
            depth += 1
        else:
            depth -= 1
            if depth < 0:
                raise FileFormatError(source, "'}' without '{'", _line(text, m.start()))
            opened.pop()
    if depth:
        raise FileFormatError(source, "'{' never closed (truncated file?)", _line(text, opened[-1]))


def _bif_states(text: str, source: str) -> dict[str, tuple[str, ...]]:
    states: dict[str, tuple[str, ...]] = {}
    for m in _BIF_VARIABLE.finditer(text):
        name, card, body = m.groups()
        line = _line(text, m.start())
        names = tuple(s.strip() for s in body.split(","))
        if len(names) != int(card) or not all(names) or len(set(names)) != len(names):
            raise FileFormatError(
                source, f"variable {name!r}: [{card}] states but names {list(names)}", line
            )
        if name in states:
            raise FileFormatError(source, f"variable {name!r} declared twice", line)
        states[name] = names
    if len(states) != len(re.findall(r"\bvariable\s", text)):
        raise FileFormatError(source, "a variable block is malformed or not discrete")
    return states


def _bif_table(
    head: str, body: str, states: dict, source: str, line: int
) -> tuple[str, list[str], np.ndarray]:
    """(child, parents, table (*parent_cards, card)) of one ``probability`` block."""
    child, _, rest = head.partition("|")
    child = child.strip()
    parents = [p.strip() for p in rest.split(",") if p.strip()]
    unknown = [v for v in [child, *parents] if v not in states]
    if unknown:
        raise FileFormatError(
            source, f"probability ({head.strip()}) names undeclared variable(s) {unknown}", line
        )
    pcards = [len(states[p]) for p in parents]
    card = len(states[child])
    table = np.zeros((*pcards, card))
    given: set[tuple] = set()  # parent rows read so far (a table gives every row)
    what = f"probability of {child!r}"
    for entry in body.split(";"):
        entry = entry.strip()
        if not entry:
            continue
        if entry.startswith("table"):
            values = _numbers(entry[5:], source, line, what)
            if values.size != table.size:
                raise FileFormatError(
                    source, f"{what}: table has {values.size} numbers, needs {table.size}", line
                )
            if given:
                raise FileFormatError(source, f"{what}: a table besides other rows", line)
            table = values.reshape(card, -1).T.reshape(*pcards, card)
            given.update(np.ndindex(*pcards))
            continue
        if not entry.startswith("(") or ")" not in entry:
            raise FileFormatError(source, f"{what}: unsupported row {entry[:30]!r}", line)
        config, _, numbers = entry[1:].partition(")")
        row = tuple(s.strip() for s in config.split(","))
        try:
            index = tuple(states[p].index(s) for p, s in zip(parents, row, strict=True))
        except ValueError:
            raise FileFormatError(source, f"{what}: bad parent row {row}", line) from None
        values = _numbers(numbers, source, line, what)
        if values.shape != (card,):
            raise FileFormatError(
                source, f"{what}: row {row} has {values.size} numbers, needs {card}", line
            )
        if index in given:  # the last one silently won
            raise FileFormatError(source, f"{what}: row {row} is given twice", line)
        given.add(index)
        table[index] = values
    missing = [i for i in np.ndindex(*pcards) if i not in given]
    if missing:  # it was a row of zeros, refused as not summing to 1
        first = tuple(states[p][i] for p, i in zip(parents, missing[0], strict=True))
        more = f" and {len(missing) - 1} more" if len(missing) > 1 else ""
        say = f"no row for parents {first}{more}" if parents else "no table"
        raise FileFormatError(source, f"{what}: {say}", line)
    return child, parents, table


def parse_bif(text: str, renormalize_tol: float = 1e-6, source: str = "<BIF text>") -> BayesNet:
    """A :class:`BayesNet` from the text of a discrete BIF file, without pgmpy.

    Gives the same net as :func:`read_bif` (pgmpy's ``BIFReader``, then
    :func:`from_pgmpy`): nodes in sorted name order, parents in file order, ``table``
    rows child-state-major, parent rows ``(s_1, ..., s_k) p_1, ..., p_K`` by state name,
    unlisted parent rows zero; tables renormalised as in :func:`from_pgmpy`. Some 50x
    faster than pgmpy's parser (pathfinder: 0.2 s instead of 15 s).

    Parameters
    ----------
    source : the file name quoted in error messages

    Raises
    ------
    FileFormatError
        Naming ``source`` and the line: an empty, binary or truncated text (unbalanced
        braces), a variable block that is not discrete, an undeclared variable, a
        variable without (or with two) probability blocks, an unknown state name, a
        ``default`` row, a row or table of the wrong length, a field that is not a number.
    ModelError
        (its subclasses, message prefixed by ``source``) a cycle, a row not summing to 1,
        a negative or NaN probability.
    """
    if not isinstance(text, str):
        raise InputError(f"parse_bif takes the text of a BIF file, got {type(text).__name__}")
    renormalize_tol = check_nonnegative("renormalize_tol", renormalize_tol, ModelError)
    _check_bif_text(text, source)
    states = _bif_states(text, source)
    cpds: dict[str, TabularCPD] = {}
    blocks = list(_BIF_PROBABILITY.finditer(text))
    if len(blocks) != len(re.findall(r"\bprobability\s*\(", text)):
        raise FileFormatError(source, "a probability block is malformed")
    for m in blocks:
        line = _line(text, m.start())
        child, parents, table = _bif_table(m.group(1), m.group(2), states, source, line)
        if child in cpds:
            raise FileFormatError(source, f"second probability block for {child!r}", line)
        try:
            table = _renormalized(child, table, renormalize_tol)
            cpds[child] = TabularCPD(child, parents, table)
        except DBNError as exc:
            raise type(exc)(f"{source}:{line}: {exc}") from None
    order = sorted(states)
    missing = [n for n in order if n not in cpds]
    if missing:
        raise FileFormatError(source, f"no probability block for variable(s) {missing}")
    variables = [DiscreteVariable(n, len(states[n]), states[n]) for n in order]
    try:
        return BayesNet(variables, [cpds[n] for n in order])
    except DBNError as exc:
        raise type(exc)(f"{source}: {exc}") from None


def bundled_network(name: str) -> BayesNet:
    """A network bundled with pgmpy (see :func:`bundled_networks`), read by
    :func:`parse_bif`: equal to :func:`example_network` and much faster."""
    ref = resources.files("pgmpy") / "utils" / "example_models" / f"{name}.bif.gz"
    if not ref.is_file():
        raise ModelError(f"pgmpy ships no BIF network named {name!r}: {bundled_networks()}")
    with resources.as_file(ref) as path, gzip.open(path, "rt", encoding="utf-8") as f:
        return parse_bif(f.read())
