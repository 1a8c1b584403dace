"""One entry point for filtering any declared DBN: :func:`filter` (exact, Boyen-Koller,
particle, Rao-Blackwellised particle), and :func:`online_filter` for step-by-step use.

::

    res = inference.filter(dbn, {"y0": ys[:, 0], "y1": ys[:, 1]})   # method="auto"
    res.marginals["x0"]          # (T, 2) filtered marginals
    res.method, res.info["auto"] # which engine ran, and why

``auto`` runs exact structured filtering when its predicted largest table (the frontier)
fits under ``max_size``, else Boyen-Koller; for DBNs with continuous variables it runs the
bootstrap particle filter (which needs ``key``). The approximate engines live in
:mod:`inference.adf.boyen_koller`, :mod:`inference.particle.dbn_adapter` and
:mod:`inference.particle.rbpf` and are imported only when asked for.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from types import MappingProxyType
from typing import Any

from numpy.typing import ArrayLike

from dbn.checks import check_count, check_mapping, instance_of
from dbn.dbn import TwoSliceDBN
from dbn.errors import (
    FrontierTooLargeError,
    InputError,
    ModelError,
    ShapeError,
    as_memory_limit,
)
from dbn.variables import DiscreteVariable
from inference.evidence_columns import check_columns, columns_from_frame, columns_from_slices
from inference.exact.frontier import MAX_FRONTIER_SIZE, check_max_size
from inference.results import DBNFilterResult

__all__ = ["filter", "online_filter", "as_two_slice_dbn", "method_options", "METHODS",
           "METHOD_OPTIONS"]

METHODS = ("auto", "exact", "bk", "particle", "rbpf")
METHOD_OPTIONS: Mapping[str, frozenset[str]] = MappingProxyType({  # read-only: one table
    "exact": frozenset({"max_size"}),  # and max_size under "auto" whatever it chose
    "bk": frozenset({"clusters"}),
    "particle": frozenset({"num_particles", "particle_method"}),
    "rbpf": frozenset({"num_particles"}),
})
"""The ``**options`` each method of :func:`filter` takes (``auto``: ``max_size`` and those of
the method it chooses)."""
_UNBOUNDED = 2**62


def method_options(method: str, chosen: str | None = None) -> frozenset[str]:
    """The ``**options`` keys :func:`filter` takes under ``method``: those of
    :data:`METHOD_OPTIONS`; under ``auto``, ``max_size`` and those of the method it ``chose``
    (before the choice, of any method: what a config file may hold for ``auto``).

    Raises :class:`~dbn.errors.InputError` for a method not in :data:`METHODS`, or a
    ``chosen`` not a method ``auto`` may choose."""
    if method not in METHODS:
        raise InputError(f"method must be one of {METHODS}, got {method!r}")
    if chosen is not None and (method != "auto" or chosen not in METHOD_OPTIONS):
        raise InputError(f"chosen = {chosen!r}: only 'auto' chooses, one of "
                         f"{tuple(METHOD_OPTIONS)}")  # fmt: skip
    if method != "auto":
        return METHOD_OPTIONS[method]
    chosen_options = METHOD_OPTIONS.values() if chosen is None else [METHOD_OPTIONS[chosen]]
    return frozenset({"max_size"}).union(*chosen_options)


def as_two_slice_dbn(model: Any) -> TwoSliceDBN:
    """A :class:`TwoSliceDBN` as is, or a pgmpy ``DynamicBayesianNetwork`` converted by
    :func:`dbn.pgmpy_adapter.dbn_from_pgmpy` (node names become ``str``)."""
    if isinstance(model, TwoSliceDBN):
        return model
    if instance_of(model, "pgmpy", "DynamicBayesianNetwork"):  # or a subclass of it
        from dbn.pgmpy_adapter import dbn_from_pgmpy

        return dbn_from_pgmpy(model)
    raise ModelError(
        f"model must be a TwoSliceDBN or a pgmpy DynamicBayesianNetwork, got {type(model).__name__}"
    )


def _check_evidence(
    dbn: TwoSliceDBN,
    evidence: Mapping[str, ArrayLike] | None,
    soft: Mapping[str, ArrayLike] | None,
    num_timesteps: int | None,
) -> tuple[Mapping[str, ArrayLike] | None, Mapping[str, ArrayLike] | None]:
    """Every column in full, as every engine reads it
    (:func:`~inference.evidence_columns.check_columns`), and its length against
    ``num_timesteps`` where given, before any engine runs. Returns the evidence and soft
    evidence as the checked arrays (state names read as indices, in the caller's order),
    so that the engine does not read the caller's columns a second time."""
    check_mapping("evidence", evidence)
    check_mapping("soft evidence", soft)
    if num_timesteps is not None:
        check_count("num_timesteps", num_timesteps, ShapeError)
    if not (evidence or soft):  # without, the exact engine asks for num_timesteps
        return evidence, soft
    cols = check_columns(dbn, evidence, soft, num_timesteps)
    checked = {**cols.discrete, **cols.continuous}
    return ({name: checked[name] for name in evidence} if evidence else evidence,
            {name: cols.soft[name] for name in soft} if soft else soft)


def _choose(dbn: TwoSliceDBN, evars: Sequence[str], query, max_size: int) -> tuple[str, dict]:
    """(method, info) for ``auto``."""
    if not all(isinstance(v, DiscreteVariable) for v in dbn.variables):
        cont = [v.name for v in dbn.variables if not isinstance(v, DiscreteVariable)]
        return "particle", {
            "auto": f"continuous variables {cont}: exact and Boyen-Koller need discrete DBNs; "
            "ran the bootstrap particle filter (ask for method='rbpf' on conditionally "
            "linear-Gaussian models)"
        }
    from inference.exact.structured_filter import StructuredFilter

    try:
        size = StructuredFilter(dbn, query, max_size=_UNBOUNDED).predicted_size(evars)
    except FrontierTooLargeError as exc:  # too many variables in one step to even count
        return "bk", {"predicted_size": None, "max_size": max_size, "auto": f"bk: {exc}"}
    info = {"predicted_size": size, "max_size": max_size}
    if size <= max_size:
        info["auto"] = f"exact: the largest table per slice has {size:,} entries <= {max_size:,}"
        return "exact", info
    info["auto"] = (
        f"bk: exact filtering would need a table of {size:,} entries > max_size {max_size:,}"
    )
    return "bk", info


def filter(  # noqa: A001  (the library's verb; shadows the builtin inside this module only)
    model: Any,
    evidence: Mapping[str, ArrayLike] | None,
    method: str = "auto",
    query: Sequence[str] | None = None,
    *,
    key: Any = None,
    soft_evidence: Mapping[str, ArrayLike] | None = None,
    num_timesteps: int | None = None,
    **options: Any,
) -> DBNFilterResult:
    """Filter a DBN over a whole evidence sequence with one of the generic engines.

    Parameters
    ----------
    model : TwoSliceDBN or pgmpy DynamicBayesianNetwork
    evidence : mapping name -> array
        Columnar evidence: discrete ``name -> (T,) int`` (``-1`` = unobserved; or floats
        of whole numbers, NaN = unobserved) or ``(T,)`` state names (``None`` =
        unobserved), continuous ``name -> (T, dim) float`` (a row of NaN = unobserved).
        Or pgmpy's ``{(name, t): state}`` (discrete), read as pgmpy reads it by
        :func:`~inference.evidence_columns.columns_from_slices`. Or a pandas
        ``DataFrame``, a column per variable and a row per slice, missing values
        unobserved; ``(name, component)`` column pairs for a continuous variable's
        dimensions (:func:`~inference.evidence_columns.columns_from_frame`).
    method : {"auto", "exact", "bk", "particle", "rbpf"}
    query : sequence of str, optional
        Variables whose marginals are returned (default: the engine's default, the
        interface for exact filtering).
    key : jax PRNG key
        Required by ``particle`` and ``rbpf`` (and ``auto`` on continuous models).
    soft_evidence : mapping name -> (T, cardinality) float, optional
        Likelihood rows on discrete variables (all-NaN row = none): exact and bk only.
        Or a ``DataFrame`` with ``(name, state)`` column pairs.
    num_timesteps : int, optional
        ``T``: with evidence, every column's length must equal it; without, only
        ``exact`` reads it.
    **options
        ``max_size`` (exact and auto: largest exact table, entries; default
        :data:`~inference.exact.frontier.MAX_FRONTIER_SIZE`), ``clusters`` (bk),
        ``num_particles`` (particle, rbpf), ``particle_method`` (particle: passed as the
        adapter's ``method``, e.g. ``"bootstrap"``). An option the engine that runs does
        not read is refused, not ignored.

    Returns
    -------
    DBNFilterResult
        ``method`` says which engine ran; ``info["auto"]`` why ``auto`` chose it.

    Raises
    ------
    ModelError, EvidenceError, ShapeError, InputError
        Bad model, evidence, method or option, before any engine runs;
        :class:`~dbn.errors.FrontierTooLargeError` for ``exact`` above ``max_size``.
    """
    dbn = as_two_slice_dbn(model)
    if method not in METHODS:
        raise InputError(f"method must be one of {METHODS}, got {method!r}")
    evidence = columns_from_frame(evidence)  # a pandas DataFrame: its columns
    soft_evidence = columns_from_frame(soft_evidence)
    if isinstance(evidence, Mapping) and any(isinstance(k, tuple) for k in evidence):
        evidence = columns_from_slices(dbn, evidence, num_timesteps)  # pgmpy's {(name, t): s}
    evidence, soft_evidence = _check_evidence(dbn, evidence, soft_evidence, num_timesteps)
    max_size = check_max_size(options.get("max_size", MAX_FRONTIER_SIZE))
    info: dict[str, Any] = {}
    _check_options(options, method)  # a key no method takes: before auto's size estimate
    if method == "auto":
        evars = [*(evidence or {}), *(soft_evidence or {})]
        method, info = _choose(dbn, evars, query, max_size)
        _check_options(options, "auto", method)
    if method != "exact" and num_timesteps is not None and not (evidence or soft_evidence):
        raise InputError(f"method {method!r} takes the number of slices from the evidence "
                         "columns: num_timesteps without evidence is read by 'exact' only")
    if method in ("particle", "rbpf"):
        if key is None:
            raise InputError(
                f"method {method!r} needs a PRNG key: filter(..., key=jax.random.key(0))"
            )
        if soft_evidence:
            raise InputError(f"method {method!r} takes no soft evidence")
    try:
        res = _dispatch(
            method, dbn, evidence, query, key, soft_evidence, num_timesteps, options, max_size
        )
    except (MemoryError, RuntimeError) as exc:  # jax's JaxRuntimeError is a RuntimeError
        shrink = (f"fewer particles (num_particles = {options.get('num_particles', 1000):,})"
                  if method in ("particle", "rbpf") else "a shorter sequence")
        oom = as_memory_limit(exc, f"method {method!r}", f"use {shrink}")
        if oom is None:
            raise
        raise oom from None
    return dataclasses.replace(res, info={**res.info, **info})


def _check_options(options: Mapping[str, Any], method: str, chosen: str | None = None) -> None:
    """:class:`~dbn.errors.InputError` for keys :func:`method_options` does not list."""
    unknown = set(options) - method_options(method, chosen)
    if unknown:
        name = method if chosen is None else chosen
        raise InputError(f"options {sorted(unknown)} do not apply to method {name!r}; valid: "
                         f"{sorted(method_options(method, chosen))}")


def _dispatch(method, dbn, evidence, query, key, soft, num_timesteps, options, max_size):
    if method == "exact":
        from inference.exact.structured_filter import StructuredFilter

        flt = StructuredFilter(dbn, query, max_size=max_size)
        res = flt.filter(evidence, soft, num_timesteps)
        evars = [*(evidence or {}), *(soft or {})]
        plan = flt._plan("next", frozenset(evars))
        return DBNFilterResult(
            marginals=res.marginals,
            log_likelihoods=res.log_normalizers,
            method="exact",
            info={
                "predicted_size": flt.predicted_size(evars),
                "interface": flt.interface,
                "elimination_order": plan.order,
            },
        )
    if method == "bk":
        from inference.adf.boyen_koller import bk_filter

        return bk_filter(dbn, evidence, query, clusters=options.get("clusters"), soft_evidence=soft)
    if method == "particle":
        from inference.particle.dbn_adapter import particle_filter_dbn

        kw = {"num_particles": options.get("num_particles", 1000)}  # the engine checks it
        if "particle_method" in options:
            kw["method"] = options["particle_method"]
        return particle_filter_dbn(key, dbn, evidence, query, **kw)
    from inference.particle.rbpf import rbpf_filter_dbn

    return rbpf_filter_dbn(
        key, dbn, evidence, query, num_particles=options.get("num_particles", 1000)
    )


def online_filter(
    model: Any, query: Sequence[str] | None = None, *, max_size: int = MAX_FRONTIER_SIZE
):
    """The exact structured filter of a model for on-line use (``init`` / ``step`` /
    ``marginals``); see :class:`~inference.exact.structured_filter.StructuredFilter`.

    Raises :class:`~dbn.errors.FrontierTooLargeError` when exact filtering does not fit
    (then use Boyen-Koller's or the particle filters' own on-line objects).
    """
    from inference.exact.structured_filter import StructuredFilter

    return StructuredFilter(as_two_slice_dbn(model), query, max_size=max_size)
