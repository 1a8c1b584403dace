"""Write the tiny SIMULATED box files of the group labeller (run from the repository root):
4 people over 240 frames (models.jorge.simulate, seed 3), as CAVIAR CVML XML (with
grouplists), PETS2009-style XML and MOTChallenge gt.txt; and regions.jsonl, the strokes
the SIMULATED low-level tracker makes of caviar.xml with seed 3, as a regions file
(models.io.jorge_regions: what your own tracker would write)."""

import numpy as np

from models.jorge.simulate import simulate_ground_truth

out = "tests/data/jorge/"
gt = simulate_ground_truth(3, num_people=4, num_frames=240)


def objects(r, indent):
    lines = []
    for j, pid in enumerate(gt.ids):
        b = gt.boxes[r, j]
        if np.isnan(b[0]):
            continue
        lines.append(
            f'{indent}<object id="{pid}"><box xc="{b[0]:.1f}" yc="{b[1]:.1f}" '
            f'w="{b[2]:.1f}" h="{b[3]:.1f}"/></object>'
        )
    return lines


with open(out + "caviar.xml", "w") as f:
    f.write('<?xml version="1.0" encoding="UTF-8"?>\n<dataset name="simulated">\n')
    for r, fr in enumerate(gt.frames):
        obj = objects(r, "      ")
        f.write(
            f'  <frame number="{fr}">\n    <objectlist>\n'
            + "\n".join(obj)
            + "\n    </objectlist>\n    <grouplist/>\n  </frame>\n"
        )
    f.write("</dataset>\n")
with open(out + "pets2009.xml", "w") as f:
    f.write('<?xml version="1.0" encoding="utf-8"?>\n<dataset name="simulated-pets">\n')
    for r, fr in enumerate(gt.frames):
        f.write(
            f'  <frame number="{fr}">\n    <objectlist>\n'
            + "\n".join(objects(r, "      "))
            + "\n    </objectlist>\n  </frame>\n"
        )
    f.write("</dataset>\n")
with open(out + "gt.txt", "w") as f:
    for r, fr in enumerate(gt.frames):
        for j, pid in enumerate(gt.ids):
            b = gt.boxes[r, j]
            if not np.isnan(b[0]):
                f.write(
                    f"{fr},{pid},{b[0] - b[2] / 2:.1f},{b[1] - b[3] / 2:.1f},{b[2]:.1f},{b[3]:.1f},1,1,1\n"
                )
with open(out + "bad_gt.txt", "w") as f:
    f.write("1,1,10,10,20,40,1,1,1\n2,1,10,10,-5,40,1,1,1\n")

from models.io.jorge_regions import write_regions  # noqa: E402
from models.jorge.strokes import build_strokes, load_caviar  # noqa: E402

strokes = build_strokes(3, load_caviar(out + "caviar.xml"))
write_regions(out + "regions.jsonl", strokes, fps=strokes.fps)
