"""Write the tiny SIMULATED path-recovery example (run from the repository root):
a 2 x 2 Manhattan grid (street blocks of 2 cameras), 20 walkers, 12 steps (models.pathrecovery.simulate; seeds 5 and 27, a scene whose target walks through a gap)."""

import numpy as np

from models.pathrecovery.simulate import manhattan_grid, simulate_scene

out = "tests/data/pathrecovery/"
net = manhattan_grid(5, 2, 2, block=(2, 2))
sc = simulate_scene(27, net, num_objects=20, num_timesteps=12, cm=0.2)
src = np.repeat(np.arange(net.indptr.size - 1), np.diff(net.indptr))
with open(out + "edges.csv", "w") as f:
    f.write("from,to,prob,gap_mean\n")
    for a, b, p, g in zip(src, net.indices, net.probs, net.gap_mean):
        f.write(f"{a},{b},{float(p)!r},{g:g}\n")
with open(out + "cameras.csv", "w") as f:
    f.write("camera,x,y\n" + "".join(f"{i},{x:g},{y:g}\n" for i, (x, y) in enumerate(net.coords)))
odb = sc.odb
d = odb.feat.shape[1]
t_of = np.repeat(np.arange(odb.num_timesteps), np.diff(odb.time_ptr))
with open(out + "observations.csv", "w") as f:
    f.write("obs,t,camera," + ",".join(f"f{i}" for i in range(d)) + ",object\n")
    for i in range(odb.cam.size):
        if t_of[i] == 0 and odb.obj[i] != sc.target:
            continue  # only the target is listed at t = 0: its start
        feats = ",".join(f"{x:.5f}" for x in odb.feat[i])
        f.write(f"{i},{t_of[i]},{odb.cam[i]},{feats},{odb.obj[i]}\n")
with open(out + "truth_path.csv", "w") as f:
    f.write("t,state,camera,ta,obs\n")
    for t in range(odb.num_timesteps):
        state = "visible" if sc.true_ta[t] == 0 else "hidden"
        f.write(f"{t},{state},{sc.true_cam[t]},{sc.true_ta[t]},{sc.true_obs[t]}\n")
with open(out + "bad_edges.csv", "w") as f:
    f.write("from,to,prob\n0,0,0.5\n0,1,0.7\n1,1,1.0\n")
