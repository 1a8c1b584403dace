"""Sharded particle filter measurements, run in a process of its own.

``XLA_FLAGS=--xla_force_host_platform_device_count=4 python -m benchmarks._sharded_pf``
prints one JSON line: the largest difference between the globally-resampled sharded
filter and the unsharded one (same key), the largest z-score of the island (local
resampling) filter's mean against the Kalman filter over independent keys, and the time
per particle-step of the sharded run. The device count must be forced before jax starts,
hence the separate process (the ``scale_out`` benchmark and the tests spawn it).
"""

from __future__ import annotations

import argparse
import functools
import json

import jax
import jax.numpy as jnp
import numpy as np

from benchmarks._common import best_time
from inference.kalman import LinearGaussianParams, kalman_filter, lgssm_sample
from inference.particle.filters import bootstrap_filter, run
from inference.particle.linear_gaussian import LinearGaussianSSM
from inference.particle.sharding import sharded_filter


def _params() -> LinearGaussianParams:
    return LinearGaussianParams(
        F=np.array([[1.0, 0.5], [0.0, 0.8]]),
        Q=np.array([[0.2, 0.05], [0.05, 0.3]]),
        H=np.array([[1.0, 0.0]]),
        R=np.array([[0.4]]),
        m0=np.array([0.5, -0.3]),
        P0=np.array([[1.0, 0.2], [0.2, 0.5]]),
    )


def measure(num_particles: int, num_timesteps: int, reps: int, timing: bool = True) -> dict:
    """The figures of the module docstring (float64 throughout)."""
    params = _params()
    _, ys = lgssm_sample(7, params, num_timesteps)
    ys = jnp.asarray(ys)
    kf = kalman_filter(params, np.asarray(ys))
    make = functools.partial(bootstrap_filter, LinearGaussianSSM(params), dtype=jnp.float64)
    key = jax.random.key(0)
    plain = jax.jit(lambda k, o: run(k, make(num_particles), o))
    _, infos, means = plain(key, ys)
    glob = sharded_filter(make, num_particles)
    g = glob(key, ys)
    diff = max(
        float(jnp.abs(g.means - means).max()),
        float(jnp.abs(g.log_likelihoods - infos.log_likelihood).max()),
    )
    per = num_particles * num_timesteps / 1e9
    ns_sharded = ns_plain = None
    if timing:
        ns_sharded = best_time(lambda: jax.block_until_ready(glob(key, ys).means), 3) / per
        ns_plain = best_time(lambda: jax.block_until_ready(plain(key, ys)[2]), 3) / per
    local_run = sharded_filter(make, num_particles, resampling="local")
    local = np.stack(
        [np.asarray(local_run(k, ys).means) for k in jax.random.split(jax.random.key(2), reps)]
    )
    se = local.std(axis=0, ddof=1) / np.sqrt(reps)
    z = np.abs(local.mean(axis=0) - kf.filtered_means) / se
    return {
        "devices": jax.device_count(),
        "sharded_pf_max_abs_diff": diff,
        "sharded_pf_ns_per_particle_step": ns_sharded,
        "unsharded_pf_ns_per_particle_step": ns_plain,
        "local_pf_max_z": float(z.max()),
    }


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--particles", type=int, default=40_000)
    parser.add_argument("--timesteps", type=int, default=50)
    parser.add_argument("--reps", type=int, default=16)
    parser.add_argument("--no-timing", action="store_true", help="skip the timings (tests)")
    args = parser.parse_args()
    with jax.enable_x64(True):
        out = measure(args.particles, args.timesteps, args.reps, not args.no_timing)
    print(json.dumps(out))


if __name__ == "__main__":
    main()
