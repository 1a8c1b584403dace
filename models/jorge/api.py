"""The on-line group labeller of seed 004 under the tracker protocol.

:class:`~models.jorge.online.OnlineLabeller` mutates itself (its label graph, labels,
beliefs and inference log grow with every stroke). For a pure ``step`` the adapter's
:class:`JorgeState` holds a labeller and ``step`` works on a deep copy of it
(copy-on-step): the state handed in is never touched, and a rejected stroke raises before
the copy is changed. Cost: the copy is ``O(num_strokes)`` (graph, domains, beliefs), so a
protocol ``run`` of ``K`` strokes costs ``O(K^2)`` in copying on top of the labelling
itself: on ETH ``seq_eth`` (1,035 strokes) a copy of the full labeller takes ~0.12 s
against ~8 ms of labelling per stroke. :meth:`JorgeTracker.fold` (what ``dbntrack track
jorge`` uses) needs no copy: the fold's own labeller takes every stroke in place, the
same labels (ETH through the CLI: the labelling phase 87.6 s with a step loop, 13.1 s
with ``fold``, the same outputs byte for byte).
:func:`~models.jorge.online.label_online` stays the batch entry point.
:meth:`JorgeTracker.save` / ``load`` write and resume the labeller
(:mod:`models.jorge.checkpoint`: its strokes and links, added again on loading).
Deterministic (the key is checked, not used). Info's ``log_prob`` is the log eq. 12 posterior
probability of the label given to the new stroke. An observation is a
:class:`~models.jorge.strokes.Stroke` (linked by the on-line link rule) or a
:class:`LinkedStroke` (a stroke with the links a low-level tracker reported for it).
"""

from __future__ import annotations

import copy
import dataclasses
from collections.abc import Callable, Iterable, Sequence
from typing import NamedTuple

import jax
import numpy as np

from models.jorge.checkpoint import load_labeller, save_labeller
from models.jorge.online import OnlineConfig, OnlineLabeller
from models.jorge.strokes import Stroke
from models.protocol import Example, StepTracker, check_key, seed_from_key

__all__ = ["JorgeState", "JorgeInfo", "LinkedStroke", "JorgeTracker", "make", "example"]


class JorgeState(NamedTuple):
    """A labeller after some strokes (never mutated by the protocol)."""

    labeller: OnlineLabeller


class LinkedStroke(NamedTuple):
    """A stroke with its links given (its parents: indices of earlier strokes,
    :meth:`models.jorge.network.LabelGraph.check_links`) instead of the link rule."""

    stroke: Stroke
    parents: tuple[int, ...]


class JorgeInfo(NamedTuple):
    """The new stroke's eq. 12 label (sorted members), its log posterior probability, and
    the periodic inferences this step ran (count, MAP log probability of the last)."""

    label: tuple
    log_prob: float
    num_inferences: int
    inference_log_prob: float


def _label(lab) -> tuple:
    return tuple(sorted(lab))


def _add(lab: OnlineLabeller, obs: Stroke | LinkedStroke) -> JorgeInfo:
    """Add one stroke to ``lab`` in place (checked before anything changes); its Info."""
    stroke, parents = (obs.stroke, obs.parents) if isinstance(obs, LinkedStroke) else (obs, None)
    before = len(lab.records)
    label = lab.add_stroke(stroke, parents)
    post = lab.beliefs[stroke.index]
    lp = float(np.log(post[lab.graph.nodes[stroke.index].domain.index(label)]))
    ran = lab.records[before:]
    return JorgeInfo(_label(label), lp, len(ran), ran[-1].log_prob if ran else float("nan"))


class JorgeTracker(StepTracker):
    """Protocol adapter over :class:`OnlineLabeller` (one stroke per step); ``fps``, the
    strokes' frame rate, is required (no rate is assumed)."""

    name = "jorge"
    score_field = "log_prob"
    can_save = True

    def __init__(self, config: OnlineConfig | None = None, fps: float | None = None) -> None:
        self.config = OnlineConfig() if config is None else config
        self.fps = OnlineLabeller(self.config, fps).fps  # checks the configuration and the rate now

    def init(self, key: jax.Array) -> JorgeState:
        """An empty labeller (deterministic: the key is checked, not used)."""
        check_key(key)
        return JorgeState(OnlineLabeller(self.config, self.fps))

    def step(self, key: jax.Array, state: JorgeState,
             obs: Stroke | LinkedStroke) -> tuple[JorgeState, JorgeInfo]:
        """Add one stroke (in start order) to a copy of the labeller; a
        :class:`LinkedStroke` brings its own links (the key is checked, not used)."""
        check_key(key)
        stroke = obs.stroke if isinstance(obs, LinkedStroke) else obs
        state.labeller.graph.check_stroke(stroke)  # reject before copying (the links: on the copy)
        new = copy.deepcopy(state.labeller)
        return JorgeState(new), _add(new, obs)

    def fold(self, key: jax.Array, observations: Sequence[Stroke | LinkedStroke],
             progress: Callable[[Iterable, int], Iterable] | None = None) -> tuple[JorgeState, list[JorgeInfo]]:
        """:meth:`~models.protocol.StepTracker.fold` without the copy-on-step: the fold's
        own labeller takes every stroke in place, so ``K`` strokes cost the labelling alone,
        not ``O(K^2)`` copying. The same final state and infos as ``run``; a rejected stroke
        raises (the partial state is dropped)."""
        state, steps = self._start(key, observations, progress)
        return state, [_add(state.labeller, obs) for _, obs in steps]

    def save(self, state: JorgeState, path) -> None:
        """Write the labeller's strokes and links to ``.npz``
        (:func:`models.jorge.checkpoint.save_labeller`)."""
        save_labeller(path, state.labeller)

    def load(self, path) -> JorgeState:
        """The labeller written by :meth:`save` under this tracker's configuration and frame
        rate, its strokes added again (:func:`models.jorge.checkpoint.load_labeller`)."""
        return JorgeState(load_labeller(path, self.config, self.fps))

    def fingerprint(self, state: JorgeState):
        """Labels, beliefs, domains and the inference log (without wall times)."""
        lab = state.labeller
        nodes = lab.graph.nodes
        return (
            {k: _label(v) for k, v in lab.labels.items()},
            dict(lab.beliefs),
            [tuple(_label(d) for d in nd.domain) for nd in nodes],
            [
                (
                    r.frame,
                    r.num_active,
                    r.num_boundary,
                    r.max_domain,
                    r.max_clique_entries,
                    r.log_prob,
                )
                for r in lab.records
            ],
            lab._next_inference,
        )


def make(config: OnlineConfig | None = None, fps: float | None = None) -> JorgeTracker:
    """The adapter for an :class:`OnlineConfig` and the strokes' frame rate (required)."""
    return JorgeTracker(config, fps)


def example(key: jax.Array) -> Example:
    """A SIMULATED sequence of 3 walkers over 150 frames, its first strokes; bad: a stroke
    with the wrong index."""
    from models.jorge.simulate import simulate_ground_truth
    from models.jorge.strokes import build_strokes

    seed = seed_from_key(key)
    strokes = build_strokes(seed, simulate_ground_truth(seed, num_people=3, num_frames=150))
    steps = list(strokes.strokes[:5])
    bad = dataclasses.replace(steps[1], index=7)
    return Example(make(fps=strokes.fps), steps, bad)
