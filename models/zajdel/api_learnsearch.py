"""The learn-search tracker of seed 000 under the tracker protocol.

:func:`learn_search` is a batch algorithm: given all observations so far it returns the
``T`` most probable partitions (with EM-learned parameters). Its on-line reading, the
seed's: after each new observation, the answer for all observations so far. The adapter's
immutable :class:`LearnSearchState` holds the observations seen and the current answer;
``step`` appends one observation (validated with the rest, before anything changes) and
re-runs :func:`learn_search` on the whole prefix. Cost: one full search per step, so
``O(K)`` per step and ``O(K^2)`` over a run of ``K`` observations -- the protocol's
reference semantics; call :func:`learn_search` once for a batch. Deterministic (the key is
checked, not used). Info's ``log_score`` is the unnormalised log posterior of the MAP partition.
Both adapters save and load their state (:mod:`models.zajdel.learnsearch_checkpoint`).

``make(..., window=W)`` gives the streaming form instead (:class:`StreamLearnSearchTracker`,
:class:`models.zajdel.learnsearch_stream.StreamSearch`): hypotheses over the last ``W``
observations only, older ones committed, so time and memory per step are bounded whatever
the stream's length; each Info hands out the labels committed by that step and the
window's current labels.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import numpy as np

from dbn.checks import check_type
from models.protocol import Example, StepTracker, check_key, seed_from_key
from models.zajdel.data import Observations, concat_observations, take, validate_observations
from models.zajdel.learnsearch import LearnSearchConfig, LSParams, learn_search
from models.zajdel.learnsearch_checkpoint import load_search, load_stream, save_search, save_stream
from models.zajdel.learnsearch_stream import StreamSearch

__all__ = [
    "LearnSearchState",
    "LearnSearchInfo",
    "LearnSearchTracker",
    "StreamLearnSearchInfo",
    "StreamLearnSearchTracker",
    "make",
    "example",
]


class LearnSearchState(NamedTuple):
    """Observations so far (num_obs) and the search's answer for them.

    labels (num_obs,) MAP partition; hypotheses (T', num_obs); log_scores (T',);
    params: the learned (or given) :class:`LSParams`.
    """

    observations: Observations
    labels: np.ndarray
    hypotheses: np.ndarray
    log_scores: np.ndarray
    params: LSParams


class LearnSearchInfo(NamedTuple):
    """The MAP partition after the step and its unnormalised log posterior."""

    labels: np.ndarray
    log_score: float


class LearnSearchTracker(StepTracker):
    """Protocol adapter over :func:`learn_search` (``params`` are EM's starting point)."""

    name = "zajdel_learnsearch"
    score_field = "log_score"
    can_save = True

    def __init__(self, params: LSParams, config: LearnSearchConfig | None = None) -> None:
        self.params = check_type("params", params, LSParams)
        self.config = LearnSearchConfig() if config is None else config
        check_type("config", self.config, LearnSearchConfig).validate()

    def init(self, key: jax.Array) -> LearnSearchState:
        """No observation yet (deterministic: the key is checked, not used)."""
        check_key(key)
        d = self.params.obs_dim
        empty = Observations(np.zeros((0, d)), np.zeros(0, np.int64), np.zeros(0), np.zeros(0),
                             np.zeros(0, np.int64), np.zeros(0, np.int64))  # fmt: skip
        return LearnSearchState(
            empty, np.zeros(0, np.int64), np.zeros((1, 0), np.int64), np.zeros(1), self.params
        )

    def step(self, key: jax.Array, state: LearnSearchState, obs: Observations):
        """Append ``obs`` (one or more observations) and search again over all of them."""
        check_key(key)
        p = self.params
        tq = np.asarray(state.observations.t_quit)
        last = float(tq[-1]) if tq.size else -np.inf
        obs = validate_observations(  # before concatenating: a library error, state intact
            obs, p.obs_dim, p.path.num_cameras, p.path.num_borders, last_t_quit=last
        )
        allobs = concat_observations([state.observations, obs])
        res = learn_search(allobs, self.params, self.config)  # validates before searching
        new = LearnSearchState(allobs, res.labels, res.hypotheses, res.log_scores, res.params)
        return new, LearnSearchInfo(res.labels, float(res.log_scores[0]))

    def save(self, state: LearnSearchState, path) -> None:
        """Write ``state`` to ``.npz``
        (:func:`models.zajdel.learnsearch_checkpoint.save_search`)."""
        save_search(path, state, self.params, self.config)

    def load(self, path) -> LearnSearchState:
        """A state written by :meth:`save` of a tracker with these parameters and config."""
        return load_search(path, self.params, self.config)


class StreamLearnSearchInfo(NamedTuple):
    """What a streaming step settles and what it still revises.

    committed : (m,) labels of the observations committed by this step (stream order;
        the ``num_committed_before`` observations before them were handed out earlier)
    window_labels : (W,) labels of the observations still in the window, best hypothesis
        (before the first ``n0`` observations: the plain search's labels of those seen)
    log_score : the window part of the best hypothesis' log posterior (differences
        between hypotheses are those of the full posterior)
    """

    committed: np.ndarray
    window_labels: np.ndarray
    log_score: float


class StreamLearnSearchTracker(StepTracker):
    """Protocol adapter over the fixed-lag search: state is a :class:`StreamSearch`
    (the window, its hypotheses and the parameters), copied by each pure ``step``."""

    name = "zajdel_learnsearch"
    score_field = "log_score"
    can_save = True

    def __init__(self, params, config, window: int, close_z: float | None = 5.0) -> None:
        self.params = check_type("params", params, LSParams)
        self.config = LearnSearchConfig() if config is None else config
        check_type("config", self.config, LearnSearchConfig)
        self.window, self.close_z = window, close_z
        StreamSearch(params, self.config, window, close_z)  # check the arguments now

    def init(self, key: jax.Array) -> StreamSearch:
        """No observation yet (deterministic: the key is checked, not used)."""
        check_key(key)
        return StreamSearch(self.params, self.config, self.window, self.close_z)

    def step(self, key: jax.Array, state: StreamSearch, obs: Observations):
        """Push ``obs`` (one or more observations, validated first) into a copy of ``state``."""
        check_key(key)
        p = self.params
        tq = np.asarray(state.buf.t_quit)
        last = float(tq[-1]) if tq.size else -np.inf
        obs = validate_observations(
            obs, p.obs_dim, p.path.num_cameras, p.path.num_borders, last_t_quit=last
        )
        new = state.copy()
        for i in range(obs.num_obs):
            new.push(take(obs, slice(i, i + 1)))
        if new.st is None:  # fewer than n0 seen: the plain search over them
            res = learn_search(new.buf, new.theta, self.config)
            info = StreamLearnSearchInfo(np.zeros(0, np.int64), res.labels, 0.0)
        else:
            score = float(new.log_scores()[0])
            info = StreamLearnSearchInfo(new.pop_committed(), new.window_labels(), score)
        return new, info

    def save(self, state: StreamSearch, path) -> None:
        """Write ``state`` to ``.npz``
        (:func:`models.zajdel.learnsearch_checkpoint.save_stream`)."""
        save_stream(path, state)

    def load(self, path) -> StreamSearch:
        """A search written by :meth:`save` of a tracker with these parameters, config,
        window and ``close_z``."""
        return load_stream(path, self.params, self.config, self.window, self.close_z)

    def fingerprint(self, state: StreamSearch):
        """The arrays that determine the state (its window, hypotheses and parameters)."""
        st = {} if state.st is None else state.st
        return (tuple(state.buf), st, tuple(state.theta), state.num_seen, state.committed)


def make(
    params: LSParams,
    config: LearnSearchConfig | None = None,
    window: int | None = None,
    close_z: float | None = 5.0,
) -> LearnSearchTracker | StreamLearnSearchTracker:
    """The adapter for EM starting point / fixed ``params`` and a search ``config``;
    ``window``: the streaming form with that lag (``close_z`` as
    :func:`models.zajdel.learnsearch_stream.stream_learn_search`), None: the plain search."""
    if window is None:
        return LearnSearchTracker(params, config)
    return StreamLearnSearchTracker(params, config, window, close_z)


def example(key: jax.Array) -> Example:
    """A SIMULATED office (3 people, 3 cameras, 6 observations), T = 3, n0 = 2, fixed
    parameters; bad: NaN appearance."""
    from models.zajdel.learnsearch import params_from_zajdel
    from models.zajdel.simulate import OfficeConfig, simulate_office

    sc = simulate_office(seed_from_key(key), OfficeConfig(num_people=3, num_cameras=3, num_obs=6))
    steps = [take(sc.obs, slice(i, i + 1)) for i in range(sc.obs.num_obs)]
    bad = steps[1]._replace(appearance=np.full_like(steps[1].appearance, np.nan))
    config = LearnSearchConfig(num_hypotheses=3, n0=2, learn=False)
    return Example(make(params_from_zajdel(sc.params), config), steps, bad)
