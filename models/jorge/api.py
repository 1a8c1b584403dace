"""The on-line group labeller of seed 004 under the tracker protocol.

:class:`~models.jorge.online.OnlineLabeller` mutates itself (its label graph, labels,
beliefs and inference log grow with every stroke). For a pure ``step`` the adapter's
:class:`JorgeState` holds a labeller and ``step`` works on a deep copy of it
(copy-on-step): the state handed in is never touched, and a rejected stroke raises before
the copy is changed. Cost: the copy is ``O(num_strokes)`` (graph, domains, beliefs), so a
protocol run of ``K`` strokes costs ``O(K^2)`` in copying on top of the labelling itself
-- measured on the simulated 5-person, 900-frame sequence (30 strokes): a copy of the
full labeller takes ~1.4 ms against ~14 ms of labelling per stroke (shared 2-core machine);
:func:`~models.jorge.online.label_online` stays the batch entry point.
Deterministic (the key is not used). Info's ``log_prob`` is the log eq. 12 posterior
probability of the label given to the new stroke. An observation is a
:class:`~models.jorge.strokes.Stroke` (linked by the on-line link rule) or a
:class:`LinkedStroke` (a stroke with the links a low-level tracker reported for it).
"""

from __future__ import annotations

import copy
import dataclasses
from typing import NamedTuple

import jax
import numpy as np

from models.jorge.online import OnlineConfig, OnlineLabeller
from models.jorge.strokes import Stroke
from models.protocol import Example, StepTracker, seed_from_key

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


class JorgeTracker(StepTracker):
    """Protocol adapter over :class:`OnlineLabeller` (one stroke per step); ``fps``, the
    strokes' frame rate, is required (no rate is assumed)."""

    name = "jorge"
    score_field = "log_prob"
    can_save = False

    def __init__(self, config: OnlineConfig | None = None, fps: float | None = None) -> None:
        self.config = OnlineConfig() if config is None else config
        self.fps = OnlineLabeller(self.config, fps).fps  # checks the configuration and the rate now

    def init(self, key: jax.Array) -> JorgeState:
        """An empty labeller (deterministic: the key is not used)."""
        return JorgeState(OnlineLabeller(self.config, self.fps))

    def step(self, key: jax.Array, state: JorgeState,
             obs: Stroke | LinkedStroke) -> tuple[JorgeState, JorgeInfo]:
        """Add one stroke (in start order) to a copy of the labeller; a
        :class:`LinkedStroke` brings its own links."""
        lab = state.labeller
        stroke, parents = (obs.stroke, obs.parents) if isinstance(obs, LinkedStroke) else (obs, None)
        lab.graph.check_stroke(stroke)  # reject before copying (the links: on the copy)
        new = copy.deepcopy(lab)
        before = len(new.records)
        label = new.add_stroke(stroke, parents)
        k = stroke.index
        post = new.beliefs[k]
        lp = float(np.log(post[new.graph.nodes[k].domain.index(label)]))
        ran = new.records[before:]
        info = JorgeInfo(_label(label), lp, len(ran), ran[-1].log_prob if ran else float("nan"))
        return JorgeState(new), info

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
