"""Saving the learn-search of seed 000 and resuming it (both protocol adapters).

A state is written as named arrays with a versioned, checksummed header
(:mod:`inference.checkpoint`, no pickle) under the tracker's configuration and a SHA-256
of its starting parameters (:func:`params_digest`: a file saved by a tracker that started
from other parameters is refused). Of the parameters, only what EM learns is stored
(``mean``, ``prior_cov``, ``bias``, ``noise_cov``, ``travel_mean``, ``travel_std``); the
layout tables, window and ``p_new`` are the tracker's own, which EM never changes.

- :class:`~models.zajdel.api_learnsearch.LearnSearchState` (the plain search): the
  observations so far, the MAP labels, the kept hypotheses and their log scores.
- :class:`~models.zajdel.learnsearch_stream.StreamSearch` (the fixed-lag search): the
  window's observations, its hypotheses and open-track sums (every array of its working
  dict), the labels committed and not yet handed out, and its counters.
"""

from __future__ import annotations

import hashlib

import numpy as np

from dbn.errors import CheckpointError
from inference.checkpoint import load_arrays, save_arrays
from models.zajdel.data import Observations
from models.zajdel.learnsearch import LearnSearchConfig, LSParams
from models.zajdel.learnsearch_stream import StreamSearch

__all__ = ["params_digest", "save_search", "load_search", "save_stream", "load_stream"]

_LEARNED = ("mean", "prior_cov", "bias", "noise_cov", "travel_mean", "travel_std")
_OBS = Observations._fields


def params_digest(params: LSParams) -> str:
    """SHA-256 of every array of ``params`` (as float64: shape and bytes) and of ``p_new``
    (a number or None)."""
    h = hashlib.sha256(repr(None if params.p_new is None else float(params.p_new)).encode())
    for name, value in [*params._asdict().items(), *params.path._asdict().items()]:
        if name in ("path", "p_new"):
            continue
        a = np.ascontiguousarray(np.asarray(value, np.float64))
        h.update(f"{name}|{a.shape}|".encode() + a.tobytes())
    return h.hexdigest()


def _learned(theta: LSParams) -> dict[str, np.ndarray]:
    out = {f"theta_{k}": np.asarray(getattr(theta, k)) for k in _LEARNED[:4]}
    out |= {f"theta_{k}": np.asarray(getattr(theta.path, k)) for k in _LEARNED[4:]}
    return out


def _check_shapes(path, start: LSParams, a: dict, prefix: str) -> Observations:
    """The file's observations (``prefix``) and learned arrays, checked against each other
    and against the starting parameters' shapes; else a CheckpointError."""
    for key, want in _learned(start).items():
        if a[key].shape != want.shape:
            raise CheckpointError(path, f"array {key!r} of shape {a[key].shape}, the "
                                  f"parameters' is {want.shape}")
    obs = Observations(*(a[f"{prefix}_{k}"] for k in _OBS))
    n = obs.num_obs
    if obs.appearance.shape != (n, start.obs_dim) or any(
            np.shape(v) != (n,) for v in obs[1:]):
        raise CheckpointError(path, f"the {prefix} arrays do not hold {n} observations of "
                              f"dimension {start.obs_dim}")
    return obs


def _theta(start: LSParams, a: dict) -> LSParams:
    """``start`` with the learned arrays of a file."""
    path = start.path._replace(travel_mean=a["theta_travel_mean"], travel_std=a["theta_travel_std"])
    return start._replace(**{k: a[f"theta_{k}"] for k in _LEARNED[:4]}, path=path)


def _check_learned_only(path, start: LSParams, theta: LSParams) -> None:
    """Refuse to save parameters that differ from ``start`` beyond the learned arrays."""
    again = _theta(start, _learned(theta))
    if params_digest(again) != params_digest(theta):
        raise CheckpointError(path, "the state's parameters differ from the tracker's beyond "
                              "what EM learns (layout tables, window or p_new)")


def _observations(prefix: str, obs: Observations) -> dict[str, np.ndarray]:
    return {f"{prefix}_{k}": np.asarray(v) for k, v in obs._asdict().items()}


def _names(prefix: str) -> list[str]:
    """The names :func:`_observations` (``prefix``) and :func:`_learned` write."""
    return [f"{prefix}_{k}" for k in _OBS] + [f"theta_{k}" for k in _LEARNED]


def _config(config: LearnSearchConfig, params: LSParams, **more) -> dict:
    return {"config": config._asdict(), "params_sha256": params_digest(params), **more}


def save_search(path, state, params: LSParams, config: LearnSearchConfig) -> None:
    """Write a :class:`~models.zajdel.api_learnsearch.LearnSearchState` of the tracker
    started from ``params`` with ``config`` to ``path`` (``.npz``)."""
    _check_learned_only(path, params, state.params)
    arrays = {**_observations("obs", state.observations), **_learned(state.params),
              "labels": state.labels, "hypotheses": state.hypotheses,
              "log_scores": state.log_scores}
    save_arrays(path, arrays, "zajdel-learnsearch", _config(config, params),
                neg_inf=("log_scores",))


def load_search(path, params: LSParams, config: LearnSearchConfig):
    """The state written by :func:`save_search` under the same ``params`` and ``config``.

    Raises
    ------
    CheckpointError
        Naming the file (:func:`inference.checkpoint.load_arrays`), or arrays of
        inconsistent sizes.
    """
    from models.zajdel.api_learnsearch import LearnSearchState

    names = [*_names("obs"), "labels", "hypotheses", "log_scores"]
    a, _ = load_arrays(path, "zajdel-learnsearch", names, _config(config, params),
                       neg_inf=("log_scores",))
    obs = _check_shapes(path, params, a, "obs")
    n = obs.num_obs
    if a["labels"].shape != (n,) or a["hypotheses"].shape[1:] != (n,) \
            or a["log_scores"].shape != a["hypotheses"].shape[:1]:
        raise CheckpointError(path, f"labels, hypotheses and log_scores do not fit {n} "
                              "observations")
    return LearnSearchState(obs, a["labels"], a["hypotheses"], a["log_scores"],
                            _theta(params, a))


ST_ARRAYS = ("A", "E", "P", "Q", "c", "cnt", "col_id", "h", "lab", "lbq", "lcam", "lidx", "ltq",
             "ncol", "ntr", "score", "wpath", "wpb", "wpc", "wprior", "wpt")
"""The arrays of :class:`StreamSearch`'s working dict (its one scalar: ``win_start``)."""

_COUNTERS = ("num_seen", "since", "em_iterations", "max_candidates", "max_open_tracks",
             "max_window")
_ST = tuple(f"st_{k}" for k in ST_ARRAYS)


def _stream_config(params: LSParams, config: LearnSearchConfig, window: int,
                   close_z: float | None) -> dict:
    return _config(config, params, window=int(window), close_z=close_z)


def save_stream(path, search: StreamSearch) -> None:
    """Write a :class:`StreamSearch` to ``path`` (``.npz``): its window, hypotheses,
    learned parameters, labels committed and not yet handed out, and counters."""
    _check_learned_only(path, search.start_params, search.theta)
    st = search.st
    if st is not None and set(st) != {*ST_ARRAYS, "win_start"}:
        raise CheckpointError(path, f"a working state of keys {sorted(st)}, this format holds "
                              f"{sorted(ST_ARRAYS)} and win_start")
    arrays = {**_observations("buf", search.buf), **_learned(search.theta),
              "committed": np.asarray(search.committed, np.int64)}
    arrays |= {f"st_{k}": np.zeros(0) if st is None else st[k] for k in ST_ARRAYS}
    extra = {"started": st is not None, "win_start": None if st is None else int(st["win_start"]),
             **{k: int(getattr(search, k)) for k in _COUNTERS}}
    config = _stream_config(search.start_params, search.cfg, search.window, search.close_z)
    save_arrays(path, arrays, "zajdel-learnsearch-stream", config, extra, neg_inf=_ST)


def _check_window(path, a: dict, width: int) -> None:
    """The working arrays hold one row per hypothesis, and ``lab`` one column per window
    observation; else a CheckpointError."""
    rows = a["st_score"].shape[:1]
    bad = [k for k in ST_ARRAYS if a[f"st_{k}"].shape[:1] != rows or a[f"st_{k}"].ndim == 0]
    if bad or rows == (0,) or a["st_lab"].shape != (*rows, width):
        raise CheckpointError(path, f"the working arrays {bad or ['lab']} do not fit "
                              f"{rows[0] if rows else 0} hypotheses over {width} observations")


def load_stream(path, params: LSParams, config: LearnSearchConfig | None, window: int,
                close_z: float | None = 5.0) -> StreamSearch:
    """The search written by :func:`save_stream` from a tracker of the same ``params``,
    ``config``, ``window`` and ``close_z``; it goes on as the one saved would have.

    Raises
    ------
    CheckpointError
        Naming the file (:func:`inference.checkpoint.load_arrays`), or a header that does
        not fit this format.
    """
    search = StreamSearch(params, config, window, close_z)
    names = [*_names("buf"), "committed", *_ST]
    a, header = load_arrays(path, "zajdel-learnsearch-stream", names,
                            _stream_config(params, search.cfg, window, close_z), neg_inf=_ST)
    try:
        counters = {k: int(header[k]) for k in _COUNTERS}
        started = bool(header["started"])
        win_start = int(header["win_start"]) if started else None
    except (KeyError, TypeError, ValueError) as exc:
        raise CheckpointError(path, f"header does not fit this format ({exc!r})") from None
    search.buf = _check_shapes(path, params, a, "buf")
    if started:
        _check_window(path, a, search.buf.num_obs)
    search.committed = [int(x) for x in a["committed"]]
    for k, v in counters.items():
        setattr(search, k, v)
    if started:
        search.st = {**{k: a[f"st_{k}"] for k in ST_ARRAYS}, "win_start": win_start}
    search.use_params(_theta(params, a))
    return search
