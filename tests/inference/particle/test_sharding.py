"""Particle filters sharded over jax devices (inference.particle.sharding).

The multi-device checks run in a subprocess with 4 forced host devices (the count must
be set before jax starts): global resampling equals the unsharded filter for the same
key, and the island (local resampling) filter's means agree with the Kalman filter
within Monte-Carlo standard errors over independent keys.
"""

from __future__ import annotations

import functools
import json
import os
import subprocess
import sys
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from dbn.errors import InputError
from inference.kalman import LinearGaussianParams, lgssm_sample
from inference.particle import LinearGaussianSSM, bootstrap_filter, run
from inference.particle.sharding import particle_mesh, run_sharded, sharded_filter

ROOT = Path(__file__).resolve().parents[3]


def _setup():
    params = LinearGaussianParams(
        F=np.array([[0.9]]),
        Q=np.array([[0.2]]),
        H=np.array([[1.0]]),
        R=np.array([[0.5]]),
        m0=np.zeros(1),
        P0=np.eye(1),
    )
    _, ys = lgssm_sample(3, params, 10)
    return functools.partial(bootstrap_filter, LinearGaussianSSM(params), dtype=jnp.float32), ys


def test_one_device_mesh_equals_the_plain_filter() -> None:
    make, ys = _setup()
    ys = jnp.asarray(ys, jnp.float32)
    mesh = particle_mesh(jax.devices()[:1])
    key = jax.random.key(5)
    _, infos, means = run(key, make(256), ys)
    out = run_sharded(key, make, 256, ys, mesh=mesh)
    np.testing.assert_allclose(out.means, means, rtol=0, atol=1e-5)
    np.testing.assert_allclose(out.log_likelihoods, infos.log_likelihood, rtol=0, atol=1e-4)
    local = run_sharded(key, make, 256, ys, mesh=mesh, resampling="local")
    assert local.means.shape == means.shape and np.isfinite(local.log_likelihoods).all()


def test_bad_arguments_raise_library_errors() -> None:
    make, _ = _setup()
    mesh = particle_mesh(jax.devices()[:1])
    with pytest.raises(InputError, match="resampling"):
        sharded_filter(make, 8, resampling="nearby", mesh=mesh)
    for bad in (0, 2.5, "8", True):  # 2.5 passed as 2 particles, "8" raised int()'s error
        with pytest.raises(InputError, match="num_particles must be an integer >= 1"):
            sharded_filter(make, bad, mesh=mesh)


@pytest.mark.heavy  # ~10 s: a subprocess with 4 host devices; CI runs it (pytest -m heavy)
def test_four_devices_global_equals_unsharded_and_local_matches_kalman() -> None:
    env = dict(os.environ, XLA_FLAGS="--xla_force_host_platform_device_count=4")
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")])
    args = ["--particles", "1000", "--timesteps", "10", "--reps", "32", "--no-timing"]
    proc = subprocess.run(
        [sys.executable, "-m", "benchmarks._sharded_pf", *args],
        capture_output=True,
        text=True,
        env=env,
        cwd=ROOT,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    assert out["devices"] == 4
    assert out["sharded_pf_max_abs_diff"] <= 1e-6
    # 20 comparisons (10 slices x 2 dims) of a t(31) statistic: 4.5 is ~1e-4 per comparison
    assert out["local_pf_max_z"] <= 4.5
