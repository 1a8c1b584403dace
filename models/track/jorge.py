"""``dbntrack track jorge BOXES`` (or ``REGIONS.jsonl``): group/person labels of the strokes
of a video (seed 004; formats in :mod:`models.io.jorge` and :mod:`models.io.jorge_regions`).

A regions file gives the strokes of your own low-level tracker (boxes per frame, dominant
colours, optionally the links and the truth): they are checked against the network, then
labelled as they are, nothing simulated (the stroke builder's settings and ``view`` do
not apply; ``--seed`` changes nothing), and ``eval`` scores them against the same file.

The boxes (CAVIAR / PETS2009 XML or MOTChallenge; an ETH / UCY ``obsmat`` file's tracks in
metres through a SIMULATED :class:`~models.jorge.eth.ObliqueView`, the default one or the
config's ``view``, which the run notes and ``simulated_view`` in the summary records) go
through the simulated low-level tracker :func:`models.jorge.strokes.build_strokes`
(regions of overlapping boxes followed without a break; occlusion gaps and dominant colours
simulated from ``--seed``, as in the benchmark), then the registry's on-line labeller, one
stroke per protocol step, and its final re-identification pass. Config keys: the fields of
:class:`~models.jorge.strokes.StrokeConfig`, ``fps`` (else the file's rate,
:mod:`models.io.jorge`; ``fps_source`` in the summary says which), ``split_cover``
(true or false, default true: the split prior that prefers partitions,
:data:`models.jorge.config.FITTED_SPLIT_COVER`, on by default since issue 16's
twenty-second round and normalised since the twenty-third, ``LabelParams.split_normalise``;
false: seed 004's eq. 5 alone), for an obsmat file ``view`` (an object of
:class:`~models.jorge.eth.ObliqueView` fields, e.g. ``{"tilt_deg": 60}``), and the
labeller's settings laid over its fitted defaults (:func:`labeller_config`): ``network``
(scalar fields of :class:`~models.jorge.network.NetworkConfig`, e.g.
``{"max_gap_frames": 45}``), ``labels`` (of :class:`~models.jorge.labels.LabelParams`
over :data:`~models.jorge.config.FITTED_LABELS`, e.g. ``{"max_group_size": 6}``) and
``online`` (of :class:`~models.jorge.online.OnlineConfig`, e.g. ``{"max_active": 24}``);
a fitted table is set as nested lists (as ``dbntrack fit jorge`` writes it,
:mod:`models.track.jorge_fit`) or switched off, ``[]``.

``strokes.csv``'s header keeps the seed, the stroke settings, the view and the frame rate,
so ``dbntrack eval`` (and ``--truth``) rebuilds the same strokes from the box file; its
``parents`` column keeps the links, from which ``eval`` tells who came into a region without
one (:func:`models.jorge.recall.missed_links`), replaying the link rule of the network the
header's ``# network=`` line (the config's ``network`` fields, where it has any) sets.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from dbn.errors import ConfigError, InputError
from models.io.jorge import (
    MOT_DEFAULT_FPS,
    frame_rate_source,
    is_mot,
    is_obsmat,
    read_boxes,
    read_stroke_rows,
    read_strokes_header,
    write_mot_tracks,
    write_strokes,
)
from models.io.jorge_regions import check_regions, is_regions, read_regions
from models.jorge.eth import ObliqueView
from models.track.context import RunContext
from models.track.options import build, check_keys, flag, number, override

LABELLER_KEYS = ("network", "labels", "online")
"""Config keys of the labeller's settings (:func:`labeller_config`)."""
INPUTS = ("BOXES: CAVIAR CVML .xml, PETS2009 .xml, MOTChallenge gt.txt or ETH/UCY obsmat.txt, "
          "or REGIONS.jsonl: your own tracker's strokes (may be .gz)",)


class Options(NamedTuple):
    """A jorge config read (:func:`read_options`): ``own`` (its keys that are not the
    stroke builder's), the split cover flag, the labeller's ``overrides`` (the
    :data:`LABELLER_KEYS` objects it has), the labeller's config they give and the
    config's frame rate (None: the file's)."""

    own: frozenset
    split_cover: bool
    overrides: dict
    online: Any
    fps: float | None


def read_options(config: dict) -> Options:
    """The config of ``dbntrack track jorge`` and ``fit``, checked before any file is read
    (an unknown key, a bad value: a :class:`ConfigError` naming it)."""
    from models.jorge.strokes import StrokeConfig

    own = frozenset({"fps", "split_cover", "view", *LABELLER_KEYS})
    check_keys(config, set(StrokeConfig.__dataclass_fields__) | own)
    split_cover = flag(config, "split_cover", True)
    overrides = {k: config[k] for k in LABELLER_KEYS if k in config}
    online = labeller_config(split_cover, overrides)
    fps = number(config, "fps") if "fps" in config else None
    if fps is not None and not fps > 0:
        raise ConfigError(f"config fps = {fps!r}: expected a number > 0")
    return Options(own, split_cover, overrides, online, fps)


def builder_keys(config: dict, own: frozenset) -> list[str]:
    """The config's stroke-builder settings (keys outside ``own``, and ``view``), which
    apply to box files only."""
    return sorted(set(config) - own) + (["view"] if "view" in config else [])


def track(ctx: RunContext, inputs: list[str], config: dict) -> dict:
    """Label the strokes; write ``strokes.csv``, ``tracks.txt`` and ``strokes.png``."""
    if len(inputs) != 1:
        raise InputError(f"jorge needs one box or regions file, got {len(inputs)} inputs")
    opt = read_options(config)
    online, overrides = opt.online, opt.overrides
    read = _regions if is_regions(inputs[0]) else _boxes
    strokes, steps, fps, params, head = read(ctx, inputs[0], config, opt.own, opt.fps, online)
    labels, parents = label_steps(ctx, online, steps, fps)
    network = {k: getattr(online.network, k) for k in overrides.get("network", {})}
    write_strokes(ctx.outdir / "strokes.csv", strokes, labels, parents=parents, fps=fps,
                  network=network or None, **head)  # fmt: skip
    write_mot_tracks(ctx.outdir / "tracks.txt", strokes, labels)
    _plot(ctx, strokes, labels)
    params = {"num_strokes": len(strokes), "num_groups": sum(len(s.truth) > 1 for s in strokes),
              "fps": fps, **params, "split_cover": opt.split_cover,
              **_set_fields(online, overrides)}  # fmt: skip
    return {"parameters": params, "outputs": ["strokes.csv", "tracks.txt", "strokes.png"]}


def fit(ctx: RunContext, train: list[str], validate: list[str], config: dict,
        seeds: int = 1, prior_strength: float | list[float] = 0.0, folds: int = 0,
        fold_by: str | None = None) -> dict:
    """``dbntrack fit jorge``: the network's parameters fitted on your files
    (:func:`models.track.jorge_fit.fit`)."""
    from models.track.jorge_fit import fit as fit_files

    return fit_files(ctx, train, validate, config, seeds, prior_strength, folds, fold_by)


def fit_report(summary: dict) -> list[str]:
    """What ``dbntrack fit`` prints of ``summary`` (:func:`models.track.jorge_fit.fit_report`)."""
    from models.track.jorge_fit import fit_report as lines

    return lines(summary)


def label_steps(ctx: RunContext, online, steps: list, fps: float,
                phase: str | None = "label") -> tuple[list, list]:
    """The registry's labeller over ``steps`` (strokes, or :class:`LinkedStroke`), then its
    re-identification pass, timed as ``phase`` (None: the caller times it): ``(labels,
    parents)``, one per stroke."""
    import contextlib

    import models

    tracker = models.get("jorge").make(online, fps=fps)
    timed = contextlib.nullcontext() if phase is None else ctx.timed(phase)
    with timed:  # fold: one labeller stepped in place (run's copies are quadratic)
        state, _ = tracker.fold(ctx.key(), steps, ctx.bar("strokes"))
        final = state.labeller.finish()  # the re-identification pass (the batch's last step)
    labels = [final[k] for k in range(len(steps))]
    return labels, [node.parents for node in state.labeller.graph.nodes]


def _boxes(ctx: RunContext, path: str, config: dict, own: set, fps: float | None, online):
    """Strokes built from a box file by the SIMULATED low-level tracker: ``(strokes, steps,
    fps, parameters, header)``."""
    from models.jorge.strokes import StrokeConfig, build_strokes

    with ctx.timed("read"):
        truth, scfg, view, source = read_box_truth(ctx, path, config, own, fps)
        strokes = build_strokes(ctx.seed, truth, scfg)
    params = {"fps_source": source, "num_frames": truth.num_frames, "sequence": truth.name,
              "simulated_view": None if view is None else repr(view), "input": "boxes",
              **{k: getattr(scfg, k) for k in StrokeConfig.__dataclass_fields__}}  # fmt: skip
    fps = truth.fps if fps is None else fps
    return strokes, list(strokes), fps, params, {"seed": ctx.seed, "view": view}


def read_box_truth(ctx: RunContext, path: str, config: dict, own: set, fps: float | None):
    """A box file's people and the SIMULATED stroke builder's settings (the config's keys
    outside ``own``): ``(truth, stroke config, view, fps source)``; notes an assumed frame
    rate and a SIMULATED camera."""
    from models.jorge.strokes import StrokeConfig

    scfg = build(StrokeConfig, {k: v for k, v in config.items() if k not in own})
    view = _view(config, path)
    truth = read_boxes(path, view)
    source = "config" if fps is not None else frame_rate_source(path)
    if source.startswith("assumed"):
        ctx.note(source)
    if view is not None:
        ctx.note(f"tracks in metres: boxes from a SIMULATED camera, {view!r}")
    return truth, scfg, view, source


def _regions(ctx: RunContext, path: str, config: dict, own: set, fps: float | None, online):
    """Strokes of your own low-level tracker (:mod:`models.io.jorge_regions`), labelled as
    they are, with the file's links where it has them: ``(strokes, steps, fps, parameters,
    header)``. The stroke builder's settings and ``view`` do not apply (a
    :class:`ConfigError`); the file is checked against the network before any labelling."""
    with ctx.timed("read"):
        regions, fps, source = read_checked_regions(ctx, path, config, own, fps, online)
    strokes = regions.strokes
    steps = linked_steps(strokes, regions.parents)
    params = {"fps_source": source, "input": "regions",
              "links": "rule" if regions.parents is None else "file",
              "num_frames": int(max(s.end for s in strokes) - strokes[0].start + 1),
              "sequence": Path(path).name}  # fmt: skip
    return strokes, steps, fps, params, {"seed": None, "view": None, "source": "regions"}


def read_checked_regions(ctx: RunContext, path: str, config: dict, own: set,
                         fps: float | None, online):
    """A regions file, checked against ``online``'s network before any labelling: ``(regions,
    fps, fps source)``. A stroke-builder setting (a config key outside ``own``, or
    ``view``) is a :class:`ConfigError`: they apply to box files only."""
    builder = builder_keys(config, own)
    if builder:
        raise ConfigError(f"config {builder}: stroke-builder settings apply to box files, not "
                          f"to a regions file's strokes")  # fmt: skip
    regions = read_regions(path)
    if fps is not None:
        source = "config"
    elif regions.fps is not None:
        fps, source = regions.fps, "file"
    else:
        fps = MOT_DEFAULT_FPS
        source = f"assumed {fps:g} fps (no '# fps=' line in {path})"
        ctx.note(source)
    check_regions(regions, online.network, fps)
    return regions, fps, source


def linked_steps(strokes: list, links: list | None) -> list:
    """The labeller's steps: the strokes, each with its links
    (:class:`~models.jorge.api.LinkedStroke`) where ``links`` (one per stroke) is given."""
    from models.jorge.api import LinkedStroke

    return list(strokes) if links is None else [LinkedStroke(s, p) for s, p in zip(strokes, links)]


def require_truth(regions, why: str) -> None:
    """Refuse a regions file without the people of every stroke (``truth``), naming the
    first line without, for ``why`` (e.g. ``"scoring"``)."""
    if not regions.has_truth:
        k = next(i for i, s in enumerate(regions.strokes) if not s.truth)
        raise InputError(f"{regions.path}:{regions.lines[k]}: stroke {k} has no truth: {why} "
                         "needs the people of every stroke (a 'truth' list on every line)")


def _view(config: dict, path: str) -> ObliqueView | None:
    """The SIMULATED camera of an obsmat file (the config's ``view`` fields, else the
    default); ``None`` for image boxes, where a ``view`` key is a :class:`ConfigError`."""
    if not is_obsmat(path):
        if "view" in config:
            raise ConfigError("config view: applies only to an ETH / UCY obsmat file (tracks in metres)")
        return None
    fields = config.get("view", {})
    if not isinstance(fields, dict):
        raise ConfigError(f"config view = {fields!r}: expected an object of ObliqueView fields")
    try:
        return _oblique_view(fields)
    except ConfigError as exc:
        raise ConfigError(f"config view: {exc}") from None


def _oblique_view(fields: dict) -> ObliqueView:
    """An :class:`ObliqueView` from a config's or a strokes CSV header's fields (a
    :class:`ConfigError` naming an unknown or bad one)."""
    check_keys(fields, ObliqueView.__dataclass_fields__)
    return build(ObliqueView, fields)


def labeller_config(split_cover: bool = True, overrides: dict | None = None):
    """The on-line labeller's :class:`~models.jorge.online.OnlineConfig`: the fitted
    defaults (split cover on; off if asked) with the config's ``network``, ``labels`` and
    ``online`` objects laid over the :class:`~models.jorge.network.NetworkConfig`, its
    :class:`~models.jorge.labels.LabelParams` and the ``OnlineConfig``
    (:func:`models.track.options.override`: scalar fields, and tables set or switched off;
    a :class:`ConfigError` naming ``network.FIELD`` etc. for a bad one)."""
    from dataclasses import replace

    from models.jorge.network import FITTED_LABELS, NetworkConfig
    from models.jorge.online import OnlineConfig

    over = {} if overrides is None else overrides
    labels = override(FITTED_LABELS, over.get("labels", {}), "labels")
    if not split_cover:
        labels = replace(labels, split_cover=())
    network = override(NetworkConfig(labels=labels), over.get("network", {}), "network")
    return override(OnlineConfig(network=network), over.get("online", {}), "online")


def _set_fields(online, overrides: dict) -> dict:
    """The labeller's fields the config set, by key (``{"network": {...}, ...}``, each
    empty where the config has none), with the values the run used."""
    where = {"network": online.network, "labels": online.network.labels, "online": online}
    return {k: {f: getattr(where[k], f) for f in overrides.get(k, {})} for k in LABELLER_KEYS}


def _plot(ctx: RunContext, strokes, labels) -> None:
    import matplotlib

    tab = matplotlib.colormaps["tab10"]
    palette = [tab(i) for i in range(10) if i != 7]  # tab10 without its grey
    singles = sorted({o for lab in labels if len(lab) == 1 for o in lab})
    colour_of = {o: palette[i % len(palette)] for i, o in enumerate(singles)}
    with ctx.figure("strokes.png", ncols=2, figsize=(13, 5)) as (_, (ax0, ax1)):
        for s, lab in zip(strokes, labels):
            colour = colour_of[min(lab)] if len(lab) == 1 else "0.3"
            ax0.plot([s.start, s.end], [s.index, s.index], color=colour, lw=3)
            ax0.annotate(",".join(map(str, sorted(lab))), (s.end, s.index), fontsize=6,
                         xytext=(2, -2), textcoords="offset points")  # fmt: skip
            ax1.plot(
                s.positions[:, 0], s.positions[:, 1], color=colour, lw=1.5 if len(lab) == 1 else 3
            )
        ax0.set_xlabel("frame")
        ax0.set_ylabel("stroke")
        ax0.set_title("strokes and their labels (object ids; grey: groups)")
        ax1.invert_yaxis()
        ax1.set_aspect("equal")
        ax1.set_title("region centres (image coordinates)")


def iou_distance(a: np.ndarray, b: np.ndarray, max_distance: float = 0.5) -> np.ndarray:
    """``1 - IoU`` of boxes ``a`` (n, 4) and ``b`` (m, 4) as ``(left, top, w, h)``; NaN
    (no match) above ``max_distance`` (motmetrics' convention; its own ``iou_matrix``
    calls ``np.asfarray``, gone in numpy 2)."""
    lo = np.maximum(a[:, None, :2], b[None, :, :2])
    hi = np.minimum(a[:, None, :2] + a[:, None, 2:], b[None, :, :2] + b[None, :, 2:])
    inter = np.prod(np.clip(hi - lo, 0, None), axis=-1)
    union = np.prod(a[:, 2:], -1)[:, None] + np.prod(b[:, 2:], -1)[None] - inter
    d = 1.0 - inter / union
    return np.where(d > max_distance, np.nan, d)


def _mot(result: str, truth: str) -> dict:
    """MOTA, IDF1, ... of MOTChallenge tracks against the truth boxes (motmetrics, IoU)
    over the truth's frames (:func:`_scored_frames`): a box in one of them that matches
    no person is a false positive. A MOT16/17/20 truth's pedestrians are scored, and a box
    matched to one of its distractors (:func:`on_distractors`) is dropped first. An
    obsmat truth is seen through the view in the header of the ``strokes.csv`` beside the
    tracks (the same run's), else the default one."""
    import motmetrics as mm

    from models.io.jorge import read_mot, read_mot_truth

    if is_regions(truth):
        raise InputError(f"{truth}: tracks are scored against boxes of each person (a box "
                         "file); a regions file has the regions' boxes only")  # fmt: skip
    view, ignored = None, {}
    beside = Path(result).with_name("strokes.csv")  # the same run's view, for an obsmat truth
    if is_obsmat(truth) and beside.is_file():
        view = _settings(str(beside), read_strokes_header(beside))[1]
    pred = read_mot(result)
    if is_mot(truth):
        ref, ignored = read_mot_truth(truth)
    else:
        ref = read_boxes(truth, view)
    acc = mm.MOTAccumulator(auto_id=True)
    pf = {int(f): i for i, f in enumerate(pred.frames)}
    rf = {int(f): i for i, f in enumerate(ref.frames)}
    absent = np.full((ref.ids.size, 4), np.nan)

    def tlwh(b):
        return np.column_stack([b[:, 0] - b[:, 2] / 2, b[:, 1] - b[:, 3] / 2, b[:, 2], b[:, 3]])

    for f in _scored_frames(rf, pf, is_mot(truth)):
        rb = ref.boxes[rf[f]] if f in rf else absent
        ok = ~np.isnan(rb[:, 0])
        pb = pred.boxes[pf[f]] if f in pf else np.zeros((0, 4))
        pok = ~np.isnan(pb[:, 0])
        if f in ignored:
            pok[pok] = ~on_distractors(tlwh(pb[pok]), *ignored[f])
        d = iou_distance(tlwh(rb[ok]), tlwh(pb[pok]))
        acc.update(ref.ids[ok].tolist(), pred.ids[pok].tolist() if f in pf else [], d)
    mh = mm.metrics.create()
    s = mh.compute(acc, metrics=["mota", "idf1", "num_switches", "precision", "recall"], name="x")
    return {k: float(s[k].iloc[0]) for k in s.columns}


def on_distractors(boxes: np.ndarray, truth: np.ndarray, distractor: np.ndarray) -> np.ndarray:
    """Which result ``boxes`` (n, 4) of one frame a MOTChallenge evaluation drops: those
    that the one-to-one matching with every ground-truth box of the frame, ``truth`` (m, 4)
    (all ``(left, top, w, h)``), maximising the IoU among pairs with IoU >= 0.5, pairs with
    a ``distractor`` (m,) box. Returns a bool array (n,)."""
    from scipy.optimize import linear_sum_assignment

    iou = 1.0 - iou_distance(truth, boxes)  # NaN where IoU < 0.5: no pair
    iou = np.where(np.isnan(iou), 0.0, iou)
    rows, cols = linear_sum_assignment(iou, maximize=True)
    hit = (iou[rows, cols] > 0) & distractor[rows]
    out = np.zeros(len(boxes), bool)
    out[cols[hit]] = True
    return out


def _scored_frames(truth_frames, result_frames, mot: bool) -> list[int]:
    """The frames ``_mot`` scores: those the truth lists (XML lists every frame, obsmat
    its annotated ones) and, for MOTChallenge truth, where an empty frame has no row,
    also the result's frames inside the truth's span. Frames outside are not annotated."""
    frames = set(truth_frames)
    if mot and frames:
        lo, hi = min(frames), max(frames)
        frames |= {f for f in result_frames if lo <= f <= hi}
    return sorted(frames)


def _settings(result: str, head: dict):
    """The :class:`StrokeConfig` and view that the header ``head`` of the strokes CSV
    ``result`` records (:func:`read_strokes_header`; defaults where a file of an earlier
    version has none); an :class:`InputError` naming the file."""
    from models.jorge.strokes import StrokeConfig

    try:
        scfg = build(StrokeConfig, head.get("strokes", {}))
        view = _oblique_view(head["view"]) if "view" in head else None
    except ConfigError as exc:
        raise InputError(f"{result}: header: {exc}") from None
    return scfg, view


def evaluate(result: str, truth: str) -> dict:
    """``strokes.csv``: label error rate LE / NT (seed 004, Table 3; objects matched to
    people one to one, as the benchmark's ``error_rate``) against the truth boxes' strokes
    rebuilt with the file's seed, the same over the strokes of three or more people
    (``error_rate_group_3plus``, null without any, and ``strokes_group_3plus``, as the
    benchmark's), the number of first mistakes (errors not carried from an earlier one,
    :func:`models.jorge.scoring.first_errors`) and, where the file has its links (a
    ``parents`` column), the people seen before who came into a stroke without a link,
    by the link rule's reason, over all strokes and at the first mistakes (``missed_links``,
    ``first_mistake_missed_links``, as the benchmark's). ``tracks.txt`` (MOTChallenge):
    MOTA, IDF1 (motmetrics)."""
    from types import SimpleNamespace

    from models.jorge.scoring import first_errors, group_errors, score
    from models.jorge.strokes import build_strokes

    if not str(result).endswith(".csv"):
        return _mot(result, truth)
    head = read_strokes_header(result)
    rows = read_stroke_rows(result)
    network = _network(result, head)
    if is_regions(truth):
        strokes, made = _truth_regions(truth), ""
    else:
        seed = head.get("seed")
        if head.get("input") == "regions":
            raise InputError(f"{result}: labels of a regions file's strokes (# input=regions): "
                             f"score them against that file, not the boxes of {truth}")  # fmt: skip
        if seed is None:
            raise InputError(f"{result}:1: no '# seed=S' line (written by dbntrack track jorge)")
        scfg, view = _settings(result, head)
        strokes = build_strokes(seed, read_boxes(truth, view), scfg)
        made = f"with seed {seed} and the file's stroke settings"
    _check_rows(result, truth, made, rows, strokes)
    shown = [SimpleNamespace(index=r["stroke"], truth=s.truth) for r, s in zip(rows, strokes)]
    sc = score(shown, [r["label"] for r in rows])
    wrong_big, big = group_errors(strokes, sc.errors)
    first = first_errors(list(strokes), sc.errors)
    out = {"error_rate": sc.error_rate, "label_errors": sc.label_errors,
           "num_strokes": sc.num_strokes, "id_switches": sc.id_switches,
           "error_rate_group_3plus": wrong_big / big if big else float("nan"),
           "strokes_group_3plus": big, "first_mistakes": len(first)}  # fmt: skip
    if all(r["parents"] is not None for r in rows):
        fps = head.get("fps", getattr(strokes, "fps", MOT_DEFAULT_FPS))
        out.update(_missed_links(result, rows, strokes, fps, first, network))
    return out


def _check_rows(result: str, truth: str, made: str, rows: list, strokes) -> None:
    """The rows of ``result`` are the ``strokes`` of ``truth`` (rebuilt from its boxes, or
    read from a regions file: ``made`` says how, ``""`` for a regions file), in order (an
    :class:`InputError` naming the first that is not)."""
    what = "boxes (or settings)" if made else "strokes"
    if len(strokes) != len(rows):
        raise InputError(f"{result}: {len(rows)} strokes, but {truth} gives {len(strokes)} "
                         f"{made or 'strokes'}")  # fmt: skip
    for k, (r, s) in enumerate(zip(rows, strokes)):
        if r["stroke"] != s.index:  # rows are matched to strokes by position
            raise InputError(f"{result}: row {k + 1} is stroke {r['stroke']}, but stroke "
                             f"{s.index} belongs there (rows in stroke order, as "
                             "written)")  # fmt: skip
        if (r["start"], r["end"]) != (s.start, s.end):
            raise InputError(f"{result}: stroke {r['stroke']} spans frames {r['start']}-{r['end']}, but "
                             f"{truth} gives {s.start}-{s.end}{' ' + made if made else ''}: "
                             f"not the {what} this result was made from")  # fmt: skip


def _truth_regions(truth: str) -> list:
    """The strokes of a regions file scored against: each must have its ``truth``."""
    regions = read_regions(truth)
    require_truth(regions, "scoring")
    return regions.strokes


def _network(result: str, head: dict):
    """The labeller's :class:`~models.jorge.network.NetworkConfig` that the header ``head``
    of the strokes CSV ``result`` records (``# network=``: the fields the run's config
    set; the default network where the file has none); an :class:`InputError` naming the
    file."""
    try:
        return labeller_config(overrides={"network": head.get("network", {})}).network
    except ConfigError as exc:
        raise InputError(f"{result}: header: {exc}") from None


def _missed_links(result: str, rows: list, strokes, fps: float, first, network) -> dict:
    """``missed_links`` and ``first_mistake_missed_links`` (:func:`evaluate`): the file's
    links laid on the rebuilt strokes in a graph (links only) of the run's ``network``,
    whose rule :func:`models.jorge.recall.missed_links` replays at the labeller's frame
    rate ``fps`` (links it would have made that the file lacks count as
    ``given_links``). Links no graph can hold (a parent that does not end before the
    stroke starts, or one with ``max_children`` children already) are refused, naming
    the stroke."""
    from models.jorge.network import LabelGraph
    from models.jorge.recall import missed_link_counts, missed_links

    graph = LabelGraph(network, with_domains=False, fps=fps)
    for r, s in zip(rows, strokes):
        try:
            graph.add_stroke(s, r["parents"])
        except InputError as exc:
            raise InputError(f"{result}: {exc}") from None
    missed = missed_links(strokes, graph)
    mask = np.zeros(len(strokes), bool)
    mask[list(first)] = True
    return {"missed_links": missed_link_counts(missed),
            "first_mistake_missed_links": missed_link_counts(missed, mask)}


__all__ = ["INPUTS", "LABELLER_KEYS", "Options", "builder_keys", "evaluate", "fit",
           "label_steps", "labeller_config", "linked_steps", "read_box_truth",
           "read_checked_regions", "read_options", "require_truth", "track"]
