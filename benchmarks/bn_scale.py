"""``bn_scale``: every marginal of pgmpy's bundled networks, first call included.

Per network (read offline by :func:`dbn.pgmpy_adapter.bundled_network`): three evidence
nodes drawn at random, their values taken from an ancestral sample (so the evidence has
positive probability; seeded). The task is every unobserved node's posterior marginal.

- ``ours_first_ms``: a fresh :class:`~inference.exact.engine.ExactInference` on the net,
  one ``marginals(evidence)`` call: pruning, triangulation, compile and run, nothing
  cached (what a user moving from pgmpy sees on the first query).
- ``ours_repeat_ms``: median of ``marginals`` with new values for the same evidence
  nodes (the compiled tree reused).
- ``pgmpy_ms``: pgmpy's ``VariableElimination`` built once, then ``query([node],
  evidence)`` per unobserved node (as a user would call it; pgmpy prunes per query).
  The queries go in a random order, a few per ``VariableElimination``; where all of them
  would take longer than a budget (2 s per network in ``--quick``, 60 s in the full
  run) pgmpy stops there, ``pgmpy_ms`` is the random sample's time scaled to all queries
  (``pgmpy_queries`` of ``queries`` answered, ``pgmpy_extrapolated``), and
  ``max_abs_diff`` is over the queries pgmpy answered.

Summary keys: ``networks``, ``min_speedup_first_call`` (min of pgmpy_ms /
ours_first_ms), ``geomean_speedup_repeat``, ``max_abs_diff``, ``ok`` (all diffs <= 1e-9).
"""

from __future__ import annotations

import math
import time

import numpy as np

from benchmarks._common import log, median_time
from dbn import pgmpy_adapter as pa
from dbn.bayesnet import BayesNet
from dbn.errors import MemoryLimitError
from inference.exact.engine import ExactInference

QUICK = ("alarm", "hepar2", "water", "mildew", "pathfinder", "munin1", "pigs", "link")
QUICK_PGMPY_BUDGET_S = 2.0  # --quick: pgmpy's time per network before it extrapolates
FULL_PGMPY_BUDGET_S = 60.0  # full run: the same, per network
PGMPY_CHUNK = 4  # queries per VariableElimination (building one costs ~1 ms)


def sampled_evidence(bn: BayesNet, rng: np.random.Generator, nodes: list[str]) -> dict[str, str]:
    """Values for ``nodes`` from one ancestral sample of ``bn`` (positive probability)."""
    x = bn.sample(rng, 1)
    return {n: bn.variable(n).state_names[int(x[n][0])] for n in nodes}


def _pgmpy(
    model, hidden: list[str], ev: dict[str, str], rng: np.random.Generator, budget_s: float
) -> tuple[dict, float, int]:
    """pgmpy's marginals of ``hidden`` in a random order, in chunks, until all are answered
    or ``budget_s`` is spent; seconds scaled to all of them (an unbiased sample)."""
    order = [hidden[i] for i in rng.permutation(len(hidden))]
    answers: dict = {}
    elapsed = 0.0
    for k in range(0, len(order), PGMPY_CHUNK):
        t0 = time.perf_counter()
        answers.update(pa.pgmpy_marginals(model, order[k : k + PGMPY_CHUNK], ev))
        elapsed += time.perf_counter() - t0
        if elapsed > budget_s:
            break
    return answers, elapsed * len(hidden) / len(answers), len(answers)


def one_network(name: str, rng: np.random.Generator, quick: bool) -> dict:
    bn = pa.bundled_network(name)
    model = pa.to_pgmpy(bn)
    observed = [str(n) for n in rng.choice(list(bn.nodes), size=3, replace=False)]
    ev = sampled_evidence(bn, rng, observed)
    hidden = [n for n in bn.nodes if n not in ev]
    t0 = time.perf_counter()
    engine = ExactInference(bn)
    ours = engine.marginals(ev)
    first_s = time.perf_counter() - t0
    others = [sampled_evidence(bn, rng, observed) for _ in range(3)]
    it = iter(others * 3)
    repeat_s = median_time(lambda: engine.marginals(next(it)), repeat=len(others))
    budget = QUICK_PGMPY_BUDGET_S if quick else FULL_PGMPY_BUDGET_S
    theirs, pgmpy_s, asked = _pgmpy(model, hidden, ev, rng, budget)
    diff = max(float(np.max(np.abs(ours.marginals[n] - theirs[n]))) for n in theirs)
    return {
        "network": name,
        "nodes": len(bn),
        "evidence": ev,
        "engine": ours.engine,
        "largest_clique_entries": ours.max_table_size,
        "total_table_entries": ours.total_table_size,
        "ours_first_ms": 1e3 * first_s,
        "ours_repeat_ms": 1e3 * repeat_s,
        "pgmpy_ms": 1e3 * pgmpy_s,
        "queries": len(hidden),
        "pgmpy_queries": asked,
        "pgmpy_extrapolated": asked < len(hidden),
        "speedup_first_call": pgmpy_s / first_s,
        "speedup_repeat": pgmpy_s / repeat_s,
        "max_abs_diff": diff,
    }


def run(quick: bool, seed: int) -> dict:
    rng = np.random.default_rng(seed)
    names = QUICK if quick else pa.bundled_networks()
    rows, skipped = [], {}
    for name in names:
        try:
            row = one_network(name, rng, quick)
        except MemoryLimitError as err:  # a net too large for exact inference here
            skipped[name] = str(err)
            log(f"{name:11s} skipped: {err}")
            continue
        rows.append(row)
        log(
            f"{name:11s} {row['nodes']:5d} nodes {row['engine']:2s} clique "
            f"{row['largest_clique_entries']:9d}: first {row['ours_first_ms']:8.1f} ms, repeat "
            f"{row['ours_repeat_ms']:7.1f} ms, pgmpy {row['pgmpy_ms']:9.1f} ms "
            f"({row['pgmpy_queries']}/{row['queries']} q) first x{row['speedup_first_call']:.1f} "
            f"repeat x{row['speedup_repeat']:.1f} diff {row['max_abs_diff']:.1e}"
        )
    max_diff = max(r["max_abs_diff"] for r in rows)
    return {
        "networks": len(rows),
        "min_speedup_first_call": min(r["speedup_first_call"] for r in rows),
        "geomean_speedup_repeat": math.exp(
            float(np.mean([math.log(r["speedup_repeat"]) for r in rows]))
        ),
        "max_abs_diff": max_diff,
        "skipped": skipped,
        "rows": rows,
        "ok": bool(max_diff <= 1e-9),
    }
