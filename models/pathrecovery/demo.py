"""``dbntrack demo`` part for seed 001: recover a target's path on a SIMULATED Manhattan
grid of cameras, default against the paper's faithful reading."""

from __future__ import annotations

import numpy as np

from models.pathrecovery.filter import FilterConfig, make_model, run_filter
from models.pathrecovery.metrics import kbest_score, path_score
from models.pathrecovery.recover import recover_path
from models.pathrecovery.simulate import manhattan_grid, simulate_scene


def _state(kind: int, cam: int, ta: int) -> str:
    if kind == 0:
        return f"cam {cam:3d}"
    if kind == 1:
        return f"gap->{cam:3d} ({ta})"
    return "-"


def run_demo(quick: bool = True) -> None:
    """Print the scores of both phases and the first steps of the recovered path."""
    steps = 60 if quick else 150
    net = manhattan_grid(0)
    scene = simulate_scene(1, net, num_objects=2000, num_timesteps=steps, cm=0.17)
    print(
        f"SIMULATED data: Manhattan grid of {net.num_cameras} cameras (mean degree "
        f"{net.degrees().mean():.2f}), 2000 moving objects, {steps} steps, confusion measure "
        f"CM = {scene.cm:.3f}, target hidden in gaps {100 * scene.hidden_fraction:.0f}% of steps"
    )
    truth = scene.true_obs[1:]
    paths = {}
    print(f"{'':10s} {'top-1':>6s} {'10-best':>8s} {'phase 2':>8s} {'visible':>8s} {'hidden':>7s} {'ms/step':>8s}")
    for name, cfg in (("default", FilterConfig()), ("faithful", FilterConfig(faithful=True)),
                      ("no gaps", FilterConfig(gaps=False))):
        model = make_model(net, scene.c0, scene.f0, scene.sigma, cfg)
        lists = run_filter(2, model, scene.odb)
        path = recover_path(model, lists, scene.odb.feat, k=7)
        ps = path_score(path.kind, path.obs, truth)
        paths[name] = path
        print(
            f"{name:10s} {kbest_score(lists.kind, lists.obs, truth, 1):6.2f} "
            f"{kbest_score(lists.kind, lists.obs, truth, 10):8.2f} {ps.overall:8.2f} "
            f"{ps.visible:8.2f} {ps.hidden:7.2f} {1e3 * np.median(lists.step_seconds):8.2f}"
        )
    print("\n t  truth            default          faithful")
    shown = 0
    for t in range(1, steps):
        if shown >= 12:
            break
        if t > 3 and scene.true_ta[t] == 0 and scene.true_ta[t - 1] == 0 and t % 5:
            continue  # show the gaps and every 5th step
        i = t - 1
        marks = []
        for name in ("default", "faithful"):
            p = paths[name]
            ok = (p.obs[i] == truth[i]) if truth[i] >= 0 else (p.kind[i] == 1)
            marks.append(f"{_state(p.kind[i], p.cam[i], p.ta[i]):15s}{'ok' if ok else 'XX'}")
        print(f"{t:3d} {_state(0 if truth[i] >= 0 else 1, scene.true_cam[t], scene.true_ta[t]):16s} "
              f"{marks[0]}  {marks[1]}")
        shown += 1
