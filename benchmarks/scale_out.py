"""Scale-out: sweeps on Dask distributed and particle filters sharded over jax devices.

Keys (issue 18):

- ``sweep_identical_to_serial``: a sweep on a 2-worker ``LocalCluster`` returns exactly
  the serial run's results (JSON-equal, every bit of every float).
- ``speedup_2_workers``: serial wall time / 2-worker wall time on a CPU-bound sweep of
  ``num_tasks`` >= 8 points (exact filtering of coupled chains with the hand-written numpy
  pass, ~0.5 s a point); the cluster is started before timing (``cluster_start_s``).
- ``resume_skips_done``: a sweep interrupted after half its points, resumed, runs only
  the other half and ends with one record per point.
- ``worker_loss_survived``: one point kills its worker process on its first attempt; the
  nanny restarts the worker, Dask reschedules the point, every point finishes ``ok``.
- ``failing_task_recorded``: a point that raises is recorded as an error, the rest finish.
- ``sharded_pf_max_abs_diff``, ``sharded_pf_ns_per_particle_step``,
  ``unsharded_pf_ns_per_particle_step``, ``local_pf_max_z``: from
  :mod:`benchmarks._sharded_pf` in a subprocess with 4 forced host devices.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from benchmarks._chains_numpy import numpy_factored_filter
from benchmarks._common import log
from dbn.examples import sample_coupled_chains
from models.experiments import GridPoint, local_cluster, make_grid, read_results, run_grid


def chain_task(point: GridPoint) -> dict:
    """A CPU-bound sweep point: exact filtering of ``n`` coupled chains over ``T`` slices.

    Parameters (``point.params``): ``n`` (chains, default 9), ``T`` (slices, default 200),
    ``fail`` (raise, to test error records), ``die_once`` (a marker path: kill this worker
    process the first time, to test worker loss).
    """
    p = dict(point.params)
    marker = p.get("die_once")
    if marker and not os.path.exists(marker):
        Path(marker).touch()
        os._exit(1)  # the worker process dies mid-task
    if p.get("fail"):
        raise RuntimeError(f"point {point.seed} fails on purpose")
    rng = np.random.default_rng(point.rng_seed)
    _, ys = sample_coupled_chains(rng, p.get("n", 9), p.get("T", 200))  # they check both
    marg, logz = numpy_factored_filter(ys)
    return {"log_likelihood": float(logz.sum()), "mean_on": float(marg[:, :, 1].mean())}


chain_task.params = ("n", "T", "fail", "die_once")  # what models.experiments.check_params allows


def _results(records: list[dict]) -> list:
    return [(r["id"], r["status"], r["result"]) for r in records]


def _sweeps(quick: bool, seed: int, tmp: Path) -> dict:
    from dask.distributed import Client

    num = 8 if quick else 16
    grid = make_grid(
        ["chains"], seeds=range(seed, seed + num), params={"n": [11 if quick else 12], "T": [1000]}
    )
    t0 = time.perf_counter()
    serial = run_grid(chain_task, grid, serial=True, progress=False)
    serial_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    with local_cluster(2) as cluster, Client(cluster) as client:
        start_s = time.perf_counter() - t0
        client.submit(chain_task, grid[0]).result()  # warm the workers' imports
        t0 = time.perf_counter()
        dist = run_grid(chain_task, grid, client=client, out=tmp / "dist.jsonl", progress=False)
        dist_s = time.perf_counter() - t0
        identical = _results(serial) == _results(dist)
        half = grid[: num // 2]
        run_grid(chain_task, half, client=client, out=tmp / "resume.jsonl", progress=False)
        resumed = run_grid(
            chain_task, grid, client=client, out=tmp / "resume.jsonl", resume=True, progress=False
        )
        lines = read_results(tmp / "resume.jsonl")
        resume_ok = len(lines) == num and _results(resumed) == _results(serial)
        chaos = make_grid(["chains"], seeds=range(4), params={"n": [6]})
        chaos[1] = GridPoint("chains", "simulated", 1, (("die_once", str(tmp / "died")), ("n", 6)))
        survived = run_grid(chain_task, chaos, client=client, progress=False)
        loss_ok = (tmp / "died").exists() and all(r["status"] == "ok" for r in survived)
        bad = make_grid(["chains"], seeds=range(3), params={"n": [6]})
        bad[2] = GridPoint("chains", "simulated", 2, (("fail", True), ("n", 6)))
        failed = run_grid(chain_task, bad, client=client, progress=False)
        fail_ok = [r["status"] for r in failed] == ["ok", "ok", "error"]
    log(f"serial {serial_s:.2f} s, 2 workers {dist_s:.2f} s (cluster start {start_s:.2f} s)")
    return {
        "num_tasks": num,
        "serial_s": serial_s,
        "two_workers_s": dist_s,
        "cluster_start_s": start_s,
        "speedup_2_workers": serial_s / dist_s,
        "sweep_identical_to_serial": identical,
        "resume_skips_done": resume_ok,
        "worker_loss_survived": loss_ok,
        "failing_task_recorded": fail_ok,
    }


def _sharded(quick: bool) -> dict:
    env = dict(os.environ, XLA_FLAGS="--xla_force_host_platform_device_count=4")
    args = ["--particles", "8000" if quick else "40000", "--timesteps", "30", "--reps", "8"]
    proc = subprocess.run(
        [sys.executable, "-m", "benchmarks._sharded_pf", *args],
        capture_output=True,
        text=True,
        env=env,
        cwd=Path(__file__).resolve().parents[1],
        timeout=600,
    )
    if proc.returncode != 0:
        raise RuntimeError(f"sharded particle filter run failed:\n{proc.stderr[-2000:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def run(quick: bool = False, seed: int = 0) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        out = _sweeps(quick, seed, Path(tmp))
    out.update(_sharded(quick))
    out["ok"] = bool(
        out["sweep_identical_to_serial"]
        and out["resume_skips_done"]
        and out["worker_loss_survived"]
        and out["failing_task_recorded"]
        and out["sharded_pf_max_abs_diff"] <= 1e-6
    )
    return out
