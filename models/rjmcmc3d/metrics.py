"""CLEAR-MOT and identity metrics on ground-plane positions, through py-motmetrics.

MOTA, IDF1 and identity switches are computed by ``motmetrics`` (not rewritten here);
a hypothesis matches a true person when their ground-plane distance is below the
threshold (0.5 m by default, as asked by the issue).
"""

from __future__ import annotations

from collections.abc import Sequence

import motmetrics as mm
import numpy as np

from dbn.checks import is_real_number
from dbn.errors import InputError
from models.rjmcmc3d.tracker import FrameResult
from models.rjmcmc3d.types import FrameTruth

__all__ = ["evaluate"]


def evaluate(
    truth: Sequence[FrameTruth], results: Sequence[FrameResult], threshold: float = 0.5
) -> dict[str, float]:
    """MOTA, IDF1, ID switches, misses and false positives over a sequence.

    Parameters
    ----------
    truth : sequence of FrameTruth, length num_frames
    results : sequence of FrameResult, length num_frames
    threshold : float
        Match distance on the ground plane (m).

    Returns
    -------
    dict
        ``mota``, ``idf1``, ``id_switches``, ``misses``, ``false_positives``,
        ``num_objects``, ``precision``, ``recall``.
    """
    if len(truth) != len(results):
        raise InputError(f"truth has {len(truth)} frames but results has {len(results)}")
    if not is_real_number(threshold) or not 0 < threshold < float("inf"):
        raise InputError(f"threshold={threshold!r} must be a positive number (m)")  # nan ran
    acc = mm.MOTAccumulator(auto_id=True)
    for ft, res in zip(truth, results, strict=True):
        hyp = res.X[:, :2] if len(res.ids) else np.zeros((0, 2))
        dist = mm.distances.norm2squared_matrix(ft.u, hyp, max_d2=threshold**2)
        acc.update(list(map(int, ft.ids)), list(map(int, res.ids)), np.sqrt(dist))
    mh = mm.metrics.create()
    names = [
        "mota",
        "idf1",
        "num_switches",
        "num_misses",
        "num_false_positives",
        "num_objects",
        "precision",
        "recall",
    ]
    summary = mh.compute(acc, metrics=names, name="seq")
    row = summary.loc["seq"]
    return {
        "mota": float(row["mota"]),
        "idf1": float(row["idf1"]),
        "id_switches": int(row["num_switches"]),
        "misses": int(row["num_misses"]),
        "false_positives": int(row["num_false_positives"]),
        "num_objects": int(row["num_objects"]),
        "precision": float(row["precision"]),
        "recall": float(row["recall"]),
    }
