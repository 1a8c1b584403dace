r"""What a label node remembers of its last CPD table and colour evidence (issue 16: speed).

The on-line labeller scores a node many times while it is active: once when its stroke
starts, again when a later stroke widens its domain, and in every window it takes part in.
Between two scorings its domain and its parents' domains mostly only shrink (pruning,
freezing), and the entries that are left are the same numbers:

* a CPD row of :func:`~models.jorge.labels.child_table` with ``truncate`` (the default,
  ``NetworkConfig.truncate_pruned``) is divided by the mass over *all* admissible labels,
  and each of its entries is summed from the parent labels' piece laws alone (a join
  label from its source's mass): an entry does not depend on which other labels the
  domains hold;
* the colour and palette evidence of a label (:func:`~models.jorge.evidence.colour_log_likelihood`,
  :func:`~models.jorge.evidence.palette_count_log_likelihood`,
  :func:`~models.jorge.evidence.palette_gain_log_likelihood`) reads only that label's
  objects: their palettes and joiner records.

So the table or evidence of a sub-domain is the remembered one's entries, picked out,
bit for bit (``tests/models/jorge/test_jorge_memo.py`` checks this against computing
afresh). Anything else (another config, sharing, structure, or a label or record the
memo does not hold) is a miss and the caller computes afresh. One memo per active node:
memory stays bounded as the network grows.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from models.jorge.labels import Label

__all__ = ["TableMemo", "EvidenceMemo", "ChainMemo"]


def _positions(axis: Mapping[Label, int], labels: Sequence[Label]) -> list[int] | None:
    """Index of each of ``labels`` on a remembered axis; None if one is missing."""
    try:
        return [axis[lab] for lab in labels]
    except KeyError:
        return None


def _same_records(memo: EvidenceMemo | ChainMemo, config: object, structure: str,
                  records: Mapping[int, tuple]) -> bool:
    """Whether ``memo`` was computed under ``config`` (by identity) and ``structure`` with
    the palette records ``records`` (object -> (own palette stroke, joiner label))."""
    return (config is memo.config and structure == memo.structure
            and all(memo.records.get(o) == rec for o, rec in records.items()))


@dataclass(frozen=True)
class TableMemo:
    """A node's CPD table over the parents' domains and its domain when it was computed.

    Attributes
    ----------
    config : object
        The ``NetworkConfig`` it was computed under (compared by identity).
    shared : tuple of bool
        Whether each parent had a second child.
    axes : tuple of dict Label -> int
        Each parent domain's and then the node's labels, by position in ``table``.
    table : ndarray, shape (*parent_domain_sizes, domain_size)
    exact : bool
        Rows renormalised over the domain (``truncate_pruned`` off) or a root's table:
        an entry depends on the other labels, so only the same domains, in the same
        order, hit.
    """

    config: object
    shared: tuple
    axes: tuple
    table: np.ndarray
    exact: bool

    @classmethod
    def of(cls, config: object, shared: Sequence[bool], parent_domains: Sequence[Sequence[Label]],
           domain: Sequence[Label], table: np.ndarray, exact: bool) -> TableMemo:
        axes = tuple({lab: i for i, lab in enumerate(d)} for d in (*parent_domains, domain))
        return cls(config, tuple(shared), axes, table, exact)

    def select(self, config: object, shared: Sequence[bool], parent_domains: Sequence[Sequence[Label]],
               domain: Sequence[Label]) -> np.ndarray | None:
        """The table over these domains (a fresh array), or None if it cannot be read
        off the remembered one."""
        if config is not self.config or tuple(shared) != self.shared:
            return None
        doms = (*parent_domains, domain)
        if len(doms) != len(self.axes):
            return None
        index = []
        for axis, dom in zip(self.axes, doms):
            pos = _positions(axis, dom)
            if pos is None or (self.exact and pos != list(range(len(axis)))):
                return None
            index.append(pos)
        return self.table[np.ix_(*index)]


@dataclass(frozen=True)
class EvidenceMemo:
    """A node's colour and palette log-likelihoods per label when they were computed.

    Attributes
    ----------
    config : object
        The ``NetworkConfig`` (compared by identity).
    structure : str
        The node's structure then (``palette_continued`` weighs an OCCLUSION node).
    records : dict object -> (own palette stroke or None, joiner label or None)
        What the labels' objects had then.
    axis : dict Label -> int
    colour, palette : ndarray, shape (len(axis),)
    """

    config: object
    structure: str
    records: dict
    axis: dict
    colour: np.ndarray
    palette: np.ndarray

    def select(self, config: object, structure: str, records: Mapping[int, tuple],
               domain: Sequence[Label]) -> tuple[np.ndarray, np.ndarray] | None:
        """``(colour, palette)`` over ``domain`` (fresh arrays), or None if they cannot be
        read off the remembered ones; ``records``: the current records of the objects of
        ``domain`` (or of more)."""
        pos = _positions(self.axis, domain)
        if pos is None or not _same_records(self, config, structure, records):
            return None
        return self.colour[pos], self.palette[pos]


@dataclass(frozen=True)
class ChainMemo:
    """A node's chain-palette correction (``NetworkConfig.chain_palette``) when it was
    computed: each cell (parent label, label) is one person alone whose palette is
    borrowed, and its value reads only that person's records, so it is read off as the
    evidence is.

    Attributes
    ----------
    config, structure, records
        As :class:`EvidenceMemo`'s (``records``: of the node's domain's objects).
    axes : (dict Label -> int, dict Label -> int)
        The parent's and the node's labels.
    table : ndarray, shape (len(axes[0]), len(axes[1]))
    cells : ndarray of bool, same shape
        Where a correction was computed (0 elsewhere).
    """

    config: object
    structure: str
    records: dict
    axes: tuple
    table: np.ndarray
    cells: np.ndarray

    def select(self, config: object, structure: str, records: Mapping[int, tuple],
               parent_domain: Sequence[Label], domain: Sequence[Label]) -> tuple[bool, np.ndarray | None]:
        """``(True, table)`` over these domains (None where no cell is left, as computing
        afresh gives), or ``(False, None)`` if it cannot be read off."""
        rows, cols = _positions(self.axes[0], parent_domain), _positions(self.axes[1], domain)
        if rows is None or cols is None or not _same_records(self, config, structure, records):
            return False, None
        index = np.ix_(rows, cols)
        return True, (self.table[index] if self.cells[index].any() else None)
