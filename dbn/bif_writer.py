"""A discrete Bayes net as the text of a BIF file, which :func:`dbn.pgmpy_adapter.parse_bif`
and :func:`dbn.pgmpy_adapter.read_bif` (pgmpy's ``BIFReader``) read back.

The layout of pgmpy's ``BIFWriter``, without properties: one ``variable`` block per node
(in the net's order), then one ``probability`` block per node, whose parents are in the
CPD's order; a root's block is one ``table`` row, any other one row per parent
configuration, ``(s_1, ..., s_m) p_1, ..., p_K;`` by state name. Probabilities are written with ``repr``, so they
read back to the same doubles. Deterministic CPDs are written as their 0/1 tables.

Names BIF cannot hold are refused rather than written into a file that reads back as
another net (:func:`check_bif_name`): a variable name must be letters, digits, ``_``, ``-``
or ``.`` (what pgmpy's grammar reads in a ``probability`` block); a state name may hold
more (``<7.5``, as in pgmpy's bundled ``child`` network; ``no rain``) but no separator
of the format (``, ; ( ) { } |``), comment (``//``, ``/*``), control character or
whitespace at an end, and the only state of a variable no whitespace at all (pgmpy's reader
splits ``{ no rain }`` in two states). Neither may hold a BIF keyword as a word.
"""

from __future__ import annotations

import re

import numpy as np

from dbn.bayesnet import BayesNet, check_discrete_net
from dbn.errors import InputError, ModelError

__all__ = ["BIF_KEYWORDS", "format_bif", "check_bif_name", "pgmpy_splits_lone_state"]

BIF_KEYWORDS = frozenset(
    {"network", "variable", "probability", "property", "type", "discrete", "table", "default"}
)
"""Words of the format's structure: as a word of a name (``my variable``, ``default.x``) they
break pgmpy's reader or this library's (:func:`dbn.pgmpy_adapter.parse_bif`)."""

_VARIABLE = re.compile(r"[\w.-]+")
_STATE_BAD = re.compile(r"[,;(){}|\x00-\x1f\x7f]|//|/\*")
_KEYWORD = re.compile(r"\b(?:" + "|".join(sorted(BIF_KEYWORDS)) + r")\b")


def check_bif_name(name: object, what: str, state: bool = False, alone: bool = False) -> str:
    """``name`` if a BIF file can hold it as a variable name (``state``: a state name,
    ``alone``: its variable's only state; the module docstring), else a
    :class:`~dbn.errors.ModelError` naming ``what`` (e.g. ``"state 2 of 'Rain'"``)."""
    text = str(name)
    if _KEYWORD.search(text):
        why = "a BIF keyword stands in it"
    elif not state and not _VARIABLE.fullmatch(text):
        why = "only letters, digits, '_', '-' and '.' can stand in a BIF variable name"
    elif state and (not text or text != text.strip() or _STATE_BAD.search(text)):
        why = ("a BIF state name must be non-empty, without whitespace at its ends and "
               "without ', ; ( ) { } |', '//', '/*' or control characters")
    elif alone and pgmpy_splits_lone_state(text):
        why = "pgmpy's reader splits a variable's only state at its whitespace"
    else:
        return text
    raise ModelError(f"{what} is {text!r}: {why}; rename it before writing BIF")


def pgmpy_splits_lone_state(state: str) -> bool:
    """Whether pgmpy's BIF reader splits ``state`` when it is its variable's only state
    (``{ no rain }``: no comma, so it splits at the whitespace)."""
    return any(ch.isspace() for ch in state)


def _numbers(row: np.ndarray) -> str:
    return ", ".join(repr(float(p)) for p in row)


def _probability_block(bn: BayesNet, node: str) -> list[str]:
    """The ``probability`` block of ``node``: its table ``(*parent_cards, card)`` as rows."""
    parents = bn.parents(node)
    table = bn.table(node)
    head = f"probability ( {node}{' | ' + ', '.join(parents) if parents else ''} ) {{"
    if not parents:
        return [head, f"    table {_numbers(table)} ;", "}"]
    states = [bn.variable(p).state_names for p in parents]
    rows = [f"    ({', '.join(s[i] for s, i in zip(states, index))}) {_numbers(table[index])} ;"
            for index in np.ndindex(*table.shape[:-1])]  # fmt: skip
    return [head, *rows, "}"]


def format_bif(bn: BayesNet, name: str = "unknown") -> str:
    """The text of a BIF file holding the discrete Bayes net ``bn``.

    Parameters
    ----------
    bn : BayesNet
        Every variable discrete (tabular or deterministic CPDs).
    name : str
        The ``network`` name written in the header.

    Returns
    -------
    str
        Ending in a newline; ``parse_bif(format_bif(bn))`` is ``bn`` with its nodes in
        sorted order (as every BIF reader here gives them) and the same tables.

    Raises
    ------
    ModelError
        ``bn`` is not a discrete :class:`BayesNet`, or a network, variable or state name
        cannot stand in a BIF file (:func:`check_bif_name`).
    """
    check_discrete_net(bn, "format_bif")
    if not isinstance(name, str):
        raise InputError(f"format_bif: name must be a str, got {type(name).__name__}")
    check_bif_name(name, "the network name")
    lines = [f"network {name} {{", "}"]
    for node in bn.nodes:
        check_bif_name(node, "a variable name")
        states = bn.variable(node).state_names
        for i, s in enumerate(states):
            check_bif_name(s, f"state {i} of {node!r}", state=True, alone=len(states) == 1)
        declared = f"    type discrete [ {len(states)} ] {{ {', '.join(states)} }};"
        lines += [f"variable {node} {{", declared, "}"]
    for node in bn.nodes:
        lines += _probability_block(bn, node)
    return "\n".join(lines) + "\n"
