"""Foreground (seed 003, eq. 9) and colour (eq. 10) likelihoods, incremental and full.

The log likelihood of a joint configuration, summed over views (eq. 8), is

.. math::

    \\log p(Z | \\tilde X) = \\sum_v \\Big[ c_1 \\sum_{x \\in S_v} (D_v(x) - c_2)
      - \\lambda_{im} \\sum_{i \\in \\mathcal K} \\sum_{b=1}^3 |R_{i,b}^v|
        (D_c(I_v, D_v, R_{i,b}^v) - D_{min}) \\Big] + \\text{const},

with ``S_v`` the union of the body boxes of the existing people in view ``v`` and
``R_{i,b}^v`` the pixels of body region ``b`` of person ``i`` not covered by a person
closer to the camera. ``D_c = (1 - lambda_f) D_h^2(H_b) + lambda_f D_h^2(h_b)`` with
``H_b`` the histogram of all pixels of the region, ``h_b`` that of its foreground pixels
(``D > c_2``), ``D_h(H) = min_k D_bh(H, ref_k)`` over the person's K reference
histograms of that region and ``D_bh^2 = 1 - BC`` (Bhattacharyya coefficient). People
without reference histograms yet (born in the current frame) have no colour term.

:class:`IncrementalLikelihood` keeps per-view coverage counts and per-person colour
terms, and a move recomputes only the pixels inside the boxes of the people it changes
(plus the colour terms of people overlapping them); :func:`full_loglik` recomputes
everything from scratch (the baseline and the oracle of the incremental one).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from models.rjmcmc3d import compiled
from models.rjmcmc3d.compiled import (
    frame_codes,
    one_person_delta,
    patch_foreground_delta,
    region_colour_cost,
    union_sum,
)
from models.rjmcmc3d.model import TrackerParams
from models.rjmcmc3d.types import Frame

__all__ = [
    "Config",
    "FrameData",
    "IncrementalLikelihood",
    "colour_cost",
    "full_loglik",
    "histograms_of",
    "prepare_frame",
]


class FrameData(NamedTuple):
    """Per-frame images the likelihood reads.

    Attributes
    ----------
    fgw : ndarray, shape (num_views, height, width), float64
        ``c1 (D(x) - c2)``: the per-pixel foreground gain of eq. 9.
    code : ndarray, shape (num_views, height, width), int64
        Colour bin ``+ num_bins * [D(x) > c2]``.
    num_bins : int
        Colour bins per histogram (``colour_levels^3``).
    ii : ndarray, shape (num_views, (height + 1) * (width + 1))
        Flattened integral images of ``fgw`` (zero first row and column).
    """

    fgw: np.ndarray
    code: np.ndarray
    num_bins: int
    ii: np.ndarray


class Config(NamedTuple):
    """Image-side description of a joint configuration.

    Attributes
    ----------
    boxes : ndarray, shape (num_views, M, 3, 4), int64
        Body part boxes ``(x0, y0, x1, y1)`` (empty when not seen).
    bbox : ndarray, shape (num_views, M, 4), int64
        Union box of each person's parts.
    depth : ndarray, shape (num_views, M)
        Distance to each camera (smaller occludes larger; ties by index).
    present : ndarray, shape (M,), bool
        Existence flags ``k_i``.
    """

    boxes: np.ndarray
    bbox: np.ndarray
    depth: np.ndarray
    present: np.ndarray


def prepare_frame(params: TrackerParams, frame: Frame) -> FrameData:
    """Quantise the colour images and weight the foreground maps of one frame."""
    L = params.colour_levels
    if compiled.AVAILABLE and frame.image.dtype == np.float32 and frame.D.dtype == np.float32:
        code, fgw, ii = frame_codes(frame.image, frame.D, L, params.c1, params.c2)
        return FrameData(fgw, code, L**3, ii)
    q = np.clip((frame.image * L).astype(np.int64), 0, L - 1)
    bins = (q[..., 0] * L + q[..., 1]) * L + q[..., 2]
    nb = L**3
    fg = frame.D > params.c2
    code = bins + nb * fg
    fgw = params.c1 * (frame.D.astype(np.float64) - params.c2)
    V, H, W = fgw.shape
    ii = np.zeros((V, H + 1, W + 1))
    np.cumsum(np.cumsum(fgw, axis=1), axis=2, out=ii[:, 1:, 1:])
    return FrameData(fgw, code, nb, ii.reshape(V, -1))


def union_bbox(boxes: np.ndarray) -> np.ndarray:
    """Union of the part boxes (..., 3, 4) -> (..., 4), empty parts ignored."""
    empty = (boxes[..., 2] <= boxes[..., 0]) | (boxes[..., 3] <= boxes[..., 1])
    big = np.iinfo(np.int64).max
    x0 = np.where(empty, big, boxes[..., 0]).min(-1)
    y0 = np.where(empty, big, boxes[..., 1]).min(-1)
    x1 = np.where(empty, -1, boxes[..., 2]).max(-1)
    y1 = np.where(empty, -1, boxes[..., 3]).max(-1)
    allempty = empty.all(-1)
    out = np.stack([x0, y0, x1, y1], axis=-1)
    return np.where(allempty[..., None], 0, out)


def colour_cost(
    params: TrackerParams, counts: np.ndarray, sref: np.ndarray, nref: np.ndarray
) -> np.ndarray:
    """Colour log-likelihood term of eq. 10 per person, from region histograms.

    Parameters
    ----------
    counts : ndarray, shape (..., 3, 2, num_bins)
        Pixel counts per region, background/foreground pixel, colour bin.
    sref : ndarray, shape (..., 3, K, num_bins)
        Square roots of the normalised reference histograms.
    nref : ndarray, shape (..., 3), int
        Number of valid references per region (0: no colour term).

    Returns
    -------
    ndarray, shape (...)
        ``-lambda_im sum_b |R_b| (D_c - D_min)``.
    """
    counts = counts.astype(np.float64)
    H = counts[..., 0, :] + counts[..., 1, :]
    hf = counts[..., 1, :]
    nR = H.sum(-1)
    nF = hf.sum(-1)
    sH = np.sqrt(H / np.maximum(nR, 1.0)[..., None])
    sh = np.sqrt(hf / np.maximum(nF, 1.0)[..., None])
    K = sref.shape[-2]
    valid = np.arange(K) < nref[..., None]
    bcH = np.where(valid, np.einsum("...kc,...c->...k", sref, sH), -1.0).max(-1)
    bch = np.where(valid, np.einsum("...kc,...c->...k", sref, sh), -1.0).max(-1)
    d2H = np.clip(1.0 - bcH, 0.0, 1.0)
    d2h = np.where(nF > 0, np.clip(1.0 - bch, 0.0, 1.0), d2H)
    dc = (1.0 - params.lambda_f) * d2H + params.lambda_f * d2h
    term = np.where((nref > 0) & (nR > 0), -params.lambda_im * nR * (dc - params.d_min), 0.0)
    return term.sum(-1)


def _owner_map(cfg: Config, v: int, height: int, width: int) -> tuple[np.ndarray, np.ndarray]:
    """Painter's algorithm: owner region ``3 j + b`` per pixel (-1: none), coverage count."""
    owner = np.full((height, width), -1, dtype=np.int64)
    count = np.zeros((height, width), dtype=np.int16)
    idx = np.flatnonzero(cfg.present)
    # far to near; among equal depths the smaller index is nearer (painted last)
    order = idx[np.lexsort((-idx, -cfg.depth[v, idx]))]
    for j in order:
        for b in range(3):
            x0, y0, x1, y1 = cfg.boxes[v, j, b]
            if x1 > x0 and y1 > y0:
                owner[y0:y1, x0:x1] = 3 * j + b
                count[y0:y1, x0:x1] += 1
    return owner, count


def histograms_of(data: FrameData, cfg: Config) -> np.ndarray:
    """Region histograms of every person in every view, from scratch.

    Returns
    -------
    ndarray, shape (num_views, M, 3, 2, num_bins), int64
    """
    V, H, W = data.fgw.shape
    M = cfg.present.shape[0]
    nb = data.num_bins
    out = np.zeros((V, M, 3, 2, nb), dtype=np.int64)
    for v in range(V):
        owner, _ = _owner_map(cfg, v, H, W)
        sel = owner >= 0
        lab = owner[sel] * (2 * nb) + data.code[v][sel]
        out[v] = np.bincount(lab, minlength=M * 3 * 2 * nb).reshape(M, 3, 2, nb)
    return out


def full_loglik(
    params: TrackerParams, data: FrameData, cfg: Config, sref: np.ndarray, nref: np.ndarray
) -> float:
    """Eqs. 8-10 recomputed from scratch over every pixel of every view (the baseline).

    Parameters
    ----------
    data : FrameData
    cfg : Config
    sref : ndarray, shape (M, 3, K, num_bins)
    nref : ndarray, shape (M, 3)
    """
    V, H, W = data.fgw.shape
    M = cfg.present.shape[0]
    nb = data.num_bins
    total = 0.0
    active = nref * cfg.present[:, None]
    for v in range(V):
        owner, count = _owner_map(cfg, v, H, W)
        total += float(data.fgw[v][count > 0].sum())
        sel = owner >= 0
        lab = owner[sel] * (2 * nb) + data.code[v][sel]
        counts = np.bincount(lab, minlength=M * 3 * 2 * nb).reshape(M, 3, 2, nb)
        total += float(colour_cost(params, counts, sref, active).sum())
    return total


def _rect_sum(get, st: int, x0: int, y0: int, x1: int, y1: int) -> float:
    """Sum over ``[y0, y1) x [x0, x1)`` from a flattened integral image (row stride ``st``)."""
    if x1 <= x0 or y1 <= y0:
        return 0.0
    return get(y1 * st + x1) - get(y0 * st + x1) - get(y1 * st + x0) + get(y0 * st + x0)


def _union_sum(get, st: int, boxes: list) -> float:
    """Sum over the union of up to three boxes by inclusion-exclusion."""
    total = 0.0
    n = len(boxes)
    for a in range(n):
        A = boxes[a]
        total += _rect_sum(get, st, A[0], A[1], A[2], A[3])
        for b in range(a + 1, n):
            B = boxes[b]
            x0 = A[0] if A[0] > B[0] else B[0]
            y0 = A[1] if A[1] > B[1] else B[1]
            x1 = A[2] if A[2] < B[2] else B[2]
            y1 = A[3] if A[3] < B[3] else B[3]
            if x1 <= x0 or y1 <= y0:
                continue
            total -= _rect_sum(get, st, x0, y0, x1, y1)
            for c in range(b + 1, n):
                C = boxes[c]
                cx0 = x0 if x0 > C[0] else C[0]
                cy0 = y0 if y0 > C[1] else C[1]
                cx1 = x1 if x1 < C[2] else C[2]
                cy1 = y1 if y1 < C[3] else C[3]
                total += _rect_sum(get, st, cx0, cy0, cx1, cy1)
    return total


def _with_lists(val: tuple) -> tuple:
    """``ov`` entry ``(present, boxes, bbox, depth, *arrays)`` with its lists filled in
    from the arrays when the proposal carried arrays only."""
    if val[1] is not None:
        return val
    b, bb, d = val[4:7]
    return (val[0], b.tolist(), bb.tolist(), d.tolist(), b, bb, d)


class _Pending(NamedTuple):
    delta: float
    patches: list
    colour: list
    ov: dict


class IncrementalLikelihood:
    """The likelihood of eqs. 8-10 maintained incrementally over moves.

    Keeps, per view, the coverage count of every pixel (how many body boxes cover it),
    the foreground sum of eq. 9 and each person's colour term of eq. 10. A proposal
    reads only the pixels inside the union box of the changed people's old and new
    boxes, and recomputes the colour terms of the people whose boxes meet it.

    Parameters
    ----------
    params : TrackerParams
    data : FrameData
    cfg : Config
        Initial configuration (computed from scratch once).
    sref : ndarray, shape (M, 3, K, num_bins)
    nref : ndarray, shape (M, 3)
    """

    def __init__(
        self,
        params: TrackerParams,
        data: FrameData,
        cfg: Config,
        sref: np.ndarray,
        nref: np.ndarray,
    ) -> None:
        self.params = params
        self.data = data
        self.sref = sref
        self.nref_l = nref.tolist()
        self.nref_a = np.ascontiguousarray(nref, dtype=np.int64)
        self.active_l = (nref.sum(1) > 0).tolist()
        V, H, W = data.fgw.shape
        self.num_views = V
        self.count = np.zeros((V, H, W), dtype=np.int16)
        self.fg = np.zeros(V)
        M = cfg.present.shape[0]
        self.M = M
        self.cc = [[0.0] * M for _ in range(V)]
        hist = histograms_of(data, cfg)
        for v in range(V):
            _, self.count[v] = _owner_map(cfg, v, H, W)
            self.fg[v] = float(data.fgw[v][self.count[v] > 0].sum())
            self.cc[v] = colour_cost(params, hist[v], sref, nref * cfg.present[:, None]).tolist()
        self.boxes_l = cfg.boxes.tolist()
        self.bbox_l = cfg.bbox.tolist()
        self.depth_l = cfg.depth.tolist()
        self.present_l = cfg.present.tolist()
        self.total = float(self.fg.sum() + sum(map(sum, self.cc)))
        nb = data.num_bins
        self._dump = 3 * 2 * nb  # label of covered pixels: a bin beyond the 3 regions
        self._stride = W + 1
        self.alive = [j for j in range(M) if self.present_l[j]]
        self._box_geometry(data, W)
        self._array_mirrors(cfg)

    def _box_geometry(self, data: FrameData, W: int) -> None:
        """Per view and person: its non-empty part boxes (``nz_l``) and the sum of
        c1 (D - c2) over their union (``usum``, from the integral image); [] and 0.0 for
        people not present."""
        rows = range(self.num_views)
        self.nz_l = [
            [
                [b for b in self.boxes_l[v][j] if b[2] > b[0] and b[3] > b[1]]
                if self.present_l[j]
                else []
                for j in range(self.M)
            ]
            for v in rows
        ]
        self.usum = [
            [
                _union_sum(data.ii[v].item, W + 1, self.nz_l[v][j]) if self.present_l[j] else 0.0
                for j in range(self.M)
            ]
            for v in rows
        ]

    def _array_mirrors(self, cfg: Config) -> None:
        """Array copies of the per-view geometry and terms, for the compiled path."""
        V, M = self.num_views, self.M
        self.usum_a = np.array(self.usum, dtype=np.float64).reshape(V, M)
        self.boxes_a = np.array(cfg.boxes, dtype=np.int64, order="C")
        self.bbox_a = np.array(cfg.bbox, dtype=np.int64, order="C")
        self.depth_a = np.array(cfg.depth, dtype=np.float64, order="C")
        self.cc_a = np.array(self.cc, dtype=np.float64).reshape(V, M)
        self.present_a = np.array(self.present_l, dtype=np.bool_)
        self.active_a = np.array(self.active_l, dtype=np.bool_)

    def _colour_one(self, counts: np.ndarray, j: int) -> float:
        """:func:`colour_cost` of one person from its (3, 2, num_bins) counts (fast path)."""
        p = self.params
        C = counts.astype(np.float64)
        C[:, 0] += C[:, 1]  # C[:, 0] is now H_b (all pixels), C[:, 1] h_b (foreground)
        n = C.sum(2).tolist()  # (3, 2): |R_b| and its foreground pixel count
        np.sqrt(C, out=C)
        bc = (self.sref[j] @ C.transpose(0, 2, 1)).tolist()  # (3, K, 2), unnormalised
        nref = self.nref_l[j]
        total = 0.0
        lf = p.lambda_f
        for b in range(3):
            k = nref[b]
            nR, nF = n[b]
            if k == 0 or nR == 0:
                continue
            bH = bh = -1.0
            for r0, r1 in bc[b][:k]:
                bH = r0 if r0 > bH else bH
                bh = r1 if r1 > bh else bh
            d2H = 1.0 - bH / math.sqrt(nR)
            d2H = 0.0 if d2H < 0.0 else (1.0 if d2H > 1.0 else d2H)
            if nF > 0:
                d2h = 1.0 - bh / math.sqrt(nF)
                d2h = 0.0 if d2h < 0.0 else (1.0 if d2h > 1.0 else d2h)
            else:
                d2h = d2H
            total -= p.lambda_im * nR * ((1.0 - lf) * d2H + lf * d2h - p.d_min)
        return total

    def _slot_cost(
        self, v: int, j: int, boxes: list, bbox: list, dj: float, occ: list, arrays=None
    ) -> float:
        """Colour term of person ``j`` in view ``v`` with part boxes ``boxes``.

        ``occ`` lists the other present people of the configuration as
        ``(k, boxes_k, bbox_k, depth_k)``; the nearer ones hide their pixels. Compiled
        (:func:`~models.rjmcmc3d.compiled.region_colour_cost`) when numba is available.
        """
        if not compiled.AVAILABLE:
            return self._slot_cost_numpy(v, j, boxes, bbox, dj, occ)
        x0, y0, x1, y1 = bbox
        if x1 <= x0 or y1 <= y0:
            return 0.0
        hidden = []
        for k, bk, bbk, dk in occ:
            if dk > dj or (dk == dj and k > j) or k == j:
                continue
            if bbk[0] >= x1 or bbk[2] <= x0 or bbk[1] >= y1 or bbk[3] <= y0:
                continue
            hidden += bk
        p = self.params
        return region_colour_cost(
            self.data.code[v],
            np.array(bbox, dtype=np.int64) if arrays is None else arrays[1],
            np.array(boxes, dtype=np.int64) if arrays is None else arrays[0],
            np.array(hidden, dtype=np.int64).reshape(-1, 4),
            self.sref[j],
            self.nref_a[j],
            self.data.num_bins,
            p.lambda_im,
            p.lambda_f,
            p.d_min,
        )

    def _slot_cost_numpy(
        self, v: int, j: int, boxes: list, bbox: list, dj: float, occ: list
    ) -> float:
        """:meth:`_slot_cost` with numpy (the reference of the compiled path)."""
        x0, y0, x1, y1 = bbox
        if x1 <= x0 or y1 <= y0:
            return 0.0
        nb2 = 2 * self.data.num_bins
        reg = np.full((y1 - y0, x1 - x0), self._dump, dtype=np.int64)
        for b, (bx0, by0, bx1, by1) in enumerate(boxes):
            if bx1 > bx0 and by1 > by0:
                reg[by0 - y0 : by1 - y0, bx0 - x0 : bx1 - x0] = b * nb2
        for k, bk, bbk, dk in occ:
            if dk > dj or (dk == dj and k > j) or k == j:
                continue
            if bbk[0] >= x1 or bbk[2] <= x0 or bbk[1] >= y1 or bbk[3] <= y0:
                continue
            for bx0, by0, bx1, by1 in bk:
                cx0 = bx0 if bx0 > x0 else x0
                cy0 = by0 if by0 > y0 else y0
                cx1 = bx1 if bx1 < x1 else x1
                cy1 = by1 if by1 < y1 else y1
                if cx1 > cx0 and cy1 > cy0:
                    reg[cy0 - y0 : cy1 - y0, cx0 - x0 : cx1 - x0] = self._dump
        reg += self.data.code[v, y0:y1, x0:x1]
        counts = np.bincount(reg.ravel(), minlength=2 * self._dump)[: self._dump]
        return self._colour_one(counts.reshape(3, 2, -1), j)

    def propose(self, ov: dict) -> tuple[float, _Pending]:
        """Log-likelihood change when the people in ``ov`` change (the others stay).

        ``ov[j] = (present, boxes (V, 3, 4), bbox (V, 4), depth (V,))`` as lists: person
        ``j``'s new existence flag and image geometry.

        Only the pixels inside the union box of the changed people's old and new boxes
        are read for eq. 9, and only the colour terms of the changed people and of the
        people whose boxes meet that union box and who are (or were) behind a changed
        person are recomputed for eq. 10 (the visible pixels of the others stay).

        Returns
        -------
        delta : float
            ``log p(Z | new) - log p(Z | current)``.
        pending : object
            Pass to :meth:`commit` if the move is accepted.
        """
        items = list(ov.items())
        if compiled.AVAILABLE and len(items) == 1:
            return self._propose_one(items, ov)
        delta = 0.0
        patches = []
        colour = []
        stay = [k for k in self.alive if k not in ov]  # present, unchanged
        for v in range(self.num_views):
            got = self._foreground_view(v, items, stay)
            if got is None:
                continue
            patch, others = got
            delta += patch[2]
            patches.append(patch)
            for c in self._colour_view(v, items, stay, others):
                delta += c[2] - self.cc[v][c[1]]
                colour.append(c)
        return delta, _Pending(delta, patches, colour, ov)

    def _propose_one(self, items: list, ov: dict) -> tuple[float, _Pending]:
        """:meth:`propose` for one changed person: eqs. 8-10 in one compiled call."""
        j, val = items[0]
        pr = val[0]
        if len(val) > 4:
            bxa, bba, dpa = val[4], val[5], val[6]
        else:
            bxa = np.array(val[1], dtype=np.int64)
            bba = np.array(val[2], dtype=np.int64)
            dpa = np.array(val[3], dtype=np.float64)
        p = self.params
        delta, touched, d_fg, new_usum, cv, ck, cc = one_person_delta(
            self.count,
            self.data.fgw,
            self.data.ii,
            self._stride,
            self.data.code,
            j,
            self.present_l[j],
            self.present_a,
            self.active_a,
            self.boxes_a,
            self.bbox_a,
            self.depth_a,
            self.usum_a,
            self.cc_a,
            pr,
            bxa,
            bba,
            dpa,
            self.sref,
            self.nref_a,
            p.lambda_im,
            p.lambda_f,
            p.d_min,
        )
        patches = [
            (v, None, d, {j: u})
            for v, d, u, t in zip(
                range(self.num_views), d_fg.tolist(), new_usum.tolist(), touched.tolist()
            )
            if t
        ]
        colour = list(zip(cv.tolist(), ck.tolist(), cc.tolist()))
        return delta, _Pending(delta, patches, colour, ov)

    def _foreground_view(self, v: int, items: list, stay: list) -> tuple | None:
        """Eq. 9 change in view ``v`` and the unchanged people meeting the changed area.

        Returns ``None`` when no changed person is (or becomes) visible in the view, else
        ``((v, signed boxes, d_fg, new union sums), others)``.
        """
        present_l = self.present_l
        nz_v = self.nz_l[v]
        signed = []
        new_nz = []
        for j, (pr, bx, *_) in items:
            if present_l[j]:
                signed += [(bx_, -1) for bx_ in nz_v[j]]
            nz = [b for b in bx[v] if b[2] > b[0] and b[3] > b[1]] if pr else []
            new_nz.append(nz)
            signed += [(bx_, 1) for bx_ in nz]
        if not signed:
            return None
        X0 = Y0 = 1 << 40
        X1 = Y1 = -1
        for (b0, b1, b2, b3), _ in signed:
            X0 = b0 if b0 < X0 else X0
            Y0 = b1 if b1 < Y0 else Y0
            X1 = b2 if b2 > X1 else X1
            Y1 = b3 if b3 > Y1 else Y1
        bbox_v = self.bbox_l[v]
        others = []  # unchanged people whose boxes meet the changed area
        for k in stay:
            kx0, ky0, kx1, ky1 = bbox_v[k]
            if kx0 >= X1 or kx1 <= X0 or ky0 >= Y1 or ky1 <= Y0:
                continue
            others.append(k)
        st = self._stride
        new_usum = {}
        if compiled.AVAILABLE:
            ii_v = self.data.ii[v]
            for (j, _), nz in zip(items, new_nz):
                new_usum[j] = union_sum(ii_v, st, np.array(nz, dtype=np.int64)) if nz else 0.0
        else:
            get = self.data.ii[v].item
            for (j, _), nz in zip(items, new_nz):
                new_usum[j] = _union_sum(get, st, nz) if nz else 0.0
        if not others and len(items) == 1:
            # nobody else covers these pixels: eq. 9 change from the integral image
            j = items[0][0]
            d_fg = new_usum[j] - (self.usum[v][j] if present_l[j] else 0.0)
        elif compiled.AVAILABLE:
            d_fg = patch_foreground_delta(
                self.count[v],
                self.data.fgw[v],
                np.array((X0, Y0, X1, Y1), dtype=np.int64),
                np.array([(*b, sign) for b, sign in signed], dtype=np.int64),
            )
        else:
            cold = self.count[v, Y0:Y1, X0:X1]
            cnew = cold.copy()
            for (bx0, by0, bx1, by1), sign in signed:
                cnew[by0 - Y0 : by1 - Y0, bx0 - X0 : bx1 - X0] += sign
            f = self.data.fgw[v, Y0:Y1, X0:X1]
            d_fg = float(
                np.add.reduce(f, axis=None, where=cnew > 0)
                - np.add.reduce(f, axis=None, where=cold > 0)
            )
        return (v, signed, d_fg, new_usum), others

    def _colour_view(self, v: int, items: list, stay: list, others: list) -> list:
        """Eq. 10 terms ``(v, j, new cost)`` of the changed people and of the unchanged
        ones behind a changed person (their visible pixels change) in view ``v``."""
        active = self.active_l
        present_l = self.present_l
        boxes_v, depth_v, bbox_v = self.boxes_l[v], self.depth_l[v], self.bbox_l[v]
        # the configuration after the move, as seen from view v
        occ = [(k, boxes_v[k], bbox_v[k], depth_v[k]) for k in stay]
        occ += [(j, bx[v], bb[v], dp[v]) for j, (pr, bx, bb, dp, *_) in items if pr]
        out = []
        for j, (pr, bx, bb, dp, *arr) in items:
            if active[j]:
                a = (arr[0][v], arr[1][v]) if arr else None
                c_new = self._slot_cost(v, j, bx[v], bb[v], dp[v], occ, a) if pr else 0.0
                out.append((v, j, c_new))
        for k in others:
            if not active[k]:
                continue
            # k's visible pixels change only if a changed person is (or was) nearer
            dk = depth_v[k]
            for j, (pr, _, _, dp, *_) in items:
                dj = depth_v[j]
                if present_l[j] and (dj < dk or (dj == dk and j < k)):
                    break
                dj = dp[v]
                if pr and (dj < dk or (dj == dk and j < k)):
                    break
            else:
                continue
            a = (self.boxes_a[v, k], self.bbox_a[v, k])
            out.append((v, k, self._slot_cost(v, k, boxes_v[k], bbox_v[k], dk, occ, a)))
        return out

    def commit(self, pending: _Pending) -> None:
        """Make the proposed configuration current."""
        ov = {j: _with_lists(val) for j, val in pending.ov.items()}
        for v, signed, d_fg, new_usum in pending.patches:
            for j, u in new_usum.items():
                self.usum[v][j] = u
                self.usum_a[v, j] = u
            if signed is None:  # one changed person: its old boxes out, its new ones in
                ((j, (pr, bx, *_)),) = ov.items()
                signed = [(b, -1) for b in self.nz_l[v][j]] if self.present_l[j] else []
                if pr:
                    signed += [(b, 1) for b in bx[v] if b[2] > b[0] and b[3] > b[1]]
            cv = self.count[v]
            for (bx0, by0, bx1, by1), sign in signed:
                cv[by0:by1, bx0:bx1] += sign
            self.fg[v] += d_fg
        for v, j, c in pending.colour:
            self.cc[v][j] = c
            self.cc_a[v, j] = c
        for j, (pr, bx, bb, dp, *_) in ov.items():
            self.present_l[j] = pr
            for v in range(self.num_views):
                self.boxes_l[v][j] = bx[v]
                self.bbox_l[v][j] = bb[v]
                self.depth_l[v][j] = dp[v]
                self.nz_l[v][j] = [b for b in bx[v] if b[2] > b[0] and b[3] > b[1]] if pr else []
            arrays = ov[j][4:]  # the projection's arrays, when it gave them
            self.boxes_a[:, j] = arrays[0] if arrays else bx
            self.bbox_a[:, j] = arrays[1] if arrays else bb
            self.depth_a[:, j] = arrays[2] if arrays else dp
            self.present_a[j] = pr
        self.alive = [j for j in range(self.M) if self.present_l[j]]
        self.total += pending.delta
