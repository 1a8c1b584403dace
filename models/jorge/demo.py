"""``dbntrack demo`` part for seed 004: label the strokes of CAVIAR Meet_Split_3rdGuy.

Real boxes from ``../shared/data/caviar/ms3ggt.xml.gz`` when present; otherwise a
SIMULATED sequence (and the demo says so). Occlusion gaps and colours are always
simulated (the ground truth has neither).
"""

from __future__ import annotations

from models import datasets
from models.jorge.labels import format_label
from models.jorge.online import label_online
from models.jorge.scoring import colour_only_labels, score
from models.jorge.simulate import simulate_ground_truth
from models.jorge.strokes import build_strokes, load_caviar

__all__ = ["run_demo", "load_or_simulate"]


def load_or_simulate(seed: int = 0):
    """The Meet_Split_3rdGuy ground truth, or a simulated sequence when it is absent.

    Returns
    -------
    truth : GroundTruth
    real : bool
    """
    try:
        return load_caviar(datasets.require("caviar", "ms3ggt.xml.gz")), True
    except FileNotFoundError:
        return simulate_ground_truth(seed, num_people=5, num_frames=900), False


def run_demo(quick: bool = True) -> None:
    """Build the strokes, label them on line, print the errors against the baseline."""
    truth, real = load_or_simulate(0)
    if real:
        print(f"real CAVIAR ground truth: {truth.name}, {truth.num_frames} frames, "
              f"{truth.ids.size} people (occlusion gaps and colours simulated)")
    else:
        print("CAVIAR ground truth not found: using a SIMULATED sequence instead")
    strokes = build_strokes(0, truth)
    res = label_online(strokes)
    ours = score(strokes, res.labels)
    base = score(strokes, colour_only_labels(strokes))
    print(f"{len(strokes)} strokes ({strokes.num_groups} groups) labelled in {res.seconds:.2f} s "
          f"for {strokes.duration_s:.1f} s of video ({strokes.duration_s / res.seconds:.0f}x real time)")
    print(f"labelling errors: Bayes net {ours.label_errors}/{ours.num_strokes} "
          f"({ours.error_rate:.1%}), colour only {base.label_errors}/{base.num_strokes} "
          f"({base.error_rate:.1%})")
    shown = strokes.strokes[: 8 if quick else len(strokes)]
    for s in shown:
        mark = " <- error" if s.index in ours.errors else ""
        print(f"  stroke {s.index:2d} frames {s.start:3d}-{s.end:3d} true {sorted(s.truth)} "
              f"label {format_label(res.labels[s.index])}{mark}")


if __name__ == "__main__":
    run_demo()
