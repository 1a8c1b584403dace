"""Which recording a ground truth is (issue 16: held-out figures that nothing leaks into).

A sequence someone adds to the data folder may be one the parameters were fitted on under
another name, cut, renumbered or converted: CAVIAR's archives hold ``mws1gt.xml`` beside
``mws1gt1.xml``, the same Meet_WalkSplit recording from frame 100 on; MOTChallenge's
``gt.txt`` counts frames from 1 where PETS2009's XML counts from 0, numbers the people its
own way and rounds the corners of the boxes to whole pixels. :func:`same_recording` tells
recordings apart by their boxes, not their names, frame numbers or ids, so the benchmark
never scores a training recording as held out.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from dbn.errors import InputError
from models.jorge.strokes import GroundTruth

__all__ = ["frame_offset", "shared_boxes", "same_recording"]

SAMPLE = 256
"""Boxes of a ground truth that vote on the frame offset (:func:`frame_offset`), evenly
spread over its boxes in frame order: no randomness."""


def _present(truth: GroundTruth) -> tuple[np.ndarray, np.ndarray]:
    """Frame numbers ``(n,)`` and boxes ``(n, 4)`` of every annotated box, in frame order."""
    fi, ii = np.nonzero(np.isfinite(truth.boxes[..., 0]))
    return truth.frames[fi], truth.boxes[fi, ii]


def frame_offset(truth: GroundTruth, other: GroundTruth, tol: float = 1.0) -> int | None:
    """The shift ``d`` of frame numbers (``other``'s frame ``f + d`` is ``truth``'s frame
    ``f``) under which the most of :data:`SAMPLE` of ``truth``'s boxes have a box of
    ``other``, any person's, with every coordinate within ``tol`` pixels; the smallest
    ``|d|`` (then ``d``) among ties; None if no sampled box has one.

    A box that stays put votes for many shifts, a moving one for its own only, so the
    shift of a cut or a renumbering wins."""
    frames, boxes = _present(truth)
    o_frames, o_boxes = _present(other)
    if frames.size == 0 or o_frames.size == 0:
        return None
    pick = np.unique(np.linspace(0, frames.size - 1, min(SAMPLE, frames.size)).astype(int))
    votes = []
    for f, b in zip(frames[pick], boxes[pick]):
        near = np.all(np.abs(o_boxes - b) <= tol, axis=1)
        votes.append(np.unique(o_frames[near] - f))  # one vote per shift per box
    shifts, counts = np.unique(np.concatenate(votes), return_counts=True)
    if shifts.size == 0:
        return None
    best = shifts[counts == counts.max()]
    return int(best[np.lexsort((best, np.abs(best)))[0]])


def shared_boxes(truth: GroundTruth, other: GroundTruth, tol: float = 1.0) -> float:
    """Share of ``truth``'s boxes that ``other`` annotates too: under the frame shift of
    :func:`frame_offset`, a box of ``other`` in that frame, any person's, with every
    coordinate within ``tol`` pixels.

    Returns
    -------
    float
        In [0, 1]; 0 for a ground truth without boxes or without a box in common.
    """
    total = truth.num_boxes
    shift = frame_offset(truth, other, tol)
    if total == 0 or shift is None:
        return 0.0
    _, fi, fj = np.intersect1d(truth.frames + shift, other.frames, return_indices=True)
    shared = 0
    for a, b in zip(truth.boxes[fi], other.boxes[fj]):  # (num_ids, 4), (other ids, 4)
        a, b = a[np.isfinite(a[:, 0])], b[np.isfinite(b[:, 0])]
        if a.size and b.size:
            near = np.all(np.abs(a[:, None] - b[None]) <= tol, axis=-1)  # (n_a, n_b)
            shared += int(near.any(axis=1).sum())
    return shared / total


def same_recording(truth: GroundTruth, others: Mapping[str, GroundTruth],
                   share: float = 0.5, tol: float = 1.0) -> str | None:
    """The key of the first of ``others`` that ``truth`` is (a cut of) the same recording
    as: at least ``share`` of its boxes are that one's (:func:`shared_boxes`, whatever the
    frame numbering and the ids); None if none is.

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
