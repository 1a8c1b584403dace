r"""A generic assumed-density filter (ADF) driver (seed 002, section 1.2.2).

An ADF keeps a belief in an assumed family and, for every observation, takes the exact
Bayes step from that belief and projects the result back onto the family. The driver
knows nothing of the model: the model hands it three pure, jit-able hooks (the verbs of
dynamax; the model-apart-from-algorithm split of the ``particles`` library)

* ``predict(params, state, x) -> prior``: the predictive scores of the hypotheses for
  observation ``x`` under the current belief (e.g. unnormalised log joint weights);
* ``condition(params, state, x, prior) -> posterior``: the exact posterior of those
  hypotheses given ``x`` (e.g. normalised in log space, with the one-step log
  likelihood);
* ``project(params, state, x, posterior) -> (state, info)``: the new belief, the KL
  projection of the exact posterior onto the assumed family, and what the step reports;

and, optionally, host-side helpers:

* ``grow(state, margin) -> state``: enlarge array capacities so that ``margin`` more
  steps fit (called before every chunk; each growth recompiles once);
* ``record(state) -> pytree``: extra per-step output taken from the new state;
* ``prune(params, state) -> (state, report)`` (jit-able): run after every ``project``,
  e.g. dropping hypotheses below a posterior-mass threshold
  (:mod:`inference.adf.compact`); its per-step ``report`` is returned
  (``ADFOutput.reports``);
* ``overflow(state_before, state_after, reports) -> state | None`` (an argument of
  :func:`adf_filter` / :func:`adf_filter_lag`, host): after each chunk (each
  observation with fixed lag), a state to run the chunk again from (e.g.
  ``state_before`` with a larger capacity, when the table filled up during the chunk)
  or ``None`` to keep the result;
* for fixed-lag revision, ``window_predict(params, state, xs) -> scores`` (jit-able:
  the scores of a window of observations against one belief) and
  ``revise(state, start, num_valid, scores) -> posterior`` (host: the posterior of the
  window's first observation once the window has been seen).

What the driver does: one step is ``project(condition(predict))`` (then ``prune``); :func:`adf_filter`
runs the step over observations in fixed-size chunks (one compiled ``lax.scan`` per
chunk shape, padded steps skipped, so that a run split anywhere and resumed from the
returned state gives bit-identical results), growing capacities between chunks;
:func:`adf_filter_lag` delays each observation's conditioning by ``lag`` observations
(``window_predict``, ``revise``, then ``project``).

Precision: every entry point runs inside ``jax.enable_x64(x64)`` (default ``True``:
float64, the house rule for filters), so no global jax configuration is needed or
changed; arrays a model creates for its state should be made inside the same context
(:func:`x64_context`).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from functools import partial
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from dbn.checks import check_size
from dbn.errors import InputError

__all__ = [
    "ADFHooks",
    "ADFOutput",
    "x64_context",
    "adf_step",
    "adf_filter",
    "adf_filter_lag",
]


class ADFHooks(NamedTuple):
    """The model side of an ADF (see the module docstring for each hook's contract).

    The three jax hooks must be pure and jit-able; static configuration is captured in
    them (build one ``ADFHooks`` per configuration and reuse it: it is a static argument
    of the compiled functions, hashed by identity).
    """

    predict: Callable[..., Any]
    condition: Callable[..., Any]
    project: Callable[..., Any]
    record: Callable[..., Any] | None = None
    window_predict: Callable[..., Any] | None = None
    prune: Callable[..., Any] | None = None


class ADFOutput(NamedTuple):
    """What :func:`adf_filter` returns.

    state : the belief after the last observation
    infos : the stacked per-step infos (numpy; leading axis ``num_obs``)
    records : per-chunk list of the stacked ``record(state)`` outputs (numpy; leading
        axis the chunk's valid steps; shapes may change between chunks when the
        capacity grows), empty without a ``record`` hook
    reports : the stacked per-step ``prune`` reports (numpy), ``None`` without a
        ``prune`` hook
    """

    state: Any
    infos: Any
    records: list
    reports: Any = None


def x64_context(x64: bool = True):
    """The precision context of the driver: ``jax.enable_x64(x64)`` (thread-local)."""
    return jax.enable_x64(x64)


def _pruned(hooks: ADFHooks, params, out):
    """``(state, info)`` of ``project``, then ``prune``: ``(state, (info, report))``
    with a ``prune`` hook, unchanged without."""
    if hooks.prune is None:
        return out
    state, report = hooks.prune(params, out[0])
    return state, (out[1], report)


def _step(hooks: ADFHooks, params, state, x):
    prior = hooks.predict(params, state, x)
    posterior = hooks.condition(params, state, x, prior)
    return _pruned(hooks, params, hooks.project(params, state, x, posterior))


@partial(jax.jit, static_argnames=("hooks",))
def _step_jit(hooks: ADFHooks, params, state, x):
    return _step(hooks, params, state, x)


@partial(jax.jit, static_argnames=("hooks",))
def _project_jit(hooks: ADFHooks, params, state, x, posterior):
    return _pruned(hooks, params, hooks.project(params, state, x, posterior))


@partial(jax.jit, static_argnames=("hooks",))
def _window_jit(hooks: ADFHooks, params, state, xs):
    return hooks.window_predict(params, state, xs)


@partial(jax.jit, static_argnames=("hooks",))
def _scan_chunk(hooks: ADFHooks, params, state, xs, num_valid):
    """``lax.scan`` of the step over one chunk; steps ``i >= num_valid`` are padding
    (the state passes through unchanged, outputs are zeros)."""

    def body(carry, inp):
        i, x = inp

        def do(s):
            s2, info = _step(hooks, params, s, x)
            return s2, (info, hooks.record(s2) if hooks.record is not None else jnp.zeros(0))

        out_shape = jax.eval_shape(do, carry)[1]

        def skip(s):
            return s, jax.tree_util.tree_map(lambda a: jnp.zeros(a.shape, a.dtype), out_shape)

        return jax.lax.cond(i < num_valid, do, skip, carry)

    idx = jnp.arange(jax.tree_util.tree_leaves(xs)[0].shape[0])
    return jax.lax.scan(body, state, (idx, xs))


def adf_step(hooks: ADFHooks, params, state, x, x64: bool = True):
    """One compiled ADF step ``project(condition(predict(x)))``: ``(state, info)``
    (with a ``prune`` hook, pruned after: ``(state, (info, report))``).

    ``x`` is one observation (a pytree of arrays without the time axis)."""
    with x64_context(x64):
        return _step_jit(hooks, params, state, x)


def _num_obs(xs) -> int:
    sizes = {int(np.shape(v)[0]) for v in jax.tree_util.tree_leaves(xs)}
    if len(sizes) != 1:
        raise InputError(f"observations: leaves disagree on the number of steps {sorted(sizes)}")
    return sizes.pop()


def _take(xs, idx):
    return jax.tree_util.tree_map(lambda v: np.asarray(v)[idx], xs)


def _progress(it: Iterable, progress: bool, desc: str, unit: str) -> Iterable:
    if not progress:
        return it
    from inference.progress import progress_bar

    return progress_bar(it, desc=desc, unit=unit)


def _stack_infos(parts: list, empty_info) -> Any:
    if not parts:
        return empty_info
    return jax.tree_util.tree_map(lambda *a: np.concatenate(a), *parts)


def _split(hooks: ADFHooks, out):
    """Per-step outputs ``info`` or ``(info, report)`` -> ``(info, report or None)``."""
    return out if hooks.prune is not None else (out, None)


def _first(tree, n: int):
    return jax.tree_util.tree_map(lambda a: np.asarray(a)[:n], tree)


def adf_filter(
    hooks: ADFHooks,
    params,
    state,
    xs,
    chunk: int,
    grow: Callable[[Any, int], Any] | None = None,
    empty_info=None,
    progress: bool = False,
    x64: bool = True,
    overflow: Callable[[Any, Any, Any], Any] | None = None,
) -> ADFOutput:
    """Run the ADF over observations ``xs`` in compiled chunks of ``chunk`` steps.

    Parameters
    ----------
    hooks : ADFHooks
    params : the model's parameters (a pytree of arrays; dynamic argument)
    state : the belief to start from
    xs : pytree of host arrays with leading axis ``num_obs`` (validated by the caller)
    chunk : steps per compiled ``lax.scan`` (every chunk has this shape; the last one is
        padded by repeating the last observation, and the padded steps are skipped)
    grow : ``grow(state, margin)`` called before each chunk with ``margin = chunk``
    empty_info : what ``infos`` is when ``num_obs == 0``
    progress : tqdm bar over chunks
    x64 : run in float64 (``jax.enable_x64``)
    overflow : ``overflow(state_before, state_after, reports)`` after each chunk (the
        chunk's valid steps' ``prune`` reports, or ``None``): a state to run the chunk
        again from, or ``None`` to keep it (see the module docstring)

    Returns
    -------
    ADFOutput
    """
    if chunk < 1:
        raise InputError(f"chunk = {chunk}: must be >= 1")
    K = _num_obs(xs)
    infos, records, reports = [], [], []
    with x64_context(x64):
        for s in _progress(range(0, K, chunk), progress, "ADF", "chunk"):
            n = min(chunk, K - s)
            if grow is not None:
                state = grow(state, chunk)
            pad = np.minimum(np.arange(s, s + chunk), K - 1)  # fixed chunk shape
            xc = _take(xs, pad)
            while True:
                new, (out, rec) = _scan_chunk(hooks, params, state, xc, np.int64(n))
                info, rep = _split(hooks, out)
                rep = None if rep is None else _first(rep, n)
                again = None if overflow is None else overflow(state, new, rep)
                if again is None:
                    break
                state = again
            state = new
            infos.append(_first(info, n))
            if rep is not None:
                reports.append(rep)
            if hooks.record is not None:
                records.append(_first(rec, n))
    return ADFOutput(state, _stack_infos(infos, empty_info), records, _reports(hooks, reports))


def _reports(hooks: ADFHooks, parts: list):
    if hooks.prune is None:
        return None
    return _stack_infos(parts, None)


def adf_filter_lag(
    hooks: ADFHooks,
    params,
    state,
    xs,
    lag: int,
    revise: Callable[..., Any],
    chunk: int,
    grow: Callable[[Any, int], Any] | None = None,
    empty_info=None,
    progress: bool = False,
    x64: bool = True,
    overflow: Callable[[Any, Any, Any], Any] | None = None,
) -> ADFOutput:
    """ADF with fixed-lag revision: observation k is conditioned on after the window
    ``x_k .. x_{k+lag}`` has been seen.

    For each k: ``scores = window_predict(params, state, xs[k : k + lag + 1])`` (the
    window has the fixed length ``lag + 1``, padded past the end by repeating the last
    observation), ``posterior = revise(state, k, num_valid, scores)`` on the host
    (``num_valid`` real window entries), then ``project(params, state, x_k,
    posterior)`` (and ``prune``). The revision only changes how observation k is
    weighed; the belief stays in the assumed family. ``grow`` is called every ``chunk``
    observations, ``overflow`` after every observation (its ``reports`` of length 1).

    Returns
    -------
    ADFOutput (``records`` holds one entry per observation)
    """
    lag = check_size("lag", lag)
    if hooks.window_predict is None:
        raise InputError("fixed-lag revision needs a window_predict hook")
    K = _num_obs(xs)
    infos, records, reports = [], [], []
    with x64_context(x64):
        for k in _progress(range(K), progress, f"ADF lag {lag}", "obs"):
            if grow is not None and k % chunk == 0:
                state = grow(state, chunk)
            n = min(K, k + lag + 1) - k
            win = np.minimum(np.arange(k, k + lag + 1), K - 1)
            while True:
                scores = jax.device_get(_window_jit(hooks, params, state, _take(xs, win)))
                posterior = revise(state, k, n, scores)
                new, out = _project_jit(hooks, params, state, _take(xs, k), posterior)
                info, rep = _split(hooks, out)
                if rep is not None:
                    rep = jax.tree_util.tree_map(lambda a: np.asarray(a)[None], rep)
                again = None if overflow is None else overflow(state, new, rep)
                if again is None:
                    break
                state = again
            state = new
            infos.append(jax.tree_util.tree_map(lambda a: np.asarray(a)[None], info))
            if rep is not None:
                reports.append(rep)
            if hooks.record is not None:
                records.append(
                    jax.tree_util.tree_map(lambda a: np.asarray(a)[None], hooks.record(state))
                )
    return ADFOutput(state, _stack_infos(infos, empty_info), records, _reports(hooks, reports))
