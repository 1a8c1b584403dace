"""``dbntrack demo`` part: seed 000's learn-search tracker and its MCMC baseline on one
SIMULATED office data set (no real data with per-pass appearance features exists for
this setting; see ``../shared/data/README.md``)."""

from __future__ import annotations

import time

from models.zajdel.data import take
from models.zajdel.greedy import greedy_labels
from models.zajdel.learnsearch import LearnSearchConfig, initial_params, learn_search
from models.zajdel.mcmc import MCMCConfig, partition_mcmc
from models.zajdel.metrics import num_objects, pairwise_prf, partition_accuracy
from models.zajdel.simulate import simulate_office

__all__ = ["run_demo"]


def run_demo(quick: bool = True) -> None:
    """Print partition accuracy q, pairwise F1 and objects of the learn-search tracker
    (T = 1, 5, 20, parameters learned by EM), the greedy baseline and a short MCMC run."""
    sc = simulate_office(0)
    K, people = sc.obs.num_obs, num_objects(sc.labels)
    print(f"SIMULATED office data: {K} observations of {people} people, "
          f"{sc.config.num_cameras} cameras (models.zajdel.simulate, seed 0)")
    p0 = initial_params(take(sc.obs, slice(0, 6)), sc.params.path, sc.params.p_new)
    print(f"{'method':<28}{'q':>7}{'F1':>7}{'objects':>9}{'time s':>9}")

    def row(name, labels, dt):
        f1 = pairwise_prf(labels, sc.labels)[2]
        print(f"{name:<28}{partition_accuracy(labels, sc.labels):>7.3f}{f1:>7.3f}"
              f"{num_objects(labels):>9d}{dt:>9.2f}")

    t0 = time.perf_counter()
    g = greedy_labels(sc.obs, sc.params)
    row("greedy (given params)", g, time.perf_counter() - t0)
    theta = None
    for T in (1, 5, 20):
        t0 = time.perf_counter()
        res = learn_search(sc.obs, p0, LearnSearchConfig(num_hypotheses=T))
        row(f"learn-search T={T} (EM)", res.labels, time.perf_counter() - t0)
        theta = res.params
    steps = 1000 if quick else 10_000
    t0 = time.perf_counter()
    mc = partition_mcmc(0, sc.obs, theta, steps, MCMCConfig(init="greedy"))
    row(f"MCMC {steps} steps (greedy)", mc.best_labels, time.perf_counter() - t0)
    print(f"true number of people: {people}; seed 000 Table 1 (real data): q = 0.48 for "
          "T = 1, 0.77 for T = 5")
