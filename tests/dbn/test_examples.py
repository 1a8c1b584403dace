"""The simulators of dbn.examples: shapes, values, and bad sizes refused by name."""

from __future__ import annotations

import numpy as np
import pytest

from dbn.errors import ModelError
from dbn.examples import sample_coupled_chains


def test_sample_coupled_chains_shapes_and_states() -> None:
    xs, ys = sample_coupled_chains(np.random.default_rng(0), 3, 7)
    assert xs.shape == ys.shape == (7, 3)
    assert set(np.unique(xs)) <= {0, 1} and set(np.unique(ys)) <= {0, 1}


@pytest.mark.parametrize("T", [0, -1, 2.5, True])
def test_sample_coupled_chains_refuses_a_bad_length(T) -> None:
    """A sweep point with ``T = -1`` used to end in numpy's 'negative dimensions'."""
    with pytest.raises(ModelError, match="num_timesteps"):
        sample_coupled_chains(np.random.default_rng(0), 3, T)
