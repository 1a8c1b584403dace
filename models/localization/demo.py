"""``dbntrack demo``: robot localisation with the auxiliary particle filter (seed 002, 1.3)."""

from __future__ import annotations

import numpy as np


def run_demo(quick: bool = True) -> None:
    """Print SIR against APF on the SIMULATED aliased world, then a short real MRCLAM run.

    Falls back to the simulated world alone (and says so) when the MRCLAM data is absent.
    """
    from models.localization.experiments import mrclam_trials, synthetic_trials
    from models.localization.simulate import build_trained_world

    trained = build_trained_world(0)
    steps = 60 if quick else 120
    runs = 5 if quick else 10
    res = synthetic_trials(0, trained, num_runs=runs, num_timesteps=steps, num_particles=1000)
    print(
        f"SIMULATED aliased floor ({len(trained.sensor.train_poses)} training poses, k-NN sensor "
        f"J={trained.sensor.num_neighbours}, 10% occlusions), {runs} runs x {steps} steps, N=1000:"
    )
    for name in ("sir", "apf"):
        r = res[name]
        print(
            f"  {name.upper()}: position RMSE {r['rmse'].mean():.3f} m, "
            f"failures (>1 m at the end) {np.mean(r['final_error'] > 1.0):.0%}"
        )
    print(f"  odometry alone: RMSE {res['dead_reckoning_rmse'].mean():.3f} m")
    try:
        mr = mrclam_trials(0, num_runs=1, num_particles=1000, duration=60.0 if quick else 300.0)
    except FileNotFoundError:
        print("MRCLAM data absent (../shared/data/mrclam6): shown on simulated data only.")
        return
    print(
        f"Real UTIAS MRCLAM dataset 6, robot 1, first {60 if quick else 300} s, APF N=1000: "
        f"RMSE {mr['rmse'].mean():.3f} m (odometry alone {mr['dead_reckoning_rmse']:.3f} m)"
    )


if __name__ == "__main__":
    run_demo()
