"""How well the default pipeline labels SIMULATED meetings, measured over many scenes
(issue 16, thirty-sixth round).

The benchmark scores ten meeting scenes per group size (``benchmarks/jorge.py``,
``meeting_sim``); the scenes differ far more from each other than the stroke seeds do, so
ten scenes leave the error of strokes of three and more people uncertain by about 0.1.
:func:`estimate_meetings` labels many scenes (:func:`models.jorge.meeting.simulate_meeting`,
built into strokes as :func:`models.jorge.fit.meeting_strokes` builds them: scene ``s``,
stroke seed ``s``) and reports, per group size, the pooled error rates (label errors /
strokes, seed 004's Table 3), the mean of the per-scene rates with its standard error, and
how many scenes are above a given rate, where the first mistakes lost their right
label (:meth:`models.jorge.recall.DomainRecall.where_lost`) and why the link rule left out
the people who came into a stroke without a link (:func:`models.jorge.recall.missed_links`).
With ``true_links`` the labeller gets the true predecessors
(:func:`models.jorge.scoring.true_links`) instead of the on-line link rule: the share of
the error the links cause.

It measures, it chooses nothing: use scenes that no fit, search or confirmation has used
(:data:`models.jorge.fit.CONFIRM_SEEDS` lists those), and nothing here is real data.

``python -m models.jorge.estimate --scenes 5000 5200 --fps 7 --workers 2`` prints one JSON
line.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from dbn.checks import check_count
from dbn.errors import InputError
from models.jorge.links import WHY_NOT_PARENT
from models.jorge.network import NetworkConfig

__all__ = ["MeetingEstimate", "estimate_meetings", "main"]


class MeetingEstimate(NamedTuple):
    """The labelling error of the meetings of one group size over many scenes.

    Attributes
    ----------
    scenes : int
        Scenes labelled.
    strokes, strokes_3plus : int
        Strokes, and strokes whose true group has three or more people, over all scenes.
    error, error_3plus : float
        Pooled error rates (label errors / strokes) of all strokes and of the 3+ strokes.
    scene_mean, scene_se : float
        Mean and standard error of the per-scene error rates (NaN with one scene).
    scene_mean_3plus, scene_se_3plus : float
        The same for the 3+ strokes, over the scenes that have any.
    scenes_above : int
        Scenes whose 3+ error rate is above ``above`` (:func:`estimate_meetings`).
    first_mistakes : int
        Errors none of whose people's true predecessors is an error
        (:func:`models.jorge.scoring.first_errors`), over all scenes.
    first_unrepresentable, first_pruned, first_not_chosen : float
        Their shares with no right label admissible nor kept, admissible but pruned, kept
        but not chosen (:mod:`models.jorge.recall`; NaN without first mistakes).
    missed_links, first_mistake_missed_links : dict str -> int
        People seen before who came into a stroke without a link, by the link rule's
        reason (every reason of :data:`models.jorge.links.WHY_NOT_PARENT`), over all
        strokes and at the first mistakes (:func:`models.jorge.recall.missed_links`).
    """

    scenes: int
    strokes: int
    error: float
    scene_mean: float
    scene_se: float
    strokes_3plus: int
    error_3plus: float
    scene_mean_3plus: float
    scene_se_3plus: float
    scenes_above: int
    first_mistakes: int
    first_unrepresentable: float
    first_pruned: float
    first_not_chosen: float
    missed_links: dict
    first_mistake_missed_links: dict


_COUNTS = 8
"""Leading counts of a scene's row (:func:`_label_scene`); the missed links follow."""


def _label_scene(job: tuple) -> tuple[int, ...]:
    """(strokes, errors, 3+ strokes, 3+ errors, first mistakes, and those unrepresentable,
    pruned, not chosen) of one scene, then its missed links by reason over all strokes and
    at the first mistakes (:data:`models.jorge.links.WHY_NOT_PARENT`'s order)."""
    from models.jorge.fit import meeting_strokes
    from models.jorge.online import OnlineConfig, label_online
    from models.jorge.recall import missed_link_counts, missed_links, result_recall
    from models.jorge.scoring import first_errors, score, true_links

    scene, size, fps, oracle, config = job
    (strokes,) = meeting_strokes((scene,), (size,), fps=fps)
    links = true_links(strokes.strokes) if oracle else None
    res = label_online(strokes, OnlineConfig(network=config), links=links)
    wrong = set(score(strokes, res.labels).errors)
    big = [i for i, s in enumerate(strokes.strokes) if len(s.truth) >= 3]
    first = np.zeros(len(strokes.strokes), bool)
    first[list(first_errors(strokes.strokes, wrong))] = True
    lost = result_recall(strokes.strokes, res).where_lost(first)
    missed = missed_links(strokes.strokes, res.labeller.graph)
    return (len(strokes.strokes), len(wrong), len(big), sum(i in wrong for i in big), int(first.sum()),
            *(int(lost[k].sum()) for k in ("unrepresentable", "pruned", "not_chosen")),
            *missed_link_counts(missed).values(), *missed_link_counts(missed, first).values())


def mean_and_standard_error(values: np.ndarray) -> tuple[float, float]:
    """Mean of ``values`` (n,) and its standard error ``std(ddof=1) / sqrt(n)``: NaN for
    both when n = 0, and for the standard error when n = 1."""
    values = np.asarray(values, dtype=np.float64)
    if values.size == 0:
        return math.nan, math.nan
    se = float(np.std(values, ddof=1) / np.sqrt(values.size)) if values.size > 1 else math.nan
    return float(np.mean(values)), se


def _summarise(rows: np.ndarray, above: float) -> MeetingEstimate:
    """Rows (strokes, errors, 3+ strokes, 3+ errors, first mistakes, and those
    unrepresentable, pruned, not chosen, then the missed links by reason over all strokes
    and at the first mistakes), one per scene, as an estimate."""
    total = [int(v) for v in rows.sum(axis=0)]
    n, e, nb, eb, nf, *lost = total[:_COUNTS]
    r = len(WHY_NOT_PARENT)
    missed = dict(zip(WHY_NOT_PARENT, total[_COUNTS:_COUNTS + r]))
    first_missed = dict(zip(WHY_NOT_PARENT, total[_COUNTS + r:]))
    has = rows[:, 2] > 0
    big = rows[has, 3] / rows[has, 2]
    per_scene = rows[:, 1] / np.maximum(rows[:, 0], 1)
    return MeetingEstimate(
        len(rows), n, e / n if n else math.nan, *mean_and_standard_error(per_scene),
        nb, eb / nb if nb else math.nan, *mean_and_standard_error(big), int(np.sum(big > above)),
        nf, *(v / nf if nf else math.nan for v in lost), missed, first_missed,
    )


def estimate_meetings(scenes: Sequence[int], sizes: Sequence[int] = (3, 4, 5), fps: float | None = None,
                      true_links: bool = False, config: NetworkConfig | None = None, above: float = 0.35,
                      workers: int = 1) -> dict[int, MeetingEstimate]:
    """Label the SIMULATED meetings of every scene and group size (module docstring).

    Parameters
    ----------
    scenes : sequence of int
        Distinct scene seeds (scene ``s`` and its strokes are drawn with seed ``s``).
    sizes : sequence of int
        Group sizes ``k >= 2`` of the meetings.
    fps : float, optional
        Frame rate: the scene's 25 fps (default) or, lower, resampled to it (PETS2009's
        7 fps: :data:`models.jorge.strokes.PETS2009_FPS`).
    true_links : bool
        Give the labeller the true predecessors instead of the on-line link rule.
    config : NetworkConfig, optional
        The network (default: :class:`NetworkConfig`, the fitted default).
    above : float
        The 3+ error rate a scene is counted above (:attr:`MeetingEstimate.scenes_above`;
        0.35 is issue 16's held-out bar for groups of three and more).
    workers : int
        Processes labelling in parallel (1: in this process).

    Returns
    -------
    dict group size -> MeetingEstimate

    Raises
    ------
    InputError
        No scenes or a repeated one, a group size below 2, an ``fps`` that is not a
        positive number, or ``workers`` below 1 (before anything is labelled).
    """
    scenes = [int(s) for s in scenes]
    sizes = [int(k) for k in sizes]
    if not scenes or len(set(scenes)) != len(scenes):
        raise InputError(f"estimate_meetings: scenes must be distinct and at least one, got {scenes}")
    if not sizes or min(sizes) < 2 or len(set(sizes)) != len(sizes):
        raise InputError(f"estimate_meetings: sizes must be distinct group sizes >= 2, got {sizes}")
    if fps is not None and not (isinstance(fps, (int, float)) and math.isfinite(fps) and fps > 0):
        raise InputError(f"estimate_meetings: fps must be a positive number, got {fps!r}")
    check_count("estimate_meetings: workers", workers)
    from models.jorge.fit import _map

    config = NetworkConfig() if config is None else config
    jobs = [(s, k, fps, bool(true_links), config) for k in sizes for s in scenes]
    width = _COUNTS + 2 * len(WHY_NOT_PARENT)
    rows = np.array(_map(_label_scene, jobs, workers), dtype=np.int64)
    rows = rows.reshape(len(sizes), len(scenes), width)
    return {k: _summarise(rows[i], above) for i, k in enumerate(sizes)}


def main(argv: Sequence[str] | None = None) -> None:
    """``python -m models.jorge.estimate --scenes FIRST STOP [--fps 7] [--true-links]
    [--workers 2]``: the default network on SIMULATED meetings of scenes ``FIRST`` ..
    ``STOP - 1``; one JSON line, one entry per group size (:class:`MeetingEstimate`)."""
    import argparse

    from models.jorge.meeting import FPS

    ap = argparse.ArgumentParser(prog="python -m models.jorge.estimate", description=main.__doc__)
    ap.add_argument("--scenes", nargs=2, type=int, required=True, metavar=("FIRST", "STOP"),
                    help="scene seeds FIRST .. STOP - 1 (not used by any fit: models.jorge.fit.CONFIRM_SEEDS)")
    ap.add_argument("--sizes", nargs="+", type=int, default=[3, 4, 5], help="group sizes (default 3 4 5)")
    ap.add_argument("--fps", type=float, default=None, help="frame rate (default the scenes' 25 fps)")
    ap.add_argument("--true-links", action="store_true", help="label with the true links (oracle)")
    ap.add_argument("--workers", type=int, default=1, help="processes labelling in parallel")
    args = ap.parse_args(argv)
    if args.scenes[1] <= args.scenes[0]:
        raise InputError(f"--scenes {args.scenes[0]} {args.scenes[1]}: STOP must be above FIRST")
    out = estimate_meetings(range(*args.scenes), args.sizes, args.fps, args.true_links, workers=args.workers)
    print(json.dumps({"simulated": "SIMULATED meetings (models.jorge.meeting), not real data",
                      "scenes": list(args.scenes), "fps": args.fps or FPS, "true_links": args.true_links,
                      **{str(k): v._asdict() for k, v in out.items()}}))


if __name__ == "__main__":
    main()
