r"""One inference window of seed 004's label network (eq. 11 over the active nodes) as a
:class:`dbn.bayesnet.BayesNet`, and its exact MAP labelling and marginals with
:mod:`inference.exact`.

:func:`build_window` assembles the net of a :class:`models.jorge.network.LabelGraph`'s
active nodes: a label node ``x{k}`` per active stroke (its CPD,
:meth:`LabelGraph.cpd_table`), its frozen parents and siblings as one-state nodes, a
restriction node ``r{i}_{j}`` per sibling pair (eq. 5, observed 1), an observed node
``m{k}`` for the mass a pruned domain kept times the chain factor's row sums
(:func:`kept_name`), and every active node's soft evidence (colours, eq. 6, size and
palette).
:func:`solve` returns the MAP labels (eq. 1) and the marginals. Moved here from
:mod:`models.jorge.network`, which still exports every name (issue 16, thirty-sixth
round); no behaviour change.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from dbn.bayesnet import BayesNet
from dbn.cpds import TabularCPD
from dbn.errors import InputError, UnknownVariableError
from dbn.variables import DiscreteVariable
from inference.exact import JunctionTree, map_assignment
from models.jorge.labels import Label, format_label

if TYPE_CHECKING:
    from models.jorge.network import LabelGraph

__all__ = [
    "WindowNet",
    "Inference",
    "build_window",
    "solve",
    "node_name",
    "restriction_name",
    "kept_name",
    "colour_name",
]


def node_name(k: int) -> str:
    """Name of the hidden label node of stroke ``k``."""
    return f"x{k}"


def restriction_name(i: int, j: int) -> str:
    """Name of the restriction node of the sibling pair ``i < j``."""
    return f"r{min(i, j)}_{max(i, j)}"


def kept_name(k: int) -> str:
    """Name of the observed node carrying the mass node ``k``'s pruned domain kept
    (``NetworkConfig.truncate_pruned``), times the row sums of the chain factor
    (``NetworkConfig.chain_palette``, :meth:`LabelGraph.chain_log_ratio`)."""
    return f"m{k}"


def colour_name(k: int) -> str:
    """Name of the explicit colour node (only in :meth:`WindowNet.with_colour_nodes`)."""
    return f"y{k}"


def build_window(graph: LabelGraph, active: Sequence[int]) -> WindowNet:
    """The Bayes net of a graph's active nodes (seed 004, eq. 11 over the active window).

    Frozen parents and frozen siblings of active nodes enter as one-state variables,
    so the active nodes' CPDs and restriction nodes see their fixed labels; all other
    frozen nodes are left out (they are constants).

    Parameters
    ----------
    graph : LabelGraph
    active : sequence of int
        Node indices of ``graph``, none frozen; every parent of one is active or frozen.

    Returns
    -------
    WindowNet

    Raises
    ------
    UnknownVariableError
        A node that is not in the graph.
    InputError
        A frozen active node, or a parent neither active nor frozen.
    ModelError
        An active node's CPD table would hold more than 5e7 entries (checked for
        every node before any table is built).
    """
    active = sorted(int(a) for a in active)
    _check_active(graph, active)
    boundary, pairs = _boundary_and_pairs(graph, active)
    variables, cpds = [], []
    domains: dict[str, tuple[Label, ...]] = {}
    for b in boundary:
        name = node_name(b)
        lab = graph.nodes[b].frozen
        domains[name] = (lab,)
        variables.append(DiscreteVariable(name, 1, (format_label(lab),)))
        cpds.append(TabularCPD(name, [], np.ones(1)))
    soft, kept_nodes = _active_nodes(graph, active, variables, cpds, domains)
    evidence: dict[str, int] = {}
    # p(m_k = 1 | parents) = mass kept (truncate_pruned) times the chain factor's row sums
    for name, parents, kept in kept_nodes:
        variables.append(DiscreteVariable(name, 2, ("0", "1")))
        kept = np.minimum(kept, 1.0)  # rounding: a full row may sum to 1 + 1e-16
        cpds.append(TabularCPD(name, parents, np.stack([1.0 - kept, kept], axis=-1)))
        evidence[name] = 1
    for i, j in pairs:
        name = restriction_name(i, j)
        variables.append(DiscreteVariable(name, 2, ("0", "1")))
        cpds.append(_restriction_cpd(graph, name, i, j, domains))
        evidence[name] = 1
    bn = BayesNet(variables, cpds)
    return WindowNet(bn, evidence, soft, domains, tuple(active), tuple(boundary))


def _check_active(graph: LabelGraph, active: list[int]) -> None:
    """Raise unless every active node exists and is not frozen, then unless every CPD
    table fits (:meth:`LabelGraph.check_table_size`); nothing is built before."""
    for a in active:
        if not 0 <= a < len(graph.nodes):
            raise UnknownVariableError(f"window: unknown node {a}")
        if graph.nodes[a].frozen is not None:
            raise InputError(f"window: node {a} is frozen and cannot be active")
    for a in active:  # every table's size checked before any is built
        graph.check_table_size(a, graph.parent_domains(a))


def _boundary_and_pairs(graph: LabelGraph, active: list[int]) -> tuple[list[int], list[tuple[int, int]]]:
    """The frozen parents and siblings of the active nodes (sorted), and the sibling pairs
    ``(i, j)``, ``i < j``, both in the window (sorted), whose restriction node enters.

    Raises
    ------
    InputError
        A parent of an active node that is neither active nor frozen.
    """
    act = set(active)
    boundary: set[int] = set()
    pairs: set[tuple[int, int]] = set()
    for a in active:
        for p in graph.nodes[a].parents:
            if p not in act:
                if graph.nodes[p].frozen is None:
                    raise InputError(
                        f"window: parent {p} of active node {a} is neither active nor frozen"
                    )
                boundary.add(p)
        for s in graph.siblings(a):
            pairs.add((min(a, s), max(a, s)))
            if s not in act:
                boundary.add(s)
    # a sibling outside the window that is not frozen yet (a later node) stays out
    boundary = {b for b in boundary if graph.nodes[b].frozen is not None}
    pairs = {(i, j) for i, j in pairs if (i in act or i in boundary) and (j in act or j in boundary)}
    return sorted(boundary), sorted(pairs)


def _active_nodes(graph: LabelGraph, active: list[int], variables: list, cpds: list,
                  domains: dict) -> tuple[dict[str, np.ndarray], list]:
    """Append each active node's variable and CPD (times the chain factor of
    :meth:`LabelGraph.chain_log_ratio`, rows normalised) and record its domain.

    Returns
    -------
    soft : dict name -> ndarray, shape (num_labels,)
        The node's soft evidence (:meth:`LabelGraph.evidence_loglik`), scaled to max 1.
    kept_nodes : list of (name, parent names, ndarray)
        Nodes whose CPD rows kept less than all their mass: the mass kept per parent row.
    """
    soft: dict[str, np.ndarray] = {}
    kept_nodes: list = []
    for a in active:
        name = node_name(a)
        dom = graph.nodes[a].domain
        domains[name] = dom
        variables.append(DiscreteVariable(name, len(dom), tuple(format_label(x) for x in dom)))
        parents = [node_name(p) for p in graph.nodes[a].parents]
        table = graph.cpd_table(a)
        corr = graph.chain_log_ratio(a)
        if corr is not None:  # chain_palette: a factor on (parent, x_a), scaled to max 1,
            table = table * np.exp(corr - corr.max())  # row sums to m_a with the kept mass
        kept = table.sum(axis=-1)
        cpds.append(TabularCPD(name, parents, table / kept[..., None]))
        if parents and np.any(kept < 1.0 - 1e-12):
            kept_nodes.append((kept_name(a), parents, kept))
        ll = graph.evidence_loglik(a)
        soft[name] = np.exp(ll - ll.max())
    return soft, kept_nodes


def _restriction_cpd(graph: LabelGraph, name: str, i: int, j: int, domains: dict) -> TabularCPD:
    """Restriction node of siblings ``i < j`` (eq. 5); the group of :meth:`LabelGraph.cover_parent`,
    where there is one in the window, is its parent too
    (:func:`models.jorge.labels.restriction_table`)."""
    di, dj = domains[node_name(i)], domains[node_name(j)]
    group = graph.cover_parent(i, j)
    if group is not None and node_name(group) in domains:
        p = node_name(group)
        return TabularCPD(name, [p, node_name(i), node_name(j)], graph.restriction(i, j, di, dj, domains[p]))
    return TabularCPD(name, [node_name(i), node_name(j)], graph.restriction(i, j, di, dj))


@dataclass(frozen=True)
class Inference:
    """Result of exact inference on a window.

    Attributes
    ----------
    labels : dict int -> Label
        MAP label of every active node (eq. 1 / eq. 11).
    log_prob : float
        :math:`\\log P(x^*, r = 1)` times the colour likelihoods (scaled to max 1 per node).
    marginals : dict int -> ndarray (num_labels,)
        Posterior of every active node's labels.
    log_evidence : float
    """

    labels: dict
    log_prob: float
    marginals: dict
    log_evidence: float


@dataclass(frozen=True)
class WindowNet:
    """A Bayes net of one inference window and its evidence.

    Attributes
    ----------
    bn : BayesNet
    evidence : dict name -> int
        ``r = 1`` for every restriction node.
    soft_evidence : dict name -> ndarray
        Colour likelihood of every active node (scaled to max 1).
    domains : dict name -> tuple of Label
        States of every label node (one label for frozen boundary nodes).
    active, boundary : tuple of int
    """

    bn: BayesNet
    evidence: dict
    soft_evidence: dict
    domains: dict
    active: tuple
    boundary: tuple

    def with_colour_nodes(self) -> tuple[BayesNet, dict]:
        """The same model with the soft evidence (colours, and size where recorded) as
        explicit binary children ``y{k}``
        observed 1, ``p(y = 1 | x) = lambda(x)`` (virtual evidence as a node), for engines
        without soft evidence (pgmpy). Its joint with the evidence equals ours exactly.

        Returns
        -------
        bn : BayesNet
        evidence : dict name -> int
        """
        variables = list(self.bn.variables.values())
        cpds = list(self.bn.cpds.values())
        evidence = dict(self.evidence)
        for name, lik in self.soft_evidence.items():
            k = int(name[1:])
            y = colour_name(k)
            variables.append(DiscreteVariable(y, 2, ("0", "1")))
            cpds.append(TabularCPD(y, [name], np.stack([1.0 - lik, lik], axis=-1)))
            evidence[y] = 1
        return BayesNet(variables, cpds), evidence


def solve(win: WindowNet, marginals: bool = True) -> Inference:
    """MAP labelling and marginals of a window with :mod:`inference.exact`.

    Parameters
    ----------
    win : WindowNet
    marginals : bool
        Also calibrate a junction tree for every active node's posterior.

    Returns
    -------
    Inference
    """
    assignment, log_prob = map_assignment(win.bn, win.evidence, win.soft_evidence)
    labels = {k: win.domains[node_name(k)][assignment[node_name(k)]] for k in win.active}
    marg: dict[int, np.ndarray] = {}
    log_ev = float("nan")
    if marginals:
        cal = JunctionTree(win.bn).calibrate(win.evidence, win.soft_evidence)
        marg = {k: cal.marginals[node_name(k)] for k in win.active}
        log_ev = cal.log_evidence
    return Inference(labels, log_prob, marg, log_ev)
