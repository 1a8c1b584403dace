r"""The link rule of seed 004's label network (sec. 4): which earlier strokes are the
parents of a new one.

Links: ``i -> j`` when stroke ``j`` starts after ``i`` ends and the gap is physically
possible. A region's centre jumps when regions merge or split, so we admit
``distance <= radius + v_max * gap`` (``radius`` is our addition; the seed gives only the
speed bound) and ``gap <= max_gap_frames``. A node has at most 2 parents and 2 children;
candidates are taken by increasing spatial gap (the seed's pruning preference), greedily
in start order, as an on-line builder must. The other gates (box gate, merge test, nested
links) are ours, for issue 16 (``NetworkConfig.gate``, ``merge_area``, ``merge_cover``,
``nested_links``).

:class:`LinkRule` is a mixin of :class:`models.jorge.network.LabelGraph`, which holds
the graph and the per-stroke arrays it reads. Moved here from :mod:`models.jorge.network`
(issue 16, thirty-sixth round); no behaviour change.
"""

from __future__ import annotations

import operator
from collections.abc import Iterable

import numpy as np

from dbn.errors import InputError
from models.jorge.config import NetworkConfig
from models.jorge.strokes import Stroke

__all__ = ["LinkRule", "WHY_NOT_PARENT"]

WHY_NOT_PARENT = ("gap", "reach", "slot", "superseded", "outranked", "merge_test", "given_links")
"""The reasons :meth:`LinkRule.why_not_parent` gives, in the order the rule applies them."""


class LinkRule:
    """Parents of a new stroke: the on-line link rule (:meth:`candidate_parents`) and the
    check of links given from outside (:meth:`check_links`), and whether two siblings
    are nested (:meth:`nested`). Nothing here changes the graph.

    A mixin: the class using it provides ``config`` (a
    :class:`~models.jorge.config.NetworkConfig`), ``fps``, ``nodes`` (each with
    ``stroke``, ``parents`` and ``children``) and, for the first ``len(nodes)`` strokes,
    the arrays ``_end`` (last frame, shape (n,)), ``_end_pos`` and ``_end_ext`` (last
    centre and box width, height in pixels, shape (n, 2); NaN: no box), ``_nchild``
    (number of children, shape (n,)) and ``_scale`` (median sqrt of the box area, shape
    (n,); NaN: no box), as :class:`models.jorge.network.LabelGraph` does.
    """

    config: NetworkConfig
    fps: float
    nodes: list
    _end: np.ndarray
    _end_pos: np.ndarray
    _end_ext: np.ndarray
    _nchild: np.ndarray
    _scale: np.ndarray

    def candidate_parents(self, stroke: Stroke) -> np.ndarray:
        r"""Parents of a new stroke: ended before it starts, reachable, with a free child
        slot; at most ``max_parents``, by increasing spatial gap (seed 004, sec. 4). A
        candidate that is an ancestor of another is dropped (the new stroke continues the
        descendant), unless it is kept as a nested link (``NetworkConfig.nested_links``).

        A stroke ``i`` can precede ``j`` when
        :math:`0 < t^{start}_j - t^{end}_i \le` ``max_gap_frames`` and
        :math:`\|p^{start}_j - p^{end}_i\| \le` ``radius`` + ``v_max`` :math:`(t^{start}_j - t^{end}_i)`
        (the other gates: ``NetworkConfig.gate``). Two parents (a merge) must pass the
        merge test (``NetworkConfig.merge_area``, ``NetworkConfig.merge_cover``), else only
        the nearest is kept.

        Returns
        -------
        ndarray of int, shape (num_parents,)
            Parent stroke indices, nearest first.
        """
        n = len(self.nodes)
        if n == 0:
            return np.zeros(0, dtype=np.int64)
        gates, dist = self._gates(stroke, n, self._nchild[:n])
        cand = np.flatnonzero(gates["gap"] & gates["reach"] & gates["slot"])
        return self._choose(stroke, n, cand, dist)[0]

    def why_not_parent(self, k: int, i: int) -> str | None:
        """Why the link rule did not make earlier node ``i`` a parent of node ``k`` (a
        diagnosis, :func:`models.jorge.recall.missed_links`): the rule of
        :meth:`candidate_parents` replayed as it ran when stroke ``k`` arrived (``i``'s
        children then: those before ``k``). The first of

        - ``"gap"``: ``i`` does not end before ``k`` starts, or ends more than
          ``max_gap_frames`` before (frames at 25 fps under the scaled and box gates);
        - ``"reach"``: too far (the distance or box gate, ``NetworkConfig.gate``);
        - ``"slot"``: ``i`` had ``max_children`` children, or one child and ``k`` starts
          more than ``sibling_window`` after ``i`` ends;
        - ``"superseded"``: a descendant of ``i`` was a candidate too;
        - ``"outranked"``: ``max_parents`` nearer candidates;
        - ``"merge_test"``: the farther of two candidates that failed the merge test;
        - ``"given_links"``: the rule would have linked ``i``, but ``k``'s links were
          given from outside (:meth:`check_links`; e.g. the true ones);

        or ``None`` where ``i`` is a parent of ``k`` (:data:`WHY_NOT_PARENT` lists the
        reasons in this order).

        Raises
        ------
        InputError
            ``i`` is not a node before ``k``.
        """
        if not (0 <= k < len(self.nodes) and 0 <= i < k):
            raise InputError(f"why_not_parent: need 0 <= i < k < {len(self.nodes)}, "
                             f"got i={i}, k={k}")
        if i in self.nodes[k].parents:
            return None
        stroke = self.nodes[k].stroke
        nchild = np.array([sum(c < k for c in self.nodes[j].children) for j in range(k)],
                          dtype=np.int64)
        gates, dist = self._gates(stroke, k, nchild)
        for name in ("gap", "reach", "slot"):
            if not gates[name][i]:
                return name
        cand = np.flatnonzero(gates["gap"] & gates["reach"] & gates["slot"])
        chosen, superseded, ranked = self._choose(stroke, k, cand, dist)
        if i in chosen:  # not a parent, yet the replay links it: links from outside
            return "given_links"
        return "superseded" if i in superseded else "outranked" if i not in ranked else "merge_test"

    def _gates(self, stroke: Stroke, n: int, nchild: np.ndarray) -> tuple[dict, np.ndarray]:
        """The per-candidate gates of :meth:`candidate_parents` for the first ``n`` nodes
        with ``nchild`` children each (shape (n,)): bool arrays ``"gap"`` (ended before
        the stroke, within ``max_gap_frames``), ``"reach"`` (distance or box gate) and
        ``"slot"`` (a free child slot within ``sibling_window``), and the distances in
        pixels from each node's last centre to the stroke's first, shape (n,)."""
        cfg = self.config
        gap = stroke.start - self._end[:n]
        dist = np.linalg.norm(self._end_pos[:n] - stroke.positions[0], axis=1)
        if cfg.gate in ("scaled", "boxes"):
            # distances in units of the parent region's size, times in seconds; a parent
            # without a recorded size falls back to the pixel gate
            unit = np.where(np.isfinite(self._scale[:n]), self._scale[:n], np.nan)
            secs = gap / self.fps
            f25 = 25.0 / self.fps  # the frame limits were set at 25 fps
            reach = np.where(np.isfinite(unit), unit * (cfg.radius_scaled + cfg.v_max_scaled * secs),
                             cfg.radius + cfg.v_max * gap)
            max_gap, window = cfg.max_gap_frames / f25, cfg.sibling_window / f25
        else:
            reach = cfg.radius + cfg.v_max * gap
            max_gap, window = cfg.max_gap_frames, cfg.sibling_window
        near = dist <= reach
        if cfg.gate == "boxes":
            near = self._boxes_near(stroke, self._box_slack(stroke, slice(0, n)), near)
        # a second child (the other part of a split) must start within ``sibling_window``
        # frames of the parent's end
        slot = (nchild < cfg.max_children) & ((nchild == 0) | (gap <= window))
        return {"gap": (gap > 0) & (gap <= max_gap), "reach": near, "slot": slot}, dist

    def _choose(self, stroke: Stroke, n: int, cand: np.ndarray,
                dist: np.ndarray) -> tuple[np.ndarray, set, np.ndarray]:
        """The parents among the candidates ``cand`` that passed the gates (indices into
        the first ``n`` nodes, ``dist`` as :meth:`_gates` gives it): drop superseded
        ancestors, take the ``max_parents`` nearest, keep two only if they pass the merge
        test. Returns the parents (nearest first), the superseded candidates and the
        ``max_parents`` nearest before the merge test."""
        cfg = self.config
        # a candidate that is an ancestor of another candidate is superseded by it (the
        # new stroke continues the descendant, it is not its sibling)
        cset = set(cand.tolist())
        superseded = {a for c in cand.tolist() for a in self._ancestors(c, 3) if a in cset}
        back = ({a for a in superseded if self._merges_back(stroke, a, cset, n)}
                if cfg.nested_links > 0 else set())
        cand = np.array([c for c in cand.tolist() if c not in superseded - back], dtype=np.int64)
        order = np.lexsort((cand, dist[cand]))
        ranked = cand = cand[order][: cfg.max_parents]
        # a nested pair passed its own merge test in _merges_back
        nested = len(cand) == 2 and self.nested(*sorted(int(c) for c in cand))
        if len(cand) == 2 and not nested and not self._merge_fits(stroke, cand):
            cand = cand[:1]
        return cand, superseded - back, ranked

    def nested(self, i: int, j: int) -> bool:
        """Whether node ``i`` (``i < j``) is a parent of node ``j``: two siblings in a nested
        link (``NetworkConfig.nested_links``; :func:`models.jorge.labels.restriction_allows`)."""
        return i in self.nodes[j].parents

    def _merges_back(self, stroke: Stroke, a: int, cset: set, n: int) -> bool:
        """Nested link (``NetworkConfig.nested_links``): candidate ``a``, superseded by its
        only child ``c`` (also a candidate), stays a parent of the new stroke when ``c``
        looks like a part of ``a`` (``a``'s last box at least ``nested_links`` times the
        area of ``c``'s first) and the new stroke's first box passes the merge test
        against ``c``'s last box: the new stroke is the rest of ``a``, alone or merging
        back with ``c`` (issue 16, twelfth round). ``a``'s children are those of the first
        ``n`` nodes (the new stroke is node ``n``)."""
        kids = [c for c in self.nodes[a].children if c < n]
        if len(kids) != 1 or kids[0] not in cset:
            return False
        c = kids[0]
        first = getattr(self.nodes[c].stroke, "extent", None)
        if first is None or not np.all(np.isfinite(self._end_ext[a])):
            return False
        part = float(np.prod(self._end_ext[a])) >= self.config.nested_links * float(np.prod(first[0]))
        return part and self._merge_fits(stroke, np.array([c]))

    def _merge_fits(self, stroke: Stroke, parents: np.ndarray) -> bool:
        """Merge test (``NetworkConfig.merge_area``, ``merge_cover``): the new stroke's
        first box has at least ``merge_area`` times the area of each parent's last box,
        and covers at least ``merge_cover`` of each parent's last box grown by the box
        gate's slack (True where a box is unknown)."""
        ext = getattr(stroke, "extent", None)
        areas = np.prod(self._end_ext[parents], axis=1)
        if ext is None or not np.all(np.isfinite(areas)):
            return True
        if not np.all(float(np.prod(ext[0])) >= self.config.merge_area * areas):
            return False
        return self.config.merge_cover <= 0 or bool(np.all(self._cover(stroke, parents) >= self.config.merge_cover))

    def _cover(self, stroke: Stroke, parents: np.ndarray) -> np.ndarray:
        r"""Share of each parent's last box, grown by the box gate's slack
        (:meth:`_box_slack`), inside the new stroke's first box; shape ``(len(parents),)``.
        A merged region covers both its parts; a neighbour that only touches it does not."""
        half = 0.5 * stroke.extent[0]
        lo, hi = stroke.positions[0] - half, stroke.positions[0] + half
        slack = np.nan_to_num(self._box_slack(stroke, parents))[:, None]
        plo = self._end_pos[parents] - 0.5 * self._end_ext[parents] - slack
        phi = self._end_pos[parents] + 0.5 * self._end_ext[parents] + slack
        inter = np.prod(np.clip(np.minimum(hi, phi) - np.maximum(lo, plo), 0.0, None), axis=1)
        return inter / np.prod(phi - plo, axis=1)

    def _box_slack(self, stroke: Stroke, idx) -> np.ndarray:
        """The box gate's slack in pixels for earlier strokes ``idx``: ``v_box`` times each
        one's scale (NaN where it has no boxes) times the seconds from its end to the new
        stroke's start."""
        return self._scale[idx] * self.config.v_box * (stroke.start - self._end[idx]) / self.fps

    def _boxes_near(self, stroke: Stroke, slack: np.ndarray, fallback: np.ndarray) -> np.ndarray:
        """Box gate: the new stroke's first region box meets each earlier stroke's last
        box grown by ``slack`` pixels on every side (``slack`` and the result: shape
        ``(n,)``, the first ``n`` strokes); where either box is unknown, ``fallback``
        (the centre-distance gate).

        A split part's box lies inside its group's last box and a merged region's box
        covers its parts', wherever their centres are, while a neighbour's box in a crowd
        is apart from it: the gate admits the first two and not the third.
        """
        ext = getattr(stroke, "extent", None)
        n = slack.shape[0]
        if ext is None:
            return fallback
        sep = np.abs(self._end_pos[:n] - stroke.positions[0]) - 0.5 * (self._end_ext[:n] + ext[0])
        with np.errstate(invalid="ignore"):
            meets = np.all(sep <= slack[:, None], axis=1)
        known = np.all(np.isfinite(self._end_ext[:n]), axis=1) & np.isfinite(slack)
        return np.where(known, meets, fallback)

    def _ancestors(self, k: int, depth: int) -> set[int]:
        out: set[int] = set()
        front = set(self.nodes[k].parents)
        for _ in range(depth):
            out |= front
            front = {p for f in front for p in self.nodes[f].parents} - out
        return out

    def check_links(self, stroke: Stroke, parents: Iterable[int]) -> tuple[int, ...]:
        """Validate links given for a new stroke instead of :meth:`candidate_parents`
        (from a low-level tracker that reports its merges and splits, or the true
        predecessors as an oracle); nothing changes.

        Parameters
        ----------
        stroke : Stroke
            The next stroke (index ``len(self)``).
        parents : iterable of int
            Indices of earlier strokes, at most ``max_parents``, distinct, each ended
            before ``stroke.start`` and with fewer than ``max_children`` children.

        Returns
        -------
        tuple of int
            The parents, sorted.

        Raises
        ------
        InputError
            A parent that is not an earlier stroke, repeated, not ended before the stroke
            starts, already with ``max_children`` children, or too many parents.
        """
        k = len(self.nodes)
        try:
            links = [operator.index(p) for p in parents]
        except TypeError as err:
            raise InputError(f"stroke {k}: parents must be stroke indices (ints), got {parents!r}") from err
        cfg = self.config
        if len(set(links)) != len(links) or len(links) > cfg.max_parents:
            raise InputError(f"stroke {k}: parents {links} must be distinct and at most "
                             f"max_parents={cfg.max_parents}")
        for p in links:
            if not 0 <= p < k:
                raise InputError(f"stroke {k}: parent {p} is not an earlier stroke (0..{k - 1})")
            if self._end[p] >= stroke.start:
                raise InputError(f"stroke {k}: parent {p} ends at frame {self._end[p]}, not before "
                                 f"the stroke starts (frame {stroke.start})")
            if self._nchild[p] >= cfg.max_children:
                raise InputError(f"stroke {k}: parent {p} already has max_children="
                                 f"{cfg.max_children} children")
        return tuple(sorted(links))
