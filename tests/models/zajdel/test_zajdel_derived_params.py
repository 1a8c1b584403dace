"""The tracker's travel-time normalisers, compiled as one program, equal the op-by-op
values bit for bit (the filter's figures must not move with how they are compiled)."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
import pytest

from inference.adf.driver import x64_context
from models.zajdel.birth_leave import (
    estimate_arrival_profile,
    estimate_birth_leave,
    with_birth_leave,
)
from models.zajdel.path import PathModel, travel_log_norm
from models.zajdel.simulate import large_config, simulate_office
from models.zajdel.tracker import _path_lognorm


def _office(seed: int):
    return simulate_office(seed).params


def _large(seed: int):
    return simulate_office(seed, large_config(500)).params


def _birth_leave(seed: int):
    config = large_config(500)
    train = [simulate_office(s, config) for s in (seed + 100, seed + 101)]
    _, leave = estimate_birth_leave(train)
    profile = estimate_arrival_profile(train, 300.0)
    return with_birth_leave(_large(seed), profile, leave, 300.0)


@pytest.mark.parametrize("make", [_office, _large, _birth_leave],
                         ids=["office-7-cameras", "large-20-cameras", "birth-leave"])
@pytest.mark.parametrize("seed", [0, 3])
def test_path_lognorm_equals_op_by_op_bit_for_bit(make, seed: int) -> None:
    params = make(seed)
    with x64_context():
        path = PathModel(*(jnp.asarray(np.asarray(v, float)) for v in params.path))
        got, want = np.asarray(_path_lognorm(path)), np.asarray(travel_log_norm(path))
    assert got.dtype == want.dtype == np.float64
    assert got.shape == (params.path.num_cameras,) * 2
    np.testing.assert_array_equal(got, want)
