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
  On networks where that would be slow, pgmpy answers an evenly spaced sample of the
  queries (``pgmpy_queries`` of ``queries``) and ``pgmpy_ms`` is the sample's time scaled
  to all queries (``pgmpy_extrapolated``); ``max_abs_diff`` is over the queries pgmpy
  answered.

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
QUICK_PGMPY_QUERIES = 24  # pgmpy answers at most this many queries per network in --quick
FULL_PGMPY_BUDGET_S = 300.0  # full run: pgmpy queries until this much time, then scales


def sampled_evidence(bn: BayesNet, rng: np.random.Generator, nodes: list[str]) -> dict[str, str]:
    """Values for ``nodes`` from one ancestral sample of ``bn`` (positive probability)."""
    x = bn.sample(rng, 1)
    return {n: bn.variable(n).state_names[int(x[n][0])] for n in nodes}


def _pgmpy(model, hidden: list[str], ev: dict[str, str], quick: bool) -> tuple[dict, float, int]:
    """pgmpy's marginals of (a sample of) ``hidden``; seconds scaled to all of them."""
    if quick and len(hidden) > QUICK_PGMPY_QUERIES:
        idx = np.linspace(0, len(hidden) - 1, QUICK_PGMPY_QUERIES).round().astype(int)
        asked = [hidden[i] for i in dict.fromkeys(idx.tolist())]
    else:
        asked = list(hidden)
    answers: dict = {}
    t0 = time.perf_counter()
    if quick:
        answers = pa.pgmpy_marginals(model, asked, ev)
    else:
        for n in asked:  # one at a time, stopping at the budget
            answers.update(pa.pgmpy_marginals(model, [n], ev))
            if time.perf_counter() - t0 > FULL_PGMPY_BUDGET_S:
                break
    elapsed = time.perf_counter() - t0
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
    theirs, pgmpy_s, asked = _pgmpy(model, hidden, ev, quick)
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
