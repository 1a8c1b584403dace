"""The protocol's ``fold`` for the group labeller: one labeller stepped in place.

``JorgeTracker.step`` copies the labeller (the protocol's pure step), so a ``run`` of ``K``
strokes copies ``O(K^2)``; ``fold`` (what ``dbntrack track jorge`` uses) must give the same
labelling with no copy at all.
"""

from __future__ import annotations

import copy

import jax
import pytest

from dbn.errors import InputError
from models.jorge import api
from models.jorge.online import OnlineConfig, OnlineLabeller, label_online
from models.jorge.simulate import simulate_ground_truth
from models.jorge.strokes import build_strokes
from tests.models.test_protocol import _assert_same


@pytest.fixture(scope="module")
def strokes():
    """A SIMULATED sequence of five walkers (groups form and split)."""
    return build_strokes(4, simulate_ground_truth(4, num_people=5, num_frames=600))


def _count_copies(monkeypatch) -> list:
    """Patch ``copy.deepcopy`` to note every labeller copied (jax copies its own objects)."""
    calls: list = []
    real = copy.deepcopy

    def counting(x, *args, **kwargs):
        if isinstance(x, OnlineLabeller):
            calls.append(x)
        return real(x, *args, **kwargs)

    monkeypatch.setattr(api.copy, "deepcopy", counting)
    return calls


def test_fold_labels_as_the_batch_labeller_without_copying(strokes, monkeypatch) -> None:
    assert len(strokes) >= 15
    tracker = api.make(fps=strokes.fps)
    calls = _count_copies(monkeypatch)
    state, infos = tracker.fold(jax.random.key(0), strokes)
    assert calls == []  # no copy-on-step in a fold
    assert len(infos) == len(strokes)
    batch = label_online(strokes, OnlineConfig())
    assert [tuple(sorted(x)) for x in batch.instant] == [i.label for i in infos]
    final = state.labeller.finish()
    assert [final[k] for k in range(len(strokes))] == batch.labels
    # the same state as the protocol's run, which copies at every step
    states, run_infos = tracker.run(jax.random.key(0), strokes)
    assert len(calls) == len(strokes)
    _assert_same(tracker.fingerprint(states[-1]), tracker.fingerprint(tracker.fold(jax.random.key(0), strokes)[0]))
    _assert_same(run_infos, infos)  # NaN equal to NaN: a step without inference


def test_fold_raises_on_a_bad_stroke(strokes) -> None:
    tracker = api.make(fps=strokes.fps)
    bad = list(strokes.strokes[:3]) + [strokes.strokes[5]]  # out of order: index 5 after 2
    with pytest.raises(InputError, match="next stroke must have index 3"):
        tracker.fold(jax.random.key(0), bad)
