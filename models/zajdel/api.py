"""The Zajdel assumed-density filter (seed 002, sec. 1.4) under the tracker protocol.

:class:`ZajdelADF`'s own ``init`` / ``step`` / ``save`` / ``load`` are already pure on an
immutable :class:`ADFState`; the adapter adds the protocol's key argument (unused: the
filter is deterministic) and runs every call inside float64
(:func:`inference.precision.precision_scope`), so the tracker computes in float64 without
jax's global 64-bit switch. One ``step`` observation is an :class:`Observations` of one
observation; Info is :class:`ADFInfo`, whose ``loglik`` is
``log p(y_k | y_1..y_{k-1})`` under the ADF.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from inference.precision import precision_scope
from models.protocol import Example, StepTracker, check_key, seed_from_key
from models.zajdel.data import Observations, take
from models.zajdel.tracker import ADFConfig, ADFInfo, ADFState, ZajdelADF

__all__ = ["ZajdelADFTracker", "make", "example"]


class ZajdelADFTracker(StepTracker):
    """Protocol adapter over :class:`ZajdelADF`."""

    name = "zajdel_adf"
    score_field = "loglik"
    can_save = True

    def __init__(self, adf: ZajdelADF) -> None:
        self.adf = adf

    def init(self, key: jax.Array) -> ADFState:
        """Empty belief (deterministic: the key is checked, not used)."""
        check_key(key)
        with precision_scope(jnp.float64):
            return self.adf.init()

    def step(self, key: jax.Array, state: ADFState, obs: Observations) -> tuple[ADFState, ADFInfo]:
        """One ADF update with one observation (the key is checked, not used)."""
        check_key(key)
        with precision_scope(jnp.float64):
            return self.adf.step(state, obs)

    def save(self, state: ADFState, path) -> None:
        """Write ``state`` to ``.npz`` (:meth:`ZajdelADF.save`)."""
        self.adf.save(state, path)

    def load(self, path) -> ADFState:
        """Read a state written by :meth:`save` (:meth:`ZajdelADF.load`)."""
        with precision_scope(jnp.float64):
            return self.adf.load(path)


def make(params, config: ADFConfig | None = None) -> ZajdelADFTracker:
    """The adapter over ``ZajdelADF(params, config)`` (params or a ZajdelModel declaration)."""
    with precision_scope(jnp.float64):
        return ZajdelADFTracker(ZajdelADF(params, config))


def one_per_step(obs: Observations) -> list[Observations]:
    """Split a batch of observations into the protocol's one-observation steps."""
    return [take(obs, slice(i, i + 1)) for i in range(obs.num_obs)]


def example(key: jax.Array) -> Example:
    """A SIMULATED office (3 people, 3 cameras, 6 observations), a small ADF; bad: NaN
    appearance."""
    from models.zajdel.simulate import OfficeConfig, simulate_office

    sc = simulate_office(seed_from_key(key), OfficeConfig(num_people=3, num_cameras=3, num_obs=6))
    config = ADFConfig(max_open=8, persons_per_slot=4, init_persons=16, chunk=4, mix_top=8)
    steps = one_per_step(sc.obs)
    bad = steps[1]._replace(appearance=np.full_like(steps[1].appearance, np.nan))
    return Example(make(sc.params, config), steps, bad)
