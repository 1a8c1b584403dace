"""Write the tiny SIMULATED localisation example (generic CSVs and an MRCLAM-style folder).

A robot drives a circle of radius 1.5 m at 0.3 m/s among 4 landmarks for 8 s; odometry at
20 Hz with noise, range-bearing measurements of every landmark at 5 Hz, ground truth at
20 Hz. Run from this folder: ``python make_example.py`` (seed fixed).
"""

import numpy as np

rng = np.random.default_rng(15)
landmarks = np.array([[11, 0.0, 0.0], [12, 3.0, 0.0], [13, 0.0, 3.0], [14, 3.0, 3.0]])
t = 100.0 + np.arange(0, 8.0, 0.05)
v, w = 0.3, 0.2
theta = w * (t - t[0])
x = 1.5 + (v / w) * np.sin(theta)
y = 0.0 + (v / w) * (1 - np.cos(theta))
gt = np.column_stack([t, x, y, np.angle(np.exp(1j * theta))])
odo = np.column_stack(
    [t, v + 0.01 * rng.standard_normal(t.size), w + 0.01 * rng.standard_normal(t.size)]
)
meas = []
for k in range(0, t.size, 4):
    for sid, lx, ly in landmarks:
        r = np.hypot(lx - x[k], ly - y[k]) + 0.05 * rng.standard_normal()
        b = np.angle(
            np.exp(
                1j * (np.arctan2(ly - y[k], lx - x[k]) - theta[k] + 0.02 * rng.standard_normal())
            )
        )
        meas.append([t[k], sid, r, b])
meas = np.array(meas)


def csv(name, header, rows, fmt):
    np.savetxt(name, rows, delimiter=",", header=header, comments="", fmt=fmt)


csv("odometry.csv", "t,v,w", odo, "%.3f")
csv("measurements.csv", "t,landmark,range,bearing", meas, ["%.3f", "%d", "%.4f", "%.4f"])
csv("landmarks.csv", "id,x,y", landmarks, ["%d", "%.3f", "%.3f"])
csv("groundtruth.csv", "t,x,y,theta", gt, "%.4f")
head = "# simulated, MRCLAM layout\n"
np.savetxt("mrclam/Robot1_Odometry.dat", odo, fmt="%.3f", header=head.strip(), delimiter="\t")
np.savetxt(
    "mrclam/Robot1_Measurement.dat", meas, fmt=["%.3f", "%d", "%.4f", "%.4f"], delimiter="\t"
)
np.savetxt("mrclam/Robot1_Groundtruth.dat", gt, fmt="%.4f", delimiter="\t")
lm = np.column_stack([landmarks, np.zeros((4, 2))])
np.savetxt(
    "mrclam/Landmark_Groundtruth.dat",
    lm,
    fmt=["%d", "%.3f", "%.3f", "%.1f", "%.1f"],
    delimiter="\t",
)
np.savetxt(
    "mrclam/Barcodes.dat",
    np.array([[1, 5], [11, 11], [12, 12], [13, 13], [14, 14]]),
    fmt="%d",
    delimiter="\t",
)
with open("bad_odometry.csv", "w") as f:
    f.write("t,v,w\n100.0,0.3,0.2\n100.05,0.3,oops\n")
