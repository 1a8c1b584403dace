"""Benchmark ``rjmcmc3d``: the seed 003 multi-camera RJ-MCMC 3-D tracker on SIMULATED data.

Scene: the default partial-overlap hall (3 cameras, most of the floor seen by one
camera; rendered foreground maps, colour images and a noisy per-view detector), about 6
people at a time walking in and out (Langevin walkers, seed 003 eq. 7). The tracker runs
1,500 RJ-MCMC moves per frame with 500 burn-in (as in the seed) in both modes.

Reported:
- ``mota``, ``idf1``, ``id_switches``: py-motmetrics on ground-plane positions, 0.5 m;
- ``mota_without_ground_noise`` (and idf1/switches): the same data tracked with
  ``C(u) = 0`` in eq. 7 (the ablation of seed fig. 6; the update kernel then uses a fixed
  isotropic covariance);
- ``ms_per_frame``: mean wall time of one tracker step (``cpu_ms_per_frame``: process
  CPU time, less sensitive to other processes on a shared machine), after two untimed
  warm-up frames (``warmup_s``: the numba compile of the per-move loops on a machine's
  first run, a cache load afterwards);
- ``speedup_vs_full_likelihood``: the same chain (same seed, same moves) with the
  likelihood of eqs. 8-10 recomputed from scratch at every move, time ratio (best of 3
  interleaved runs of each, to damp the noise of other processes); ``ok``
  requires the two chains to end in the same state and the incremental likelihood to
  equal the full recompute.

``--quick``: one seed, 25 frames, the same 6 people and the same 1,500 moves per frame;
the speed-up is measured over 300 moves of one frame (and over 100 moves at 768 x 576,
the same cameras at PAL-like resolution, where a full recompute touches 4 times more
pixels). Full: 3 seeds x 300 frames, speed-up over 1,500 (500) moves.
``speedup_cpu_time`` is the same ratio in process CPU time (less noisy on a shared
machine); ``speedup_likelihood_only`` compares only the time spent projecting the changed people
and evaluating eqs. 8-10 (the proposals, priors and interaction terms, shared by both
chains, excluded); ``ms_per_move_shared`` is that shared work per move (wall time, in
the incremental chain), which bounds the whole-chain ratio by
``ms_per_move_full / ms_per_move_shared``.

Profile of the incremental chain (one frame, 1,500 moves, 384 x 288): before issue 13,
about 70 us per move of numpy per-call overhead and Python bookkeeping (proposal 15,
projection 13, priors and interactions 11, loop 5, incremental eqs. 8-10 25) capped the
speed-up at about 8x. The moves are now declarations run by ``inference.mcmc.sample``
and the per-move inner loops are compiled (``models/rjmcmc3d/compiled.py``, numba: the
projection of a person, eq. 9 over all views, the eq. 10 colour term, the update and add
proposal densities, the interaction row); what remains is Python glue spread over
about thirty ~1 us steps per move (measured under load: 96 -> 50 us of thread CPU per
move on the same frame, full recompute unchanged at about 0.7-1 ms).
"""

from __future__ import annotations

import math
import os
import time

import numpy as np

from benchmarks._common import log
from inference.progress import progress_bar
from models.rjmcmc3d.metrics import evaluate
from models.rjmcmc3d.model import TrackerParams
from models.rjmcmc3d.scene import coverage_fractions, default_scene, render_frame, simulate_walkers
from models.rjmcmc3d.tracker import RJMCMCTracker


def _track(tracker: RJMCMCTracker, seed: int, scene, truth, render_seed: int, label: str):
    state = tracker.init_state()
    results, wall, cpu = [], 0.0, 0.0
    snapshot = None
    n = len(truth.frames)
    for t in progress_bar(range(n), desc=label, leave=False):
        frame = render_frame(render_seed, scene, truth, t)
        w0, c0 = time.perf_counter(), time.process_time()
        state, res = tracker.step(seed * 100_003 + t, state, frame)
        wall += time.perf_counter() - w0
        cpu += time.process_time() - c0
        results.append(res)
        if t == n // 2:
            snapshot = (state, truth, t + 1, render_seed)
    return results, 1000 * wall / n, 1000 * cpu / n, snapshot


def _warm_up(tracker: RJMCMCTracker, scene, seed: int) -> float:
    """Two untimed frames: the numba loops compile on a machine's first run (then load
    from the on-disk cache); returns the seconds spent (reported as ``warmup_s``)."""
    t0 = time.perf_counter()
    truth = simulate_walkers(seed, scene, 2, 4)
    state = tracker.init_state()
    for t in range(2):
        state, _ = tracker.step(t, state, render_frame(seed, scene, truth, t))
    return time.perf_counter() - t0


def _speedup(
    tracker: RJMCMCTracker, snapshot, num_moves: int, seed: int, scene=None, repeats: int = 3
) -> tuple[float, bool, dict]:
    """Same chain, incremental vs full likelihood: time ratio and whether they agree.

    ``scene`` (default: the tracker's) may be the same cameras at another resolution:
    the carried state is in world coordinates.
    """
    params = tracker.params._replace(num_moves=num_moves, burn_in=num_moves // 3)
    state, truth, t, render_seed = snapshot
    scene = scene if scene is not None else tracker.scene
    frame = render_frame(render_seed, scene, truth, t)
    tr = RJMCMCTracker(scene, params, tracker.noise if scene is tracker.scene else None)
    times = {"incremental": math.inf, "full": math.inf}
    cpu_times = dict(times)
    lik_times = dict(times)
    shared = dict(times)
    chains = {}
    for _ in range(repeats):  # interleaved, best of `repeats` (other processes add noise)
        for mode in ("incremental", "full"):
            chain = tr.frame_chain(state, frame, mode)
            t0, c0 = time.perf_counter(), time.process_time()
            chain.run(np.random.default_rng(seed))
            times[mode] = min(times[mode], time.perf_counter() - t0)
            cpu_times[mode] = min(cpu_times[mode], time.process_time() - c0)
            lik_times[mode] = min(lik_times[mode], chain.lik_time)
            shared[mode] = min(shared[mode], time.perf_counter() - t0 - chain.lik_time)
            chains[mode] = chain
    a, b = chains["incremental"], chains["full"]
    full_now = a.full_loglik()
    agree = (
        bool(np.array_equal(a.present, b.present))
        and bool(np.allclose(a.S, b.S))
        and abs(a.loglik - b.loglik) < 1e-6 * max(1.0, abs(b.loglik))
        and abs(a.loglik - full_now) < 1e-6 * max(1.0, abs(full_now))
    )
    info = {
        "ms_per_move_incremental": 1000 * times["incremental"] / num_moves,
        "ms_per_move_full": 1000 * times["full"] / num_moves,
        "speedup_likelihood_only": lik_times["full"] / lik_times["incremental"],
        "speedup_cpu_time": cpu_times["full"] / cpu_times["incremental"],
        "ms_per_move_shared": 1000 * shared["incremental"] / num_moves,
    }
    return times["full"] / times["incremental"], agree, info


def _per_seed(
    tracker: RJMCMCTracker,
    ablation: RJMCMCTracker,
    scene,
    seeds: list[int],
    num_frames: int,
    num_people: int,
) -> tuple[list[dict], list[dict], list[float], list[float], object]:
    """Track every seed's SIMULATED walkers with ``C(u)`` and without (the ablation).

    Returns the metrics with and without, wall and CPU ms per frame, and the first
    frame snapshot (for :func:`_speedup`)."""
    ours, abl, walls, cpus = [], [], [], []
    snapshot = None
    for s in seeds:
        truth = simulate_walkers(s, scene, num_frames, num_people)
        res, wall, cpu, snap = _track(tracker, s, scene, truth, s + 1000, f"seed {s}")
        snapshot = snapshot or snap
        m = evaluate(truth.frames, res)
        res0, _, _, _ = _track(ablation, s, scene, truth, s + 1000, f"seed {s} C(u)=0")
        m0 = evaluate(truth.frames, res0)
        log(
            f"seed {s}: with C(u) mota={m['mota']:.3f} idf1={m['idf1']:.3f} sw={m['id_switches']}"
            f" | C(u)=0 mota={m0['mota']:.3f} idf1={m0['idf1']:.3f} sw={m0['id_switches']}"
            f" | {wall:.0f} ms/frame wall, {cpu:.0f} ms cpu"
        )
        ours.append(m)
        abl.append(m0)
        walls.append(wall)
        cpus.append(cpu)
    return ours, abl, walls, cpus, snapshot


def _speedups(
    tracker: RJMCMCTracker, snapshot, quick: bool, seed: int
) -> tuple[float, dict, float, dict, bool]:
    """The incremental likelihood's speed-up over the full one, at the scene's size and at
    768x576; returns both speed-ups, their details, and whether the two agreed."""
    speed, agree, info = _speedup(tracker, snapshot, 300 if quick else 1500, seed)
    log(f"speed-up vs full likelihood: {speed:.1f} ({info})")
    pal = default_scene(0, width=768, height=576)
    speed_pal, agree_pal, info_pal = _speedup(tracker, snapshot, 100 if quick else 500, seed, pal)
    log(f"at 768x576: speed-up {speed_pal:.1f} ({info_pal})")
    return speed, info, speed_pal, info_pal, agree and agree_pal


def run(quick: bool, seed: int) -> dict:
    num_frames = 25 if quick else 300
    num_people = 6
    seeds = [seed] if quick else [seed, seed + 1, seed + 2]
    scene = default_scene(0)
    params = TrackerParams(num_moves=1500, burn_in=500)
    tracker = RJMCMCTracker(scene, params)
    ablation = RJMCMCTracker(scene, params._replace(ground_noise=False), tracker.noise)
    log(
        f"rjmcmc3d: SIMULATED 3-camera scene, {num_people} people, {num_frames} frames, "
        f"seeds {seeds}, {params.num_moves} moves/frame ({params.burn_in} burn-in)"
    )
    warmup = _warm_up(tracker, scene, seed + 7)
    log(f"warm-up (numba compile or cache load): {warmup:.1f} s")
    cov = coverage_fractions(scene, step=0.2)
    log(f"floor seen by 0/1/2/3 cameras: {np.round(cov, 3).tolist()}")
    ours, abl, walls, cpus, snapshot = _per_seed(tracker, ablation, scene, seeds, num_frames, num_people)
    speed, info, speed_pal, info_pal, agree = _speedups(tracker, snapshot, quick, seed)

    def pooled(ms: list[dict], key: str) -> float:
        return float(np.mean([m[key] for m in ms]))

    out = {
        "mota": pooled(ours, "mota"),
        "idf1": pooled(ours, "idf1"),
        "id_switches": int(sum(m["id_switches"] for m in ours)),
        "mota_without_ground_noise": pooled(abl, "mota"),
        "idf1_without_ground_noise": pooled(abl, "idf1"),
        "id_switches_without_ground_noise": int(sum(m["id_switches"] for m in abl)),
        "ms_per_frame": float(np.mean(walls)),
        "cpu_ms_per_frame": float(np.mean(cpus)),
        "speedup_vs_full_likelihood": float(speed),
        **info,
        "speed_moves": 300 if quick else 1500,
        "image_size": [scene.width, scene.height],
        "speedup_vs_full_likelihood_768x576": float(speed_pal),
        "speedup_likelihood_only_768x576": info_pal["speedup_likelihood_only"],
        "speedup_cpu_time_768x576": info_pal["speedup_cpu_time"],
        "moves_per_frame": params.num_moves,
        "burn_in": params.burn_in,
        "num_frames": num_frames,
        "num_people": num_people,
        "num_seeds": len(seeds),
        "floor_seen_by_0_1_2_3_cameras": np.round(cov, 3).tolist(),
        "warmup_s": warmup,
        "load_average_1min": os.getloadavg()[0],
        "data": "simulated",
    }
    finite = all(math.isfinite(v) for v in (out["mota"], out["idf1"], out["ms_per_frame"]))
    out["ok"] = bool(agree and finite)
    return out
