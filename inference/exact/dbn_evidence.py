"""Evidence of discrete DBNs turned into per-slice likelihood vectors, checked first.

Every form of evidence on a discrete variable ``v`` at slice ``t`` becomes one likelihood
vector :math:`\\lambda_{v,t}(x)` of length ``cardinality(v)``: ones where unobserved, a
one-hot row for hard evidence, the given vector for soft (virtual) evidence, their
product when both are given. The structured filter multiplies it into ``v``'s CPD.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from numpy.typing import ArrayLike

from dbn.bayesnet import check_likelihood
from dbn.checks import check_count, check_mapping
from dbn.errors import ShapeError, UnknownEvidenceError
from dbn.variables import DiscreteVariable
from inference.evidence_columns import slice_states, soft_column, state_column

__all__ = ["sequence_likelihoods", "slice_likelihoods", "distinct_rows"]


def _variable(variables: Mapping[str, DiscreteVariable], name: str, what: str):
    if name not in variables:
        raise UnknownEvidenceError(
            f"{what} on unknown variable {name!r} (known: {sorted(variables)})"
        )
    return variables[name]


def sequence_likelihoods(
    variables: Mapping[str, DiscreteVariable],
    evidence: Mapping[str, ArrayLike] | None,
    soft_evidence: Mapping[str, ArrayLike] | None = None,
    num_timesteps: int | None = None,
) -> tuple[int, dict[str, np.ndarray]]:
    """Check columnar evidence and turn it into likelihoods.

    Parameters
    ----------
    variables : mapping name -> DiscreteVariable
    evidence : mapping name -> array, shape (T,)
        Observed state per slice: by index (``-1`` where unobserved) or by name (``None``
        where unobserved); :func:`~inference.evidence_columns.state_column`.
    soft_evidence : mapping name -> float array, shape (T, cardinality), optional
        A likelihood row per slice (nonnegative, finite, not all zero); a row of NaN means
        no soft evidence on that slice.
    num_timesteps : int, optional
        ``T``; needed only without any column.

    Returns
    -------
    T : int
    lam : dict name -> float array, shape (T, cardinality)

    Raises
    ------
    EvidenceError, ShapeError
        Unknown variable, states neither integers nor names, a state out of range or not
        a state name, lengths that differ, a soft row of the wrong shape or not a likelihood.
    """
    if num_timesteps is not None:
        check_count("num_timesteps", num_timesteps, ShapeError)
    check_mapping("evidence", evidence)
    check_mapping("soft evidence", soft_evidence)
    T = num_timesteps
    lam: dict[str, np.ndarray] = {}
    for name, col in (evidence or {}).items():
        v = _variable(variables, name, "evidence")
        arr, T = state_column(name, v, col, T)
        k = v.cardinality
        rows = np.ones((arr.shape[0], k))
        seen = arr >= 0
        rows[seen] = np.eye(k)[arr[seen]]
        lam[name] = rows
    for name, col in (soft_evidence or {}).items():
        rows, T = soft_column(name, _variable(variables, name, "soft evidence"), col, T)
        lam[name] = lam[name] * rows if name in lam else rows
    if T is None or T < 1:
        raise ShapeError("filtering needs num_timesteps >= 1 (give it or an evidence column)")
    return int(T), lam


def slice_likelihoods(
    variables: Mapping[str, DiscreteVariable],
    evidence: Mapping[str, int | str] | None,
    soft_evidence: Mapping[str, ArrayLike] | None = None,
) -> dict[str, np.ndarray]:
    """One slice's evidence (name -> state, name -> likelihood vector) as likelihoods,
    each of shape (1, cardinality)."""
    hard = slice_states(variables, evidence)  # checks the mapping (or a pandas Series)
    check_mapping("soft evidence", soft_evidence)
    lam: dict[str, np.ndarray] = {}
    for name, state in hard.items():
        lam[name] = np.eye(variables[name].cardinality)[state][None]
    for name, vec in (soft_evidence or {}).items():
        v = _variable(variables, name, "soft evidence")
        row = check_likelihood(name, v.cardinality, vec)[None]
        lam[name] = lam[name] * row if name in lam else row
    return lam


def distinct_rows(lam: Mapping[str, np.ndarray], names: tuple[str, ...], start: int, stop: int):
    """The distinct evidence rows of slices ``start..stop-1``.

    Returns
    -------
    rows : dict name -> (R, cardinality)
        One likelihood per distinct row.
    inverse : int array, shape (stop - start,)
        The distinct row of every slice.
    """
    n = stop - start
    if not names:
        return {}, np.zeros(n, np.int64)
    mat = np.concatenate([lam[v][start:stop] for v in names], axis=1)
    uniq, inverse = np.unique(mat, axis=0, return_inverse=True)
    rows, col = {}, 0
    for v in names:
        k = lam[v].shape[1]
        rows[v] = uniq[:, col : col + k]
        col += k
    return rows, np.asarray(inverse).reshape(-1)
