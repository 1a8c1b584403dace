"""``dbntrack demo`` part: the Zajdel ADF tracker (seed 002, section 1.4) on one
SIMULATED office scenario, against the single-hypothesis greedy tracker."""

from __future__ import annotations

__all__ = ["run_demo"]


def run_demo(quick: bool = True) -> None:
    """Simulate an office building, track with ADF, print partition scores."""
    from models.zajdel.greedy import greedy_labels
    from models.zajdel.metrics import num_objects, pairwise_prf, partition_accuracy
    from models.zajdel.model import declare_model
    from models.zajdel.simulate import simulate_office
    from models.zajdel.tracker import ADFConfig, ZajdelADF

    sc = simulate_office(3)
    print(
        f"SIMULATED office: {sc.config.num_cameras} cameras, {num_objects(sc.labels)} people, "
        f"{sc.obs.num_obs} observations (no public data with per-pass appearance exists)"
    )
    tracker = ZajdelADF(
        declare_model(sc.params), ADFConfig(max_open=64, init_persons=128, chunk=64)
    )
    _, res = tracker.run(sc.obs)
    rows = {"ADF chain decoding": res.labels_chain(), "ADF on-line MAP": res.labels_online()}
    if not quick:
        _, res3 = tracker.run(sc.obs, lag=3)
        rows["ADF fixed lag 3"] = res3.labels_chain()
    rows["greedy, 1 hypothesis"] = greedy_labels(sc.obs, sc.params)
    print(f"  {'method':22s} {'q':>6s} {'F1':>6s} objects")
    for name, lab in rows.items():
        f1 = pairwise_prf(lab, sc.labels)[2]
        print(
            f"  {name:22s} {partition_accuracy(lab, sc.labels):6.3f} {f1:6.3f} {num_objects(lab):7d}"
        )
    print(f"  final counter: {res.counter_mean[-1]:.2f} +- {res.counter_std[-1]:.2f} people")


if __name__ == "__main__":
    run_demo()
