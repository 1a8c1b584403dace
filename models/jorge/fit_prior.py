r"""Parameters fitted on little data, shrunk towards a prior network (``dbntrack fit jorge
--prior-strength``).

:func:`models.jorge.fit.fit_counts` gives every CPD row the add-one smoothed frequency of
its events: a rate :math:`\hat p = (n + 1) / (N + 2)`, a row of a palette table
:math:`\hat p_i = (n_i + 1) / (N + K)`. On a few training files a row has few events and
its smoothing floor, :math:`1 / (N + K)`, decides labels: with clean SIMULATED palettes a
refit on three stroke seeds instead of ten raised a held-out wk2gt run from 0.000 to 0.522
(the gain table's floor for one person with eight colours decided a pair at the start).

:func:`shrink` takes the posterior mean under a Dirichlet (Beta) prior centred on a prior
network's row :math:`p^0` with :math:`\lambda` pseudo-observations, on top of the add-one
counts:

.. math::

    \tilde p_i = \frac{n_i + 1 + \lambda p^0_i}{N + K + \lambda}
               = \frac{(N + K) \hat p_i + \lambda p^0_i}{N + K + \lambda},

so :math:`\lambda = 0` is the fit itself and :math:`\lambda \to \infty` the prior; a row
with many events keeps its own frequencies, a row with few moves to the prior's. This
holds for :math:`P_{new}`, the three :math:`P_{merge}`, :math:`P_{split}`,
:math:`P_{part}`, :math:`P_{join}`, :math:`q_m`, the split cover and every row of the
palette tables. The prior's tables index rows as the evidence does: a row beyond its last
takes its last.

The region-size likelihood is a linear regression, :math:`a = \beta_0 + \beta_1 \log k +
\varepsilon`, :math:`\varepsilon \sim N(0, \sigma^2)`, of a stroke's relative log area on
its number of people (``size_mu_single``, ``size_slope``, ``size_sigma``), fitted by least
squares on :math:`N` strokes with design :math:`X`. Its prior is the conjugate
Normal-Inverse-Gamma one centred on the prior network's :math:`(\beta^0, \sigma_0^2)` with
the weight of :math:`\lambda` strokes like the training ones, :math:`\beta \mid \sigma^2
\sim N(\beta^0, \sigma^2 / (\lambda S))` with :math:`S = X^T X / N`, and
:math:`\sigma^2 \sim IG(\lambda / 2, \lambda \sigma_0^2 / 2)`. The posterior mean of
:math:`\beta` and the inverse posterior mean of :math:`\sigma^{-2}` are, with
:math:`d = \hat\beta - \beta^0`,

.. math::

    \tilde\beta = \frac{N \hat\beta + \lambda \beta^0}{N + \lambda}, \qquad
    \tilde\sigma^2 = \frac{N \hat\sigma^2 + \lambda \sigma_0^2
                      + \frac{N \lambda}{N + \lambda} d^T S d}{N + \lambda},

the same limits: the fit at :math:`\lambda = 0`, the prior as :math:`\lambda \to \infty`.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from dbn.errors import InputError
from models.jorge.evidence import palette_gain_bin
from models.jorge.fit import EventCounts, as_config_table
from models.jorge.network import NetworkConfig

__all__ = ["shrink"]

_TABLES = ("palette_count_table", "palette_gain_table", "palette_missing_table")


def shrink(fitted: NetworkConfig, prior: NetworkConfig, counts: EventCounts,
           strength: float) -> NetworkConfig:
    """``fitted`` (:func:`~models.jorge.fit.fit_counts` of ``counts``) shrunk towards
    ``prior`` with ``strength`` :math:`\\lambda` pseudo-observations per row, and per
    region-size regression (module docstring). A table the prior has off (empty) is kept
    as fitted.

    Raises
    ------
    InputError
        ``strength`` negative or not finite; a prior table whose width differs from the
        fitted one's (another ``pool_size``).
    """
    if not (np.isfinite(strength) and strength >= 0):
        raise InputError(f"prior strength {strength!r}: expected a finite number >= 0")
    if strength == 0:
        return fitted
    gmax = fitted.labels.max_group_size
    labels = _labels(fitted.labels, prior.labels, counts, strength, gmax)
    fields = _size(fitted, prior, counts, strength, gmax)
    totals = _table_totals(counts, fitted, gmax)
    for name in _TABLES:
        mine, theirs = getattr(fitted, name), getattr(prior, name)
        if not mine or not theirs:
            continue
        fields[name] = _shrunk_table(name, np.asarray(mine), np.asarray(theirs), totals[name],
                                     strength)  # fmt: skip
    return replace(fitted, labels=labels, **fields)


def _size(fitted: NetworkConfig, prior: NetworkConfig, c: EventCounts, lam: float,
          gmax: int) -> dict:
    """The region-size likelihood's Normal-Inverse-Gamma posterior (module docstring):
    ``size_mu_single``, ``size_slope`` and ``size_sigma`` shrunk towards the prior's."""
    k = np.minimum(np.array([n for n, _ in c.sizes], dtype=np.float64), gmax)
    n = float(k.size)
    beta = np.array([fitted.size_mu_single, fitted.size_slope])
    beta0 = np.array([prior.size_mu_single, prior.size_slope])
    if n == 0:  # nothing fitted: the prior's
        beta, var = beta0, prior.size_sigma**2
    else:
        x = np.stack([np.ones_like(k), np.log(k)], axis=1)
        d = beta - beta0
        spread = float(d @ (x.T @ x / n) @ d) * n * lam / (n + lam)
        beta = (n * beta + lam * beta0) / (n + lam)
        var = (n * fitted.size_sigma**2 + lam * prior.size_sigma**2 + spread) / (n + lam)
    return {"size_mu_single": float(beta[0]), "size_slope": float(beta[1]),
            "size_sigma": float(np.sqrt(var))}


def _mean(p: float, total: float, p0: float, lam: float) -> float:
    """The posterior mean of a rate estimated as ``p`` from ``total`` (add-one) counts."""
    return float((total * p + lam * p0) / (total + lam))


def _labels(mine, theirs, c: EventCounts, lam: float, gmax: int):
    """The label CPD parameters shrunk; each rate's total is its add-one denominator."""
    rates = {"p_new": c.children, "p_split": c.split_total, "p_part": c.part_total,
             "p_join": c.non_new, "p_merge": c.two_parent[0],
             "p_merge_one_split": c.two_parent[1], "p_merge_both_split": c.two_parent[2]}
    out = {k: _mean(getattr(mine, k), float(n) + 2.0, getattr(theirs, k), lam)
           for k, n in rates.items()}  # fmt: skip
    for k in ("p_merge", "p_merge_one_split", "p_merge_both_split"):
        out[k] = min(out[k], 0.98 - out["p_new"])  # as fit_counts keeps p_new + p_merge < 1
    if len(mine.new_group_probs) > 1:
        q0 = _resized(np.asarray(theirs.new_group_probs, dtype=np.float64), gmax)
        q = np.asarray(mine.new_group_probs, dtype=np.float64)
        total = float(c.new_sizes[:gmax].sum()) + gmax
        out["new_group_probs"] = tuple(float(x) for x in (total * q + lam * q0) / (total + lam))
    if mine.split_cover and theirs.split_cover:
        p0 = _resized(np.asarray(theirs.split_cover, dtype=np.float64), gmax, renormalise=False)
        got = [sum(1 for m, _ in c.splits if m == n) + 2.0 for n in range(1, gmax + 1)]
        out["split_cover"] = tuple(1.0 if n <= 2 else _mean(p, t, p0[n - 1], lam) for n, p, t in
                                   zip(range(1, gmax + 1), mine.split_cover, got))  # fmt: skip
    return replace(mine, **out)


def _resized(p: np.ndarray, n: int, renormalise: bool = True) -> np.ndarray:
    """``p`` cut or padded to ``n`` entries (a pad repeats the last for a rate, is zero for
    a distribution, which is renormalised)."""
    if p.size >= n:
        out = p[:n]
    else:
        out = np.concatenate([p, np.full(n - p.size, 0.0 if renormalise else p[-1])])
    return out / out.sum() if renormalise else out


def _table_totals(c: EventCounts, fitted: NetworkConfig, gmax: int) -> dict:
    """Each palette table's add-one row totals (events per row plus its width), shaped as
    the table's rows."""
    bins = fitted.palette_gain_bins
    pool = fitted.pool_size
    out = {}
    for name, triples, width in (("palette_gain_table", c.palette_gains, 2 * pool + 1),
                                 ("palette_missing_table", c.palette_missing, pool + 1)):
        n = np.full((gmax + 1, len(bins)), float(width))
        for m, u, _ in triples:
            n[min(m, gmax), int(palette_gain_bin(bins, u))] += 1.0
        out[name] = n
    n = np.full(gmax, float(pool + 1))
    for k, _ in c.palette_counts:
        if k <= gmax:
            n[k - 1] += 1.0
    out["palette_count_table"] = n
    return out


def _shrunk_table(name: str, mine: np.ndarray, theirs: np.ndarray, totals: np.ndarray,
                  lam: float) -> tuple:
    """A log table's rows shrunk towards the prior's (rows beyond the prior's last take its
    last), as nested tuples."""
    if theirs.ndim != mine.ndim or theirs.shape[1:] != mine.shape[1:]:
        raise InputError(f"prior {name}: shape {theirs.shape} does not fit the fitted "
                         f"{mine.shape} (another pool_size or bins?); fit without a prior")
    rows = np.minimum(np.arange(mine.shape[0]), theirs.shape[0] - 1)
    p0 = np.exp(theirs[rows])
    t = totals[..., None]
    p = (t * np.exp(mine) + lam * p0) / (t + lam)
    table = np.log(p / p.sum(axis=-1, keepdims=True))
    return as_config_table(table)
