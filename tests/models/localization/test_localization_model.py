"""The robot, the k-NN sensor model (seed 002, eq. 1.14) and the range-bearing sensor,
checked against direct numpy formulas and brute force."""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.special import logsumexp

from dbn.errors import InputError, ModelError, NonFiniteError, ShapeError
from models.localization.model import (
    KNNLocalizationModel,
    KNNObservation,
    KNNSensor,
    MotionNoise,
    RangeBearingLocalizationModel,
    RangeBearingObservation,
    RobotModel,
    compose,
    fit_pca,
    knn_log_likelihood,
    relative_pose,
    wrap_angle,
)

finite = st.floats(-10, 10, allow_nan=False)


@settings(max_examples=50, deadline=None)
@given(st.tuples(finite, finite, finite), st.tuples(finite, finite, finite))
def test_compose_and_relative_pose_are_inverse(a, b) -> None:
    a, b = np.array(a), np.array(b)
    a[2], b[2] = wrap_angle(a[2]), wrap_angle(b[2])
    back = compose(a, relative_pose(a, b))
    np.testing.assert_allclose(back[:2], b[:2], atol=1e-9)
    assert abs(wrap_angle(back[2] - b[2])) < 1e-9


def _robot() -> RobotModel:
    return RobotModel([1.0, 2.0, 0.3], [0.1, 0.1, 0.05], MotionNoise(0.02, 0.1, 0.03, 0.2))


def test_prepared_step_reproduces_composition_and_noise_law() -> None:
    m = _robot()
    odo = np.array([0.3, -0.1, 0.4, 0.5])
    step = m.prepare_actions(odo)
    assert step.shape == (4, 3)
    x = np.array([[1.0, 2.0, 3.1], [0.0, -1.0, -2.0]])
    mean = np.asarray(m.transition_mean(jnp.asarray(x), jnp.asarray(step)))
    np.testing.assert_allclose(mean, compose(x, odo[:3]), atol=1e-12)
    sxy = 0.02 * math.sqrt(0.5) + 0.1 * math.hypot(0.3, -0.1)
    sth = 0.03 * math.sqrt(0.5) + 0.2 * 0.4
    np.testing.assert_allclose(step[3], [sxy, sxy, sth])
    # Monte Carlo: samples have that mean and sd (4 standard errors)
    n = 20000
    xs = jnp.tile(jnp.asarray(x[:1]), (n, 1))
    s = np.asarray(m.sample_transition(jax.random.key(0), xs, jnp.asarray(step)))
    d = s - mean[0]
    d[:, 2] = wrap_angle(d[:, 2])
    sd = np.array([sxy, sxy, sth])
    assert np.all(np.abs(d.mean(0)) < 4 * sd / math.sqrt(n))
    assert np.all(np.abs(d.std(0) / sd - 1) < 4 * math.sqrt(0.5 / n))
    assert np.all((s[:, 2] >= -math.pi) & (s[:, 2] < math.pi))


def test_prepare_actions_rejects_bad_odometry() -> None:
    m = _robot()
    with pytest.raises(NonFiniteError, match=r"odometry\[1, 2\]"):
        m.prepare_actions(np.array([[0.1, 0, 0, 1], [0.1, 0, np.nan, 1]]))
    with pytest.raises(ShapeError, match="odometry"):
        m.prepare_actions(np.zeros(3))
    with pytest.raises(InputError, match="dt"):
        m.prepare_actions(np.array([0.1, 0, 0, -1.0]))


def _brute_knn(x, centres, log_lam, bw):
    d = x[:, None, :] - centres[None]
    d[..., 2] = wrap_angle(d[..., 2])
    log_phi = (
        -0.5 * np.sum((d / bw) ** 2, axis=2) - np.sum(np.log(bw)) - 1.5 * math.log(2 * math.pi)
    )
    return logsumexp(log_lam[None] + log_phi, axis=1)


@pytest.mark.parametrize("scale", [1.0, 40.0])  # 40: particles far from every centre (exact path)
def test_knn_log_likelihood_matches_brute_force(scale: float) -> None:
    rng = np.random.default_rng(0)
    J = 10
    centres = rng.normal(size=(J, 3))
    centres[:, 2] = wrap_angle(centres[:, 2] * 3)
    j = np.arange(1, J + 1)
    log_lam = np.log(2 * (J - j + 1) / (J * (J + 1)))
    bw = np.array([0.1, 0.1, 0.13])
    x = rng.normal(size=(500, 3)) * scale
    x[:, 2] = wrap_angle(x[:, 2])
    obs = KNNObservation(jnp.asarray(centres), jnp.asarray(log_lam), jnp.asarray(True), 0.0)
    log_norm = float(-np.sum(np.log(bw)) - 1.5 * math.log(2 * math.pi))
    got = np.asarray(
        jax.jit(knn_log_likelihood)(jnp.asarray(x), obs, jnp.asarray(1 / bw), log_norm)
    )
    want = _brute_knn(x, centres, log_lam, bw)
    np.testing.assert_allclose(got, want, rtol=1e-10, atol=1e-9)
    # float32 path: the same numbers to float32 accuracy
    obs32 = KNNObservation(
        jnp.asarray(centres, jnp.float32), jnp.asarray(log_lam, jnp.float32), jnp.asarray(True), 0.0
    )
    got32 = np.asarray(
        knn_log_likelihood(
            jnp.asarray(x, jnp.float32), obs32, jnp.asarray(1 / bw, jnp.float32), log_norm
        )
    )
    assert got32.dtype == np.float32
    np.testing.assert_allclose(got32, want, rtol=2e-5, atol=2e-3)
    skip = obs._replace(valid=jnp.asarray(False))
    assert np.all(
        np.asarray(knn_log_likelihood(jnp.asarray(x), skip, jnp.asarray(1 / bw), log_norm)) == 0
    )


def test_pca_is_the_top_principal_subspace() -> None:
    rng = np.random.default_rng(1)
    y = (
        rng.normal(size=(400, 12))
        @ np.diag(np.linspace(3, 0.1, 12))
        @ np.linalg.qr(rng.normal(size=(12, 12)))[0]
    )
    pca = fit_pca(y, 4)
    np.testing.assert_allclose(pca.components @ pca.components.T, np.eye(4), atol=1e-10)
    _, _, vt = np.linalg.svd(y - y.mean(0), full_matrices=False)
    # same subspace: projector equality
    np.testing.assert_allclose(pca.components.T @ pca.components, vt[:4].T @ vt[:4], atol=1e-8)


def test_knn_sensor_neighbours_weights_and_outlier_rule() -> None:
    rng = np.random.default_rng(2)
    poses = np.column_stack(
        [rng.uniform(0, 5, 300), rng.uniform(0, 5, 300), rng.uniform(-3, 3, 300)]
    )
    scans = np.column_stack(
        [np.cos(poses[:, 0] * k) + np.sin(poses[:, 1] * k) for k in range(1, 31)]
    )
    sensor = KNNSensor(
        poses, scans, feature_dim=6, num_neighbours=5, cell_xy=0.2, cell_theta=0.3, threshold=0.5
    )
    y = scans[:3] + 0.01 * rng.normal(size=(3, 30))
    y = np.vstack([y, 50 + scans[:1]])  # the last one is far from every training scan
    obs = sensor.preprocess(y)
    z_train = sensor.pca.project(scans)
    for t in range(len(y)):
        d = np.linalg.norm(z_train - sensor.pca.project(y[t]), axis=1)
        nearest = np.argsort(d)[:5]
        np.testing.assert_allclose(np.asarray(obs.centres[t]), poses[nearest])
        assert bool(obs.valid[t]) == (d.min() <= 0.5)
    lam = np.exp(np.asarray(obs.log_lambda[0]))
    np.testing.assert_allclose(lam, 2 * (5 - np.arange(1, 6) + 1) / 30)
    assert lam.sum() == pytest.approx(1.0)
    assert not bool(obs.valid[-1]) and all(bool(v) for v in obs.valid[:3])
    np.testing.assert_allclose(sensor.bandwidth, [0.1, 0.1, 0.15])
    with pytest.raises(NonFiniteError):
        sensor.preprocess(np.full(30, np.inf))
    with pytest.raises(ShapeError):
        sensor.preprocess(np.zeros(29))
    model = KNNLocalizationModel(sensor, poses[0], [0.1, 0.1, 0.1])
    one = sensor.preprocess(y[0])
    ll = np.asarray(model.log_likelihood(jnp.asarray(poses[:50]), one))
    want = _brute_knn(
        poses[:50].copy(), np.asarray(one.centres), np.asarray(one.log_lambda), sensor.bandwidth
    )
    np.testing.assert_allclose(ll, want, rtol=1e-10, atol=1e-9)


@pytest.mark.parametrize(("change", "error", "needle"), [
    ({"train_poses": np.zeros((6, 3)) + 0j}, ModelError, "train_poses holds complex numbers"),
    ({"train_observations": np.full((6, 4), "x")}, ModelError, "train_observations is not"),
    ({"cell_xy": 0.0}, ModelError, "cell_xy, cell_theta = [0.0, 0.3]: every number must be >="),
    ({"cell_theta": np.nan}, NonFiniteError, "cell_xy, cell_theta = [0.5, nan]"),
    ({"cell_xy": "a"}, ModelError, "cell_xy, cell_theta must be numbers"),
    ({"threshold": np.nan}, ModelError, "threshold = nan: a distance > 0"),
    ({"threshold": -1.0}, ModelError, "threshold = -1.0: a distance > 0"),
    ({"threshold": "a"}, ModelError, "threshold = 'a'"),
    ({"threshold": np.complex128(2 + 1j)}, ModelError, "threshold = np.complex128(2+1j)"),
    ({"num_neighbours": 2.5}, InputError, "num_neighbours must be an integer >= 1, got 2.5"),
    ({"num_neighbours": True}, InputError, "num_neighbours must be an integer >= 1, got True"),
    ({"feature_dim": 1.5}, InputError, "feature_dim must be an integer >= 1, got 1.5"),
])  # fmt: skip
def test_knn_sensor_names_a_bad_setting(change, error, needle) -> None:
    """A cell size of 0 or NaN gave a NaN kernel, a NaN or negative threshold skipped
    every observation, 2.5 neighbours ran as 2 and True as 1, complex training data lost
    its imaginary parts, and text or a fractional feature_dim raised Python's errors."""
    rng = np.random.default_rng(0)
    base = dict(train_poses=rng.normal(size=(6, 3)), train_observations=rng.normal(size=(6, 4)),
                feature_dim=2, num_neighbours=3, cell_xy=0.5, cell_theta=0.3)  # fmt: skip
    KNNSensor(**base)
    with pytest.raises(error) as exc:
        KNNSensor(**{**base, **change})
    assert needle in str(exc.value)


def test_range_bearing_likelihood_matches_formula() -> None:
    lms = np.array([[0.0, 0.0], [3.0, 1.0], [-2.0, 4.0]])
    m = RangeBearingLocalizationModel(
        lms,
        [0, 0, 0],
        [1, 1, 1],
        sigma_range=0.2,
        sigma_bearing=0.05,
        outlier_prob=0.1,
        max_range=8.0,
    )
    x = np.array([[1.0, 1.0, 0.3], [-1.0, 2.0, -2.0]])
    obs = RangeBearingObservation(
        np.array([1, 2, 0]),
        np.array([2.1, 3.5, 9.0]),
        np.array([-0.5, 1.2, 0.0]),
        np.array([True, True, False]),
    )
    got = np.asarray(m.log_likelihood(jnp.asarray(x), jax.tree_util.tree_map(jnp.asarray, obs)))
    want = []
    for p in x:
        tot = 0.0
        for lm, r, b, use in zip(obs.landmark, obs.range, obs.bearing, obs.mask):
            if not use:
                continue
            dx, dy = lms[lm] - p[:2]
            er = (r - math.hypot(dx, dy)) / 0.2
            eb = wrap_angle(b - (math.atan2(dy, dx) - p[2])) / 0.05
            g = 0.9 * math.exp(-0.5 * (er**2 + eb**2)) / (2 * math.pi * 0.2 * 0.05)
            tot += math.log(g + 0.1 / (8.0 * 2 * math.pi))
        want.append(tot)
    np.testing.assert_allclose(got, want, rtol=1e-10)


_LMS = np.array([[0.0, 0.0], [3.0, 1.0]])


@pytest.mark.parametrize(("change", "error", "needle"), [
    ({"initial_pose": [0, 0]}, ShapeError, "initial_pose has 2 numbers"),
    ({"initial_pose": ["a", 0, 0]}, ModelError, "initial_pose must be numbers"),
    ({"initial_std": [-1, 1, 1]}, ModelError, "initial_std"),
    ({"initial_std": [1e300, 1, 1]}, NonFiniteError, "initial_std"),
    ({"noise": MotionNoise(np.nan)}, NonFiniteError, "noise"),
    ({"noise": MotionNoise(-0.1)}, ModelError, "noise"),
    ({"noise": (0.1, 0.2)}, ShapeError, "noise has 2 numbers"),
    ({"landmarks": np.array([[np.nan, 0.0]])}, NonFiniteError, "landmarks"),
    ({"landmarks": np.zeros((0, 2))}, ShapeError, "landmarks"),
    ({"landmarks": [["a", "b"]]}, ModelError, "landmarks must be numbers"),
    ({"sigma_range": 0.0}, ModelError, "sigma_range"),
    ({"sigma_bearing": np.nan}, NonFiniteError, "sigma_bearing"),
    ({"outlier_prob": 0.0}, ModelError, "outlier_prob"),
    ({"outlier_prob": 1.5}, ModelError, "outlier_prob"),
    ({"max_range": -1.0}, ModelError, "max_range"),
    ({"range_bias": np.inf}, NonFiniteError, "range_bias"),
])  # fmt: skip
def test_a_bad_model_parameter_is_refused_naming_it(change, error, needle) -> None:
    """The Python constructor checks what ``dbntrack``'s config reader checks: a zero
    sigma_range or a NaN noise term ran to NaN log-likelihoods, an outlier_prob of 0 to
    math's "domain error", a 2-number pose to numpy's reshape error."""
    args = {"landmarks": _LMS, "initial_pose": [0, 0, 0], "initial_std": [1, 1, 1],
            "noise": MotionNoise()} | change  # fmt: skip
    with pytest.raises(error, match=needle):
        RangeBearingLocalizationModel(args.pop("landmarks"), args.pop("initial_pose"),
                                      args.pop("initial_std"), **args)  # fmt: skip
