"""Compiled inner loops of the per-move work of the seed 003 tracker (numba).

The RJ-MCMC chain of seed 003 (sec. 3.4) makes about 1,500 moves per frame, each
changing one or two people; what a move costs is dominated by small per-call overheads
(a few dozen numpy calls on arrays of a few hundred elements). Two of them are compiled
here, each as one call:

- :func:`project_person`: the body model of fig. 3 projected into every view (the part
  boxes, their union and the camera distances), the same arithmetic as
  :class:`~models.rjmcmc3d.projection.BoxProjector`;
- :func:`region_colour_cost`: the colour term of eq. 10 of one person in one view, from
  the pixels of its part boxes not hidden by nearer people, the same arithmetic as
  :meth:`~models.rjmcmc3d.likelihood.IncrementalLikelihood._slot_cost`.

numba is imported lazily; without it :data:`AVAILABLE` is False and the callers keep
their numpy paths (same results up to floating-point summation order).
"""

from __future__ import annotations

import math

import numpy as np

LOG_2PI = math.log(2.0 * math.pi)

__all__ = [
    "AVAILABLE",
    "add_log_q",
    "far_detections",
    "foreground_one",
    "frame_codes",
    "interaction_row",
    "one_person_delta",
    "patch_foreground_delta",
    "project_person",
    "region_colour_cost",
    "union_sum",
    "update_log_q",
    "update_log_q_at",
    "update_log_q_pair",
]

try:  # numba is optional: the numpy paths are the reference
    from numba import njit
except ImportError:  # pragma: no cover - exercised where numba is absent
    AVAILABLE = False

    def njit(*args, **kwargs):  # type: ignore[no-redef]
        return lambda f: f

else:
    AVAILABLE = True


@njit(cache=True, nogil=True)
def project_person(
    C: np.ndarray,
    x: float,
    y: float,
    h: float,
    a: float,
    num_views: int,
    width: int,
    height: int,
    centers: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Part boxes (V, 3, 4), union boxes (V, 4) and camera distances (V,) of one person.

    Parameters
    ----------
    C : ndarray, shape (6, 3 * V * 3 * P)
        Projection coefficients (``projection._projection_coefficients``), columns
        ordered (coordinate, view, part, point), ``P`` sampled points per part.
    x, y, h, a : float
        Ground position, height and orientation.
    centers : ndarray, shape (V, 2)
        Camera centres on the ground.
    """
    f = (x, y, 1.0, math.cos(a), math.sin(a), h)
    npts = C.shape[1] // (3 * num_views * 3)
    stride = num_views * 3 * npts
    boxes = np.zeros((num_views, 3, 4), dtype=np.int64)
    bbox = np.zeros((num_views, 4), dtype=np.int64)
    depth = np.empty(num_views)
    for v in range(num_views):
        ux0 = uy0 = 1 << 40
        ux1 = uy1 = -1
        for part in range(3):
            base = (v * 3 + part) * npts
            ok = True
            mnx = mny = math.inf
            mxx = mxy = -math.inf
            for k in range(npts):
                col = base + k
                X = 0.0
                Y = 0.0
                W = 0.0
                for r in range(6):
                    X += f[r] * C[r, col]
                    Y += f[r] * C[r, col + stride]
                    W += f[r] * C[r, col + 2 * stride]
                if not W > 1e-6:
                    ok = False
                    break
                px = X / W
                py = Y / W
                mnx = min(mnx, px)
                mny = min(mny, py)
                mxx = max(mxx, px)
                mxy = max(mxy, py)
            if not ok:
                continue
            x0 = int(math.floor(min(max(mnx, 0.0), width)))
            y0 = int(math.floor(min(max(mny, 0.0), height)))
            x1 = -int(math.floor(min(max(-mxx, -width), 0.0)))
            y1 = -int(math.floor(min(max(-mxy, -height), 0.0)))
            boxes[v, part, 0] = x0
            boxes[v, part, 1] = y0
            boxes[v, part, 2] = x1
            boxes[v, part, 3] = y1
            if x1 > x0 and y1 > y0:
                ux0 = min(ux0, x0)
                uy0 = min(uy0, y0)
                ux1 = max(ux1, x1)
                uy1 = max(uy1, y1)
        if ux1 >= 0:
            bbox[v, 0] = ux0
            bbox[v, 1] = uy0
            bbox[v, 2] = ux1
            bbox[v, 3] = uy1
        depth[v] = math.hypot(x - centers[v, 0], y - centers[v, 1])
    return boxes, bbox, depth


@njit(cache=True, nogil=True)
def region_colour_cost(
    code: np.ndarray,
    bbox: np.ndarray,
    parts: np.ndarray,
    hidden: np.ndarray,
    sref: np.ndarray,
    nref: np.ndarray,
    num_bins: int,
    lambda_im: float,
    lambda_f: float,
    d_min: float,
) -> float:
    """Colour term of eq. 10 of one person in one view (``-lambda_im sum_b |R_b| (D_c -
    D_min)``).

    Parameters
    ----------
    code : ndarray, shape (height, width), int64
        Colour bin ``+ num_bins * [D > c2]`` per pixel.
    bbox : ndarray, shape (4,)
        Union box of the person's parts.
    parts : ndarray, shape (3, 4)
        Part boxes (a later part owns the pixels it shares with an earlier one).
    hidden : ndarray, shape (n, 4)
        Boxes of nearer people (their pixels are not the person's).
    sref : ndarray, shape (3, K, num_bins)
        Square roots of the reference histograms; ``nref`` (3,) how many are valid.
    """
    X0, Y0, X1, Y1 = bbox[0], bbox[1], bbox[2], bbox[3]
    counts = _region_counts(code, X0, Y0, X1, Y1, parts, hidden, num_bins)
    return _colour_term(counts, sref, nref, num_bins, lambda_im, lambda_f, d_min)


@njit(cache=True, nogil=True)
def _region_counts(code, X0, Y0, X1, Y1, parts, hidden, num_bins):
    """Pixel counts (3, 2, num_bins) per part region, background/foreground and colour
    bin, of the pixels of ``[Y0, Y1) x [X0, X1)`` in a part box and in no hiding box."""
    flat = np.zeros(3 * 2 * num_bins, dtype=np.int64)  # (region, fg, bin) = region, code
    nb2 = 2 * num_bins
    nh = hidden.shape[0]
    lo = np.empty(3, dtype=np.int64)  # this row's x-interval of each part (later wins)
    hi = np.empty(3, dtype=np.int64)
    hlo = np.empty(nh, dtype=np.int64)  # and of each hiding box
    hhi = np.empty(nh, dtype=np.int64)
    for yy in range(Y0, Y1):
        for b in range(3):
            inside = parts[b, 1] <= yy < parts[b, 3]
            lo[b] = max(parts[b, 0], X0) if inside else 0
            hi[b] = min(parts[b, 2], X1) if inside else 0
        nrow = 0
        for o in range(nh):
            if hidden[o, 1] <= yy < hidden[o, 3] and hidden[o, 2] > hidden[o, 0]:
                hlo[nrow] = hidden[o, 0]
                hhi[nrow] = hidden[o, 2]
                nrow += 1
        row = code[yy]
        only = -1  # the one part on this row, when alone and unhidden (the usual case)
        for b in range(3):
            if hi[b] > lo[b]:
                only = b if only == -1 else -2
        if only >= 0 and nrow == 0:
            off = only * nb2
            for xx in range(lo[only], hi[only]):
                flat[off + row[xx]] += 1
            continue
        for xx in range(X0, X1):
            if lo[2] <= xx < hi[2]:
                r = 2
            elif lo[1] <= xx < hi[1]:
                r = 1
            elif lo[0] <= xx < hi[0]:
                r = 0
            else:
                continue
            seen = True
            for o in range(nrow):
                if hlo[o] <= xx < hhi[o]:
                    seen = False
                    break
            if seen:
                flat[r * nb2 + row[xx]] += 1
    return flat.reshape((3, 2, num_bins)).astype(np.float64)


@njit(cache=True, nogil=True)
def _colour_term(counts, sref, nref, num_bins, lambda_im, lambda_f, d_min):
    """``-lambda_im sum_b |R_b| (D_c - D_min)`` from region counts (eq. 10)."""
    total = 0.0
    K = sref.shape[1]
    sq = np.empty((2, num_bins))
    for b in range(3):
        k = nref[b]
        nR = 0.0
        nF = 0.0
        for c in range(num_bins):
            nR += counts[b, 0, c] + counts[b, 1, c]
            nF += counts[b, 1, c]
        if k == 0 or nR == 0.0:
            continue
        for c in range(num_bins):
            sq[0, c] = math.sqrt(counts[b, 0, c] + counts[b, 1, c])
            sq[1, c] = math.sqrt(counts[b, 1, c])
        bH = -1.0
        bh = -1.0
        for r in range(min(k, K)):
            sH = 0.0
            sh = 0.0
            for c in range(num_bins):
                sH += sref[b, r, c] * sq[0, c]
                sh += sref[b, r, c] * sq[1, c]
            bH = max(bH, sH)
            bh = max(bh, sh)
        d2H = min(max(1.0 - bH / math.sqrt(nR), 0.0), 1.0)
        d2h = min(max(1.0 - bh / math.sqrt(nF), 0.0), 1.0) if nF > 0 else d2H
        total -= lambda_im * nR * ((1.0 - lambda_f) * d2H + lambda_f * d2h - d_min)
    return total


@njit(cache=True, nogil=True)
def _rect(ii: np.ndarray, st: int, x0: int, y0: int, x1: int, y1: int) -> float:
    if x1 <= x0 or y1 <= y0:
        return 0.0
    return ii[y1 * st + x1] - ii[y0 * st + x1] - ii[y1 * st + x0] + ii[y0 * st + x0]


@njit(cache=True, nogil=True)
def union_sum(ii: np.ndarray, st: int, boxes: np.ndarray) -> float:
    """Sum of an image over the union of up to three boxes (k, 4), by inclusion-exclusion
    on its flattened integral image ``ii`` (row stride ``st``); the arithmetic (and its
    order) of :func:`models.rjmcmc3d.likelihood._union_sum`."""
    total = 0.0
    n = boxes.shape[0]
    for a in range(n):
        total += _rect(ii, st, boxes[a, 0], boxes[a, 1], boxes[a, 2], boxes[a, 3])
        for b in range(a + 1, n):
            x0 = max(boxes[a, 0], boxes[b, 0])
            y0 = max(boxes[a, 1], boxes[b, 1])
            x1 = min(boxes[a, 2], boxes[b, 2])
            y1 = min(boxes[a, 3], boxes[b, 3])
            if x1 <= x0 or y1 <= y0:
                continue
            total -= _rect(ii, st, x0, y0, x1, y1)
            for c in range(b + 1, n):
                cx0 = max(x0, boxes[c, 0])
                cy0 = max(y0, boxes[c, 1])
                cx1 = min(x1, boxes[c, 2])
                cy1 = min(y1, boxes[c, 3])
                total += _rect(ii, st, cx0, cy0, cx1, cy1)
    return total


@njit(cache=True, nogil=True)
def patch_foreground_delta(
    count: np.ndarray, fgw: np.ndarray, bounds: np.ndarray, signed: np.ndarray
) -> float:
    """Change of eq. 9's foreground sum inside ``bounds`` (x0, y0, x1, y1) when the boxes
    ``signed[:, :4]`` are added (``signed[:, 4] = +1``) or removed (``-1``) from the
    per-pixel coverage counts ``count`` (height, width)."""
    X0, Y0, X1, Y1 = bounds[0], bounds[1], bounds[2], bounds[3]
    patch = np.zeros((Y1 - Y0, X1 - X0), dtype=np.int64)
    for r in range(signed.shape[0]):
        for yy in range(signed[r, 1], signed[r, 3]):
            for xx in range(signed[r, 0], signed[r, 2]):
                patch[yy - Y0, xx - X0] += signed[r, 4]
    d = 0.0
    for yy in range(Y0, Y1):
        for xx in range(X0, X1):
            old = count[yy, xx] > 0
            new = count[yy, xx] + patch[yy - Y0, xx - X0] > 0
            if new and not old:
                d += fgw[yy, xx]
            elif old and not new:
                d -= fgw[yy, xx]
    return d


@njit(cache=True, nogil=True)
def _log_gauss2(x: float, y: float, mx: float, my: float, l00: float, l10: float, l11: float):
    z1 = (x - mx) / l00
    z2 = (y - my - l10 * z1) / l11
    return -0.5 * (z1 * z1 + z2 * z2) - math.log(l00 * l11) - LOG_2PI


@njit(cache=True, nogil=True)
def update_log_q_at(
    x1: float,
    y1: float,
    x0: float,
    y0: float,
    chol: np.ndarray,
    origin: np.ndarray,
    step: float,
    det: np.ndarray,
    gate2: float,
    w: float,
) -> float:
    """:func:`update_log_q` with the kernel factor looked up at ``(x0, y0)`` in the grid
    ``chol`` (nx, ny, 3) of ``(l00, l10, l11)`` (cell of the rounded position, clipped),
    the lookup of ``RJMCMCTracker.update_chol``."""
    i = min(max(int(round((x0 - origin[0]) / step)), 0), chol.shape[0] - 1)
    j = min(max(int(round((y0 - origin[1]) / step)), 0), chol.shape[1] - 1)
    return update_log_q(x1, y1, x0, y0, chol[i, j, 0], chol[i, j, 1], chol[i, j, 2], det, gate2, w)


@njit(cache=True, nogil=True)
def update_log_q(
    x1: float,
    y1: float,
    x0: float,
    y0: float,
    l00: float,
    l10: float,
    l11: float,
    det: np.ndarray,
    gate2: float,
    w: float,
) -> float:
    """``log q(u1 | u0)`` of seed 003's update move: with weight ``1 - w`` a random walk
    ``N(u0, L L^T)``, with weight ``w`` a jump ``N(d, L L^T)`` to a detection ``d`` (rows
    of ``det``) chosen uniformly among those within the Mahalanobis gate ``gate2`` of
    ``u0``; the arithmetic (and its order) of ``FrameChain._log_q_update``."""
    l_rw = _log_gauss2(x1, y1, x0, y0, l00, l10, l11)
    ls = np.empty(det.shape[0])
    n = 0
    for d in range(det.shape[0]):
        dx, dy = det[d, 0], det[d, 1]
        z1 = (dx - x0) / l00
        z2 = (dy - y0 - l10 * z1) / l11
        if z1 * z1 + z2 * z2 < gate2:
            ls[n] = _log_gauss2(x1, y1, dx, dy, l00, l10, l11)
            n += 1
    if n == 0:
        return l_rw
    mx = ls[0]
    for k in range(1, n):
        mx = max(mx, ls[k])
    mx = max(mx, l_rw)
    s = 0.0
    for k in range(n):
        s += math.exp(ls[k] - mx)
    mix = (1 - w) * math.exp(l_rw - mx) + w * s / n
    return mx + math.log(mix)


@njit(cache=True, nogil=True)
def far_detections(det: np.ndarray, gate_L: np.ndarray, pts: np.ndarray, gate2: float):
    """Detections (nd, 2) whose Mahalanobis distance (gate factors (nd, 2, 2)) to every
    point of ``pts`` (n, 2) exceeds ``sqrt(gate2)``: the add move's candidates (seed 003,
    sec. 3.4); the arithmetic of ``FrameChain._eligible``."""
    nd = det.shape[0]
    out = np.ones(nd, dtype=np.bool_)
    for d in range(nd):
        l00, l10, l11 = gate_L[d, 0, 0], gate_L[d, 1, 0], gate_L[d, 1, 1]
        c = math.log(l00 * l11)
        for k in range(pts.shape[0]):
            z1 = (pts[k, 0] - det[d, 0]) / l00
            z2 = (pts[k, 1] - det[d, 1] - l10 * z1) / l11
            lp = -0.5 * (z1 * z1 + z2 * z2) - c - LOG_2PI
            if not -2.0 * (lp + c + LOG_2PI) > gate2:
                out[d] = False
                break
    return out


@njit(cache=True, nogil=True)
def add_log_q(
    ux: float,
    uy: float,
    h: float,
    det: np.ndarray,
    det_L: np.ndarray,
    elig: np.ndarray,
    h_mean: float,
    h_sd0: float,
) -> float:
    """``log q`` of the add move: a detection chosen uniformly among ``elig``, the position
    drawn from its single-view Gaussian, the height from ``N(h_mean, h_sd0^2)``, the
    orientation uniform; the arithmetic of ``FrameChain._log_q_add``."""
    lps = np.empty(det.shape[0])
    n = 0
    for d in range(det.shape[0]):
        if not elig[d]:
            continue
        l00, l10, l11 = det_L[d, 0, 0], det_L[d, 1, 0], det_L[d, 1, 1]
        z1 = (ux - det[d, 0]) / l00
        z2 = (uy - det[d, 1] - l10 * z1) / l11
        lps[n] = -0.5 * (z1 * z1 + z2 * z2) - math.log(l00 * l11) - LOG_2PI
        n += 1
    if n == 0:
        return -math.inf
    mx = lps[0]
    for k in range(1, n):
        mx = max(mx, lps[k])
    s = 0.0
    for k in range(n):
        s += math.exp(lps[k] - mx)
    lq = mx + math.log(s / n)
    zh = (h - h_mean) / h_sd0
    return lq - 0.5 * zh * zh - math.log(h_sd0) - 0.5 * LOG_2PI - LOG_2PI


@njit(cache=True, nogil=True)
def frame_codes(image: np.ndarray, D: np.ndarray, levels: int, c1: float, c2: float):
    """Per-pixel colour code, foreground gain and its integral image of one frame, in one
    pass (float32 images); the arithmetic of ``likelihood.prepare_frame``.

    Returns
    -------
    code : ndarray, shape (V, H, W), int64
        Colour bin ``+ levels^3 [D > c2]``.
    fgw : ndarray, shape (V, H, W)
        ``c1 (D - c2)``.
    ii : ndarray, shape (V, (H + 1) (W + 1))
        Flattened integral images of ``fgw`` (cumulated over rows, then columns).
    """
    V, H, W = D.shape
    nb = levels**3
    Lf = np.float32(levels)
    c2f = np.float32(c2)
    code = np.empty((V, H, W), dtype=np.int64)
    fgw = np.empty((V, H, W))
    ii = np.zeros((V, H + 1, W + 1))
    col = np.zeros(W)
    for v in range(V):
        col[:] = 0.0
        for y in range(H):
            run = 0.0
            for x in range(W):
                b = 0
                for k in range(3):
                    q = int(image[v, y, x, k] * Lf)
                    q = min(max(q, 0), levels - 1)
                    b = b * levels + q
                d = D[v, y, x]
                code[v, y, x] = b + (nb if d > c2f else 0)
                g = c1 * (np.float64(d) - c2)
                fgw[v, y, x] = g
                col[x] += g
                run += col[x]
                ii[v, y + 1, x + 1] = run
    return code, fgw, ii.reshape(V, (H + 1) * (W + 1))


@njit(cache=True, nogil=True)
def interaction_row(
    s: np.ndarray,
    u: np.ndarray,
    S: np.ndarray,
    upr: np.ndarray,
    present: np.ndarray,
    c: int,
    s_along: float,
    s_across: float,
) -> np.ndarray:
    """Pair penalties ``g(X, X_j)`` of sec. 3.2 between one person (state ``s`` = (x, y,
    h, alpha), predicted position ``u``) and every present person other than ``c`` (rows
    of ``S`` (M, 4) and ``upr`` (M, 2)); zero elsewhere. The arithmetic of ``FrameChain._pair``.

    Returns
    -------
    ndarray, shape (M,)
    """
    row = np.zeros(S.shape[0])
    for j in range(S.shape[0]):
        if not present[j] or j == c:
            continue
        total = 0.0
        for k in range(2):
            if k == 0:
                dx, dy = s[0] - S[j, 0], s[1] - S[j, 1]
            else:
                dx, dy = u[0] - upr[j, 0], u[1] - upr[j, 1]
            if dx * dx + dy * dy > 9.0:  # psi < 1e-21 beyond 3 m
                continue
            for m in range(2):
                a = s[3] if m == 0 else S[j, 3]
                c, sn = math.cos(a), math.sin(a)
                al = (dx * c + dy * sn) / s_along
                ac = (-dx * sn + dy * c) / s_across
                total += math.exp(-0.5 * (al * al + ac * ac))
        row[j] = total
    return row


@njit(cache=True, nogil=True)
def _nonempty(boxes: np.ndarray, present: bool) -> np.ndarray:
    out = np.empty((3, 4), dtype=np.int64)
    n = 0
    if present:
        for b in range(3):
            if boxes[b, 2] > boxes[b, 0] and boxes[b, 3] > boxes[b, 1]:
                out[n] = boxes[b]
                n += 1
    return out[:n]


@njit(cache=True, nogil=True)
def foreground_one(
    count: np.ndarray,
    fgw: np.ndarray,
    ii: np.ndarray,
    stride: int,
    old_present: bool,
    old_boxes: np.ndarray,
    old_usum: np.ndarray,
    new_present: bool,
    new_boxes: np.ndarray,
    stay_bbox: np.ndarray,
):
    """Eq. 9 change, view by view, when one person's boxes change (the others stay).

    Parameters
    ----------
    count : ndarray, shape (V, H, W)
        Coverage counts of the current configuration.
    fgw, ii : ndarray, shapes (V, H, W) and (V, (H + 1) (W + 1))
        Foreground gains and their integral images (row stride ``stride``).
    old_present, old_boxes, old_usum : bool, (V, 3, 4), (V,)
        The person's current existence, part boxes and per-view union sums of ``fgw``.
    new_present, new_boxes : bool, (V, 3, 4)
        Its proposed existence and boxes.
    stay_bbox : ndarray, shape (V, n, 4)
        Union boxes of the unchanged present people.

    Returns
    -------
    touched : (V,) bool, whether the view changes; d_fg : (V,) eq. 9 change;
    new_usum : (V,) union sums of the new boxes; others : (V, n) bool, the unchanged
    people whose boxes meet the changed area (the arithmetic of
    ``IncrementalLikelihood._foreground_view``).
    """
    V = count.shape[0]
    touched = np.zeros(V, dtype=np.bool_)
    d_fg = np.zeros(V)
    new_usum = np.zeros(V)
    others = np.zeros((V, stay_bbox.shape[1]), dtype=np.bool_)
    for v in range(V):
        old = _nonempty(old_boxes[v], old_present)
        new = _nonempty(new_boxes[v], new_present)
        if old.shape[0] == 0 and new.shape[0] == 0:
            continue
        touched[v] = True
        X0 = Y0 = 1 << 40
        X1 = Y1 = -1
        for B in (old, new):
            for r in range(B.shape[0]):
                X0 = min(X0, B[r, 0])
                Y0 = min(Y0, B[r, 1])
                X1 = max(X1, B[r, 2])
                Y1 = max(Y1, B[r, 3])
        any_other = False
        for n in range(stay_bbox.shape[1]):
            k0, k1, k2, k3 = (
                stay_bbox[v, n, 0],
                stay_bbox[v, n, 1],
                stay_bbox[v, n, 2],
                stay_bbox[v, n, 3],
            )
            if not (k0 >= X1 or k2 <= X0 or k1 >= Y1 or k3 <= Y0):
                others[v, n] = True
                any_other = True
        if new.shape[0]:
            new_usum[v] = union_sum(ii[v], stride, new)
        if not any_other:
            d_fg[v] = new_usum[v] - (old_usum[v] if old_present else 0.0)
            continue
        signed = np.empty((old.shape[0] + new.shape[0], 5), dtype=np.int64)
        for r in range(old.shape[0]):
            signed[r, :4] = old[r]
            signed[r, 4] = -1
        for r in range(new.shape[0]):
            signed[old.shape[0] + r, :4] = new[r]
            signed[old.shape[0] + r, 4] = 1
        bounds = np.array([X0, Y0, X1, Y1], dtype=np.int64)
        d_fg[v] = patch_foreground_delta(count[v], fgw[v], bounds, signed)
    return touched, d_fg, new_usum, others


@njit(cache=True, nogil=True)
def _hidden_boxes(
    i, di, bbox, stay, boxes_a, bbox_a, depth_a, v, j, new_present, new_boxes, new_bbox, new_depth
):
    """Part boxes (n, 4) of the people nearer than person ``i`` (depth ``di``) whose union
    box meets ``bbox``, in the configuration after the move (``_slot_cost``'s ``occ``)."""
    out = np.zeros((3 * (stay.shape[0] + 1), 4), dtype=np.int64)
    n = 0
    x0, y0, x1, y1 = bbox[0], bbox[1], bbox[2], bbox[3]
    for s in range(stay.shape[0] + 1):
        if s < stay.shape[0]:
            k = stay[s]
            dk = depth_a[v, k]
            bbk = bbox_a[v, k]
            bk = boxes_a[v, k]
        else:
            if not new_present:
                continue
            k = j
            dk = new_depth[v]
            bbk = new_bbox[v]
            bk = new_boxes[v]
        if dk > di or (dk == di and k > i) or k == i:
            continue
        if bbk[0] >= x1 or bbk[2] <= x0 or bbk[1] >= y1 or bbk[3] <= y0:
            continue
        for b in range(3):
            out[n] = bk[b]
            n += 1
    return out[:n]


@njit(cache=True, nogil=True)
def _stay_people(present: np.ndarray, j: int, bbox_a: np.ndarray):
    """The present people other than ``j`` (index order) and their union boxes (V, n, 4)."""
    M = present.shape[0]
    stay = np.empty(M, dtype=np.int64)
    n = 0
    for k in range(M):
        if present[k] and k != j:
            stay[n] = k
            n += 1
    stay = stay[:n]
    out = np.empty((bbox_a.shape[0], n, 4), dtype=np.int64)
    for v in range(bbox_a.shape[0]):
        for s in range(n):
            out[v, s] = bbox_a[v, stay[s]]
    return stay, out


@njit(cache=True, nogil=True)
def _behind(k, j, dk, dj_old, dj_new, old_present, new_present) -> bool:
    """Whether person ``j`` is (or was) nearer than ``k`` (ties: the smaller index)."""
    if old_present and (dj_old < dk or (dj_old == dk and j < k)):
        return True
    return new_present and (dj_new < dk or (dj_new == dk and j < k))


@njit(cache=True, nogil=True)
def one_person_delta(
    count,
    fgw,
    ii,
    stride,
    code,
    j,
    old_present,
    present,
    active,
    boxes_a,
    bbox_a,
    depth_a,
    usum_a,
    cc_a,
    new_present,
    new_boxes,
    new_bbox,
    new_depth,
    sref,
    nref,
    lambda_im,
    lambda_f,
    d_min,
):
    """Eqs. 8-10 change when person ``j`` alone changes, all views, in one call: the
    arithmetic and order of ``IncrementalLikelihood.propose`` (eq. 9 per view, then the
    colour terms of ``j`` and of the unchanged people behind it).

    Returns
    -------
    delta, touched (V,), d_fg (V,), new_usum (V,), and the recomputed colour terms as
    views (n,), people (n,), values (n,).
    """
    V = count.shape[0]
    M = present.shape[0]
    num_bins = sref.shape[3]
    stay, stay_bbox = _stay_people(present, j, bbox_a)
    n_stay = stay.shape[0]
    touched, d_fg, new_usum, others = foreground_one(
        count,
        fgw,
        ii,
        stride,
        old_present,
        boxes_a[:, j],
        usum_a[:, j],
        new_present,
        new_boxes,
        stay_bbox,
    )
    out_v = np.empty(V * (M + 1), dtype=np.int64)
    out_k = np.empty(V * (M + 1), dtype=np.int64)
    out_c = np.empty(V * (M + 1))
    n = 0
    delta = 0.0
    for v in range(V):
        if not touched[v]:
            continue
        delta += d_fg[v]
        if active[j]:
            c_new = 0.0
            bb = new_bbox[v]
            if new_present and bb[2] > bb[0] and bb[3] > bb[1]:
                hid = _hidden_boxes(
                    j, new_depth[v], bb, stay, boxes_a, bbox_a, depth_a, v, j,
                    new_present, new_boxes, new_bbox, new_depth,
                )  # fmt: skip
                c_new = region_colour_cost(
                    code[v], bb, new_boxes[v], hid, sref[j], nref[j], num_bins, lambda_im,
                    lambda_f, d_min,
                )  # fmt: skip
            delta += c_new - cc_a[v, j]
            out_v[n], out_k[n], out_c[n] = v, j, c_new
            n += 1
        for s in range(n_stay):
            k = stay[s]
            if not others[v, s] or not active[k]:
                continue
            if not _behind(k, j, depth_a[v, k], depth_a[v, j], new_depth[v], old_present,
                           new_present):  # fmt: skip
                continue
            bb = bbox_a[v, k]
            c_new = 0.0
            if bb[2] > bb[0] and bb[3] > bb[1]:
                hid = _hidden_boxes(
                    k, depth_a[v, k], bb, stay, boxes_a, bbox_a, depth_a, v, j,
                    new_present, new_boxes, new_bbox, new_depth,
                )  # fmt: skip
                c_new = region_colour_cost(
                    code[v], bb, boxes_a[v, k], hid, sref[k], nref[k], num_bins, lambda_im,
                    lambda_f, d_min,
                )  # fmt: skip
            delta += c_new - cc_a[v, k]
            out_v[n], out_k[n], out_c[n] = v, k, c_new
            n += 1
    return delta, touched, d_fg, new_usum, out_v[:n], out_k[:n], out_c[:n]


@njit(cache=True, nogil=True)
def update_log_q_pair(x1, y1, x0, y0, chol, origin, step, det, gate2, w):
    """``(log q(u1 | u0), log q(u0 | u1))`` of the update move in one call
    (:func:`update_log_q_at` both ways)."""
    fwd = update_log_q_at(x1, y1, x0, y0, chol, origin, step, det, gate2, w)
    rev = update_log_q_at(x0, y0, x1, y1, chol, origin, step, det, gate2, w)
    return fwd, rev
