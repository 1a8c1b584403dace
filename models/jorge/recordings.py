"""Which recording a ground truth is (issue 16: held-out figures that nothing leaks into).

A sequence someone adds to the data folder may be one the parameters were fitted on under
another name or cut: CAVIAR's archives hold ``mws1gt.xml`` beside ``mws1gt1.xml``, the same
Meet_WalkSplit recording from frame 100 on. :func:`same_recording` tells them apart by their
boxes, not their names, so the benchmark never scores a training recording as held out.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from dbn.errors import InputError
from models.jorge.strokes import GroundTruth

__all__ = ["shared_boxes", "same_recording"]


def shared_boxes(truth: GroundTruth, other: GroundTruth, tol: float = 1.0) -> float:
    """Share of ``truth``'s boxes that ``other`` annotates too: the same frame number and
    person id, every coordinate within ``tol`` pixels.

    Returns
    -------
    float
        In [0, 1]; 0 for a ground truth without boxes.
    """
    total = int(np.isfinite(truth.boxes[..., 0]).sum())
    if total == 0:
        return 0.0
    _, fi, fj = np.intersect1d(truth.frames, other.frames, return_indices=True)
    _, ii, ij = np.intersect1d(truth.ids, other.ids, return_indices=True)
    a = truth.boxes[np.ix_(fi, ii)]
    b = other.boxes[np.ix_(fj, ij)]
    with np.errstate(invalid="ignore"):
        same = np.all(np.abs(a - b) <= tol, axis=-1)  # NaN on either side: not shared
    return float(same.sum()) / total


def same_recording(truth: GroundTruth, others: Mapping[str, GroundTruth],
                   share: float = 0.5, tol: float = 1.0) -> str | None:
    """The key of the first of ``others`` that ``truth`` is (a cut of) the same recording
    as: at least ``share`` of its boxes are that one's (:func:`shared_boxes`); None if
    none is.

    Raises
    ------
    InputError
        ``share`` not in (0, 1] or ``tol`` not >= 0.
    """
    if not 0.0 < share <= 1.0:
        raise InputError(f"same_recording: share must be in (0, 1], got {share!r}")
    if not tol >= 0.0:
        raise InputError(f"same_recording: tol must be >= 0, got {tol!r}")
    for key, other in others.items():
        if shared_boxes(truth, other, tol) >= share:
            return key
    return None
