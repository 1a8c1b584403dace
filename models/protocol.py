"""One protocol for every tracker: ``init`` / ``step`` / ``run`` (optional ``save`` / ``load``).

The house's shared verbs (blackjax's ``init``/``step``, dynamax's filter verbs; see
``shared/spec/style.md``), made the same for every seed tracker so that a user, the CLI, a
benchmark or a test can drive any of them without knowing which it is::

    import jax, models
    entry = models.get("pathrecovery")
    tracker, observations = entry.example(jax.random.key(0))  # tiny SIMULATED inputs
    state = tracker.init(jax.random.key(1))
    state, info = tracker.step(jax.random.key(2), state, observations[0])
    states, infos = tracker.run(jax.random.key(3), observations)

Contract (checked for every registered tracker by ``tests/models/test_protocol.py``)

* ``init(key) -> State`` and ``step(key, state, obs) -> (State, Info)`` are PURE: the
  tracker object is never mutated, the state handed in is never mutated, and the same key
  with the same state and observation gives the same result. Randomness comes only from
  the key (a tracker that wants an int seed gets :func:`seed_from_key`; a deterministic
  tracker ignores its value). Every ``init`` and ``step`` refuses anything but one jax
  PRNG key (:func:`check_key`: an :class:`~dbn.errors.InputError`), the deterministic
  trackers' too, so that a key that works with one tracker works with all.
* A rejected observation raises a :mod:`dbn.errors` class (a ``ValueError``) naming the
  field, before anything changes: the state handed in is left exactly as it was.
* ``run(key, observations) -> (states, infos)``: ``init`` with the first half of the key,
  then one ``step`` per observation with keys split from the rest; ``states[i]`` and
  ``infos[i]`` follow observation ``i``. (Trackers keep their own faster batch entry
  points, e.g. ``ZajdelADF.run``; ``run`` here is the reference semantics.)
* ``fold(key, observations) -> (state, infos)``: ``run`` keeping only the last state (the
  same keys, the same final state and infos). An adapter whose ``step`` copies its state
  may step one state in place there, as nobody else holds it (``jorge``: a long ``run``
  copies quadratically, a ``fold`` stays linear).
* ``Info`` carries the model's one-step score where it has one, under the attribute
  named by :attr:`Tracker.score_field` (e.g. ``"loglik"``: the one-step log-likelihood
  ``log p(y_k | y_1..y_{k-1})``), or ``None`` where the model has no such number.
* ``save(state, path)`` / ``load(path) -> State`` where the tracker offers persistence
  (:attr:`Tracker.can_save`).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from typing import Any, NamedTuple, Protocol, runtime_checkable

import jax
import numpy as np

from dbn.errors import InputError, TimeOrderError
from inference.particle.filters import check_key

__all__ = [
    "Example",
    "Tracker",
    "StepTracker",
    "check_key",
    "seed_from_key",
    "split_run_keys",
    "step_key_list",
    "next_frame_index",
]


class Example(NamedTuple):
    """A registry entry's tiny SIMULATED example (``entry.example(key)``).

    Attributes
    ----------
    tracker : the protocol adapter
    observations : list of per-step observations (a few steps)
    bad_observation : an observation ``step`` must reject with a :mod:`dbn.errors` class
        (after ``observations[0]``)
    """

    tracker: Any
    observations: list
    bad_observation: Any


@runtime_checkable
class Tracker(Protocol):
    """What every tracker adapter offers (see the module docstring for the contract)."""

    name: str
    score_field: str | None
    can_save: bool

    def init(self, key: jax.Array) -> Any: ...

    def step(self, key: jax.Array, state: Any, obs: Any) -> tuple[Any, Any]: ...

    def run(self, key: jax.Array, observations: Sequence[Any]) -> tuple[list, list]: ...

    def fold(self, key: jax.Array, observations: Sequence[Any],
             progress: Callable[[Iterable, int], Iterable] | None = None) -> tuple[Any, list]: ...


def seed_from_key(key: jax.Array) -> int:
    """A non-negative int seed (< 2**31) derived deterministically from a jax PRNG key.

    For trackers whose randomness is a ``numpy.random.Generator`` or an int seed: the
    same key always gives the same seed, distinct keys give (almost surely) distinct seeds
    (the key's data words hashed by ``numpy.random.SeedSequence``). Anything but one jax
    PRNG key is an :class:`~dbn.errors.InputError` (it was jax's TypeError).
    """
    check_key(key)
    words = np.asarray(jax.random.key_data(key), dtype=np.uint32).ravel().tolist()
    # hash the key's words on the host (no jax computation: ~60 us, a third of a randint)
    return int(np.random.SeedSequence(words).generate_state(1)[0] >> 1)


def next_frame_index(last: int, t: Any, field: str) -> int:
    """The frame index of the next observation after frame ``last`` (-1: none yet).

    ``t`` is the index the observation carries (``None``: it carries none, the next
    frame ``last + 1`` is assumed). A carried index must be an integer; after the first
    frame it must be exactly ``last + 1``: an earlier (replayed) or equal index, or a
    skipped frame (the one-step dynamics would silently span several), is a
    :class:`~dbn.errors.TimeOrderError` naming ``field``. Nothing is changed.
    """
    if t is None:
        return last + 1
    if isinstance(t, (bool, np.bool_)) or not isinstance(t, (int, np.integer)):
        raise InputError(f"{field} = {t!r} must be an integer frame index (or None)")
    t = int(t)
    if t < 0:
        raise TimeOrderError(f"{field} = {t} is negative")
    if last >= 0 and t != last + 1:
        what = "does not advance past" if t <= last else "skips frames after"
        raise TimeOrderError(
            f"{field} = {t} {what} the last frame {last} (expected {last + 1}; a frame "
            "without detections is an empty observation, not a gap)"
        )
    return t


def split_run_keys(key: jax.Array, num_steps: int) -> tuple[jax.Array, list]:
    """``(init_key, step_keys)`` for a run of ``num_steps`` steps (the protocol's ``run``):
    ``step_keys`` is the list of the ``max(num_steps, 1)`` keys of
    ``jax.random.split(k_steps, ...)`` (:func:`step_key_list`)."""
    k_init, k_steps = jax.random.split(key)
    return k_init, step_key_list(jax.random.split(k_steps, max(num_steps, 1)))


def step_key_list(keys: jax.Array) -> list:
    """A key array (``jax.random.split``'s) as a list of single keys, the same bits.

    Through the host: ``list(keys)`` compiles an unstack for every new number of steps
    (one to two seconds on a CPU, once per run length: more than the whole labelling of
    some trackers), this takes milliseconds. Typed keys (``jax.random.key``) stay typed
    keys of the same implementation; raw ``uint32`` keys (``jax.random.PRNGKey``) stay
    ``uint32`` arrays of shape ``(2,)``.
    """
    if jax.dtypes.issubdtype(keys.dtype, jax.dtypes.prng_key):
        impl = jax.random.key_impl(keys)
        rows = np.asarray(jax.random.key_data(keys))
        return [jax.random.wrap_key_data(row, impl=impl) for row in rows]
    return [jax.numpy.asarray(row) for row in np.asarray(keys)]


class StepTracker:
    """Base class of the adapters: the protocol's ``run`` from ``init`` and ``step``.

    Subclasses set :attr:`name`, :attr:`score_field`, :attr:`can_save` and implement
    :meth:`init` and :meth:`step` (and :meth:`save` / :meth:`load` when ``can_save``).
    """

    name: str = ""
    score_field: str | None = None
    can_save: bool = False

    def init(self, key: jax.Array) -> Any:
        raise NotImplementedError

    def step(self, key: jax.Array, state: Any, obs: Any) -> tuple[Any, Any]:
        raise NotImplementedError

    def run(self, key: jax.Array, observations: Sequence[Any]) -> tuple[list, list]:
        """``init`` then one ``step`` per observation; returns the states and infos after each.

        Parameters
        ----------
        key : PRNG key
        observations : sequence of per-step observations (the format of :meth:`step`)

        Returns
        -------
        (states, infos) : lists of length ``len(observations)``
        """
        state, steps = self._start(key, observations, None)
        states, infos = [], []
        for k, obs in steps:
            state, info = self.step(k, state, obs)
            states.append(state)
            infos.append(info)
        return states, infos

    def fold(self, key: jax.Array, observations: Sequence[Any],
             progress: Callable[[Iterable, int], Iterable] | None = None) -> tuple[Any, list]:
        """:meth:`run` keeping only the last state (a long run's states need not all be held).

        Parameters
        ----------
        key : PRNG key
            Split as :meth:`run` splits it.
        observations : sequence of per-step observations (the format of :meth:`step`)
        progress : callable ``(iterable, total) -> iterable``, optional
            Wraps the steps (e.g. a tqdm bar).

        Returns
        -------
        (state, infos)
            ``run``'s last state (the ``init`` state when there are no observations) and
            its infos, a list of length ``len(observations)``.
        """
        state, steps = self._start(key, observations, progress)
        infos = []
        for k, obs in steps:
            state, info = self.step(k, state, obs)
            infos.append(info)
        return state, infos

    def _start(self, key: jax.Array, observations: Iterable[Any],
               progress: Callable[[Iterable, int], Iterable] | None) -> tuple[Any, Iterable]:
        """``init``'s state and the ``(key, observation)`` pairs of :meth:`run` (wrapped in
        ``progress`` if given). A key that is not one jax PRNG key, or observations that
        are not a sequence, are an :class:`~dbn.errors.InputError` (they were jax's or
        Python's TypeError)."""
        check_key(key)
        if isinstance(observations, str | bytes) or not isinstance(observations, Iterable):
            raise InputError(f"observations must be a sequence of per-step observations, "
                             f"got {type(observations).__name__}")  # fmt: skip
        observations = list(observations)
        k_init, keys = split_run_keys(key, len(observations))
        steps: Iterable = zip(keys, observations, strict=False)
        return self.init(k_init), steps if progress is None else progress(steps, len(observations))

    def fingerprint(self, state: Any) -> Any:
        """A pytree of arrays/scalars that determines ``state`` (for equality checks).

        The default is the state itself; adapters whose state is an object (e.g. a copied
        labeller) return its defining arrays, without wall-clock timings.
        """
        return state

    def score(self, info: Any) -> float | None:
        """The one-step score of an ``info`` (``None`` when the model has none)."""
        return None if self.score_field is None else float(getattr(info, self.score_field))

    def save(self, state: Any, path) -> None:
        raise NotImplementedError(f"{self.name}: this tracker offers no save/load")

    def load(self, path) -> Any:
        raise NotImplementedError(f"{self.name}: this tracker offers no save/load")
