r"""Object re-identification: the on-line labeller's final off-line pass (our addition
to seed 004; :meth:`models.jorge.online.OnlineLabeller.finish` runs it).

In the seed's net a label only travels along links, so once a person's stroke takes a
new label (a missed link, or a wrong MAP at a split) every later stroke of that person
inherits the new object and the identity stays broken for the rest of the sequence.
After the last inference, :func:`reidentify` asks of each object ``b`` born as a new
label whether it is an earlier object ``a`` seen again: ``a`` must be finished before
``b`` appears (every stroke labelled with ``a`` ends before the first stroke labelled
with ``b`` starts, so the two never coexist), and the colours (eq. 6, the configured
colour model) of ``b``'s palette and of its later one-object strokes must favour
``a`` (an object born inside a group, by a join or in a new group, is asked too once
it has a stroke alone; issue 16, ninth round), with prior probability ``reid_prior``
that a new-looking object is a lost one (shared equally among the candidates; default
0.5, no preference: chosen on CAVIAR ground truth with held-out simulation seeds 20-39
and on simulated sequences). Objects are renamed in birth order; the network itself
(domains, frozen labels) is not changed. ``reid_prior = 0`` turns it off.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from dbn.errors import InputError
from models.jorge.evidence import colour_log_likelihood
from models.jorge.labels import Label, birth_stroke
from models.jorge.network import LabelGraph

__all__ = ["reidentify", "object_aliases", "renamed"]


def reidentify(graph: LabelGraph, labels: Sequence[Label], prior: float) -> list[Label]:
    r"""Final off-line pass: rename objects born as new labels that are earlier objects
    seen again (module docstring; our addition to seed 004).

    For each object :math:`b` in birth order with at least one stroke labelled exactly
    :math:`\{b\}` (the set :math:`S_b`), the candidates :math:`a` are the earlier objects
    (after renaming) whose every stroke ends before the first stroke of :math:`b` starts.
    The evidence is :math:`b`'s palette :math:`\pi_b`, taken as one more observation of the
    object's colours, and the colours of the other strokes of :math:`S_b`. :math:`\pi_b` is
    the palette of the first stroke of :math:`S_b`: the colours :math:`b` got at birth
    (seed 004 sec. 4.1) when it was born alone; for an object born inside a group (a
    newcomer who joined, or a member of a new group, whose birth palette holds the others'
    colours too; asked since issue 16's ninth round) the first stroke where it is alone.
    With :math:`\ell(c \mid \pi)` the colour log-likelihood ratio of eq. 6 (the network's
    colour model),

    .. math::
        \Lambda_a = \log\frac{\rho / |A|}{1 - \rho} + \ell(\pi_b \mid \pi_a)
          + \sum_{s \in S_b} \ell(c_s \mid \pi_a) - \ell(c_s \mid \pi_b)

    (under "b is new" its palette is a chance palette, :math:`\ell = 0`, and given
    :math:`\pi_b` the stroke it came from says nothing more), and :math:`b` is
    renamed to the best :math:`a` when :math:`\Lambda_a > 0`. Passes over all objects
    are repeated until no object is renamed.

    Parameters
    ----------
    graph : LabelGraph
        The labelled graph (strokes and the palettes objects got at birth).
    labels : sequence of Label, length num_strokes
    prior : float
        :math:`\rho` in (0, 1).

    Returns
    -------
    list of Label
        The labels with renamed objects (a renamed object takes the id of the object it
        continues).
    """
    alias = object_aliases(graph, labels, prior)
    return [renamed(lab, alias) for lab in labels]


def renamed(label: Label, aliases: Mapping[int, int]) -> Label:
    """``label`` with its objects renamed by ``aliases`` (:func:`object_aliases`; objects
    not in it keep their ids)."""
    return frozenset(aliases.get(o, o) for o in label)


def object_aliases(graph: LabelGraph, labels: Sequence[Label], prior: float) -> dict[int, int]:
    """The renaming :func:`reidentify` applies to ``labels``: each renamed object's final
    id (objects it leaves alone are not keys). Parameters and errors as
    :func:`reidentify`'s."""
    labels = list(labels)
    if len(labels) != len(graph):
        raise InputError(f"reidentify: {len(labels)} labels for {len(graph)} nodes")
    if not 0.0 < prior < 1.0:
        raise InputError(f"reidentify: prior must be in (0, 1), got {prior}")
    total: dict[int, int] = {}
    # one pass can miss a renaming because a candidate set was larger when the object was
    # examined than after later renamings; repeat until nothing changes (each pass only
    # merges objects, so at most num_objects passes)
    while labels:
        alias = _reidentify_pass(graph, labels, prior)
        if not alias:
            break
        labels = [renamed(lab, alias) for lab in labels]
        total = {o: alias.get(t, t) for o, t in total.items()} | {
            o: a for o, a in alias.items() if o not in total}
    return total


def _reidentify_pass(graph: LabelGraph, labels: list, prior: float) -> dict[int, int]:
    """One pass over the objects in birth order: each renamed object's new id."""
    cfg = graph.config
    starts = np.array([nd.stroke.start for nd in graph.nodes])
    ends = np.array([nd.stroke.end for nd in graph.nodes])
    # in birth order (a new group's members have ids past every lone newcomer's,
    # ``models.jorge.labels.NEW_STRIDE``: sorting by id examined them last; issue 16,
    # eleventh round)
    objects = sorted(set().union(*labels), key=lambda o: (birth_stroke(o), o))
    member = np.array([[o in lab for lab in labels] for o in objects])  # (num_objects, num_strokes)
    first = {o: int(starts[member[i]].min()) for i, o in enumerate(objects)}
    last = {o: int(ends[member[i]].max()) for i, o in enumerate(objects)}
    alias: dict[int, int] = {}
    roots: list[int] = []
    pal = graph.palettes([frozenset({o}) for o in objects])
    row = {o: i for i, o in enumerate(objects)}
    for i, b in enumerate(objects):
        cands = [a for a in roots if last[a] < first[b]]
        alone = frozenset({b})
        singles = [int(k) for k in np.flatnonzero(member[i]) if labels[k] == alone] if cands else []
        if not singles:  # no candidate, or never seen alone: kept as is
            roots.append(b)
            continue
        # b's palette: that of its first stroke alone (its birth stroke if born alone;
        # a newcomer who joined a group, or a member of a new group, was born with the
        # others' colours too)
        own = singles[0]
        palettes = np.zeros((len(cands) + 1, pal.shape[1]), dtype=bool)
        palettes[:-1] = pal[[row[a] for a in cands]]
        palettes[-1, graph.nodes[own].stroke.palette] = True
        score = np.full(len(cands), np.log(prior / len(cands)) - np.log1p(-prior))
        # b's palette as one more observation of the object
        score += colour_log_likelihood(np.flatnonzero(palettes[-1]), palettes[:-1],
                                       np.zeros(len(cands), dtype=bool), cfg.match_prob,
                                       cfg.pool_size, cfg.colour_mode)  # fmt: skip
        for k in singles:
            if k == own:
                continue  # given b's palette, the stroke it came from says nothing more
            ll = colour_log_likelihood(graph.nodes[k].stroke.colours, palettes,
                                       np.zeros(len(cands) + 1, dtype=bool), cfg.match_prob,
                                       cfg.pool_size, cfg.colour_mode)  # fmt: skip
            score += ll[:-1] - ll[-1]
        best = int(np.argmax(score))
        if score[best] > 0:
            a = cands[best]
            alias[b] = a
            last[a] = max(last[a], last[b])
        else:
            roots.append(b)
    return alias
