"""Benchmark ``jorge`` (issue 4): group labelling of strokes on the CAVIAR sequences.

Ground truth: CAVIAR ``ms3ggt`` (Meet_Split_3rdGuy, the sequence of seed 004) and
``mws1gt`` (Meet_WalkSplit). The occlusion gaps and the colours are SIMULATED (seeded):
the ground truth has neither. Rates are means over both sequences and the seeds.

Keys: ``strokes`` (NT, mean per run), ``groups``, ``label_errors`` (mean LE per run),
``error_rate`` (LE / NT, the network, default colour model and the region-size evidence
on the number of people, our addition (``NetworkConfig.size_evidence``), then the final
re-identification pass of :func:`models.jorge.online.reidentify`; object ids matched to
people one to one as IDF1 does), ``error_rate_network_only`` (the same network labels
before the re-identification pass), ``first_mistake_rate`` (and ``_network_only``: the
errors none of whose true predecessor strokes is in error, per stroke; the rest of the
errors are carried along the links), ``error_rate_first_seen_mapping`` (the same labels, each object
standing for the person of the stroke where it was first seen: one early mistake makes
every later stroke of that person an error), ``error_rate_colour_only`` (the baseline
without the network: best colour match among all labels up to the network's maximum
group size), ``error_rate_colour_only_singles`` (the same baseline restricted to single
objects, so it cannot label a group but is not misled by large group palettes),
``error_rate_eq6_as_written`` (the network with the seed's eq. 6 unchanged),
``id_switches``, ``realtime_factor`` (sequence duration at 25 fps
/ labelling time: network building and inference; the simulated low-level tracker is not
timed), ``max_inference_ms`` (slowest periodic inference), ``map_matches_pgmpy`` (same MAP
log probability and marginals to 1e-9 on every window compared), ``speedup_vs_pgmpy_map``
(pgmpy ``map_query`` time / ours on the same windows, after warm-up), and the memory
bound: ``max_active_nodes``, ``max_domain``, ``max_clique_entries`` and, on the longer real
PETS2009 S2.L1 ground truth, the slowest inference in the first and the second half.
"""

from __future__ import annotations

import time

import numpy as np

from benchmarks._common import log
from dbn import pgmpy_adapter
from inference.exact import JunctionTree, map_assignment
from models import datasets
from models.jorge.network import NetworkConfig, node_name
from models.jorge.online import OnlineConfig, colour_only_labels, first_errors, label_online, score
from models.jorge.strokes import build_strokes, load_caviar, load_pets2009

SEQUENCES = ("ms3ggt.xml.gz", "mws1gt.xml.gz")


def _compare_with_pgmpy(windows, max_windows: int, max_joint: float):
    """Our MAP / marginals against pgmpy's on the windows pgmpy can do: pgmpy's own
    elimination order can build tables of the size of the whole joint (a 128 GiB table
    on one window of these sequences), so only windows whose joint over the active
    labels has at most ``max_joint`` configurations are compared."""
    chosen = []
    for win in windows:
        joint = float(np.prod([win.bn.cardinality(node_name(k)) for k in win.active]))
        if joint <= max_joint and len(win.active) >= 3:
            chosen.append(win)
    chosen = chosen[:: max(1, len(chosen) // max_windows)][:max_windows]
    matches = True
    worst_marg = 0.0
    t_ours = t_pgmpy = 0.0
    for win in chosen:
        bn, ev = win.with_colour_nodes()
        names_ev = {n: bn.variable(n).state_names[s] for n, s in ev.items()}
        model = pgmpy_adapter.to_pgmpy(bn)
        ours, lp = map_assignment(bn, ev)
        theirs = pgmpy_adapter.pgmpy_map(model, names_ev)  # warm-up and result
        lp_theirs = bn.log_joint({**{n: bn.variable(n).index(s) for n, s in theirs.items()}, **ev})
        matches &= bool(abs(lp - lp_theirs) <= 1e-9 * max(1.0, abs(lp)))
        nodes = [node_name(k) for k in win.active]
        marg = pgmpy_adapter.pgmpy_marginals(model, nodes, names_ev)
        cal = JunctionTree(bn).calibrate(ev)
        worst_marg = max(worst_marg, max(float(np.max(np.abs(cal.marginals[n] - marg[n]))) for n in nodes))
        best_o = best_p = np.inf
        for _ in range(3):
            t0 = time.perf_counter()
            map_assignment(bn, ev)
            best_o = min(best_o, time.perf_counter() - t0)
            t0 = time.perf_counter()
            pgmpy_adapter.pgmpy_map(model, names_ev)
            best_p = min(best_p, time.perf_counter() - t0)
        t_ours += best_o
        t_pgmpy += best_p
    return {
        "windows_compared": len(chosen),
        "map_matches_pgmpy": bool(matches and worst_marg <= 1e-9 and chosen),
        "max_marginal_diff_vs_pgmpy": worst_marg,
        "speedup_vs_pgmpy_map": t_pgmpy / t_ours if t_ours > 0 else float("nan"),
    }


def run(quick: bool, seed: int) -> dict:
    seeds = [seed + i for i in range(5)]
    cfg = OnlineConfig()
    cfg_eq6 = OnlineConfig(network=NetworkConfig(colour_mode="eq6"))
    truths = {}
    for name in SEQUENCES:
        try:
            truths[name] = load_caviar(datasets.require("caviar", name))
        except FileNotFoundError as exc:
            log(f"jorge: {exc}")
    if not truths:
        log("jorge: no CAVIAR ground truth: nothing measured")
        return {"ok": False, "error": "CAVIAR ground truth absent"}
    rows = []
    windows = []
    ok = True
    for name, truth in truths.items():
        for s in seeds:
            strokes = build_strokes(s, truth)
            res = label_online(strokes, cfg, keep_windows=(s == seeds[0]))
            if s == seeds[0]:
                windows += res.labeller.windows
            sc = score(strokes, res.labels)
            eq6 = score(strokes, label_online(strokes, cfg_eq6).labels)
            col = score(strokes, colour_only_labels(strokes, cfg.network.labels.max_group_size,
                                                    cfg.network.match_prob, cfg.network.pool_size))
            col1 = score(strokes, colour_only_labels(strokes, 1, cfg.network.match_prob,
                                                     cfg.network.pool_size))
            strict = score(strokes, res.labels, mapping="first_seen")
            g = res.labeller.graph
            ok &= all(res.network_labels[k] in g.nodes[k].domain or res.network_labels[k] == g.nodes[k].frozen
                      for k in range(len(strokes)))
            net_only = score(strokes, res.network_labels)
            ok &= bool(np.isfinite([r.log_prob for r in res.records]).all())
            rows.append({
                "seq": name, "seed": s, "strokes": len(strokes), "groups": strokes.num_groups,
                "le": sc.label_errors, "rate": sc.error_rate, "rate_colour": col.error_rate,
                "rate_net": net_only.error_rate,
                "rate_first": len(first_errors(strokes, sc.errors)) / len(strokes),
                "rate_first_net": len(first_errors(strokes, net_only.errors)) / len(strokes),
                "rate_eq6": eq6.error_rate, "rate_colour1": col1.error_rate,
                "rate_strict": strict.error_rate, "idsw": sc.id_switches, "duration": strokes.duration_s,
                "seconds": res.seconds, "max_inf": max(r.seconds for r in res.records),
                "max_active": max(r.num_active for r in res.records),
                "max_domain": max(r.max_domain for r in res.records),
                "max_clique": max(r.max_clique_entries for r in res.records),
            })
            log(f"jorge: {name} seed {s}: NT {len(strokes)} LE {sc.label_errors} "
                f"rate {sc.error_rate:.3f} (network only {net_only.error_rate:.3f}) colour-only {col.error_rate:.3f} eq6 {eq6.error_rate:.3f} "
                f"labelling {res.seconds:.2f}s for {strokes.duration_s:.1f}s")
    cmp = _compare_with_pgmpy(windows, max_windows=4 if quick else 20,
                              max_joint=1e5 if quick else 2e6)
    ok &= cmp["map_matches_pgmpy"]

    # the bound on a longer real sequence: PETS2009 S2.L1 (19 people, 795 frames)
    bound = {}
    try:
        pets = load_pets2009(datasets.require("pets2009", "PETS2009-S2L1.xml.gz"))
        strokes = build_strokes(seed, pets)
        res = label_online(strokes, cfg)
        half = len(res.records) // 2
        bound = {
            "pets2009_strokes": len(strokes),
            "pets2009_realtime_factor": strokes.duration_s / res.seconds,
            "pets2009_max_inference_ms_first_half": 1e3 * max(r.seconds for r in res.records[:half]),
            "pets2009_max_inference_ms_second_half": 1e3 * max(r.seconds for r in res.records[half:]),
            "pets2009_max_clique_entries": max(r.max_clique_entries for r in res.records),
            "pets2009_error_rate": score(strokes, res.labels).error_rate,
        }
    except FileNotFoundError as exc:
        log(f"jorge: {exc}")

    def mean(key):
        return float(np.mean([r[key] for r in rows]))

    return {
        "strokes": mean("strokes"),
        "groups": mean("groups"),
        "label_errors": mean("le"),
        "error_rate": mean("rate"),
        "error_rate_network_only": mean("rate_net"),
        "first_mistake_rate": mean("rate_first"),
        "first_mistake_rate_network_only": mean("rate_first_net"),
        "error_rate_colour_only": mean("rate_colour"),
        "error_rate_eq6_as_written": mean("rate_eq6"),
        "error_rate_colour_only_singles": mean("rate_colour1"),
        "error_rate_first_seen_mapping": mean("rate_strict"),
        "id_switches": mean("idsw"),
        "realtime_factor": float(sum(r["duration"] for r in rows) / sum(r["seconds"] for r in rows)),
        "max_inference_ms": 1e3 * max(r["max_inf"] for r in rows),
        **cmp,
        "max_active_nodes": max(r["max_active"] for r in rows),
        "max_domain": max(r["max_domain"] for r in rows),
        "max_clique_entries": max(r["max_clique"] for r in rows),
        **bound,
        "per_sequence": {
            name: {"strokes": float(np.mean([r["strokes"] for r in rows if r["seq"] == name])),
                   "error_rate": float(np.mean([r["rate"] for r in rows if r["seq"] == name]))}
            for name in truths
        },
        "seeds": seeds,
        "simulated": "occlusion gaps and colours (the ground truth has neither)",
        "ok": bool(ok),
    }
