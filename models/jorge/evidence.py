r"""Soft evidence of a label (seed 004's colour model, eq. 6, and our additions for issue
16): the colours a stroke shows given the palettes of its label's objects, the size of its
region given the number of objects, and the palette's colour count, gain and missing
colours given the objects the label knows.

The ``*_log_likelihood`` functions return one log-likelihood per label (shape
``(num_labels,)``); :func:`gain_bins_rise` and :func:`palette_gain_bin` check and read the
bins of known colours the gain and missing-colour tables are conditioned on.
:class:`models.jorge.network.LabelGraph` adds the evidence up per node
(``evidence_loglik``). Moved here from :mod:`models.jorge.labels`, which still exports
every name.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.special import gammaln

from dbn.errors import InputError, ModelError

__all__ = [
    "colour_log_likelihood",
    "size_log_likelihood",
    "palette_count_log_likelihood",
    "gain_bins_rise",
    "palette_gain_bin",
    "palette_gain_log_likelihood",
    "palette_missing_log_likelihood",
]


def _log_binom(n: np.ndarray, total: int, p: np.ndarray) -> np.ndarray:
    p = np.clip(p, 1e-12, 1 - 1e-12)
    return (
        gammaln(total + 1) - gammaln(n + 1) - gammaln(total - n + 1)
        + n * np.log(p) + (total - n) * np.log1p(-p)
    )


def _log_comb(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    with np.errstate(invalid="ignore"):
        out = gammaln(a + 1) - gammaln(b + 1) - gammaln(a - b + 1)
    return np.where((b < 0) | (b > a), -np.inf, out)


def _log_hypergeom(n: np.ndarray, total: int, size: np.ndarray, pool_size: int) -> np.ndarray:
    """log P(n of ``total`` distinct colours drawn at random from the pool fall in a
    palette of ``size`` colours) (hypergeometric)."""
    return (_log_comb(size, n) + _log_comb(pool_size - size, total - n)
            - _log_comb(np.float64(pool_size), np.float64(total)))


def size_log_likelihood(
    rel_log_area: float,
    sizes: np.ndarray,
    mu_single: float,
    slope: float,
    sigma: float,
) -> np.ndarray:
    r"""Soft evidence of a stroke's region size on the number of people of each label.

    Our addition (seed 004 uses colours only): a region holding :math:`k` people is
    larger than one holding one. With :math:`a` the stroke's log region area (median
    over its frames of :math:`\log(w h)` of the region's box) minus the reference, the
    median log area of the strokes seen before it (mostly single people, so an
    on-line, observable stand-in for "one person's size"), the likelihood of a label
    of :math:`k = |x|` objects is the Gaussian

    .. math::
        p(a \mid k) = \mathcal{N}(a;\, \mu_1 + \beta \log k,\, \sigma^2).

    The defaults of :class:`models.jorge.config.NetworkConfig` (:math:`\mu_1`,
    :math:`\beta`, :math:`\sigma`) were estimated on the CAVIAR ground truth with the
    held-out simulation seeds 20-39 (the benchmark uses 0-4): single-person strokes
    :math:`a = -0.14 \pm 0.69`, two-person strokes :math:`0.96 \pm 0.58`, so
    :math:`\mu_1 = -0.14`, :math:`\beta = 1.1 / \log 2` and the pooled
    :math:`\sigma = 0.68` (2250 and 320 strokes; no group of three occurs there, so
    :math:`k \ge 3` follows the :math:`\log k` law untested).

    Parameters
    ----------
    rel_log_area : float
        :math:`a`; NaN when unknown (no box sizes, or no earlier stroke): no evidence.
    sizes : ndarray of int, shape (num_labels,)
        :math:`k` of each candidate label (>= 1).
    mu_single, slope, sigma : float
        :math:`\mu_1`, :math:`\beta`, :math:`\sigma > 0`.

    Returns
    -------
    ndarray, shape (num_labels,)
        Log likelihood up to a constant common to all labels (zeros without evidence).
    """
    sizes = np.asarray(sizes, dtype=np.float64)
    if sizes.ndim != 1 or np.any(sizes < 1):
        raise InputError(f"size_log_likelihood: sizes must be a 1-D array of ints >= 1, got {sizes}")
    if not sigma > 0:
        raise ModelError(f"size_log_likelihood: sigma must be > 0, got {sigma}")
    if not np.isfinite(rel_log_area):
        return np.zeros_like(sizes)
    z = (rel_log_area - (mu_single + slope * np.log(sizes))) / sigma
    return -0.5 * z * z - np.log(sigma) - 0.5 * np.log(2.0 * np.pi)


def palette_count_log_likelihood(count: int, sizes: np.ndarray, table: np.ndarray) -> np.ndarray:
    r"""Soft evidence of the number of distinct colours in a stroke's palette on the number
    of people of each label (issue 16, our addition; not in seed 004).

    A region holding more people shows more distinct dominant colours: the union of its
    people's palettes. :math:`p(c \mid k)` is a table over counts :math:`c` per group size
    :math:`k`, fitted by :func:`models.jorge.fit.fit_parameters` (add-one smoothed
    frequencies on the training split). It tells a new group from a new person, which the
    region size alone does poorly (issue 16). Caveat: with the benchmark's simulated
    colours a palette is a clean union of its people's palettes, so this evidence is
    strong there; on real images the count of colour clusters in a blob is noisier and the
    table would have to be fitted on such data.

    Parameters
    ----------
    count : int
        :math:`c`, distinct colours of the stroke's palette (``Stroke.palette``).
    sizes : ndarray of int, shape (num_labels,)
        :math:`k = |x|` of each candidate label (>= 1).
    table : ndarray, shape (max_k, max_count + 1)
        :math:`\log p(c \mid k)`; sizes above ``max_k`` use its last row, counts above
        ``max_count`` its last column. An empty table: no evidence.

    Returns
    -------
    ndarray, shape (num_labels,)
        :math:`\log p(c \mid k)` per label (zeros without a table).
    """
    sizes = np.asarray(sizes, dtype=np.int64)
    table = np.asarray(table, dtype=np.float64)
    if table.size == 0:
        return np.zeros(sizes.shape, dtype=np.float64)
    if table.ndim != 2:
        raise ModelError(f"palette_count_log_likelihood: table must be 2-D, got shape {table.shape}")
    if sizes.ndim != 1 or np.any(sizes < 1):
        raise InputError(f"palette_count_log_likelihood: sizes must be ints >= 1, got {sizes}")
    rows = np.minimum(sizes, table.shape[0]) - 1
    return table[rows, min(max(int(count), 0), table.shape[1] - 1)].copy()


def gain_bins_rise(bins) -> bool:
    """Whether ``bins`` are valid lower edges of the bins of :math:`u`: 1-D, not empty,
    rising strictly from 0 (``NetworkConfig.palette_gain_bins``)."""
    edges = np.asarray(bins)
    return bool(edges.ndim == 1 and edges.size > 0 and edges[0] == 0 and np.all(np.diff(edges) > 0))


def palette_gain_bin(bins: Sequence[int], known) -> np.ndarray:
    r""":math:`b(u)`: the index of the last of the increasing lower edges ``bins`` that is at
    most :math:`u` (``known``, an int or an array of them), as the palette gain table is
    indexed (:func:`palette_gain_log_likelihood`) and fitted
    (:func:`models.jorge.fit.fit_parameters`)."""
    return np.searchsorted(np.asarray(bins), known, side="right") - 1


def palette_gain_log_likelihood(count: int, known: np.ndarray, new: np.ndarray, table: np.ndarray,
                                bins: Sequence[int] = ()) -> np.ndarray:
    r"""Soft evidence of a stroke's palette colour count on each label, given the palettes
    its objects already have (issue 16, our addition; replaces the marginal
    :func:`palette_count_log_likelihood` when a gain table is set).

    A label :math:`x` of inherited objects :math:`A` (not born at this stroke) and
    :math:`m` objects born here explains a palette of :math:`c` distinct colours when
    :math:`c = u + e`: :math:`u = |\bigcup_{o \in A} \pi_o|` the colours its known objects'
    palettes already hold, :math:`e` the gain the newcomers bring (0 for :math:`m = 0`
    with clean palettes; negative when an object's birth palette was a group's). The
    likelihood is the table :math:`p(e \mid m)`, or :math:`p(e \mid m, b(u))` with
    :math:`b(u)` the bin of :math:`u` (issue 16, fourteenth round: one newcomer with nothing
    known adds 5 colours in 97% of the training strokes, one with 10-12 colours known adds
    none in 56%), fitted on the training split (:func:`models.jorge.fit.fit_parameters`).
    A new group (:math:`A = \emptyset`) reads :math:`p(c \mid m)`, as the marginal table does; but a merge of two people whose
    palettes happen to be disjoint (10 colours) is no longer taken for three people: the
    marginal :math:`p(c \mid k)` of a random pair makes 10 colours rare and favoured a
    join (the pair plus a newcomer) over the true merge (issue 16 diagnosis,
    ``models.jorge.fit``).

    Parameters
    ----------
    count : int
        :math:`c`, distinct colours of the stroke's palette.
    known : ndarray of int, shape (num_labels,)
        :math:`u` per label (0 for a label of new objects only).
    new : ndarray of int, shape (num_labels,)
        :math:`m` per label (objects born at this stroke).
    table : ndarray, shape (max_m + 1, 2 * pool_size + 1) or (max_m + 1, len(bins), 2 * pool_size + 1)
        :math:`\log p(e \mid m)` or :math:`\log p(e \mid m, b)`, column ``e + pool_size``;
        ``m`` above ``max_m`` uses the last row, gains outside the table its edge columns.
        Empty: no evidence.
    bins : sequence of int
        Increasing lower edges of the bins of :math:`u`, the first 0 (a 3-D ``table``):
        :math:`b(u)` is the last bin whose edge is at most :math:`u`.

    Returns
    -------
    ndarray, shape (num_labels,)
    """
    known = np.asarray(known, dtype=np.int64)
    new = np.asarray(new, dtype=np.int64)
    table = np.asarray(table, dtype=np.float64)
    if table.size == 0:
        return np.zeros(known.shape, dtype=np.float64)
    edges = np.asarray(bins, dtype=np.int64)
    if table.ndim != 2 + (edges.size > 0) or table.shape[-1] % 2 != 1:
        raise ModelError(f"palette_gain_log_likelihood: table must be {2 + (edges.size > 0)}-D (with "
                         f"{edges.size} bins of u) with an odd number of columns, got shape {table.shape}")
    if edges.size and (table.shape[1] != edges.size or not gain_bins_rise(edges)):
        raise ModelError(f"palette_gain_log_likelihood: bins {tuple(bins)} must rise from 0, one per "
                         f"entry of the table's axis 1 (shape {table.shape})")
    if known.shape != new.shape or known.ndim != 1 or np.any(known < 0) or np.any(new < 0):
        raise InputError(f"palette_gain_log_likelihood: known {known} and new {new} must be 1-D "
                         f"non-negative ints of one length")
    off = table.shape[-1] // 2
    cols = np.clip(int(count) - known + off, 0, table.shape[-1] - 1)
    rows = np.minimum(new, table.shape[0] - 1)
    if edges.size:
        return table[rows, palette_gain_bin(edges, known), cols]
    return table[rows, cols].copy()


def palette_missing_log_likelihood(missing: np.ndarray, known: np.ndarray, new: np.ndarray,
                                   table: np.ndarray, bins: Sequence[int]) -> np.ndarray:
    r"""Soft evidence of the known colours a stroke's palette lacks (issue 16, thirty-fourth
    round, our addition; beside :func:`palette_gain_log_likelihood`).

    A label's known objects :math:`A` (as there) hold the colours
    :math:`U = \bigcup_{o \in A} \pi_o`, :math:`u = |U|`; the stroke's palette :math:`P`
    lacks :math:`d = |U \setminus P|` of them. The gain :math:`e = |P| - u` counts
    :math:`|P \setminus U| - d`, so a label that swaps a member for someone else (the
    colours of one lost, of the other gained) has :math:`e = 0`, as the true label has; the
    true label's :math:`d` is 0 where its objects' palettes are their own. The likelihood
    is the table :math:`p(d \mid m, b(u))`, fitted on the training split
    (:func:`models.jorge.fit.fit_parameters` with ``NetworkConfig.palette_missing``).

    Parameters
    ----------
    missing : ndarray of int, shape (num_labels,)
        :math:`d` per label.
    known : ndarray of int, shape (num_labels,)
        :math:`u` per label.
    new : ndarray of int, shape (num_labels,)
        :math:`m` per label (objects born at this stroke).
    table : ndarray, shape (max_m + 1, len(bins), pool_size + 1)
        :math:`\log p(d \mid m, b)`; ``m`` above ``max_m`` uses the last row, ``d`` above
        ``pool_size`` the last column. Empty: no evidence.
    bins : sequence of int
        Increasing lower edges of the bins of :math:`u`, the first 0
        (:func:`palette_gain_bin`).

    Returns
    -------
    ndarray, shape (num_labels,)
    """
    missing, known, new = (np.asarray(a, dtype=np.int64) for a in (missing, known, new))
    table = np.asarray(table, dtype=np.float64)
    if table.size == 0:
        return np.zeros(missing.shape, dtype=np.float64)
    edges = np.asarray(bins, dtype=np.int64)
    if table.ndim != 3 or table.shape[1] != edges.size or not gain_bins_rise(edges):
        raise ModelError(f"palette_missing_log_likelihood: table must be 3-D with one entry of axis 1 per "
                         f"bin of u {tuple(bins)} (rising from 0), got shape {table.shape}")
    if not (missing.shape == known.shape == new.shape and missing.ndim == 1) or np.any(missing < 0) \
            or np.any(known < 0) or np.any(new < 0) or np.any(missing > known):
        raise InputError(f"palette_missing_log_likelihood: missing {missing}, known {known} and new {new} "
                         f"must be 1-D non-negative ints of one length, missing at most known")
    rows = np.minimum(new, table.shape[0] - 1)
    cols = np.minimum(missing, table.shape[2] - 1)
    return table[rows, palette_gain_bin(edges, known), cols]


def colour_log_likelihood(
    colours: np.ndarray,
    palettes: np.ndarray,
    is_new: np.ndarray,
    match_prob: float,
    pool_size: int,
    mode: str = "ratio",
) -> np.ndarray:
    r"""Soft evidence of a stroke's dominant colours on each candidate label (eq. 6).

    With :math:`n` the number of the stroke's :math:`N` colours found in the label's
    palette (the union of its objects' palettes, each taken from the stroke where the
    object was born), :math:`P` the match probability and :math:`q = m / \text{pool}` the
    chance that a colour falls in a palette of :math:`m` colours:

    * ``mode="hyper"`` (the network's default): the likelihood ratio of the colours under
      the label against chance matches of :math:`N` *distinct* colours drawn from the
      pool, :math:`\log \mathrm{Bin}(n; N, P) - \log \mathrm{Hyp}(n; \text{pool}, m, N)`,
      :math:`\mathrm{Hyp}(n; K, m, N) = \binom{m}{n}\binom{K-m}{N-n} / \binom{K}{N}`
      (exact for distinct dominant colours; the binomial below treats them as drawn
      with replacement and overstates chance matches of small palettes); a new label
      carries no colour information (ratio 1, log 0).
    * ``mode="ratio"``: the same with the binomial of chance matches,
      :math:`\log \mathrm{Bin}(n; N, P) - \log \mathrm{Bin}(n; N, q)`.
    * ``mode="eq6"``: seed 004 eq. 6 as written,
      :math:`\log \binom{N}{n} P^n (1-P)^{N-n}`, for every label, the new one included
      (its palette is the one it gets from this very stroke). For :math:`P = 0.8` this peaks
      at :math:`n = 4`, so it prefers a label matching 4 colours over one matching 5.

    Parameters
    ----------
    colours : ndarray of int, shape (num_colours,)
        The stroke's dominant colours (pool indices).
    palettes : ndarray of bool, shape (num_labels, pool_size)
        Palette of each candidate label.
    is_new : ndarray of bool, shape (num_labels,)
        Which candidate is the stroke's own new label.
    match_prob : float
        :math:`P`.
    pool_size : int
    mode : {"ratio", "hyper", "eq6"}

    Returns
    -------
    ndarray, shape (num_labels,)
        Log likelihood (up to a constant common to all labels of the stroke).
    """
    palettes = np.asarray(palettes, dtype=bool)
    colours = np.asarray(colours)
    if colours.size == 0:
        raise InputError("colour_log_likelihood: empty colour set")
    total = colours.size
    n = palettes[:, colours].sum(axis=1).astype(np.float64)
    if mode == "eq6":
        return _log_binom(n, total, np.full_like(n, match_prob))
    if mode not in ("ratio", "hyper"):
        raise ModelError(f"colour model mode must be 'ratio', 'hyper' or 'eq6', got {mode!r}")
    size = palettes.sum(axis=1).astype(np.float64)
    if mode == "hyper":
        chance = _log_hypergeom(n, total, size, pool_size)
    else:
        chance = _log_binom(n, total, size / pool_size)
    out = _log_binom(n, total, np.full_like(n, match_prob)) - chance
    return np.where(is_new, 0.0, out)
