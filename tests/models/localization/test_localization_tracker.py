"""The localiser on the SIMULATED aliased world and on the real MRCLAM data; bad input
leaves it unchanged."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from dbn.errors import InputError, NonFiniteError, ShapeError, TimeOrderError
from models.localization.experiments import dead_reckoning
from models.localization.model import RangeBearingObservation
from models.localization.simulate import (
    build_trained_world,
    cast_scans,
    knn_model_for,
    make_world,
    simulate_run,
)
from models.localization.tracker import Localizer, localize, position_errors


@pytest.fixture(scope="module")
def trained():
    return build_trained_world(0)


def test_world_is_aliased_and_scans_are_rotations() -> None:
    world = make_world()
    # two places 2 m apart along the corridor (away from the end walls) read the same scan
    a = cast_scans(world, np.array([[5.0, 1.5, 0.3]]))
    b = cast_scans(world, np.array([[7.0, 1.5, 0.3]]))
    np.testing.assert_allclose(a, b, atol=1e-9)
    c = cast_scans(world, np.array([[5.5, 1.5, 0.3]]))
    assert np.abs(a - c).max() > 0.05
    # a turn by one ray step shifts the panorama by one ray
    r0 = cast_scans(world, np.array([[5.0, 1.5, 0.0]]), num_rays=72)[0]
    r1 = cast_scans(world, np.array([[5.0, 1.5, 2 * np.pi / 72]]), num_rays=72)[0]
    np.testing.assert_allclose(np.roll(r0[:72], -1), r1[:72], atol=1e-9)


@pytest.mark.parametrize("algorithm", ["sir", "apf"])
def test_filters_track_the_simulated_robot(trained, algorithm: str) -> None:
    run = simulate_run(3, trained.world, 40, outlier_rate=0.1)
    model = knn_model_for(trained, run)
    obs = trained.sensor.preprocess(run.observations)
    res = localize(jax.random.key(1), model, run.actions, obs, 500, algorithm)
    err = position_errors(res.means, run.poses[1:])
    dead = position_errors(dead_reckoning(run.poses[0], run.actions), run.poses[1:])
    # the sensor model (cell 0.2 m, bandwidth 0.1 m) keeps the error well below dead reckoning
    assert np.sqrt(np.mean(err**2)) < 0.25
    assert np.sqrt(np.mean(err**2)) < np.sqrt(np.mean(dead**2))
    # occluded scans were caught by the outlier rule and skipped (log-likelihood 0)
    ll = np.asarray(res.infos.log_likelihood)
    skipped = ~np.asarray(obs.valid)
    assert skipped.sum() >= 1 and np.all(np.abs(ll[skipped]) < 1e-9)
    assert np.all(run.outlier[skipped])


def _snapshot(loc: Localizer):
    return (
        np.asarray(loc.state.particles).copy(),
        np.asarray(loc.state.log_weights).copy(),
        loc.timestamp,
    )


def test_bad_input_leaves_the_localizer_unchanged(trained) -> None:
    run = simulate_run(4, trained.world, 3)
    loc = Localizer(jax.random.key(0), knn_model_for(trained, run), 200, "apf")
    loc.update(jax.random.key(1), run.actions[0], run.observations[0], timestamp=1.0)
    before = _snapshot(loc)
    bad_scan = run.observations[1].copy()
    bad_scan[5] = np.nan
    bad_odo = run.actions[1].copy()
    bad_odo[0] = np.inf
    cases = [
        (NonFiniteError, dict(odometry=run.actions[1], observation=bad_scan, timestamp=2.0)),
        (NonFiniteError, dict(odometry=bad_odo, observation=run.observations[1], timestamp=2.0)),
        (
            ShapeError,
            dict(odometry=run.actions[1], observation=run.observations[1][:-1], timestamp=2.0),
        ),
        (
            ShapeError,
            dict(odometry=run.actions[1][:3], observation=run.observations[1], timestamp=2.0),
        ),
        (
            TimeOrderError,
            dict(odometry=run.actions[1], observation=run.observations[1], timestamp=0.5),
        ),
        (
            NonFiniteError,
            dict(odometry=run.actions[1], observation=run.observations[1], timestamp=np.nan),
        ),
    ]
    for err, kwargs in cases:
        with pytest.raises(err):
            loc.update(jax.random.key(2), **kwargs)
        after = _snapshot(loc)
        np.testing.assert_array_equal(before[0], after[0])
        np.testing.assert_array_equal(before[1], after[1])
        assert before[2] == after[2]
    mean = loc.update(jax.random.key(2), run.actions[1], run.observations[1], timestamp=2.0)
    assert mean.shape == (3,) and loc.timestamp == 2.0


def test_unknown_algorithm() -> None:
    with pytest.raises(InputError, match="algorithm"):
        from models.localization.tracker import make_filter

        make_filter(None, 10, "ukf")


# --- real data -----------------------------------------------------------------------------------
def test_mrclam_loader(shared_data) -> None:
    from models.localization.mrclam import build_sequence, load_robot

    data = load_robot(1)
    assert data.landmarks.shape == (15, 2)
    assert set(data.landmark_subjects) == set(range(6, 21))
    assert data.barcode_to_subject[5] == 1 and data.barcode_to_subject[63] == 6
    seq = build_sequence(data, duration=60.0, dt=0.1)
    assert seq.odometry.shape == (600, 4) and seq.truth.shape == (601, 3)
    obs = seq.observations
    assert obs.mask.sum() > 0
    assert np.all((obs.landmark[obs.mask] >= 0) & (obs.landmark[obs.mask] < 15))
    # every kept measurement is of a landmark: its range agrees with motion capture (< 1 m)
    k, j = np.nonzero(obs.mask)
    lm = seq.landmarks[obs.landmark[k, j]]
    r_true = np.hypot(lm[:, 0] - seq.truth[k + 1, 0], lm[:, 1] - seq.truth[k + 1, 1])
    assert np.median(np.abs(obs.range[k, j] - r_true)) < 0.3
    # odometry integrates to motion close to the truth over one minute
    dead = dead_reckoning(seq.truth[0], seq.odometry)
    assert np.max(position_errors(dead, seq.truth[1:])) < 1.0


@pytest.mark.heavy  # ~9 s: 90 s of real MRCLAM data; CI runs it (pytest -m heavy)
def test_mrclam_filter_beats_dead_reckoning(shared_data) -> None:
    from models.localization.mrclam import build_sequence, load_robot, mrclam_model

    seq = build_sequence(load_robot(1), duration=90.0, dt=0.1)
    model = mrclam_model(seq)
    obs = jax.tree_util.tree_map(jnp.asarray, seq.observations)
    res = localize(jax.random.key(0), model, seq.odometry, obs, 500, "apf")
    err = position_errors(res.means, seq.truth[1:])
    dead = position_errors(dead_reckoning(seq.truth[0], seq.odometry), seq.truth[1:])
    assert np.sqrt(np.mean(err**2)) < np.sqrt(np.mean(dead**2))
    assert np.sqrt(np.mean(err**2)) < 0.4
    # a RangeBearingObservation step through the stateful localiser, and a bad one
    loc = Localizer(jax.random.key(0), model, 100)
    step_obs = RangeBearingObservation(*(np.asarray(a[0]) for a in seq.observations))
    loc.update(jax.random.key(1), seq.odometry[0], step_obs)
    bad = step_obs._replace(range=np.full_like(step_obs.range, np.nan))
    before = _snapshot(loc)
    with pytest.raises(NonFiniteError, match="observation.range"):
        loc.update(jax.random.key(2), seq.odometry[1], bad)
    np.testing.assert_array_equal(before[0], _snapshot(loc)[0])


def test_equal_times_are_in_order(tmp_path) -> None:
    from models.io.localization import read_poses

    csv = tmp_path / "poses.csv"
    csv.write_text("t,x,y,theta\n0,0,0,0\n1,0,0,0\n1,1,0,0\n2,1,0,0\n")
    np.testing.assert_array_equal(read_poses(csv)[0], [0.0, 1.0, 1.0, 2.0])
    csv.write_text("t,x,y,theta\n0,0,0,0\n1,0,0,0\n0.5,1,0,0\n")
    with pytest.raises(TimeOrderError, match=r"poses\.csv:4: time goes back \(0.5 after 1.0\)"):
        read_poses(csv)


def test_mrclam_event_alignment(shared_data) -> None:
    from models.localization.mrclam import build_sequence, load_robot

    data = load_robot(1)
    grid = build_sequence(data, duration=30.0, dt=0.1)
    events = build_sequence(data, duration=30.0, dt=0.1, align="events")
    assert grid.on_grid.all() and events.on_grid.sum() == len(grid.odometry)
    assert events.observations.mask.sum() == grid.observations.mask.sum()
    # every measurement sits at the end of its own step, at its own time
    k, _ = np.nonzero(events.observations.mask)
    t_meas = np.sort(data.measurements[:, 0])
    assert np.all(np.isin(events.times[k + 1], t_meas))
    np.testing.assert_allclose(events.odometry[:, 3].sum(), 30.0, atol=1e-9)
    with pytest.raises(InputError, match="align"):
        build_sequence(data, align="nope")


def test_localize_compiles_once_for_every_noise_setting() -> None:
    """The range-bearing model's noise is traced (``run_model``): three settings on one
    SIMULATED run add one compiled scan, and each setting still gives its own poses."""
    from inference.particle import filters
    from models.localization.model import RangeBearingLocalizationModel

    rng = np.random.default_rng(3)
    landmarks = np.array([[0.0, 0.0], [2.0, 0.0], [1.0, 2.0]])
    odo = np.tile([0.05, 0.0, 0.02, 0.1], (17, 1))  # 17 steps: a shape no other test runs
    obs = RangeBearingObservation(np.tile(np.arange(3), (17, 1)), 1 + rng.random((17, 3)),
                                  rng.uniform(-1, 1, (17, 3)), np.ones((17, 3), bool))  # fmt: skip
    before = filters._run_model._cache_size()
    means = [localize(jax.random.key(0), RangeBearingLocalizationModel(
                 landmarks, [1.0, 1.0, 0.0], [0.2, 0.2, 0.1], sigma_range=s), odo, obs, 200).means
             for s in (0.1, 0.3, 0.9)]  # fmt: skip
    assert filters._run_model._cache_size() == before + 1
    assert min(np.abs(a - b).max() for a, b in [means[:2], means[1:]]) > 1e-3


def test_position_errors_refuse_shapes_that_only_broadcast() -> None:
    """One true pose against every estimate broadcast silently; a truth one step longer
    raised numpy's broadcast error. Runs (leading axes) still share one truth."""
    from dbn.errors import ShapeError

    means, truth = np.zeros((2, 5, 3)), np.ones((5, 3))
    np.testing.assert_allclose(position_errors(means, truth), np.full((2, 5), np.sqrt(2)))
    for m, t in ((means[0], truth[:1]), (means[0], np.ones((6, 3))),
                 (means, np.ones((3, 5, 3))), (np.zeros(3), np.ones(3))):  # fmt: skip
        with pytest.raises(ShapeError, match="expected"):
            position_errors(m, t)
