"""The simulators name a bad count or number (the SIMULATED data of the tutorials, the
benchmarks and the tests): 2.5 people or NaN frames raised Python's or numpy's own errors
("'float' object cannot be interpreted as an integer", "cannot convert float NaN to
integer", "negative dimensions are not allowed"); a NaN rate or noise, a negative
frame rate or world size ran to garbage."""

from __future__ import annotations

import numpy as np
import pytest

from dbn.errors import DBNError
from models.jorge.meeting import simulate_meeting
from models.jorge.simulate import simulate_ground_truth
from models.localization.model import MotionNoise
from models.localization.simulate import make_world, simulate_run
from models.pathrecovery.simulate import manhattan_grid, simulate_scene

WORLD = make_world()

CASES = [
    (lambda v: simulate_ground_truth(0, num_people=v), "num_people", [2.5, np.nan, 0]),
    (lambda v: simulate_ground_truth(0, num_frames=v), "num_frames", [2.5, np.nan]),
    (lambda v: simulate_ground_truth(0, fps=v), "fps", [np.nan, -1.0, 0.0]),
    (lambda v: simulate_meeting(0, group_size=v), "group_size", [2.5, np.nan]),
    (lambda v: simulate_meeting(0, num_walkers=v), "num_walkers", [2.5, np.nan, -1]),
    (lambda v: simulate_meeting(0, num_frames=v), "num_frames", [2.5, 0]),
    (lambda v: simulate_scene(0, manhattan_grid(3, 3), num_objects=v), "num_objects",
     [2.5, np.nan]),
    (lambda v: simulate_scene(0, manhattan_grid(3, 3), num_timesteps=v), "num_timesteps",
     [2.5, np.nan]),
    (lambda v: simulate_scene(0, manhattan_grid(3, 3), feature_dim=v), "feature_dim",
     [2.5, np.nan, -1]),
    (lambda v: make_world(width=v), "width", [np.nan, -1.0, 1e9]),
    (lambda v: make_world(period=v), "period", [np.nan, 0.0]),
    (lambda v: simulate_run(0, WORLD, v), "num_timesteps", [2.5, np.nan, -1]),
    (lambda v: simulate_run(0, WORLD, 5, num_rays=v), "num_rays", [2.5, 0]),
    (lambda v: simulate_run(0, WORLD, 5, outlier_rate=v), "outlier_rate", [np.nan, 2.0]),
    (lambda v: simulate_run(0, WORLD, 5, step_length=v), "step_length", [np.nan, -1.0]),
    (lambda v: simulate_run(0, WORLD, 5, scan_noise=v), "scan_noise", [np.nan, -1.0]),
    (lambda v: simulate_run(0, WORLD, 5, noise=v), "noise", [MotionNoise(np.nan), (0.1,)]),
]  # fmt: skip


@pytest.mark.parametrize(("simulate", "name", "values"), CASES, ids=[c[1] for c in CASES])
def test_a_bad_simulator_argument_is_refused_naming_it(simulate, name, values) -> None:
    for value in values:
        with pytest.raises(DBNError, match=name if name != "width" else "width|stripes"):
            simulate(value)


def test_the_checked_simulators_still_simulate() -> None:
    """The checks let the defaults through, numpy integers included."""
    assert simulate_ground_truth(0, num_people=np.int64(2), num_frames=20).boxes.shape[1] == 2
    assert simulate_run(0, WORLD, np.int64(5)).poses.shape[0] >= 5
