"""No import side effects on jax's configuration; engines choose float64 themselves.

The tests marked ``x32`` run with jax in its default 32-bit mode (the conftest's per-test
x64 fixture is off), so a float64 result there can only come from the engine's own
:func:`inference.precision.precision_scope`.
"""

from __future__ import annotations

import subprocess
import sys

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from inference.precision import honours_dtype, is_64bit, precision_scope

_IMPORT_ALL = """
import importlib, pkgutil, jax
before = bool(jax.config.jax_enable_x64)
import dbn, inference, models
for pkg in (dbn, inference, models):
    for m in pkgutil.walk_packages(pkg.__path__, pkg.__name__ + "."):
        importlib.import_module(m.name)
print(before, bool(jax.config.jax_enable_x64))
"""


def test_importing_the_library_leaves_jax_x64_unchanged() -> None:
    out = subprocess.run(
        [sys.executable, "-c", _IMPORT_ALL], capture_output=True, text=True, timeout=240, check=True
    )
    assert out.stdout.split()[-2:] == ["False", "False"], out.stdout + out.stderr


@pytest.mark.x32
def test_precision_scope_is_local() -> None:
    assert not jax.config.jax_enable_x64
    with precision_scope(jnp.float64):
        assert jnp.zeros(2, jnp.float64).dtype == jnp.float64
    with precision_scope(np.float32):
        assert jnp.zeros(2).dtype == jnp.float32
    assert not jax.config.jax_enable_x64
    assert is_64bit("float64") and is_64bit(np.int64) and not is_64bit(jnp.float32)
    assert not is_64bit(None)

    @honours_dtype
    def make(n: int, dtype=jnp.float64):
        return jnp.ones(n, dtype)

    assert make(2).dtype == jnp.float64 and make(2, dtype=jnp.float32).dtype == jnp.float32
    assert not jax.config.jax_enable_x64


@pytest.mark.x32
@pytest.mark.parametrize("dtype", [jnp.float64, jnp.float32])
def test_particle_filters_compute_in_their_dtype(dtype) -> None:
    from inference.kalman import LinearGaussianParams, kalman_filter, lgssm_sample
    from inference.particle import LinearGaussianSSM, bootstrap_filter, run

    params = LinearGaussianParams(
        F=np.eye(1) * 0.9, Q=np.eye(1) * 0.1, H=np.eye(1), R=np.eye(1) * 0.5,
        m0=np.zeros(1), P0=np.eye(1),
    )  # fmt: skip
    _, ys = lgssm_sample(3, params, 8)
    pf = bootstrap_filter(LinearGaussianSSM(params), 1000, dtype=dtype)
    final, infos, means = run(jax.random.key(0), pf, np.asarray(ys, dtype))
    assert final.log_weights.dtype == dtype and final.particles.dtype == dtype
    assert infos.log_likelihood.dtype == dtype and means.dtype == dtype
    assert pf.init(jax.random.key(2)).log_weights.dtype == dtype
    # and the result is the filter's, not float32 garbage: within Monte-Carlo error of Kalman
    exact = kalman_filter(params, ys).log_likelihood
    assert abs(float(np.asarray(infos.log_likelihood).sum()) - exact) < 0.5
    assert not jax.config.jax_enable_x64


@pytest.mark.x32
def test_dbn_filter_scans_in_float64() -> None:
    from dbn.cpds import TabularCPD
    from dbn.dbn import TwoSliceDBN, prev
    from dbn.variables import DiscreteVariable
    from inference.exact.dbn_filter import DBNFilter

    A = np.array([[0.9, 0.1], [0.2, 0.8]])
    B = np.array([[0.7, 0.3], [0.1, 0.9]])
    dbn = TwoSliceDBN(
        [DiscreteVariable("x", 2), DiscreteVariable("y", 2)],
        [TabularCPD("x", [], np.array([0.5, 0.5])), TabularCPD("y", ["x"], B)],
        [TabularCPD("x", [prev("x")], A), TabularCPD("y", ["x"], B)],
    )
    obs = np.random.default_rng(0).integers(2, size=3000)
    res = DBNFilter(dbn).filter({"y": obs})
    assert res.beliefs.dtype == np.float64
    # float64 normalisation: rows sum to one far below float32's resolution
    np.testing.assert_allclose(res.beliefs.sum(axis=1), 1.0, atol=1e-12)
    assert not jax.config.jax_enable_x64


@pytest.mark.x32
def test_localizer_runs_in_float64_by_default() -> None:
    from models.localization.model import RangeBearingLocalizationModel, RangeBearingObservation
    from models.localization.tracker import Localizer

    model = RangeBearingLocalizationModel(
        landmarks=np.array([[0.0, 0.0], [5.0, 0.0], [0.0, 5.0]]),
        initial_pose=np.array([1.0, 1.0, 0.0]),
        initial_std=np.array([0.1, 0.1, 0.05]),
    )
    loc = Localizer(jax.random.key(0), model, 200)
    assert loc.state.particles.dtype == jnp.float64
    obs = RangeBearingObservation(
        np.array([0, 1]), np.array([1.4, 4.1]), np.array([-2.3, -0.2]), np.array([True, True])
    )
    loc.update(jax.random.key(1), np.array([0.1, 0.0, 0.0, 0.1]), obs)
    assert loc.state.log_weights.dtype == jnp.float64 and loc.mean().dtype == np.float64
    assert not jax.config.jax_enable_x64
