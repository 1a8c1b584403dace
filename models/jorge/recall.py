r"""Does the label network keep the true labelling? (issue 16, deliverable 2: domain
pruning that keeps the true labelling with high probability, *measured* against the
ground truth rather than the model's own posterior).

For each stroke :math:`k` with true set :math:`T_k`, a label of the network is *right*
when, its objects renamed as the re-identification pass renames them
(:func:`models.jorge.reid.object_aliases`), the people it stands for are :math:`T_k`
(objects matched one to one with people by :func:`models.jorge.scoring.optimal_people` on
the final labels, as the error rate matches them; :func:`models.jorge.scoring.stands_for`).
An object born at stroke :math:`k` that no chosen label holds has no person in that
matching; in a label of node :math:`k` it may stand for a person seen for the first time in
stroke :math:`k` (a newcomer: a join or a new object), one object per such person. A
chosen label holds no such object, so a stroke's chosen label is right exactly when the
stroke is not a labelling error. The matching is the final labelling's: an object it gives
to someone else cannot stand for this stroke's people, so the flags below ask whether a
right label existed under that matching, not under every matching.

- **admissible**: some right label is admissible given the labels the parents were given
  (:meth:`models.jorge.network.LabelGraph.admissible` with each parent's label alone): the
  node could have been labelled right had its parents stayed as they were labelled. False
  where a parent is wrong, or where the structure admits no right label (someone seen
  before came in without a link, a spurious link, more newcomers than a join admits, a
  group beyond ``max_group_size``);
- **kept**: the node's domain (the last one it was scored on, after the instant cap
  ``OnlineConfig.max_labels`` and the windows' pruning) holds a right label;
- **chosen**: the node's own label is right, i.e. the stroke is not a labelling error
  (its label is in its domain, so chosen implies kept);
- **parents_right**: every parent's label is right (a root: True). A stroke with right
  parents and no admissible right label is one the network's structure cannot label
  right, whatever the pruning and the inference.

Among the strokes whose right label is admissible, the share kept is the pruning's recall;
among those kept, the share chosen is the inference's.

A stroke that someone seen before entered without a link has no right label whatever the
pruning (issue 16, forty-sixth round: most first mistakes in the PETS2009 crowds and the
7-fps meetings). :func:`missed_links` lists those entries with the link rule's reason for
not linking the person's last stroke (:meth:`models.jorge.links.LinkRule.why_not_parent`:
too long a gap, too far, no free child slot, ...). Diagnosis only: nothing is chosen on
any of it.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from dbn.errors import InputError
from models.jorge.labels import Label, birth_stroke
from models.jorge.links import WHY_NOT_PARENT
from models.jorge.network import LabelGraph
from models.jorge.reid import renamed
from models.jorge.scoring import optimal_people, stands_for
from models.jorge.strokes import Stroke

if TYPE_CHECKING:
    from models.jorge.online import OnlineResult

__all__ = ["DomainRecall", "domain_recall", "result_recall", "MissedLink", "missed_links",
           "missed_link_counts"]


@dataclass(frozen=True)
class DomainRecall:
    """Per stroke, whether a right label was admissible, kept in the domain, chosen, and
    whether its parents' labels were right (module docstring). Each a bool array, shape
    (num_strokes,)."""

    admissible: np.ndarray
    kept: np.ndarray
    chosen: np.ndarray
    parents_right: np.ndarray

    def where_lost(self, mask: np.ndarray | None = None) -> dict[str, np.ndarray]:
        """Where the right label of each error of ``mask`` (all errors by default) was lost:
        ``"unrepresentable"`` (neither admissible nor kept), ``"pruned"`` (admissible, not
        kept), ``"not_chosen"`` (kept, another chosen). Bool arrays, shape (num_strokes,),
        that partition the errors of ``mask``."""
        errors = ~self.chosen if mask is None else np.asarray(mask, bool) & ~self.chosen
        return {"unrepresentable": errors & ~self.admissible & ~self.kept,
                "pruned": errors & self.admissible & ~self.kept,
                "not_chosen": errors & self.kept}


def domain_recall(strokes: Sequence[Stroke], graph: LabelGraph, labels: Sequence[Label],
                  aliases: Mapping[int, int] | None = None) -> DomainRecall:
    """Whether each stroke's right label was admissible, kept and chosen (module docstring).

    Parameters
    ----------
    strokes : sequence of Stroke, length num_strokes
        With their true sets, in the order of the graph's nodes.
    graph : LabelGraph
        The labelled network (:attr:`models.jorge.online.OnlineResult.labeller`'s graph),
        one node per stroke.
    labels : sequence of Label, length num_strokes
        The network's own labels (:attr:`models.jorge.online.OnlineResult.network_labels`),
        in the objects its domains hold.
    aliases : mapping of int to int, optional
        The renaming of the re-identification pass
        (:func:`models.jorge.reid.object_aliases` of ``graph`` and ``labels``); ``None``:
        none (``OnlineConfig.reid_prior`` 0).

    Returns
    -------
    DomainRecall

    Raises
    ------
    InputError
        Lengths differ, or a node's stroke is not the stroke at its position.
    """
    strokes, labels = list(strokes), list(labels)
    if not len(strokes) == len(labels) == len(graph):
        raise InputError(f"domain_recall: {len(strokes)} strokes, {len(labels)} labels, "
                         f"{len(graph)} nodes")
    strokes = _check_nodes(strokes, graph, "domain_recall")
    aliases = {} if aliases is None else aliases
    people = optimal_people(strokes, [renamed(lab, aliases) for lab in labels])
    first_seen = _first_seen(strokes)
    out = np.zeros((4, len(strokes)), bool)
    for k, s in enumerate(strokes):
        truth = set(s.truth)
        newcomers = {p for p in truth if first_seen[p] == k}
        node = graph.nodes[k]
        admissible = graph.admissible(k, [[labels[p]] for p in node.parents])
        out[0, k] = any(_right(renamed(lab, aliases), k, truth, newcomers, people)
                        for lab in admissible)
        out[1, k] = any(_right(renamed(lab, aliases), k, truth, newcomers, people)
                        for lab in node.domain)
        out[2, k] = stands_for(renamed(labels[k], aliases), people) == truth
    out[3] = [all(out[2, p] for p in graph.nodes[k].parents) for k in range(len(strokes))]
    return DomainRecall(*out)


def result_recall(strokes: Sequence[Stroke], result: OnlineResult) -> DomainRecall:
    """:func:`domain_recall` of an on-line labelling (:func:`models.jorge.online.label_online`
    of ``strokes``), its objects renamed as its re-identification pass renamed them
    (:attr:`models.jorge.online.OnlineLabeller.aliases`)."""
    lab = result.labeller
    return domain_recall(strokes, lab.graph, result.network_labels, lab.aliases)


class MissedLink(NamedTuple):
    """Someone seen before who entered a stroke without a link (:func:`missed_links`).

    Attributes
    ----------
    stroke : int
        The stroke entered (position in the strokes).
    person : int
        The person (ground-truth id).
    earlier : int
        The person's last stroke before it: among the earlier strokes holding the person,
        the one that ends last.
    reason : str
        Why the link rule did not link ``earlier`` to ``stroke``
        (:meth:`models.jorge.links.LinkRule.why_not_parent`).
    """

    stroke: int
    person: int
    earlier: int
    reason: str


def missed_links(strokes: Sequence[Stroke], graph: LabelGraph) -> list[MissedLink]:
    """Each person of each stroke who is in none of its parents' true sets but was in an
    earlier stroke (module docstring): the stroke cannot be labelled right from its
    parents, whatever the pruning. In stroke order, then person order.

    Parameters
    ----------
    strokes : sequence of Stroke, length num_strokes
        With their true sets, in the order of the graph's nodes.
    graph : LabelGraph
        The network the strokes were linked in (the graph of
        :attr:`models.jorge.online.OnlineResult.labeller`).

    Raises
    ------
    InputError
        Lengths differ, or a node's stroke is not the stroke at its position.
    """
    strokes = _check_nodes(strokes, graph, "missed_links")
    out, last = [], {}  # person -> earlier stroke that ends last
    for k, s in enumerate(strokes):
        held = set().union(*(strokes[p].truth for p in graph.nodes[k].parents))
        for person in sorted(set(s.truth) - held):
            if person in last:
                j = last[person]
                out.append(MissedLink(k, person, j, graph.why_not_parent(k, j)))
        for person in s.truth:
            j = last.get(person)
            if j is None or strokes[j].end <= s.end:
                last[person] = k
    return out


def missed_link_counts(missed: Sequence[MissedLink],
                       mask: np.ndarray | None = None) -> dict[str, int]:
    """The number of missed links by reason (every reason of
    :data:`models.jorge.links.WHY_NOT_PARENT`, zeros included), over the strokes of ``mask``
    (bool, shape (num_strokes,); all strokes by default)."""
    counts = dict.fromkeys(WHY_NOT_PARENT, 0)
    for m in missed:
        if mask is None or mask[m.stroke]:
            counts[m.reason] += 1
    return counts


def _check_nodes(strokes: Sequence[Stroke], graph: LabelGraph, where: str) -> list:
    """``strokes`` as a list, checked to be the graph's nodes' strokes in order."""
    strokes = list(strokes)
    if len(strokes) != len(graph):
        raise InputError(f"{where}: {len(strokes)} strokes, {len(graph)} nodes")
    for k, s in enumerate(strokes):
        if graph.nodes[k].stroke.index != s.index:
            raise InputError(f"{where}: node {k} holds stroke {graph.nodes[k].stroke.index}, "
                             f"not stroke {s.index}")
    return strokes


def _first_seen(strokes: Sequence[Stroke]) -> dict:
    """Each person's first stroke (position in ``strokes``, which are in start order)."""
    out: dict = {}
    for k, s in enumerate(strokes):
        for p in s.truth:
            out.setdefault(p, k)
    return out


def _right(label: Label, k: int, truth: set, newcomers: set, people: Mapping) -> bool:
    """Whether ``label`` (renamed) of node ``k`` stands for ``truth``: its matched objects
    for people of ``truth``, and its objects born at ``k`` that no chosen label holds (not
    in ``people``) for the rest, who must all be ``newcomers`` (module docstring)."""
    fresh = [o for o in label if o not in people and birth_stroke(o) == k]
    meant = stands_for(label.difference(fresh), people)
    rest = truth - meant
    return meant <= truth and len(rest) == len(fresh) and rest <= newcomers
