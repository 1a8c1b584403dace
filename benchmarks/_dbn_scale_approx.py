"""The approximate half of the ``dbn_scale`` benchmark: Boyen-Koller, particle filtering
and the Rao-Blackwellised particle filter on declared DBNs.

:func:`approx_keys` returns the keys (``benchmarks/dbn_scale.py`` merges them):

- ``bk_mean_kl_n12``: mean over slices and chains of KL(exact chain marginal || BK's),
  12 coupled chains (:func:`dbn.examples.coupled_chains`, one BK cluster per chain),
  simulated sequences, exact marginals from :func:`benchmarks._chains_numpy.numpy_factored_filter`;
- ``bk_kl_late_over_early``: mean KL over the last 20 slices / over slices 10-30 (pooled
  over the sequences): > 1 would mean the error accumulates;
- ``bk_us_per_slice_n16``, ``bk_us_per_slice_n64``, ``bk_time_ratio_n64_vs_n16``: the on-line
  ``step`` loop (compiled filter reused), microseconds per slice;
- ``pf_mean_kl_n12``: the same KL for the bootstrap particle filter on the declaration
  (10,000 particles; its marginals floored at ``1 / (2 N)``, the resolution of N particles,
  so that a state no particle holds gives a finite KL);
- ``rbpf_rmse``, ``pf_rmse_same_n``: RMSE of the filtered mean of ``x`` against the
  simulated state, switching LDS (:func:`dbn.examples.switching_lds`), RBPF and bootstrap
  PF with the same number of particles, pooled over several simulated sequences;
- ``rbpf_max_z``: largest |RBPF filtered mean - exact| in Monte-Carlo standard errors
  (spread of independent runs), over a short horizon where the exact filter enumerates
  every switch path (a Kalman filter per path, :func:`slds_exact_means`).
"""

from __future__ import annotations

import time

import jax
import numpy as np

from benchmarks._chains_numpy import numpy_factored_filter
from benchmarks._common import log
from dbn.examples import coupled_chains, sample_coupled_chains, sample_switching_lds, switching_lds
from inference.adf.boyen_koller import BoyenKoller, bk_filter
from inference.particle.dbn_adapter import particle_filter_dbn
from inference.particle.rbpf import rbpf_filter_dbn

__all__ = ["approx_keys", "slds_exact_means", "chain_kl"]


def chain_kl(exact: np.ndarray, approx: np.ndarray) -> np.ndarray:
    """KL(exact || approx) per slice and chain; inputs (T, n, K), output (T, n)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        terms = np.where(exact > 0, exact * np.log(exact / approx), 0.0)
    return terms.sum(axis=-1)


def _chains_data(rng: np.random.Generator, n: int, T: int):
    _, ys = sample_coupled_chains(rng, n, T)
    return ys, {f"y{i}": ys[:, i] for i in range(n)}


def _bk_accuracy(rng: np.random.Generator, num_seq: int, T: int) -> tuple[float, float]:
    n = 12
    dbn = coupled_chains(n)
    kls = []
    for _ in range(num_seq):
        ys, ev = _chains_data(rng, n, T)
        exact, _ = numpy_factored_filter(ys)
        out = bk_filter(dbn, ev)
        approx = np.stack([out.marginals[f"x{i}"] for i in range(n)], axis=1)
        kls.append(chain_kl(exact, approx))
    kl = np.array(kls)  # (num_seq, T, n)
    return float(kl.mean()), float(kl[:, -20:].mean() / kl[:, 10:30].mean())


def _bk_us_per_slice(rng: np.random.Generator, n: int, T: int, repeat: int) -> float:
    bk = BoyenKoller(coupled_chains(n))
    _, ev = _chains_data(rng, n, T)
    slices = [{k: int(c[t]) for k, c in ev.items()} for t in range(T)]

    def loop():
        state = bk.init(slices[0])
        for e in slices[1:]:
            state = bk.step(state, e)

    loop()  # warm-up
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        loop()
        best = min(best, time.perf_counter() - t0)
    return best / T * 1e6


def _pf_kl(rng: np.random.Generator, seed: int, T: int, N: int) -> float:
    n = 12
    ys, ev = _chains_data(rng, n, T)
    exact, _ = numpy_factored_filter(ys)
    out = particle_filter_dbn(jax.random.key(seed), coupled_chains(n), ev, num_particles=N)
    approx = np.stack([out.marginals[f"x{i}"] for i in range(n)], axis=1)
    approx = np.maximum(approx, 0.5 / N)
    approx /= approx.sum(axis=-1, keepdims=True)
    return float(chain_kl(exact, approx).mean())


def slds_exact_means(
    ys: np.ndarray, stay: float = 0.95, q: tuple[float, float] = (0.01, 1.0), r: float = 0.5
) -> np.ndarray:
    """Exact filtered means (T, 2) of :func:`dbn.examples.switching_lds` by enumerating
    every switch path (a Kalman filter per path, mixed by the paths' posterior weights).
    Cost 2**T: short horizons only."""
    A = np.array([[1.0, 1.0], [0.0, 0.9]])
    H = np.array([[1.0, 0.0]])
    T = ys.shape[0]
    # prefix -> (log weight, mean, cov); extended one slice at a time
    paths = {(): (0.0, None, None)}
    out = np.empty((T, 2))
    for t in range(T):
        new = {}
        for prefix, (lw, m, P) in paths.items():
            for s in (0, 1):
                if t == 0:
                    lp, m1, P1 = np.log(0.5), np.zeros(2), np.eye(2)
                else:
                    lp = np.log(stay if s == prefix[-1] else 1 - stay)
                    m1, P1 = A @ m, A @ P @ A.T + np.diag([0.01, q[s]])
                S = H @ P1 @ H.T + r
                K = P1 @ H.T / S
                resid = ys[t] - H @ m1
                ll = -0.5 * (resid @ resid / S[0, 0] + np.log(2 * np.pi * S[0, 0]))
                m2 = m1 + (K @ resid)
                P2 = P1 - K @ H @ P1
                new[(*prefix, s)] = (lw + lp + float(ll), m2, 0.5 * (P2 + P2.T))
        paths = new
        lws = np.array([v[0] for v in paths.values()])
        w = np.exp(lws - lws.max())
        w /= w.sum()
        out[t] = sum(wi * v[1] for wi, v in zip(w, paths.values()))
    return out


def _rbpf_vs_pf(rng: np.random.Generator, seed: int, num_seq: int, T: int, N: int):
    dbn = switching_lds()
    se_rb, se_pf = [], []
    for k in range(num_seq):
        _, xs, ys = sample_switching_lds(rng, T)
        key = jax.random.key(seed * 1000 + k)
        rb = rbpf_filter_dbn(key, dbn, {"y": ys}, num_particles=N)
        pf = particle_filter_dbn(key, dbn, {"y": ys}, num_particles=N)
        se_rb.append((rb.means["x"] - xs) ** 2)
        se_pf.append((pf.means["x"] - xs) ** 2)
    return float(np.sqrt(np.mean(se_rb))), float(np.sqrt(np.mean(se_pf)))


def _rbpf_max_z(rng: np.random.Generator, seed: int, T: int, runs: int, N: int) -> float:
    dbn = switching_lds()
    _, _, ys = sample_switching_lds(rng, T)
    exact = slds_exact_means(ys)
    est = np.array(
        [
            rbpf_filter_dbn(jax.random.key(seed * 1000 + r), dbn, {"y": ys}, num_particles=N).means[
                "x"
            ]
            for r in range(runs)
        ]
    )
    se = est.std(axis=0, ddof=1) / np.sqrt(runs)
    return float(np.max(np.abs(est.mean(axis=0) - exact) / np.maximum(se, 1e-12)))


def approx_keys(quick: bool, seed: int) -> dict:
    """The approximate-inference keys of ``dbn_scale`` (see the module docstring)."""
    rng = np.random.default_rng(seed)
    out: dict = {}
    t0 = time.perf_counter()
    mean_kl, ratio = _bk_accuracy(rng, num_seq=3 if quick else 10, T=200)
    out["bk_mean_kl_n12"], out["bk_kl_late_over_early"] = mean_kl, ratio
    log(f"bk accuracy n=12: {time.perf_counter() - t0:.1f}s")
    T_time = 40 if quick else 200
    us16 = _bk_us_per_slice(rng, 16, T_time, repeat=5)
    us64 = _bk_us_per_slice(rng, 64, T_time, repeat=5)
    out["bk_us_per_slice_n16"], out["bk_us_per_slice_n64"] = us16, us64
    out["bk_time_ratio_n64_vs_n16"] = us64 / us16
    log(f"bk timing: {time.perf_counter() - t0:.1f}s")
    out["pf_mean_kl_n12"] = _pf_kl(rng, seed, T=50 if quick else 200, N=10_000)
    log(f"pf n=12: {time.perf_counter() - t0:.1f}s")
    rb, pf = _rbpf_vs_pf(rng, seed, num_seq=3 if quick else 10, T=50 if quick else 200, N=100)
    out["rbpf_rmse"], out["pf_rmse_same_n"] = rb, pf
    out["rbpf_num_particles"] = 100
    log(f"rbpf vs pf: {time.perf_counter() - t0:.1f}s")
    out["rbpf_max_z"] = _rbpf_max_z(rng, seed, T=8, runs=20, N=500 if quick else 2000)
    log(f"rbpf vs enumeration: {time.perf_counter() - t0:.1f}s")
    return out


if __name__ == "__main__":  # a look: python -m benchmarks._dbn_scale_approx [--full]
    import json
    import sys

    print(json.dumps(approx_keys("--full" not in sys.argv, 0)))
