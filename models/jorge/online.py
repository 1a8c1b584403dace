r"""On-line labelling (seed 004, section 5): periodic exact inference over a window of the
most recent strokes, instant labels between inferences, and the final re-identification.

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
    parents)``, ``label_online(..., links=...)``);
    :func:`models.jorge.scoring.true_links` gives the true predecessors, the oracle with
    which the benchmark measures what the link rule costs.

Object re-identification and scoring
    After the last inference, :func:`models.jorge.reid.reidentify` renames objects born
    new that are earlier objects seen again (``reid_prior``; 0 turns it off). Scoring,
    the true stroke graph and the colour-only baseline are in
    :mod:`models.jorge.scoring`; their names are also importable from here, as before.
"""

from __future__ import annotations

import time
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np

from dbn.checks import check_number_fields, check_type
from dbn.errors import InputError, ModelError
from inference.exact import JunctionTree, map_assignment
from models.jorge.labels import Label, prune_labels
from models.jorge.network import LabelGraph, NetworkConfig, check_frame_rate, node_name
from models.jorge.reid import object_aliases, reidentify, renamed
from models.jorge.scoring import (  # re-exported: these lived here before they had a module
    Score,
    after_crowd,
    colour_only_labels,
    first_errors,
    link_accuracy,
    object_people,
    optimal_people,
    score,
    true_links,
    true_predecessors,
)
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
        object seen again (final re-identification pass,
        :func:`models.jorge.reid.reidentify`); 0 turns the pass off.
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
        check_number_fields(self, ModelError)
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
    periodic_inferences : int
        How many of ``records`` :meth:`add_stroke` ran (the rest: :meth:`infer` or
        :meth:`finish` called from outside).
    instant_pruned_mass : list of float
        Posterior mass dropped each time a new node's eq. 12 posterior was capped to
        ``max_labels`` labels.
    free_beliefs : dict int -> ndarray
        With ``clash_free_rank``: the eq. 12 posterior without the siblings' clash, up the
        chain, of each node created since the last inference where it differs from its
        belief (the cap's ranking; dropped at the next inference).
    aliases : dict int -> int
        The renaming of the last re-identification pass (:meth:`finish`;
        :func:`models.jorge.reid.object_aliases`): each renamed object's final id; empty
        before it, or with ``reid_prior`` 0.
    """

    def __init__(self, config: OnlineConfig | None = None, fps: float | None = None,
                 keep_windows: bool = False) -> None:
        self.config = OnlineConfig() if config is None else check_type("config", config,
                                                                       OnlineConfig)
        self.graph = LabelGraph(self.config.network, fps=fps)  # checks fps
        self.fps = self.graph.fps
        self.labels: dict[int, Label] = {}
        self.beliefs: dict[int, np.ndarray] = {}
        self.free_beliefs: dict[int, np.ndarray] = {}
        self.records: list[InferenceRecord] = []
        self.periodic_inferences = 0
        self.windows: list = []
        self.keep_windows = keep_windows
        self._period_frames = self.config.period_s * self.fps
        if self._period_frames < 1.0:  # fps = 1e-9 ran 1e11 inferences per 100 frames (a hang)
            raise ModelError(
                f"OnlineConfig.period_s x fps = {self.config.period_s:g} s x {self.fps:g} fps = "
                f"{self._period_frames:g} frames: the inference period must span at least one "
                f"frame (period_s, the config's online.period_s, >= {1.0 / self.fps:g} s here)"
            )
        self._next_inference: float | None = None
        self._inferred: set[int] = set()
        self.instant_pruned_mass: list[float] = []
        self.aliases: dict[int, int] = {}

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
        before = len(self.records)
        while stroke.start >= self._next_inference:
            self.infer(int(np.floor(self._next_inference)))
            self._next_inference += self._period_frames
        self.periodic_inferences += len(self.records) - before
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
        (:func:`models.jorge.reid.reidentify`, when ``reid_prior > 0``); returns every
        node's label.

        ``self.labels`` keeps the network's own labels (before re-identification),
        ``self.aliases`` the renaming."""
        last = frame if frame is not None else max((nd.stroke.end for nd in self.graph.nodes), default=0)
        self.infer(int(last))
        labels = [self.labels[k] for k in range(len(self.graph))]
        if self.config.reid_prior > 0:
            self.aliases = object_aliases(self.graph, labels, self.config.reid_prior)
            labels = [renamed(lab, self.aliases) for lab in labels]
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
