"""The DBN primer: a small Bayes net and an HMM-like DBN a tracker would use.

- :func:`detector_bn`: is a person present, is the view occluded, does the detector fire.
- :func:`corridor_dbn`: a person walking along a corridor of three zones (left, centre,
  right) seen by a detector that reports a zone or nothing (missed detections and false
  zones), a two-slice DBN; :func:`simulate_corridor` draws a sequence from it.

Used by ``tutorials/00_dbn_primer`` and ``dbntrack demo``.
"""

from __future__ import annotations

import numpy as np

from dbn.bayesnet import BayesNet
from dbn.checks import make_rng
from dbn.cpds import TabularCPD
from dbn.dbn import TwoSliceDBN, prev
from dbn.variables import DiscreteVariable

__all__ = ["detector_bn", "corridor_dbn", "simulate_corridor", "run_demo"]

ZONES = ("left", "centre", "right")
READINGS = ("left", "centre", "right", "none")


def detector_bn() -> BayesNet:
    """Person present (P), occluded (O) -> detector fires (D)."""
    P = DiscreteVariable("present", 2, ("no", "yes"))
    O = DiscreteVariable("occluded", 2, ("no", "yes"))
    D = DiscreteVariable("detection", 2, ("no", "yes"))
    fires = np.array(
        [  # P(D | present, occluded): rows (present, occluded), columns (no, yes)
            [[0.95, 0.05], [0.97, 0.03]],  # nobody: false alarms
            [[0.10, 0.90], [0.70, 0.30]],  # somebody: missed when occluded
        ]
    )
    return BayesNet(
        [P, O, D],
        [
            TabularCPD("present", [], [0.7, 0.3]),
            TabularCPD("occluded", [], [0.8, 0.2]),
            TabularCPD("detection", ["present", "occluded"], fires),
        ],
    )


def corridor_dbn(p_stay: float = 0.8, p_detect: float = 0.85) -> TwoSliceDBN:
    """A person in one of three zones, moving to a neighbouring zone or staying.

    The reading is the true zone with probability ``p_detect``, a neighbouring zone with
    probability ``(1 - p_detect) / 2`` split over the neighbours, and ``none`` otherwise.
    """
    zone = DiscreteVariable("zone", 3, ZONES)
    reading = DiscreteVariable("reading", 4, READINGS)
    move = np.array(
        [
            [p_stay, 1 - p_stay, 0.0],
            [(1 - p_stay) / 2, p_stay, (1 - p_stay) / 2],
            [0.0, 1 - p_stay, p_stay],
        ]
    )
    miss = (1 - p_detect) / 2
    sense = np.array(
        [
            [p_detect, miss, 0.0, miss],
            [miss / 2, p_detect, miss / 2, miss],
            [0.0, miss, p_detect, miss],
        ]
    )
    return TwoSliceDBN(
        [zone, reading],
        [TabularCPD("zone", [], [1 / 3, 1 / 3, 1 / 3]), TabularCPD("reading", ["zone"], sense)],
        [TabularCPD("zone", [prev("zone")], move), TabularCPD("reading", ["zone"], sense)],
    )


def simulate_corridor(
    seed: int, num_timesteps: int, dbn: TwoSliceDBN | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Draw ``(zones, readings)``, each an int array of shape ``(num_timesteps,)``."""
    dbn = dbn or corridor_dbn()
    rng = make_rng(seed)
    bn = dbn.unroll(1)
    first = bn.sample(rng, 1)
    zones = np.empty(num_timesteps, dtype=np.int64)
    readings = np.empty(num_timesteps, dtype=np.int64)
    zones[0], readings[0] = first["zone_0"][0], first["reading_0"][0]
    move = dbn.transition_net.table("zone")
    sense = dbn.transition_net.table("reading")
    for t in range(1, num_timesteps):
        zones[t] = rng.choice(3, p=move[zones[t - 1]])
        readings[t] = rng.choice(4, p=sense[zones[t]])
    return zones, readings


def run_demo(quick: bool = True) -> None:
    """Print the primer's results: BN marginals and MAP, filtering, smoothing, Viterbi,
    and the agreement with pgmpy."""
    from dbn import pgmpy_adapter as pa
    from inference.exact import JunctionTree, map_assignment
    from inference.exact.dbn_filter import DBNFilter

    bn = detector_bn()
    cal = JunctionTree(bn).calibrate({"detection": "no"})
    print("Detector net, given no detection:")
    for n in ("present", "occluded"):
        print(f"  P({n} | detection=no) = {np.round(cal.marginals[n], 4).tolist()}")
    config, lp = map_assignment(bn, {"detection": "no"})
    named = {n: bn.variable(n).state_names[s] for n, s in config.items()}
    print(f"  MAP: {named}  log P = {lp:.4f}")
    theirs = pa.pgmpy_marginals(pa.to_pgmpy(bn), ["present", "occluded"], {"detection": "no"})
    diff = max(float(np.abs(theirs[n] - cal.marginals[n]).max()) for n in theirs)
    print(f"  pgmpy VariableElimination agrees to {diff:.1e}")

    dbn = corridor_dbn()
    T = 50 if quick else 500
    zones, readings = simulate_corridor(0, T, dbn)
    flt = DBNFilter(dbn)
    filt = flt.filter({"reading": readings})
    smooth = flt.smooth({"reading": readings})
    path, lp = flt.viterbi({"reading": readings})
    acc = lambda est: float(np.mean(est == zones))  # noqa: E731
    print(f"Corridor DBN, {T} slices (simulated):")
    print(f"  log-likelihood {filt.log_likelihood:.3f}")
    print(
        f"  zone accuracy: filtered MAP {acc(filt.beliefs.argmax(1)):.2f}, "
        f"smoothed MAP {acc(smooth.posteriors.argmax(1)):.2f}, Viterbi {acc(path['zone']):.2f}"
    )
    model = pa.dbn_to_pgmpy(dbn)
    evidence = {("reading", t): READINGS[r] for t, r in enumerate(readings[:20])}
    theirs = pa.pgmpy_dbn_forward(model, [("zone", 19)], evidence)[("zone", 19)]
    print(
        f"  pgmpy forward_inference at slice 19 agrees to {np.abs(theirs - filt.beliefs[19]).max():.1e}"
    )
