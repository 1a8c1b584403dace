"""``bn_exact``: every single-node marginal of a Bayes net, our junction tree against
pgmpy's ``VariableElimination`` queried node by node.

The networks are pgmpy's bundled alarm, child and insurance (read offline), each under a
fixed random evidence set of positive probability (3 observed nodes; seeded). Ours: one
:meth:`JunctionTree.calibrate` after the tree for that observed set is compiled (the
compile time is reported as ``compile_s``); pgmpy: one ``query`` per unobserved node, on
the same model (converted by the adapter), after a warm-up pass. Keys:
``speedup_vs_pgmpy`` (smallest over networks), ``max_abs_diff``, ``networks``.
"""

from __future__ import annotations

import time

import numpy as np

from benchmarks._common import best_time, log
from dbn import pgmpy_adapter as pa
from dbn.bayesnet import BayesNet
from inference.exact import JunctionTree, log_evidence


def random_evidence(bn: BayesNet, rng: np.random.Generator, size: int = 3) -> dict[str, str]:
    """A random evidence set of ``size`` nodes with positive probability."""
    for _ in range(100):
        nodes = rng.choice(list(bn.nodes), size=size, replace=False)
        ev = {
            str(n): bn.variable(str(n)).state_names[int(rng.integers(bn.cardinality(str(n))))]
            for n in nodes
        }
        if np.isfinite(log_evidence(bn, ev)):
            return ev
    raise RuntimeError("no evidence set of positive probability found")


def run(quick: bool, seed: int) -> dict:
    rng = np.random.default_rng(seed)
    names = ["alarm", "child", "insurance"]
    if not quick:
        names += ["asia", "cancer", "earthquake", "sachs", "survey"]
    rows = []
    for name in names:
        bn = pa.bundled_network(name)
        model = pa.to_pgmpy(bn)
        ev = random_evidence(bn, rng)
        hidden = [n for n in bn.nodes if n not in ev]
        t0 = time.perf_counter()
        jt = JunctionTree(bn)
        cal = jt.calibrate(ev)
        compile_s = time.perf_counter() - t0
        ours_s = best_time(lambda jt=jt, ev=ev: jt.calibrate(ev), repeat=20)
        pa.pgmpy_marginals(model, hidden, ev)  # warm-up
        pgmpy_s = best_time(
            lambda m=model, h=hidden, ev=ev: pa.pgmpy_marginals(m, h, ev), repeat=3 if quick else 5
        )
        theirs = pa.pgmpy_marginals(model, hidden, ev)
        diff = max(float(np.max(np.abs(cal.marginals[n] - theirs[n]))) for n in hidden)
        sums = max(abs(float(cal.marginals[n].sum()) - 1.0) for n in bn.nodes)
        rows.append(
            {
                "network": name,
                "nodes": len(bn),
                "evidence": ev,
                "ours_ms": 1e3 * ours_s,
                "pgmpy_ms": 1e3 * pgmpy_s,
                "speedup": pgmpy_s / ours_s,
                "abs_diff": diff,
                "max_sum_err": sums,
                "compile_s": compile_s,
                "max_clique_size": jt.max_clique_size,
            }
        )
        log(
            f"{name:10s} {len(bn):3d} nodes: ours {1e3 * ours_s:7.3f} ms, pgmpy {1e3 * pgmpy_s:8.2f} ms, "
            f"x{pgmpy_s / ours_s:6.1f}, diff {diff:.1e}"
        )
    max_diff = max(r["abs_diff"] for r in rows)
    return {
        "speedup_vs_pgmpy": min(r["speedup"] for r in rows),
        "max_abs_diff": max_diff,
        "networks": names,
        "compile_s": sum(r["compile_s"] for r in rows),
        "rows": rows,
        "ok": bool(max_diff <= 1e-9 and max(r["max_sum_err"] for r in rows) <= 1e-9),
    }
