r"""The label network of seed 004 (section 4), built with :mod:`dbn` and solved with
:mod:`inference.exact`.

Nodes: a hidden label node ``x{k}`` per stroke ``k`` (its states are the admissible labels
:math:`L_k`, :mod:`models.jorge.labels`), a binary restriction node ``r{i}_{j}`` for every
pair of children sharing a parent (observed :math:`r = 1`, eq. 5, hard evidence; with
``LabelParams.split_cover``, on by default since issue 16's twenty-second round, the shared
parent is its parent too and a split that loses people weighs less,
:data:`FITTED_SPLIT_COVER`, and since the twenty-third the node is normalised so that it
does not weigh a large group down, ``LabelParams.split_normalise``), and the stroke's
dominant colours as soft (virtual) evidence on ``x{k}`` (eq. 6; proper likelihood
ratio by default, the equation as written as an option), times, where the stroke has a
recorded region size, the size evidence on the number of people of the label
(:func:`models.jorge.evidence.size_log_likelihood`; our addition, ``size_evidence``).

Links (seed 004, sec. 4): the on-line link rule and the check of given links are in
:mod:`models.jorge.links` (:class:`~models.jorge.links.LinkRule`, a mixin of
:class:`LabelGraph`); the Bayes net of an inference window and its exact solution in
:mod:`models.jorge.window` (this module still exports their names).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from dbn.checks import check_type
from dbn.errors import InputError, ModelError, ShapeError, TimeOrderError
from models.jorge.config import (
    FITTED_LABELS,
    FITTED_PALETTE_COUNTS,
    FITTED_PALETTE_GAINS,
    FITTED_PALETTE_MISSING,
    FITTED_SPLIT_COVER,
    NetworkConfig,
)
from models.jorge.evidence import (
    colour_log_likelihood,
    palette_count_log_likelihood,
    palette_gain_log_likelihood,
    palette_missing_log_likelihood,
    size_log_likelihood,
)
from models.jorge.labels import (
    Label,
    LabelObjects,
    admissible_labels,
    birth_stroke,
    child_table,
    cohort_size,
    label_objects,
    restriction_table,
    root_table,
    structure_of,
    union_rows,
)
from models.jorge.links import LinkRule
from models.jorge.memo import ChainMemo, EvidenceMemo, TableMemo
from models.jorge.strokes import MAX_PIXELS as _MAX_PIXELS
from models.jorge.strokes import Stroke, _check_colours, check_frame_rate
from models.jorge.window import (
    Inference,
    WindowNet,
    build_window,
    colour_name,
    kept_name,
    node_name,
    restriction_name,
    solve,
)

__all__ = [
    "NetworkConfig",
    "FITTED_LABELS",
    "FITTED_PALETTE_COUNTS",
    "FITTED_PALETTE_GAINS",
    "FITTED_PALETTE_MISSING",
    "FITTED_SPLIT_COVER",
    "LabelGraph",
    "WindowNet",
    "Inference",
    "node_name",
    "restriction_name",
    "kept_name",
    "colour_name",
    "solve",
]


@dataclass
class _Node:
    stroke: Stroke
    parents: tuple[int, ...]
    children: list[int]
    domain: tuple[Label, ...]
    frozen: Label | None = None
    rel_log_area: float = float("nan")


class LabelGraph(LinkRule):
    """The growing graph of strokes, links and label domains (seed 004, secs. 4-5).

    Strokes are added in start order (:meth:`add_stroke`); each new node gets its parents
    among the strokes that ended before it started and its admissible labels from its
    parents' current domains; the link rule is the :class:`~models.jorge.links.LinkRule`
    it inherits. Nodes can be frozen to one label (:meth:`freeze`) and domains pruned
    (:meth:`set_domain`); :meth:`window` turns a set of active nodes into a
    :class:`WindowNet` for exact inference (:mod:`models.jorge.window`).

    Parameters
    ----------
    config : NetworkConfig
    with_domains : bool
        Compute label domains (``False``: links only, for counting training events).
    fps : float
        Frame rate of the strokes (the ``"scaled"`` link gate works in seconds). Required:
        no rate is assumed.
    """

    def __init__(self, config: NetworkConfig | None = None, with_domains: bool = True,
                 fps: float | None = None) -> None:
        self.config = (NetworkConfig() if config is None  # a dict raised AttributeError
                       else check_type("config", config, NetworkConfig, InputError))  # fmt: skip
        self.fps = check_frame_rate(fps, "LabelGraph")
        self.with_domains = with_domains
        self.nodes: list[_Node] = []
        n0 = 16
        self._end = np.zeros(n0, dtype=np.int64)
        self._end_pos = np.zeros((n0, 2))
        self._end_ext = np.full((n0, 2), np.nan)
        self._nchild = np.zeros(n0, dtype=np.int64)
        self._palettes = np.zeros((n0, self.config.pool_size), dtype=bool)
        self._log_area = np.full(n0, np.nan)
        self._foot_y = np.full(n0, np.nan)
        self._scale = np.full(n0, np.nan)
        self._own: dict[int, int] = {}  # member of a new group or joiner -> stroke with its own palette
        self._joiners: dict[int, Label] = {}  # joiner -> its birth label (frozen, or tentative)
        self._tentative: dict[int, list[int]] = {}  # unfrozen node -> its tentative joiners
        # unfrozen node -> what it remembers of its CPD table, colour evidence, chain ratio
        self._cpd_memo: dict[int, TableMemo] = {}
        self._evidence_memo: dict[int, EvidenceMemo] = {}
        self._chain_memo: dict[int, ChainMemo] = {}
        self._rel_memo: dict[int, tuple] = {}  # node -> (strokes seen, config, rel_log_area)
        self._gain_table = np.asarray(self.config.palette_gain_table, dtype=np.float64)
        self._gain_bins = self.config.palette_gain_bins if self._gain_table.ndim == 3 else ()
        self._count_table = np.asarray(self.config.palette_count_table, dtype=np.float64)
        self._missing_table = np.asarray(self.config.palette_missing_table, dtype=np.float64)

    # --- growth --------------------------------------------------------------------------
    def __len__(self) -> int:
        return len(self.nodes)

    def _grow(self) -> None:
        n = self._end.shape[0] * 2
        for name in ("_end", "_end_pos", "_end_ext", "_nchild", "_palettes", "_log_area", "_foot_y", "_scale"):
            old = getattr(self, name)
            new = np.full((n, *old.shape[1:]), np.nan) if name in ("_log_area", "_foot_y", "_scale", "_end_ext") else \
                np.zeros((n, *old.shape[1:]), dtype=old.dtype)
            new[: old.shape[0]] = old
            setattr(self, name, new)

    def check_stroke(self, stroke: Stroke) -> None:
        """Raise if ``stroke`` cannot be the next node (nothing is changed).

        Raises
        ------
        InputError
            Wrong index, bad colours.
        TimeOrderError
            Ends before it starts, or starts before the previous stroke.
        """
        k = len(self.nodes)
        if not isinstance(stroke, Stroke):  # a str's .index method passed the check below
            raise InputError(f"stroke {k}: expected a Stroke (or a LinkedStroke), got "
                             f"{type(stroke).__name__}")  # fmt: skip
        for name in ("index", "start", "end"):
            v = getattr(stroke, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)):
                raise InputError(f"stroke {k}: {name} must be an int, got {v!r}")
        if stroke.index != k:
            raise InputError(f"stroke index {stroke.index}: the next stroke must have index {k}")
        if stroke.end < stroke.start:
            raise TimeOrderError(f"stroke {k}: end frame {stroke.end} is before start frame {stroke.start}")
        if self.nodes and stroke.start < self.nodes[-1].stroke.start:
            raise TimeOrderError(
                f"stroke {k} starts at frame {stroke.start}, before stroke {k - 1} "
                f"(frame {self.nodes[-1].stroke.start}): strokes must come in start order"
            )
        _check_colours(k, stroke.colours, self.config.pool_size)
        _check_palette(k, stroke.palette, self.config.pool_size)
        pos = np.asarray(stroke.positions)
        if pos.ndim != 2 or pos.shape[1] != 2 or pos.shape[0] < 1:
            raise InputError(f"stroke {k}: positions must have shape (num_points, 2), got {pos.shape}")
        if not np.issubdtype(pos.dtype, np.number) or np.iscomplexobj(pos):
            raise InputError(f"stroke {k}: positions must be real numbers, got dtype {pos.dtype}")
        if not np.all(np.isfinite(pos)) or np.any(np.abs(pos) > _MAX_PIXELS):
            raise InputError(f"stroke {k}: positions must be finite pixels, |x| <= {_MAX_PIXELS:g}")
        _check_frames(k, stroke, pos.shape[0])
        ext = getattr(stroke, "extent", None)
        if ext is not None:
            ext = np.asarray(ext)
            if not np.issubdtype(ext.dtype, np.number) or np.iscomplexobj(ext):
                raise InputError(f"stroke {k}: extent must be real numbers, got dtype {ext.dtype}")
            ext = ext.astype(np.float64)
            if ext.shape != pos.shape:
                raise ShapeError(f"stroke {k}: extent must have shape {pos.shape}, got {ext.shape}")
            if not np.all(np.isfinite(ext)) or np.any(ext <= 0) or np.any(ext > _MAX_PIXELS):
                raise InputError(
                    f"stroke {k}: region extent (width, height) must be in (0, {_MAX_PIXELS:g}] pixels"
                )

    def add_stroke(self, stroke: Stroke, parents: Iterable[int] | None = None, *,
                   checked: bool = False) -> tuple[int, list[int]]:
        """Add the node of a new stroke (validated first: nothing changes on error).

        Parameters
        ----------
        stroke : Stroke
            The next stroke, in start order.
        parents : iterable of int, optional
            Its links, checked by :meth:`check_links`; ``None`` (default): the on-line
            link rule, :meth:`candidate_parents`.
        checked : bool
            The caller has just run :meth:`check_stroke` on ``stroke`` and, if given,
            ``parents`` is what :meth:`check_links` returned for it: not checked again.

        Returns
        -------
        k : int
            The node index (= stroke index).
        widened : list of int
            Earlier children of the new node's parents whose domain grew because their
            parent now splits (eq. 9).
        """
        if not checked:
            self.check_stroke(stroke)
        k = len(self.nodes)
        if parents is None:
            parents = tuple(int(p) for p in sorted(self.candidate_parents(stroke)))
        elif not checked:
            parents = self.check_links(stroke, parents)
        if k >= self._end.shape[0]:
            self._grow()
        self._end[k] = stroke.end
        self._end_pos[k] = stroke.positions[-1]
        self._palettes[k, stroke.palette] = True
        rel = float("nan")
        ext = getattr(stroke, "extent", None)
        if ext is not None:
            self._log_area[k] = float(np.median(np.log(ext[:, 0] * ext[:, 1])))
            self._foot_y[k] = float(np.median(stroke.positions[:, 1] + ext[:, 1] / 2))
            self._scale[k] = float(np.median(np.sqrt(ext[:, 0] * ext[:, 1])))
            self._end_ext[k] = ext[-1]
        for p in parents:
            self._nchild[p] += 1
            self.nodes[p].children.append(k)
        node = _Node(stroke, parents, [], (), rel_log_area=rel)
        self.nodes.append(node)
        node.rel_log_area = self.rel_log_area(k)  # as seen when the stroke starts
        if not self.with_domains:
            return k, []
        node.domain = self.admissible(k)
        # a parent that now splits changes its other child's structure: widen that domain
        widened = []
        for p in parents:
            for c in self.nodes[p].children:
                if c != k and self.nodes[c].frozen is None and len(self.nodes[p].children) == 2:
                    if self._extend_domain(c, self.admissible(c)):
                        widened.append(c)
        return k, widened

    # --- accessors -----------------------------------------------------------------------
    def parent_domains(self, k: int) -> list[tuple[Label, ...]]:
        """Current domains of node ``k``'s parents (a frozen parent: its label alone)."""
        return [self.current_domain(p) for p in self.nodes[k].parents]

    def cover_parent(self, i: int, j: int) -> int | None:
        """The group whose split the restriction node of siblings ``i < j`` weighs with
        ``LabelParams.split_cover`` (:func:`models.jorge.labels.restriction_table`): their one
        shared parent, if the option is on and the link is not nested; else None."""
        if not len(self.config.labels.split_cover) or self.nested(i, j):
            return None
        shared = set(self.nodes[i].parents) & set(self.nodes[j].parents)
        return min(shared) if len(shared) == 1 else None

    def shared(self, k: int) -> list[bool]:
        """For each parent of ``k``: whether it has a second child."""
        return [len(self.nodes[p].children) >= 2 for p in self.nodes[k].parents]

    def current_domain(self, k: int) -> tuple[Label, ...]:
        """The node's domain, or its frozen label alone."""
        node = self.nodes[k]
        return (node.frozen,) if node.frozen is not None else node.domain

    def structure(self, k: int) -> str:
        """Basic structure (fig. 3) of node ``k``."""
        return structure_of(len(self.nodes[k].parents), self.shared(k))

    def siblings(self, k: int) -> list[int]:
        """Other children of ``k``'s parents."""
        out = []
        for p in self.nodes[k].parents:
            out += [c for c in self.nodes[p].children if c != k and c not in out]
        return out

    def admissible(self, k: int, parent_domains: Sequence[Sequence[Label]] | None = None
                   ) -> tuple[Label, ...]:
        """Admissible labels of node ``k`` (:func:`~models.jorge.labels.admissible_labels`
        with this network's label parameters) given ``parent_domains``: one sequence of
        labels per parent of ``k``, in the order of its ``parents`` (default: their
        current domains, :meth:`parent_domains`). A node's domain starts as this set.

        Raises
        ------
        InputError
            ``k`` not a node, or not one sequence of labels per parent.
        """
        if not 0 <= k < len(self.nodes):
            raise InputError(f"admissible: no node {k} (the network has {len(self.nodes)})")
        if parent_domains is None:
            parent_domains = self.parent_domains(k)
        elif len(parent_domains) != len(self.nodes[k].parents):
            raise InputError(f"admissible: node {k} has {len(self.nodes[k].parents)} parents, "
                             f"got {len(parent_domains)} parent domains")
        labels = self.config.labels
        return tuple(
            admissible_labels(parent_domains, self.shared(k), frozenset({k}),
                              labels.max_group_size, labels.p_part > 0,
                              max_new=self._max_new(k), join=labels.p_join > 0)
        )

    def _max_new(self, k: int) -> int:
        labels = self.config.labels
        return len(labels.new_group_probs) if labels.child_new_groups or not self.nodes[k].parents else 1

    def palette_stroke(self, o: int) -> int:
        """The stroke whose palette object ``o`` has: its birth stroke (sec. 4.1), or for a
        member of a new group or a joiner the first stroke frozen to it alone
        (:meth:`freeze`), once there is one."""
        return self._own.get(int(o), birth_stroke(o))

    def palettes(self, domain: Sequence[Label]) -> np.ndarray:
        """Palette of each label: the union of its objects' palettes
        (:meth:`palette_stroke`; the members of a new group share their birth stroke's
        palette until one is frozen alone).

        Returns
        -------
        ndarray of bool, shape (num_labels, pool_size)
        """
        obj = label_objects(domain, -1, self._own, self._joiners)
        return union_rows(self._palettes, obj.palette_strokes, obj.sizes)

    def colour_loglik(self, k: int, domain: Sequence[Label] | None = None, mode: str | None = None,
                      objects: LabelObjects | None = None) -> np.ndarray:
        """Colour log-likelihood of stroke ``k`` for each label of ``domain`` (eq. 6);
        ``objects``: :func:`models.jorge.labels.label_objects` of ``domain`` at ``k`` if
        already computed.

        Returns
        -------
        ndarray, shape (num_labels,)
        """
        domain = self.nodes[k].domain if domain is None else domain
        obj = label_objects(domain, k, self._own, self._joiners) if objects is None else objects
        # a new label's palette comes from this stroke itself (seed 004, sec. 4.1)
        # (``Stroke.palette``): a label holding an object born here (a new group, or an
        # inherited label joined by a newcomer) gets no colour evidence (ratio 1)
        return colour_log_likelihood(
            self.nodes[k].stroke.colours, union_rows(self._palettes, obj.palette_strokes, obj.sizes),
            obj.is_new, self.config.match_prob, self.config.pool_size,
            self.config.colour_mode if mode is None else mode,
        )

    def rel_log_area(self, k: int) -> float:
        """Log area of stroke ``k``'s region minus the reference: the
        ``size_reference_quantile`` of the log areas of the ``size_reference_neighbours``
        strokes seen so far whose region's bottom edge (the feet, on the ground plane) is
        nearest in image height to stroke ``k``'s (itself included; people nearer the
        camera are larger). NaN: no recorded size, or fewer than ``size_min_reference``
        others. Remembered per node until the next stroke (it depends only on the strokes
        seen so far and the config; a node is scored many times between two strokes)."""
        n = len(self.nodes)
        hit = self._rel_memo.get(k)
        if hit is not None and hit[0] == n and hit[1] is self.config:
            return hit[2]
        value = self._new_rel_log_area(k, n)
        self._rel_memo[k] = (n, self.config, value)
        return value

    def _new_rel_log_area(self, k: int, n: int) -> float:
        """:meth:`rel_log_area` of stroke ``k`` over the first ``n`` strokes, computed."""
        own = self._log_area[k]
        if not np.isfinite(own):
            return float("nan")
        ok = np.flatnonzero(np.isfinite(self._log_area[:n]))
        if ok.size - 1 < self.config.size_min_reference:
            return float("nan")
        m = self.config.size_reference_neighbours
        if 0 < m < ok.size:
            near = np.argpartition(np.abs(self._foot_y[ok] - self._foot_y[k]), m - 1)[:m]
            ok = ok[near]
        return float(own - _linear_quantile(self._log_area[ok], self.config.size_reference_quantile))

    def size_loglik(self, k: int, domain: Sequence[Label] | None = None) -> np.ndarray:
        """Region-size log-likelihood of stroke ``k`` for each label of ``domain``
        (:func:`models.jorge.evidence.size_log_likelihood`; zeros when ``size_evidence`` is
        off or the stroke has no recorded extent).

        Returns
        -------
        ndarray, shape (num_labels,)
        """
        domain = self.nodes[k].domain if domain is None else domain
        cfg = self.config
        rel = self.rel_log_area(k) if cfg.size_evidence else float("nan")
        if cfg.size_once and self.structure(k) == "OCCLUSION":
            rel = float("nan")  # the same region continued: its size was counted at the parent
        sizes = np.array([len(lab) for lab in domain], dtype=np.int64)
        return size_log_likelihood(rel, sizes, cfg.size_mu_single, cfg.size_slope, cfg.size_sigma)

    def palette_count_loglik(self, k: int, domain: Sequence[Label] | None = None,
                             objects: LabelObjects | None = None) -> np.ndarray:
        """Palette colour-count log-likelihood of stroke ``k`` for each label of ``domain``:
        the marginal :math:`\\log p(c \\mid k)` with ``palette_count_table``
        (:func:`models.jorge.evidence.palette_count_log_likelihood`) plus, with
        ``palette_gain_table`` (the default, alone), the gain given the known objects'
        palettes (:func:`models.jorge.evidence.palette_gain_log_likelihood`, in the bin of
        ``palette_gain_bins`` of the colours they hold for a 3-D table) and, with
        ``palette_missing_table``, the known colours the palette lacks
        (:func:`models.jorge.evidence.palette_missing_log_likelihood`); zeros without any;
        times ``palette_continued`` at an OCCLUSION node.

        Returns
        -------
        ndarray, shape (num_labels,)
        """
        domain = self.nodes[k].domain if domain is None else domain
        count = int(np.unique(self.nodes[k].stroke.palette).size)
        sizes = np.array([len(lab) for lab in domain], dtype=np.int64)
        out = palette_count_log_likelihood(count, sizes, self._count_table)
        if self._gain_table.size or self._missing_table.size:
            obj = label_objects(domain, k, self._own, self._joiners) if objects is None else objects
            known = union_rows(self._palettes, obj.known_strokes, obj.known_counts)
            u, new = known.sum(axis=1), sizes - obj.known_counts
            out = out + palette_gain_log_likelihood(count, u, new, self._gain_table, self._gain_bins)
            if self._missing_table.size:
                missing = (known & ~self._palettes[k]).sum(axis=1)
                out = out + palette_missing_log_likelihood(missing, u, new, self._missing_table,
                                                           self.config.palette_gain_bins)
        return self._palette_weight(k) * out

    def _palette_weight(self, k: int) -> float:
        """``palette_continued`` at an OCCLUSION node (the same region continued), else 1."""
        w = self.config.palette_continued
        return w if w != 1.0 and self.structure(k) == "OCCLUSION" else 1.0

    def evidence_loglik(self, k: int, domain: Sequence[Label] | None = None) -> np.ndarray:
        """All soft evidence of stroke ``k`` per label: colours (eq. 6, default mode) plus
        region size (:meth:`size_loglik`) plus palette colour count
        (:meth:`palette_count_loglik`).

        Returns
        -------
        ndarray, shape (num_labels,)
        """
        domain = self.nodes[k].domain if domain is None else domain
        colour, palette = self._colour_and_palette_loglik(k, tuple(domain))
        return colour + self.size_loglik(k, domain) + palette

    def _colour_and_palette_loglik(self, k: int, domain: tuple[Label, ...]) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`colour_loglik` and :meth:`palette_count_loglik` of ``k`` over ``domain``,
        read off the node's :class:`~models.jorge.memo.EvidenceMemo` where it holds them
        (same config and structure, every label remembered, the same palette records for
        their objects), else computed and remembered. The size evidence is not
        remembered: its reference grows with every stroke. Each shape (len(domain),)."""
        records = self._palette_records(domain)
        structure = self.structure(k)
        memo = self._evidence_memo.get(k)
        hit = None if memo is None else memo.select(self.config, structure, records, domain)
        if hit is not None:
            return hit
        obj = label_objects(domain, k, self._own, self._joiners)
        colour = self.colour_loglik(k, domain, objects=obj)
        palette = self.palette_count_loglik(k, domain, objects=obj)
        axis = {lab: i for i, lab in enumerate(domain)}
        self._evidence_memo[k] = EvidenceMemo(self.config, structure, records, axis, colour, palette)
        return colour, palette

    def _palette_records(self, domain: Sequence[Label]) -> dict[int, tuple]:
        """What the evidence of ``domain``'s labels reads of each of their objects: its own
        palette stroke and its joiner label (None where it has none), as the memos of
        :mod:`models.jorge.memo` compare them."""
        return {o: (self._own.get(o), self._joiners.get(o)) for o in frozenset().union(*domain)}

    def chain_log_ratio(self, k: int) -> np.ndarray | None:
        """Colour correction of stroke ``k`` over (parent label, label) for
        ``NetworkConfig.chain_palette``: where the parent's label and ``k``'s are one
        person alone whose palette is not their own yet (:meth:`_borrowed`), the colour
        (eq. 6) and palette-count log-likelihoods of ``k`` with the parent stroke's palette
        as the person's, minus those of :meth:`evidence_loglik` (the recorded palette);
        0 elsewhere.

        Returns
        -------
        ndarray, shape (len(parent domain), len(domain)), or None
            None where nothing is corrected (off, not one parent, no such pair). A fresh
            array, read off the node's :class:`~models.jorge.memo.ChainMemo` where it can
            be (the same numbers as computing it afresh).
        """
        node = self.nodes[k]
        if not self.config.chain_palette or len(node.parents) != 1:
            return None
        (p,) = node.parents
        dom_p, dom = self.current_domain(p), tuple(node.domain)
        records = self._palette_records(dom)
        structure = self.structure(k)
        memo = self._chain_memo.get(k)
        hit, table = (False, None) if memo is None else memo.select(self.config, structure, records, dom_p, dom)
        if hit:
            return table
        table, cells = self._new_chain_log_ratio(k, p, dom_p, dom)
        axes = ({lab: i for i, lab in enumerate(dom_p)}, {lab: j for j, lab in enumerate(dom)})
        self._chain_memo[k] = ChainMemo(self.config, structure, records, axes, table, cells)
        return table.copy() if cells.any() else None

    def _new_chain_log_ratio(self, k: int, p: int, dom_p: tuple[Label, ...],
                             dom: tuple[Label, ...]) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`chain_log_ratio` computed afresh (``p``: the parent), as a table (zeros
        where nothing is corrected) and its cells (bool), each shape (len(dom_p), len(dom))."""
        row = {lab: i for i, lab in enumerate(dom_p)}
        cells = [(row[lab], j) for j, lab in enumerate(dom)
                 if len(lab) == 1 and lab in row and self._borrowed(next(iter(lab)), k)]
        out = np.zeros((len(dom_p), len(dom)))
        mask = np.zeros(out.shape, dtype=bool)
        if not cells:
            return out, mask
        labs = [dom[j] for _, j in cells]
        # the same evidence with the parent stroke as each person's own palette (as
        # freezing it alone would make it) against the recorded palettes
        alt = label_objects(labs, k, {**self._own, **{o: p for lab in labs for o in lab}}, self._joiners)
        rec = label_objects(labs, k, self._own, self._joiners)
        diff = (self.colour_loglik(k, labs, objects=alt) + self.palette_count_loglik(k, labs, objects=alt)
                - self.colour_loglik(k, labs, objects=rec) - self.palette_count_loglik(k, labs, objects=rec))
        for (i, j), d in zip(cells, diff):
            out[i, j] = d
            mask[i, j] = True
        return out, mask

    def _borrowed(self, o: int, k: int) -> bool:
        """Whether object ``o`` (not born at ``k``) has a palette that is not its own yet:
        a member of a new group or a joiner with no stroke frozen to it alone."""
        return birth_stroke(o) != k and int(o) not in self._own and self._born_with_others(o)

    def _born_with_others(self, o: int) -> bool:
        """Whether object ``o``'s birth palette holds others' colours too: a member of a
        new group, or a joiner (:meth:`freeze`)."""
        return cohort_size(o) > 1 or int(o) in self._joiners

    def cpd_table(self, k: int) -> np.ndarray:
        """CPD table of (non-frozen) node ``k`` over its parents' current domains.

        Returns
        -------
        ndarray, shape (*parent_domain_sizes, domain_size)
            Rows sum to 1, or (``truncate_pruned``) to the mass the pruning kept. A
            fresh array, read off the node's :class:`~models.jorge.memo.TableMemo` where
            it can be (the same numbers as computing it afresh).
        """
        node = self.nodes[k]
        parent_domains = self.parent_domains(k)
        shared = self.shared(k)
        memo = self._cpd_memo.get(k)
        table = None if memo is None else memo.select(self.config, shared, parent_domains, node.domain)
        if table is None:
            table = self._new_cpd_table(k, parent_domains, shared)
            exact = not (node.parents and self.config.truncate_pruned)
            self._cpd_memo[k] = TableMemo.of(self.config, shared, parent_domains, node.domain, table, exact)
            table = table.copy()
        return table

    def _new_cpd_table(self, k: int, parent_domains: list[tuple[Label, ...]], shared: list[bool]) -> np.ndarray:
        """:meth:`cpd_table` computed afresh (:func:`~models.jorge.labels.child_table` or
        :func:`~models.jorge.labels.root_table`)."""
        node = self.nodes[k]
        self.check_table_size(k, parent_domains)
        if node.parents:
            return child_table(parent_domains, shared, node.domain,
                               frozenset({k}), self.config.labels, truncate=self.config.truncate_pruned)
        return root_table(node.domain, frozenset({k}), self.config.labels)

    def check_table_size(self, k: int, parent_domains: list[tuple[Label, ...]]) -> None:
        """Check, before building it, that node ``k``'s CPD table over ``parent_domains``
        (one tuple of labels per parent) fits: at most ``_MAX_TABLE_ENTRIES`` (5e7)
        entries. :func:`models.jorge.window.build_window` checks every active node first.

        Raises
        ------
        ModelError
            The table would be larger (unpruned domains grow along chains of joins).
        """
        entries = math.prod(len(d) for d in parent_domains) * len(self.nodes[k].domain)
        if entries > _MAX_TABLE_ENTRIES:
            raise ModelError(
                f"node {k}: its CPD table over unpruned domains would hold {entries:.3g} entries "
                f"(limit {_MAX_TABLE_ENTRIES:.0e}); new groups and joins make admissible domains "
                "grow along a chain: label on line (OnlineLabeller prunes the domains) or "
                "prune them (set_domain)"
            )

    # --- freezing and pruning --------------------------------------------------------------
    def freeze(self, k: int, label: Label) -> None:
        """Fix node ``k`` to ``label`` (seed 004, sec. 5: dead nodes keep their MAP label).

        A member of a new group frozen alone gets that stroke's palette as its own
        (:meth:`palette_stroke`; issue 16): the group's birth palette holds every member's
        colours, so without it the members of a pair that entered together stay
        exchangeable and every later split is a coin toss. A stroke frozen to a label with
        objects born there and inherited ones (a join; with new groups anywhere, also a new
        group joining) records its newcomers as joiners, whose birth palette holds the
        inherited colours too: each is known only in a label with its whole birth label
        (:func:`models.jorge.labels.label_objects`) and takes the palette of the first
        stroke frozen to it alone in the same way (issue 16, tenth round)."""
        node = self.nodes[k]
        if label not in node.domain:
            raise InputError(f"node {k}: cannot freeze to {set(label)}, not in its domain")
        node.frozen = label
        self._cpd_memo.pop(k, None)
        self._evidence_memo.pop(k, None)
        self._chain_memo.pop(k, None)
        self._rel_memo.pop(k, None)
        self._replace_joiners(k, label)
        if len(label) == 1:
            (o,) = label
            if self._born_with_others(o) and k < self._own.get(int(o), k + 1):
                self._own[int(o)] = k

    def set_tentative_joiners(self, labels: Mapping[int, Label]) -> None:
        """Treat the newcomers of each unfrozen node ``k`` whose current label
        ``labels[k]`` is a join (objects born at ``k`` beside inherited ones) as joiners
        now, as :meth:`freeze` will (issue 16, fourteenth round); replaces ``k``'s earlier
        tentative joiners. Until its birth node froze, a joiner's birth palette (which
        holds the inherited people's colours too) counted as its own, and a continuation
        labelled the newcomer alone explained the whole pair's colours.

        Parameters
        ----------
        labels : mapping int -> Label
            Current labels of nodes (frozen ones are skipped).

        Raises
        ------
        InputError
            A node that does not exist, or a label outside its domain (nothing changes).
        """
        for k, label in labels.items():
            if not 0 <= k < len(self.nodes) or (self.nodes[k].frozen is None and label not in self.nodes[k].domain):
                raise InputError(f"set_tentative_joiners: node {k} has no label {set(label)} in its domain")
        for k, label in labels.items():
            if self.nodes[k].frozen is None:
                born = self._replace_joiners(k, label)
                if born:
                    self._tentative[k] = born

    def _replace_joiners(self, k: int, label: Label) -> list[int]:
        """Drop node ``k``'s tentative joiners, then record the newcomers of ``label`` as
        joiners when it is a join (objects born at ``k`` beside inherited ones); returns
        them (empty otherwise)."""
        for o in self._tentative.pop(k, ()):
            del self._joiners[o]
        born = [int(o) for o in label if birth_stroke(o) == k]
        if not born or len(born) == len(label):
            return []
        self._joiners.update(dict.fromkeys(born, label))
        return born

    @property
    def _joined(self) -> dict[int, Label]:
        """The joiners whose birth node is frozen (:meth:`freeze`), with their birth labels."""
        return {o: lab for o, lab in self._joiners.items() if self.nodes[birth_stroke(o)].frozen is not None}

    def set_domain(self, k: int, domain: Sequence[Label]) -> None:
        """Replace the (pruned) domain of an active node; its new label always stays."""
        node = self.nodes[k]
        if node.frozen is not None:
            raise InputError(f"node {k} is frozen; its domain cannot change")
        new = frozenset({k})
        dom = tuple(domain)
        if new not in dom:
            dom = (new, *dom)
        if not set(dom) <= set(node.domain):
            raise InputError(f"node {k}: a pruned domain must be a subset of the domain")
        if len(set(dom)) != len(dom):
            raise InputError(f"node {k}: repeated labels in the domain")
        node.domain = dom

    def widen(self, k: int, labels: Iterable[Label]) -> list[Label]:
        """Add admissible ``labels`` (given the parents' current domains) to the domain of
        active node ``k``, after its current labels; returns those added (in order).

        Raises
        ------
        InputError
            ``k`` is frozen.
        """
        node = self.nodes[k]
        if node.frozen is not None:
            raise InputError(f"node {k} is frozen; its domain cannot change")
        have = set(node.domain)
        wanted = [lab for lab in (frozenset(x) for x in labels) if lab not in have]
        if not wanted:  # nothing to add: no enumeration of the admissible labels
            return []
        admissible = set(self.admissible(k))
        return self._extend_domain(k, [lab for lab in wanted if lab in admissible])

    def _extend_domain(self, k: int, labels: Iterable[Label]) -> list[Label]:
        """Append to node ``k``'s domain those of ``labels`` it lacks (once each, in
        order); returns them. No admissibility check: :meth:`widen` and
        :meth:`add_stroke` pass admissible labels."""
        node = self.nodes[k]
        have = set(node.domain)
        added = [lab for lab in dict.fromkeys(labels) if lab not in have]
        node.domain = tuple(node.domain) + tuple(added)
        return added

    # --- the network of a window -----------------------------------------------------------
    def window(self, active: Sequence[int]) -> WindowNet:
        """The Bayes net of the active nodes (seed 004, eq. 11 over the active window):
        :func:`models.jorge.window.build_window` of this graph (its frozen parents and
        siblings enter as one-state nodes).

        Parameters
        ----------
        active : sequence of int
            Node indices, none frozen.

        Returns
        -------
        WindowNet

        Raises
        ------
        ModelError
            An active node's CPD table would hold more than 5e7 entries (checked for
            every node before any table is built).
        """
        return build_window(self, active)

    def restriction(self, i: int, j: int, domain_i: Sequence[Label], domain_j: Sequence[Label],
                    group_domain: Sequence[Label] | None = None) -> np.ndarray:
        """Table of the restriction node of siblings ``i < j`` over these domains
        (:func:`models.jorge.labels.restriction_table`, nested if :meth:`nested`), given the
        labels ``group_domain`` of their group (:meth:`cover_parent`) with this network's
        ``split_cover`` and ``split_normalise``, or without it. Shape (len(domain_i),
        len(domain_j), 2), or with ``group_domain`` (len(group_domain), ..., 2)."""
        labels = self.config.labels
        return restriction_table(domain_i, domain_j, self.nested(i, j), group_domain, labels.split_cover,
                                 labels.split_normalise)


def _linear_quantile(values: np.ndarray, q: float) -> float:
    """``np.quantile(values, q)`` (linear interpolation, Hyndman and Fan's definition 7)
    for a short 1-D array with no NaN, in about a twentieth of its time: the same value, bit for
    bit on numpy 2 (``tests/models/jorge/test_jorge_memo.py``).

    Parameters
    ----------
    values : ndarray, shape (n,), n >= 1
    q : float in [0, 1]
    """
    v = np.sort(values)
    at = (v.size - 1) * q
    if at >= v.size - 1:
        return float(v[-1])
    lo = int(math.floor(at))
    t = at - lo
    a, b = float(v[lo]), float(v[lo + 1])
    return b - (b - a) * (1 - t) if t >= 0.5 else a + (b - a) * t


_MAX_TABLE_ENTRIES = 5e7  # a CPD table of one node (400 MB of float64)


def _check_palette(k: int, palette, pool_size: int) -> None:
    """A stroke's palette: 1-D integer colour ids in ``0..pool_size-1`` (no wrap of -1)."""
    pal = np.asarray(palette)
    if pal.ndim != 1 or not np.issubdtype(pal.dtype, np.integer):
        raise InputError(f"stroke {k}: palette must be 1-D integer colour ids, got {palette!r}")
    if np.any(pal < 0) or np.any(pal >= pool_size):
        raise InputError(f"stroke {k}: palette ids must be in 0..{pool_size - 1}, got {pal.tolist()}")


def _check_frames(k: int, stroke: Stroke, num_points: int) -> None:
    """A stroke's frames: ``num_points`` increasing integers from ``start`` to ``end``."""
    fr = np.asarray(stroke.frames)
    if fr.shape != (num_points,) or not np.issubdtype(fr.dtype, np.integer):
        raise InputError(
            f"stroke {k}: frames must be {num_points} integers (one per position), "
            f"got shape {fr.shape} dtype {fr.dtype}"
        )
    if fr[0] != stroke.start or fr[-1] != stroke.end or np.any(np.diff(fr) <= 0):
        raise TimeOrderError(
            f"stroke {k}: frames must increase from start {stroke.start} to end {stroke.end}"
        )
