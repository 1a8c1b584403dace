r"""On-line labelling (seed 004, section 5), scoring and the colour-only baseline.

Periodic inference
    Every ``period_s`` seconds (T) the active window is solved exactly (eq. 11): the
    ``max_active`` (N) most recent nodes are active, every older node is frozen to the
    label it holds (its MAP label at the last inference it took part in). After each
    inference every active node's domain is pruned to the labels whose posterior is at
    least ``prune_threshold`` (at most ``max_labels``; its MAP and new labels always stay),
    so with at most N nodes, at most ``max_labels`` labels each and at most 2 parents per
    node, the cost of one inference is bounded whatever the length of the sequence.

Instant labelling between inferences (eq. 12)
    A node created after the last inference has a uniform prior (seed 004); the new
    information is its colours (eq. 6) and its links to the already labelled past: the
    CPD given its parents' current labels, and the restriction nodes against its
    already labelled siblings (a label sharing an object with one has probability 0).
    It takes :math:`\arg\max_{x} p(y | x)\, p(x | x_{pa}) \prod_s p(r_{s} = 1 | x, x_s)`.
    Nodes that took part in the last inference keep their MAP label until the next one.
    Its domain is capped at ``max_labels`` by this posterior, on the parents' beliefs of
    the moment; when the next inference relabels the parents, a continuation or merge
    whose domain lost the label they now pass on gets it back and the window runs again
    (``restore_successors``, our addition; issue 16, twenty-first round). The cap ranks
    the labels without the siblings' clash, the node's own and, through the parents'
    clash-free beliefs, its ancestors' since the last inference (``clash_free_rank``, our
    addition; issue 16, thirtieth round): a sibling's instant label is a point guess the
    window may revise, and a label it excludes would otherwise reach the children with
    belief 0 and be the first the cap drops (a member leaving a group of four was then
    labelled a new person while the group kept them: two objects for one person).

Links
    By default each new stroke is linked by the on-line link rule
    (:meth:`models.jorge.network.LabelGraph.candidate_parents`). A low-level tracker that
    knows its merges and splits can give the links instead (``add_stroke(stroke,
    parents)``, ``label_online(..., links=...)``); :func:`true_links` gives the true
    predecessors, the oracle with which the benchmark measures what the link rule costs.

Object re-identification (final off-line pass; our addition)
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

Scoring
    An object id ``o`` is the object first seen in stroke ``o``. Objects are matched one to
    one with people, by default with the matching that maximises co-occurrences (as IDF1
    matches identities); with ``mapping="first_seen"`` an object stands for the person of
    the stroke where it was first seen, if that stroke held one person not already
    claimed. A stroke is a labelling error (LE) when the people its label stands for
    differ from its true set. Identity switches: over each person's
    one-person strokes in time order, the number of consecutive pairs given different
    labels.
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import linear_sum_assignment

from dbn.errors import InputError, ModelError
from inference.exact import JunctionTree, map_assignment
from models.jorge.labels import (
    Label,
    birth_stroke,
    colour_log_likelihood,
    prune_labels,
)
from models.jorge.network import LabelGraph, NetworkConfig, check_frame_rate, node_name
from models.jorge.strokes import Stroke, StrokeSet

__all__ = [
    "OnlineConfig",
    "OnlineLabeller",
    "OnlineResult",
    "InferenceRecord",
    "Score",
    "label_online",
    "score",
    "colour_only_labels",
    "reidentify",
    "first_errors",
    "after_crowd",
    "true_predecessors",
    "true_links",
    "link_accuracy",
    "object_people",
    "optimal_people",
]


@dataclass(frozen=True)
class OnlineConfig:
    """Settings of the on-line labeller (seed 004, sec. 5).

    Attributes
    ----------
    period_s : float
        T, seconds between periodic inferences.
    max_active : int
        N, most recent nodes kept active; older ones are frozen.
    prune_threshold : float
        Labels whose posterior fell below this at the last inference are dropped.
    max_labels : int
        Largest domain kept after pruning.
    marginals : bool
        Compute every active node's marginal at each inference (junction tree); needed
        for pruning by posterior. Without it, domains are pruned to ``max_labels`` by
        nothing but the MAP (not recommended).
    reid_prior : float
        Prior probability that an object born as a new label is an earlier, finished
        object seen again (final re-identification pass, :func:`reidentify`); 0 turns
        the pass off.
    tentative_joiners : bool
        After every relabel and inference, the newcomers of an unfrozen node whose current
        label is a join are joiners already (:meth:`LabelGraph.set_tentative_joiners`;
        issue 16, fourteenth round); ``False``: only once their birth node is frozen (the
        thirteenth round's behaviour).
    restore_successors : bool
        After every inference, give back to an active continuation or merge node the label
        its parents' new labels pass on, when the eq. 12 cap dropped it, and if any was
        given back run the window again (:meth:`OnlineLabeller.restore_successors`; issue
        16, twenty-first round).
    clash_free_rank : bool
        Cap a new node's domain (``max_labels``) on its eq. 12 posterior without the
        siblings' clash at every step up its chain: its parents' beliefs too leave out the
        clash with their own siblings' instant labels (:attr:`OnlineLabeller.free_beliefs`).
        ``False``: only its own clash is left out, and a label a parent's sibling excludes
        (belief 0) is the first the cap drops from the children, for good (issue 16,
        thirtieth round).
    network : NetworkConfig
    """

    period_s: float = 1.0
    max_active: int = 16
    prune_threshold: float = 1e-3
    max_labels: int = 12
    marginals: bool = True
    reid_prior: float = 0.5
    tentative_joiners: bool = True
    restore_successors: bool = True
    clash_free_rank: bool = True
    network: NetworkConfig = field(default_factory=NetworkConfig)

    def __post_init__(self) -> None:
        if not self.period_s > 0:
            raise ModelError(f"OnlineConfig.period_s must be > 0, got {self.period_s}")
        for name in ("max_active", "max_labels"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int | np.integer):
                raise ModelError(f"OnlineConfig.{name} must be an int, got {v!r}")
        if self.max_active < 1:
            raise ModelError(f"OnlineConfig.max_active must be >= 1, got {self.max_active}")
        if not 0.0 <= self.prune_threshold < 1.0:
            raise ModelError(f"OnlineConfig.prune_threshold must be in [0, 1), got {self.prune_threshold}")
        if not 0.0 <= self.reid_prior < 1.0:
            raise ModelError(f"OnlineConfig.reid_prior must be in [0, 1), got {self.reid_prior}")
        if self.max_labels < 2:
            raise ModelError(f"OnlineConfig.max_labels must be >= 2, got {self.max_labels}")


@dataclass(frozen=True)
class InferenceRecord:
    """One periodic inference: when, how big, how long.

    Attributes
    ----------
    frame : int
    num_active, num_boundary : int
    max_domain : int
        Largest active domain.
    max_clique_entries : int
        Entries of the largest junction-tree clique table calibrated (the window's
        restriction and kept-mass nodes are observed, so indexed away; 0 without marginals).
    seconds : float
        Wall time of building the window net and solving it.
    log_prob : float
        MAP log probability.
    pruned_mass : float
        Largest posterior mass any active node's pruning dropped at this inference (the
        probability, under the window's posterior, of the labels removed).
    """

    frame: int
    num_active: int
    num_boundary: int
    max_domain: int
    max_clique_entries: int
    seconds: float
    log_prob: float
    pruned_mass: float = 0.0


class OnlineLabeller:
    """Incremental labeller: add strokes as they start, infer every T seconds.

    Parameters
    ----------
    config : OnlineConfig
    fps : float
        Frame rate of the strokes (turns ``period_s`` and the link gates' seconds into
        frames). Required: no rate is assumed (:class:`ModelError` without it).
    keep_windows : bool
        Keep every window net (for cross-checks; costs memory).

    Attributes
    ----------
    graph : LabelGraph
    labels : dict int -> Label
        Current label of every node.
    records : list of InferenceRecord
    instant_pruned_mass : list of float
        Posterior mass dropped each time a new node's eq. 12 posterior was capped to
        ``max_labels`` labels.
    free_beliefs : dict int -> ndarray
        With ``clash_free_rank``: the eq. 12 posterior without the siblings' clash, up the
        chain, of each node created since the last inference where it differs from its
        belief (the cap's ranking; dropped at the next inference).
    """

    def __init__(self, config: OnlineConfig | None = None, fps: float | None = None,
                 keep_windows: bool = False) -> None:
        self.config = OnlineConfig() if config is None else config
        self.graph = LabelGraph(self.config.network, fps=fps)  # checks fps
        self.fps = self.graph.fps
        self.labels: dict[int, Label] = {}
        self.beliefs: dict[int, np.ndarray] = {}
        self.free_beliefs: dict[int, np.ndarray] = {}
        self.records: list[InferenceRecord] = []
        self.windows: list = []
        self.keep_windows = keep_windows
        self._period_frames = self.config.period_s * self.fps
        self._next_inference: float | None = None
        self._inferred: set[int] = set()
        self.instant_pruned_mass: list[float] = []

    # --- eq. 12 ------------------------------------------------------------------------------
    def belief_of(self, k: int, free: bool = False) -> np.ndarray:
        """Current belief over node ``k``'s current domain: its marginal at the last
        inference, its eq. 12 posterior if created since (``free``: without the siblings'
        clash, :attr:`free_beliefs`, where it has one), a point mass if frozen."""
        if self.graph.nodes[k].frozen is not None:
            return np.ones(1)
        return self.free_beliefs.get(k, self.beliefs[k]) if free else self.beliefs[k]

    def instant_posterior(self, k: int, siblings: bool = True) -> np.ndarray:
        r"""Eq. 12 posterior of node ``k`` over its domain.

        .. math::
            P(x_k \mid \cdot) \propto p(y_k \mid x_k)\,p(a_k \mid |x_k|)
              \sum_{x_{pa}} p(x_k \mid x_{pa}) \prod_p b_p(x_p)
              \prod_{s} [x_k \cap \ell_s = \emptyset]

        with :math:`b_p` the parents' beliefs at the last inference (or their own eq. 12
        posteriors), :math:`\ell_s` the current labels of its labelled siblings and
        :math:`p(a_k \mid |x_k|)` the region-size evidence (1 when not recorded or off);
        where one of ``k`` and a sibling is also the other's parent (a nested link) the
        clash is :func:`~models.jorge.labels.restriction_allows`'s, nested. With
        ``LabelParams.split_cover`` (on in the default network), the factor of a sibling
        with one shared parent (not nested) is the window's restriction CPD given the
        parent's current label :math:`\ell_p` (:func:`~models.jorge.labels.restriction_table`):
        1 if :math:`x_k \cup \ell_s \supseteq \ell_p`, :math:`w_{|\ell_p|}` if not.

        Returns
        -------
        ndarray, shape (num_labels,)
        """
        return self._posterior(k, self._log_score(k), siblings)

    def _log_score(self, k: int, free: bool = False) -> np.ndarray:
        """Unnormalised log of eq. 12 without the siblings' clash: evidence plus the log
        prior through the CPD (``free``: on the parents' :attr:`free_beliefs`), shape
        (num_labels,)."""
        g = self.graph
        node = g.nodes[k]
        score = g.evidence_loglik(k)
        if node.parents:
            table = g.cpd_table(k)
            corr = g.chain_log_ratio(k)
            if corr is not None:  # NetworkConfig.chain_palette: the parent's view alone
                table = table * np.exp(corr)
            beliefs = [self.belief_of(p, free) for p in node.parents]
            prior = np.einsum("i,ik->k", beliefs[0], table) if len(beliefs) == 1 else \
                np.einsum("i,j,ijk->k", beliefs[0], beliefs[1], table)
            with np.errstate(divide="ignore"):
                score = score + np.log(prior)
        return score

    def _posterior(self, k: int, score: np.ndarray, siblings: bool) -> np.ndarray:
        """Normalised ``exp(score)``, with the labelled siblings' clash if ``siblings``."""
        g = self.graph
        domain = g.nodes[k].domain
        for sib in g.siblings(k) if siblings else ():
            if sib in self.labels:
                weight = self._restriction_weights(k, domain, sib)
                if weight.any():
                    with np.errstate(divide="ignore"):
                        score = score + np.log(weight)
        score = score - score.max()
        post = np.exp(score)
        return post / post.sum()

    def _restriction_weights(self, k: int, domain: Sequence[Label], sib: int) -> np.ndarray:
        """Restriction node (eq. 5) between each label of ``domain`` for ``k`` and sibling
        ``sib``'s current label, as the window's CPD weighs it (``r = 1`` column of
        :meth:`~models.jorge.network.LabelGraph.restriction`): nested where the earlier of the two
        is the later's parent; with ``LabelParams.split_cover``, given the current label of
        their group (:meth:`~models.jorge.network.LabelGraph.cover_parent`). Shape
        (len(domain),), in [0, 1]."""
        g = self.graph
        i, j = sorted((k, sib))
        group = g.cover_parent(i, j)
        parent = [self.labels[group]] if group is not None and group in self.labels else None
        other = [self.labels[sib]]
        di, dj = (domain, other) if k < sib else (other, domain)
        return g.restriction(i, j, di, dj, parent)[..., 1].reshape(len(domain))

    def _free_posterior(self, k: int, score: np.ndarray) -> np.ndarray:
        """Eq. 12 posterior of ``k`` without the siblings' clash, on its parents'
        :attr:`free_beliefs` (``score``: :meth:`_log_score` on their beliefs, reused where
        no parent has a free belief of its own), shape (num_labels,)."""
        if any(p in self.free_beliefs for p in self.graph.nodes[k].parents):
            score = self._log_score(k, free=True)
        return self._posterior(k, score, siblings=False)

    def _relabel(self, k: int) -> None:
        """Eq. 12 posterior of ``k``, its domain capped to ``max_labels``, its label."""
        g = self.graph
        score = self._log_score(k)  # once: evidence and CPD are the costly part
        post = self._posterior(k, score, siblings=True)
        domain = g.nodes[k].domain
        keep = [frozenset({k})] + ([self.labels[k]] if k in self.labels else [])
        # ranked without the clash with the siblings' instant labels: those are point
        # guesses the next inference may revise, and a label they exclude (posterior 0)
        # would otherwise be the first the cap drops, for good (issue 16: the two parts of
        # a split swapped once new groups and joins widened the domains past the cap)
        free = self._free_posterior(k, score) if self.config.clash_free_rank else None
        if free is not None:
            rank = free
        else:
            rank = self._posterior(k, score, siblings=False) if len(domain) > self.config.max_labels else post
        kept = prune_labels(domain, rank, 0.0, keep=keep + [domain[int(np.argmax(post))]],
                            max_labels=self.config.max_labels)
        if len(kept) < len(domain):
            idx = [domain.index(lab) for lab in kept]
            g.set_domain(k, kept)
            self.instant_pruned_mass.append(float(1.0 - post[idx].sum()))
            post = post[idx] / post[idx].sum()
            free = None if free is None else free[idx] / free[idx].sum()
        self.beliefs[k] = post
        if free is not None and not np.array_equal(free, post):
            self.free_beliefs[k] = free
        else:
            self.free_beliefs.pop(k, None)
        self.labels[k] = g.nodes[k].domain[int(np.argmax(post))]
        if self.config.tentative_joiners:
            g.set_tentative_joiners({k: self.labels[k]})

    def add_stroke(self, stroke: Stroke, parents: Iterable[int] | None = None) -> Label:
        """Add a stroke that starts now; run any periodic inference due first.

        Parameters
        ----------
        stroke : Stroke
            The next stroke, in start order.
        parents : iterable of int, optional
            Its links, if the low-level tracker knows them
            (:meth:`models.jorge.network.LabelGraph.check_links`); ``None``: the
            on-line link rule.

        Returns
        -------
        Label
            Its instant label (eq. 12).

        Raises
        ------
        InputError, TimeOrderError
            Bad stroke or links (nothing changes).
        """
        self.graph.check_stroke(stroke)
        if parents is not None:
            parents = self.graph.check_links(stroke, parents)
        if self._next_inference is None:
            self._next_inference = stroke.start + self._period_frames
        while stroke.start >= self._next_inference:
            self.infer(int(np.floor(self._next_inference)))
            self._next_inference += self._period_frames
        k, widened = self.graph.add_stroke(stroke, parents, checked=True)
        for c in sorted(set(widened)):  # parents before children
            self._relabel(c)
        self._relabel(k)
        return self.labels[k]

    # --- eq. 11 ------------------------------------------------------------------------------
    def infer(self, frame: int) -> InferenceRecord | None:
        """Periodic inference over the active window; freezes older nodes, prunes domains
        (and with ``restore_successors``, gives back passed-on labels and solves again)."""
        g = self.graph
        n = len(g)
        if n == 0:
            return None
        t0 = time.perf_counter()
        cfg = self.config
        first_active = max(0, n - cfg.max_active)
        for k in range(first_active):
            if g.nodes[k].frozen is None:
                g.freeze(k, self.labels[k])
            self.free_beliefs.pop(k, None)
        active = list(range(first_active, n))
        win, log_prob, clique, pruned = self._window_pass(active)
        if cfg.marginals and cfg.restore_successors and self.restore_successors(active):
            # decide now, before later strokes are capped on the labels' zero beliefs
            first = (clique, pruned)
            win, log_prob, clique, pruned = self._window_pass(active)
            clique, pruned = max(clique, first[0]), max(pruned, first[1])
        self._inferred.update(active)
        if cfg.tentative_joiners:
            g.set_tentative_joiners({k: self.labels[k] for k in active})
        seconds = time.perf_counter() - t0
        rec = InferenceRecord(frame, len(active), len(win.boundary),
                              max(len(win.domains[node_name(k)]) for k in active), clique,
                              seconds, log_prob, pruned)
        self.records.append(rec)
        if self.keep_windows:
            self.windows.append(win)
        return rec

    def restore_successors(self, active: Sequence[int]) -> list[int]:
        """Give back to each active continuation (OCCLUSION) or merge (MERGE) node the label
        its parents' current labels pass on (the parent's label; the union of the two),
        where its domain lacks it; :meth:`infer` then runs the window once more, so the
        label can be chosen before later strokes are capped on its zero belief.

        A node's domain is capped (``max_labels``) when its stroke starts, on its parents'
        eq. 12 beliefs. When the next window relabels the parents, the label they now pass
        on may be gone from the child's domain, and the window can then only give the
        child a new object: a group's identity lost for good (issue 16, twenty-first round,
        found on SIMULATED meetings of four). The label enters with belief 0 (the window
        decides); at the cap it replaces the lowest-belief label other than the current one
        and the node's own new object. In stroke order, so a restored label is passed on
        down a chain of continuations and merges.

        Returns
        -------
        list of int
            The nodes given a label back.
        """
        g = self.graph
        passed: dict[int, Label] = {}
        for k in sorted(active):
            node = g.nodes[k]
            if node.frozen is not None or not node.parents or g.structure(k) not in ("OCCLUSION", "MERGE"):
                continue
            label = frozenset().union(*(passed.get(p, self.labels[p]) for p in node.parents))
            if label in node.domain or len(label) > g.config.labels.max_group_size:
                continue
            domain, belief = list(node.domain), self.beliefs[k]
            drop = None
            if len(domain) >= self.config.max_labels:  # at the cap: make room first
                fixed = {frozenset({k}), self.labels[k]}
                room = [i for i, lab in enumerate(domain) if lab not in fixed]
                if not room:  # max_labels 2: the current label and the new object stay
                    continue
                drop = min(room, key=lambda i: belief[i])
            if not g.widen(k, [label]):  # not admissible given the parents' domains
                continue
            if drop is not None:
                g.set_domain(k, domain[:drop] + domain[drop + 1:] + [label])
                belief = np.delete(belief, drop)
            belief = np.append(belief, 0.0)
            self.beliefs[k] = belief / belief.sum()
            self.free_beliefs.pop(k, None)  # its domain changed; the window runs next
            passed[k] = label
        return sorted(passed)

    def _window_pass(self, active: list[int]) -> tuple:
        """Eq. 11 over the window of ``active``: every active node takes its MAP label and,
        with ``marginals``, its domain pruned by its marginal and that marginal as its
        belief. Returns (window, MAP log probability, largest clique table, largest pruned
        mass)."""
        g, cfg = self.graph, self.config
        win = g.window(active)
        assignment, log_prob = map_assignment(win.bn, win.evidence, win.soft_evidence)
        clique = 0
        marg = None
        pruned = 0.0
        if cfg.marginals:
            cal = JunctionTree(win.bn).calibrate(win.evidence, win.soft_evidence)
            marg = cal.marginals
            clique = max(table.size for table in cal.clique_tables)
        for k in active:
            name = node_name(k)
            lab = win.domains[name][assignment[name]]
            self.labels[k] = lab
            if marg is not None:
                keep = [frozenset({k}), lab]
                dom = win.domains[name]
                kept = prune_labels(dom, marg[name], cfg.prune_threshold, keep=keep,
                                    max_labels=cfg.max_labels)
                idx = [dom.index(x) for x in kept]
                g.set_domain(k, kept)
                b = marg[name][idx]
                pruned = max(pruned, float(1.0 - b.sum()))
                self.beliefs[k] = b / b.sum() if b.sum() > 0 else np.full(len(idx), 1.0 / len(idx))
                self.free_beliefs.pop(k, None)  # the window's marginal: no instant clash
        return win, log_prob, clique, pruned

    def finish(self, frame: int | None = None) -> dict[int, Label]:
        """Final inference at the end of the sequence, then the re-identification pass
        (:func:`reidentify`, when ``reid_prior > 0``); returns every node's label.

        ``self.labels`` keeps the network's own labels (before re-identification)."""
        last = frame if frame is not None else max((nd.stroke.end for nd in self.graph.nodes), default=0)
        self.infer(int(last))
        labels = [self.labels[k] for k in range(len(self.graph))]
        if self.config.reid_prior > 0:
            labels = reidentify(self.graph, labels, self.config.reid_prior)
        return dict(enumerate(labels))


@dataclass(frozen=True)
class OnlineResult:
    """Labels of a whole sequence and the inference log.

    Attributes
    ----------
    labels : list of Label
        Final label per stroke (after the re-identification pass).
    network_labels : list of Label
        The network's own final labels (MAP at the last inference each node took part
        in), before re-identification.
    instant : list of Label
        Eq. 12 label given when each stroke started.
    records : list of InferenceRecord
    seconds : float
        Total labelling time (network building and inference).
    labeller : OnlineLabeller
    """

    labels: list
    network_labels: list
    instant: list
    records: list
    seconds: float
    labeller: OnlineLabeller


def _frame_rate(strokes: StrokeSet | Sequence[Stroke], fps: float | None) -> float:
    """The strokes' frame rate for :func:`label_online`: a :class:`StrokeSet`'s own, else
    ``fps``, which a plain sequence must give (:class:`InputError` otherwise)."""
    own = strokes.fps if isinstance(strokes, StrokeSet) else None
    if fps is not None:
        fps = check_frame_rate(fps, "label_online", InputError)
    if fps is None and own is None:
        raise InputError("label_online: a plain sequence of strokes carries no frame rate; give fps= "
                         "(the link gates are in seconds) or pass the StrokeSet")
    if fps is not None and own is not None and not np.isclose(fps, own):
        raise InputError(f"label_online: fps={fps} differs from the StrokeSet's own fps={own}")
    return float(own if fps is None else fps)


def label_online(strokes: StrokeSet | Sequence[Stroke], config: OnlineConfig | None = None,
                 fps: float | None = None, keep_windows: bool = False,
                 links: Sequence[Iterable[int]] | None = None) -> OnlineResult:
    """Run the on-line labeller over a stroke set (seed 004, sec. 5).

    Parameters
    ----------
    strokes : StrokeSet or sequence of Stroke
        In start order.
    config : OnlineConfig, optional
    fps : float, optional
        Frames per second of the strokes' frame numbers: the link gates, the sibling
        window and the inference period are set in seconds. A :class:`StrokeSet` carries
        its own (``None`` takes it; a different value is an error); a plain sequence of
        strokes carries none, so it must be given (a list cut from a PETS2009 stroke set,
        7 fps, labelled at an assumed 25 fps would gate links 3.6 times too wide).
    keep_windows : bool
    links : sequence of iterable of int, optional
        Each stroke's parents (length num_strokes), e.g. :func:`true_links`; ``None``:
        the on-line link rule.

    Returns
    -------
    OnlineResult

    Raises
    ------
    InputError
        ``links`` not one entry per stroke, or a bad link; ``fps`` missing for a plain
        sequence, or not the :class:`StrokeSet`'s own.
    """
    fps = _frame_rate(strokes, fps)
    strokes = list(strokes)
    if links is not None and len(links) != len(strokes):
        raise InputError(f"label_online: {len(links)} link sets for {len(strokes)} strokes")
    lab = OnlineLabeller(config, fps, keep_windows)
    t0 = time.perf_counter()
    if links is None:
        instant = [lab.add_stroke(s) for s in strokes]
    else:
        instant = [lab.add_stroke(s, par) for s, par in zip(strokes, links)]
    final = lab.finish()
    seconds = time.perf_counter() - t0
    return OnlineResult([final[k] for k in range(len(final))], [lab.labels[k] for k in range(len(final))],
                        instant, lab.records, seconds, lab)


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
    labels = list(labels)
    if len(labels) != len(graph):
        raise InputError(f"reidentify: {len(labels)} labels for {len(graph)} nodes")
    if not 0.0 < prior < 1.0:
        raise InputError(f"reidentify: prior must be in (0, 1), got {prior}")
    if not labels:
        return []
    # one pass can miss a renaming because a candidate set was larger when the object was
    # examined than after later renamings; repeat until nothing changes (each pass only
    # merges objects, so at most num_objects passes)
    while True:
        renamed = _reidentify_pass(graph, labels, prior)
        if renamed == labels:
            return renamed
        labels = renamed


def _reidentify_pass(graph: LabelGraph, labels: list, prior: float) -> list:
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
        singles = [int(k) for k in np.flatnonzero(member[i]) if labels[k] == frozenset({b})] if cands else []
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
        score += colour_log_likelihood(np.flatnonzero(palettes[-1]), palettes[:-1], np.zeros(len(cands), dtype=bool),
                                       cfg.match_prob, cfg.pool_size, cfg.colour_mode)
        for k in singles:
            if k == own:
                continue  # given b's palette, the stroke it came from says nothing more
            ll = colour_log_likelihood(graph.nodes[k].stroke.colours, palettes, np.zeros(len(cands) + 1, dtype=bool),
                                       cfg.match_prob, cfg.pool_size, cfg.colour_mode)
            score += ll[:-1] - ll[-1]
        best = int(np.argmax(score))
        if score[best] > 0:
            a = cands[best]
            alias[b] = a
            last[a] = max(last[a], last[b])
        else:
            roots.append(b)
    return [frozenset(alias.get(o, o) for o in lab) for lab in labels]


# --------------------------------------------------------------------------------------------
# scoring
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Score:
    """Labelling errors (seed 004, Table 3) and identity switches.

    Attributes
    ----------
    label_errors : int
        LE, strokes whose label stands for a set of people other than the true set.
    num_strokes : int
        NT.
    error_rate : float
        LE / NT.
    id_switches : int
    errors : tuple of int
        Indices of the mislabelled strokes.
    """

    label_errors: int
    num_strokes: int
    error_rate: float
    id_switches: int
    errors: tuple


def object_people(strokes: Sequence[Stroke]) -> dict[int, int | None]:
    """Who each object id stands for (module docstring): ``o -> person`` or ``None``."""
    out: dict[int, int | None] = {}
    claimed: set[int] = set()
    for s in strokes:
        if len(s.truth) == 1:
            (p,) = tuple(s.truth)
            if p not in claimed:
                out[s.index] = p
                claimed.add(p)
                continue
        out[s.index] = None
    return out


def optimal_people(strokes: Sequence[Stroke], labels: Sequence[Label]) -> dict[int, int | None]:
    """Who each object id stands for under the best one-to-one matching of objects and
    people (as IDF1 does for identities): the matching maximises the number of strokes in
    which object and person occur together (Hungarian algorithm); unmatched objects stand
    for nobody."""
    objects = sorted({o for lab in labels for o in lab})
    persons = sorted({p for s in strokes for p in s.truth})
    out: dict[int, int | None] = {o: None for o in objects}
    if not objects or not persons:
        return out
    oi = {o: i for i, o in enumerate(objects)}
    pi = {p: j for j, p in enumerate(persons)}
    weight = np.zeros((len(objects), len(persons)))
    for s, lab in zip(strokes, labels):
        rows = [oi[o] for o in lab]
        cols = [pi[p] for p in s.truth]
        weight[np.ix_(rows, cols)] += 1.0
    r, c = linear_sum_assignment(weight, maximize=True)
    for i, j in zip(r, c):
        if weight[i, j] > 0:
            out[objects[i]] = persons[j]
    return out


def score(strokes: Sequence[Stroke], labels: Sequence[Label], mapping: str = "optimal") -> Score:
    """LE, LE / NT and identity switches of a labelling.

    Parameters
    ----------
    strokes : sequence of Stroke, length num_strokes
        With their true sets.
    labels : sequence of Label, length num_strokes
        Label of each stroke (sets of object ids, object ``o`` = first seen in stroke ``o``).
    mapping : {"optimal", "first_seen"}
        How object ids are matched to people: the best one-to-one matching
        (:func:`optimal_people`, default) or the person of the stroke where the object was
        first seen, if not already claimed (:func:`object_people`, stricter: one early
        mistake makes every later stroke of that person an error).

    Returns
    -------
    Score
    """
    strokes = list(strokes)
    labels = list(labels)
    if len(labels) != len(strokes):
        raise InputError(f"score: {len(labels)} labels for {len(strokes)} strokes")
    known = {s.index for s in strokes}
    for s, lab in zip(strokes, labels):
        unknown = [o for o in lab if birth_stroke(o) not in known]
        if unknown or not lab:
            raise InputError(f"score: stroke {s.index} has label {set(lab)} with unknown object ids {unknown}")
    if mapping == "optimal":
        people = optimal_people(strokes, labels)
    elif mapping == "first_seen":
        people = object_people(strokes)
    else:
        raise InputError(f"score: mapping must be 'optimal' or 'first_seen', got {mapping!r}")
    errors = []
    for s, lab in zip(strokes, labels):
        meant = {people[o] if people.get(o) is not None else ("nobody", o) for o in lab}
        if meant != set(s.truth):
            errors.append(s.index)
    switches = 0
    last: dict[int, Label] = {}
    for s, lab in zip(strokes, labels):
        if len(s.truth) == 1:
            (p,) = tuple(s.truth)
            if p in last and last[p] != lab:
                switches += 1
            last[p] = lab
    n = len(strokes)
    return Score(len(errors), n, len(errors) / n if n else 0.0, switches, tuple(errors))


def first_errors(strokes: Sequence[Stroke], errors: Iterable[int]) -> tuple:
    """The labelling errors that are first mistakes: strokes in error none of whose true
    predecessors (for each of its people, the latest earlier stroke holding that person,
    ended before it starts) is in error. The other errors are carried: a wrong label
    inherited along the links.

    Parameters
    ----------
    strokes : sequence of Stroke, length num_strokes
        In start order, with their true sets.
    errors : iterable of int
        Indices of the mislabelled strokes (:attr:`Score.errors`).

    Returns
    -------
    tuple of int
        The first mistakes, in index order.
    """
    strokes = list(strokes)
    bad = set(int(e) for e in errors)
    unknown = sorted(e for e in bad if not 0 <= e < len(strokes))
    if unknown:
        raise InputError(f"first_errors: error indices {unknown} outside 0..{len(strokes) - 1}")
    preds = true_predecessors(strokes)
    return tuple(k for k in sorted(bad) if not preds[k] & bad)


def after_crowd(strokes: Sequence[Stroke], max_group_size: int) -> np.ndarray:
    """Strokes one of whose people was earlier in a crowd: a stroke of more than
    ``max_group_size`` people that ended before this one starts.

    A label holds at most ``max_group_size`` objects, so a crowd's label leaves some of its
    people out, and a later stroke of one of them inherits a label that does not hold
    them (a diagnosis of the benchmark; nothing is chosen on it).

    Parameters
    ----------
    strokes : sequence of Stroke, length num_strokes
        With their true sets.
    max_group_size : int
        The label network's ``labels.max_group_size``.

    Returns
    -------
    ndarray of bool, shape (num_strokes,)
    """
    if isinstance(max_group_size, bool) or not isinstance(max_group_size, int | np.integer) or max_group_size < 1:
        raise InputError(f"after_crowd: max_group_size must be an int >= 1, got {max_group_size!r}")
    strokes = list(strokes)
    first_crowd_end: dict[int, int] = {}  # person -> the earliest end of a crowd stroke holding them
    for s in strokes:
        if len(s.truth) > max_group_size:
            for p in s.truth:
                first_crowd_end[p] = min(first_crowd_end.get(p, s.end), s.end)
    return np.array([any(first_crowd_end.get(p, s.start) < s.start for p in s.truth) for s in strokes], dtype=bool)


def true_predecessors(strokes: Sequence[Stroke]) -> list[frozenset]:
    """For each stroke, its true predecessors: for each of its people, the latest earlier
    stroke holding that person that ended before it starts (the links a perfect stroke
    graph would have; :func:`first_errors` uses the same rule).

    Returns
    -------
    list of frozenset of int, length num_strokes
    """
    strokes = list(strokes)
    latest: dict[int, list[int]] = {}
    out = []
    for k, s in enumerate(strokes):
        preds = set()
        for p in s.truth:
            earlier = [i for i in latest.get(p, []) if strokes[i].end < s.start]
            if earlier:
                preds.add(max(earlier, key=lambda i: strokes[i].end))
        out.append(frozenset(preds))
        for p in s.truth:
            latest.setdefault(p, []).append(k)
    return out


def true_links(strokes: Sequence[Stroke], max_parents: int = 2, max_children: int = 2) -> list[tuple]:
    """The true predecessors (:func:`true_predecessors`) as links the label network can
    hold: at most ``max_parents`` per stroke (the latest-ending first) and
    ``max_children`` per parent (first come), for :func:`label_online` ``links=`` (the
    oracle that measures what the on-line link rule costs; issue 16 diagnosis).

    Returns
    -------
    list of tuple of int, length num_strokes
    """
    strokes = list(strokes)
    children: dict[int, int] = {}
    out = []
    for preds in true_predecessors(strokes):
        kept = [p for p in sorted(preds, key=lambda i: (-strokes[i].end, i))
                if children.get(p, 0) < max_children][:max_parents]
        for p in kept:
            children[p] = children.get(p, 0) + 1
        out.append(tuple(sorted(kept)))
    return out


def link_accuracy(strokes: Sequence[Stroke], parents: Sequence[Iterable[int]]) -> float:
    """Share of strokes whose parents in the label network are exactly their true
    predecessors (:func:`true_predecessors`): how well the on-line link rule recovers
    the stroke graph (issue 16 diagnosis; about 0.5 in the PETS2009 S1 crowds, 0.7-0.95
    on CAVIAR).

    Raises
    ------
    InputError
        ``parents`` not one entry per stroke.
    """
    strokes = list(strokes)
    if len(parents) != len(strokes):
        raise InputError(f"link_accuracy: {len(parents)} parent sets for {len(strokes)} strokes")
    if not strokes:
        return float("nan")
    truth = true_predecessors(strokes)
    return float(np.mean([frozenset(int(p) for p in par) == t for par, t in zip(parents, truth)]))


def colour_only_labels(strokes: Iterable[Stroke], max_group_size: int = 3, match_prob: float = 0.8,
                       pool_size: int = 12, mode: str = "ratio") -> list[Label]:
    """Baseline without the network: each stroke takes the label whose palette matches
    its colours best (eq. 6 alone), among the objects seen so far, their groups of up to
    ``max_group_size``, and a new object (log-likelihood ratio 0 in the default mode).

    Parameters
    ----------
    strokes : iterable of Stroke
        In start order.
    max_group_size : int
    match_prob : float
    pool_size : int
    mode : {"ratio", "eq6"}

    Returns
    -------
    list of Label
        One per stroke; a stroke labelled new founds object ``stroke.index``.
    """
    objects: list[int] = []
    palettes: dict[int, np.ndarray] = {}
    out: list[Label] = []
    for s in strokes:
        new = frozenset({s.index})
        own = np.zeros(pool_size, dtype=bool)
        own[s.palette] = True
        cands: list[Label] = [new]
        blocks = [own[None]]
        obj_pal = np.array([palettes[o] for o in objects]).reshape(len(objects), pool_size)
        for r in range(1, min(max_group_size, len(objects)) + 1):
            idx = np.array(list(itertools.combinations(range(len(objects)), r)), dtype=np.int64)
            cands += [frozenset(objects[i] for i in row) for row in idx]
            blocks.append(obj_pal[idx].any(axis=1))
        pal = np.concatenate(blocks, axis=0)
        is_new = np.zeros(len(cands), dtype=bool)
        is_new[0] = True
        ll = colour_log_likelihood(s.colours, pal, is_new, match_prob, pool_size, mode)
        best = cands[int(np.argmax(ll))]
        if best == new:
            objects.append(s.index)
            palettes[s.index] = own
        out.append(best)
    return out
