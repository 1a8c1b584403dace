"""``dbn_scale``: the generic DBN engines on the coupled-chains family, scaled up.

Model: :func:`dbn.examples.coupled_chains` (``n`` binary chains, chain ``i`` depends on
chains ``i`` and ``i - 1`` at ``t - 1``: keeps its state w.p. 0.9 unless its left neighbour
is on, which flips it w.p. 0.3; one observation per chain, noise 0.2), data simulated by
:func:`dbn.examples.sample_coupled_chains`.

Exact keys (this module): ours is :class:`~inference.exact.structured_filter.StructuredFilter`
(compiled once; ``compile_s`` is the construction + plan compilation at n = 12), against

- the plain numpy forward pass that multiplies in one CPD at a time
  (:func:`benchmarks._chains_numpy.numpy_factored_filter`), on the same evidence:
  ``numpy_factored_us_per_slice_n12``, ``exact_vs_numpy_factored_n12`` (ours / numpy),
  ``exact_max_abs_diff_n12`` (marginals and per-slice log normalisers);
- pgmpy's ``DBNInference.forward_inference`` on the converted model, last-slice
  marginals of every chain given the first ``T_pgmpy`` slices (pgmpy is slow, so a few
  slices; its per-slice time is its total over ``T_pgmpy``): ``speedup_vs_pgmpy_n6``.
  At n = 6 the interface has 64 states, so our filter runs its small-interface mode (one
  64 x 64 transition matrix, one likelihood per evidence row);
  ``speedup_vs_pgmpy_n6_plan_only`` is the same with the per-slice elimination plan
  forced (``dense_limit=0``), as at n = 8 and 12.

Approximate keys (Boyen-Koller, particle, RBPF) come from
:mod:`benchmarks._dbn_scale_approx` when it is there (``approx_missing`` says why not).
"""

from __future__ import annotations

import time

import numpy as np

from benchmarks._chains_numpy import numpy_factored_filter
from benchmarks._common import best_time, log
from dbn import pgmpy_adapter as pa
from dbn.examples import coupled_chains, sample_coupled_chains
from inference.exact.structured_filter import StructuredFilter

APPROX_KEYS = (
    "bk_mean_kl_n12",
    "bk_kl_late_over_early",
    "bk_us_per_slice_n16",
    "bk_us_per_slice_n64",
    "bk_time_ratio_n64_vs_n16",
    "pf_mean_kl_n12",
    "rbpf_rmse",
    "pf_rmse_same_n",
    "rbpf_max_z",
)


def _evidence(ys: np.ndarray) -> dict[str, np.ndarray]:
    return {f"y{i}": ys[:, i] for i in range(ys.shape[1])}


def _exact(n: int, T: int, seed: int, repeat: int, **kw) -> dict:
    """Our structured filter at ``n`` chains (``kw``: its options): time per slice."""
    _, ys = sample_coupled_chains(np.random.default_rng(seed), n, T)
    ev = _evidence(ys)
    t0 = time.perf_counter()
    flt = StructuredFilter(coupled_chains(n), **kw)
    flt.predicted_size(list(ev))
    compile_s = time.perf_counter() - t0
    res = flt.filter(ev)  # warm-up
    ours = best_time(lambda: flt.filter(ev), repeat=repeat)
    out = {"ours_us": 1e6 * ours / T, "compile_s": compile_s, "result": res, "ys": ys}
    return out


def _numpy_factored(ys: np.ndarray, res, repeat: int) -> tuple[float, float]:
    """(numpy us per slice, largest |ours - numpy| over marginals and log normalisers)."""
    T, n = ys.shape
    theirs = best_time(lambda: numpy_factored_filter(ys), repeat=repeat)
    marg, logz = numpy_factored_filter(ys)
    diff = max(float(np.max(np.abs(res.marginals[f"x{i}"] - marg[:, i]))) for i in range(n))
    diff = max(diff, float(np.max(np.abs(res.log_normalizers - logz))))
    return 1e6 * theirs / T, diff


def _pgmpy(n: int, T: int, seed: int) -> tuple[float, float]:
    """(pgmpy us per slice over T slices, largest |ours - pgmpy| at the last slice)."""
    _, ys = sample_coupled_chains(np.random.default_rng(seed), n, T)
    dbn = coupled_chains(n)
    model = pa.dbn_to_pgmpy(dbn)
    evidence = {(f"y{i}", t): str(int(ys[t, i])) for i in range(n) for t in range(T)}
    query = [(f"x{i}", T - 1) for i in range(n)]
    t0 = time.perf_counter()
    theirs = pa.pgmpy_dbn_forward(model, query, evidence)
    seconds = time.perf_counter() - t0
    ours = StructuredFilter(dbn).filter(_evidence(ys))
    diff = max(float(np.max(np.abs(ours.marginals[q][-1] - theirs[(q, T - 1)]))) for q, _ in query)
    return 1e6 * seconds / T, diff


def _approx(quick: bool, seed: int) -> dict:
    try:
        from benchmarks._dbn_scale_approx import approx_keys
    except ImportError as exc:
        return {k: None for k in APPROX_KEYS} | {"approx_missing": f"{type(exc).__name__}: {exc}"}
    return dict(approx_keys(quick=quick, seed=seed))


def run(quick: bool, seed: int) -> dict:
    T = 200 if quick else 1000
    repeat = 3 if quick else 5
    n8 = _exact(8, T, seed, repeat)
    log(f"n=8: ours {n8['ours_us']:.1f} us/slice")
    n12 = _exact(12, T, seed + 1, repeat)
    numpy_us, diff = _numpy_factored(n12["ys"], n12["result"], repeat)
    log(f"n=12: ours {n12['ours_us']:.1f} us/slice, numpy factored {numpy_us:.1f}, diff {diff:.1e}")
    n6 = _exact(6, T, seed + 2, repeat)
    n6_plan = _exact(6, T, seed + 2, repeat, dense_limit=0)
    T_pgmpy = 8 if quick else 20
    pgmpy_us, pgmpy_diff = _pgmpy(6, T_pgmpy, seed + 3)
    log(f"n=6: ours {n6['ours_us']:.1f} us/slice, pgmpy {pgmpy_us:.0f} us/slice (T={T_pgmpy})")
    out = {
        "exact_us_per_slice_n8": n8["ours_us"],
        "exact_us_per_slice_n12": n12["ours_us"],
        "numpy_factored_us_per_slice_n12": numpy_us,
        "exact_vs_numpy_factored_n12": n12["ours_us"] / numpy_us,
        "exact_max_abs_diff_n12": diff,
        "exact_us_per_slice_n6": n6["ours_us"],
        "pgmpy_us_per_slice_n6": pgmpy_us,
        "pgmpy_slices_n6": T_pgmpy,
        "pgmpy_max_abs_diff_n6": pgmpy_diff,
        "speedup_vs_pgmpy_n6": pgmpy_us / n6["ours_us"],
        "exact_plan_only_us_per_slice_n6": n6_plan["ours_us"],
        "speedup_vs_pgmpy_n6_plan_only": pgmpy_us / n6_plan["ours_us"],
        "compile_s": n12["compile_s"],
        "num_timesteps": T,
    }
    out.update(_approx(quick, seed))
    out["ok"] = bool(diff <= 1e-9 and pgmpy_diff <= 1e-9)
    return out
