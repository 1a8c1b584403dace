"""A simulated sequence (boxes of walking people) for when the real CAVIAR ground truth
is absent. Everything here is simulated: say so wherever it is used.

People enter at random times, walk at a constant velocity across a 384 x 288 image (the
CAVIAR frame size) and leave; pairs are made to meet: the second of a pair heads for a
point the first passes through at about the same time, walks with it for a while (a
group) and turns away (a split).
"""

from __future__ import annotations

import numpy as np

from dbn.checks import check_count, make_rng
from dbn.errors import InputError
from models.jorge.strokes import GroundTruth, check_frame_rate

__all__ = ["simulate_ground_truth"]


def simulate_ground_truth(seed, num_people: int = 5, num_frames: int = 600,
                          fps: float = 25.0) -> GroundTruth:
    """Simulated boxes of ``num_people`` walkers, some of them meeting in pairs.

    Parameters
    ----------
    seed : int
        Randomness (explicit).
    num_people : int
    num_frames : int
    fps : float

    Returns
    -------
    GroundTruth
        ``boxes`` of shape ``(num_frames, num_people, 4)``, NaN outside each walker's
        presence; ``name = "simulated"``.
    """
    num_people = check_count("num_people", num_people)  # 2.5: Python's TypeError
    num_frames = check_count("num_frames", num_frames)
    fps = check_frame_rate(fps, "simulate_ground_truth", InputError)  # NaN, -1 ran
    if num_frames < 10:
        raise InputError(f"need num_people >= 1 and num_frames >= 10, got {num_people}, {num_frames}")
    rng = make_rng(seed)
    width, height = 384.0, 288.0
    boxes = np.full((num_frames, num_people, 4), np.nan)
    t = np.arange(num_frames)
    for i in range(num_people):
        start = int(rng.integers(0, max(1, num_frames // 2)))
        length = int(rng.integers(num_frames // 3, num_frames - start + 1)) if num_frames - start > num_frames // 3 else num_frames - start
        p0 = np.array([rng.uniform(40, width - 40), rng.uniform(40, height - 40)])
        speed = rng.uniform(0.4, 1.0)
        angle = rng.uniform(0, 2 * np.pi)
        v = speed * np.array([np.cos(angle), np.sin(angle)])
        if i % 2 == 1:  # meet the previous walker: head for where it is at a shared time
            j = i - 1
            alive = np.flatnonzero(~np.isnan(boxes[:, j, 0]))
            if alive.size > 60:
                meet = int(alive[alive.size // 3])
                together = int(rng.integers(25, 60))
                target = boxes[meet, j, :2]
                start = max(0, meet - int(rng.integers(40, 100)))
                p0 = target + rng.normal(0, 60, 2)
                v = (target - p0) / max(1, meet - start)
                length = min(num_frames - start, meet - start + together + int(rng.integers(40, 120)))
                seg = np.arange(start, start + length)
                pos = p0 + (seg - start)[:, None] * v
                during = (seg >= meet) & (seg < meet + together)
                pos[during] = boxes[seg[during], j, :2] + np.array([6.0, 0.0])
                after = seg >= meet + together
                if after.any():
                    away = rng.normal(0, 1, 2)
                    away = 0.8 * away / np.linalg.norm(away)
                    anchor = pos[~after][-1]
                    pos[after] = anchor + (seg[after] - seg[~after][-1])[:, None] * away
                pos = np.where(np.isnan(pos), p0, pos)
                ok = (pos[:, 0] > 0) & (pos[:, 0] < width) & (pos[:, 1] > 0) & (pos[:, 1] < height)
                seg, pos = seg[ok], pos[ok]
                boxes[seg, i, 0:2] = pos
                boxes[seg, i, 2:] = (18.0, 34.0)
                continue
        seg = t[start:start + length]
        pos = p0 + (seg - start)[:, None] * v
        ok = (pos[:, 0] > 0) & (pos[:, 0] < width) & (pos[:, 1] > 0) & (pos[:, 1] < height)
        # keep the first contiguous run inside the image
        if ok.any():
            first = int(np.argmax(ok))
            run = ok[first:]
            stop = first + (int(np.argmin(run)) if not run.all() else run.size)
            boxes[seg[first:stop], i, 0:2] = pos[first:stop]
            boxes[seg[first:stop], i, 2:] = (18.0, 34.0)
    keep = ~np.all(np.isnan(boxes[..., 0]), axis=0)
    boxes = boxes[:, keep]
    ids = np.flatnonzero(keep)
    return GroundTruth("simulated", np.arange(num_frames), ids, boxes, (), fps)
