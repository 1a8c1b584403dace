"""``dbntrack track zajdel_adf | zajdel_learnsearch OBSERVATIONS.csv``: who is who across
non-overlapping cameras (formats in :mod:`models.io.zajdel`).

Parameters are taken from ``--config`` where given, else from the data: the camera
layout is uniform (every camera and border equally likely, for entries and transitions),
the appearance mean is the data's mean and its variance is split evenly between people
and within a person, travel times are broad guesses from the gaps between passes
(:func:`models.zajdel.learnsearch.initial_params`). Learn-search then learns them by EM.

Config keys: ``num_cameras``, ``num_borders`` (default: the largest index + 1), ``trans``
``(C, B, C, B)``, ``entry`` ``(C, B)``, ``travel_mean``, ``travel_std``, ``window``,
``p_new``, ``within_std``, ``between_std`` (ADF), ``decode`` ('chain' or 'online', ADF),
``stream_window`` and ``close_z`` (learn-search: the streaming form with that lag, one
protocol step per pass; without it one search over all passes), and the fields of
:class:`~models.zajdel.tracker.ADFConfig` / :class:`~models.zajdel.learnsearch.LearnSearchConfig`.
A key of the other runner is refused (it would do nothing), and every value is checked
for its type and range before the observations are read.
"""

from __future__ import annotations

import jax
import numpy as np

from dbn.checks import MAX_SCALE, MIN_SCALE
from dbn.errors import ConfigError, InputError
from models.io.zajdel import read_labels, read_observations, write_labels, write_partition
from models.track.context import RunContext
from models.track.options import array, build, check_keys, integer, number, text

INPUTS = ("OBSERVATIONS.csv: one row per camera pass (or enter/leave events), "
          "appearance columns a0..",)  # fmt: skip
_MODEL_KEYS = {"num_cameras", "num_borders", "trans", "entry", "travel_mean", "travel_std",
               "window", "p_new"}  # fmt: skip
_RUNNER_KEYS = {"zajdel_adf": {"within_std", "between_std", "decode"},
                "zajdel_learnsearch": {"stream_window", "close_z"}}  # fmt: skip
# Times and spreads beyond MAX_SCALE overflow once squared (a unit mistake); spreads below
# MIN_SCALE underflow once squared: within_std = 1e-300 made the ADF's prior say
# "prior.kappa = 0.0", travel_std = 1e-300 overflowed the travel z-scores.


_MAX_PATH_ENTRIES = 10**7  # the dense (C, B, C, B) transition table: 80 MB


def check_path_size(path: str, config: dict, C: int, B: int) -> None:
    """Refuse camera and border counts whose dense path table would exceed
    ``_MAX_PATH_ENTRIES`` (an id of 3000 took 35 s and 2 GB; 100000 asked for 298 GiB),
    naming the config keys or the observations file they came from."""
    entries = (C * B) ** 2
    if entries <= _MAX_PATH_ENTRIES:
        return
    what = (f"make a dense {C} x {B} x {C} x {B} path table of {entries:.3g} entries "
            f"(limit {_MAX_PATH_ENTRIES:.0e}): number the cameras and borders from 0")
    if {"num_cameras", "num_borders"} & set(config):
        raise ConfigError(f"config num_cameras / num_borders {what}")
    raise InputError(f"{path}: camera ids up to {C - 1} and border ids up to {B - 1} {what}")


def _path_and_start(table, config: dict, path: str):
    from models.zajdel.learnsearch import initial_params
    from models.zajdel.path import make_path_model

    o = table.obs
    C = integer(config, "num_cameras", int(o.camera.max()) + 1)
    B = integer(config, "num_borders", int(max(o.border_enter.max(), o.border_quit.max())) + 1)
    check_path_size(path, config, C, B)
    trans = array(config, "trans", np.full((C, B, C, B), 1.0 / (C * B)))
    entry = array(config, "entry", np.full((C, B), 1.0 / (C * B)))
    span = float(o.t_quit.max() - o.t_enter.min())
    window = number(config, "window", max(span, 1.0))
    path = make_path_model(trans, entry, 1.0, 1.0, window)
    start = initial_params(o, path, number(config, "p_new") if "p_new" in config else None)
    travel = {k: array(config, k) for k in ("travel_mean", "travel_std") if k in config}
    if travel:
        for key, v in travel.items():
            if v.shape not in ((), (1,), (C, C)):
                raise ConfigError(f"config {key}: expected a number or a {C} x {C} table, "
                                  f"got shape {v.shape}")  # fmt: skip
        mu = np.broadcast_to(travel.get("travel_mean", start.path.travel_mean), (C, C))
        sd = np.broadcast_to(travel.get("travel_std", start.path.travel_std), (C, C))
        start = start._replace(path=make_path_model(trans, entry, mu, sd, window))
    return start


def _split_config(config: dict, cls, name: str) -> tuple[dict, object]:
    """The fields of the tracker's config class ``cls`` and the instance; every key (those
    of runner ``name`` only: another runner's key would silently do nothing), type and
    range checked (before any file is read)."""
    check_keys(config, _MODEL_KEYS | _RUNNER_KEYS[name] | set(cls._fields))
    fields = {k: config[k] for k in cls._fields if k in config}
    if text(config, "decode", "chain") not in ("chain", "online"):
        raise ConfigError(f"config decode = {config['decode']!r}, expected 'chain' or 'online'")
    _check_model_options(config)
    return fields, build(cls, fields)


def _check_model_options(config: dict) -> None:
    """Ranges of the model keys (:class:`ConfigError` naming the key): counts >= 1, a
    window and spreads in [:data:`dbn.checks.MIN_SCALE`, :data:`dbn.checks.MAX_SCALE`),
    ``p_new`` in (0, 1), times below :data:`dbn.checks.MAX_SCALE`."""
    for key in ("num_cameras", "num_borders", "stream_window"):
        if key in config and integer(config, key) < 1:
            raise ConfigError(f"config {key} = {config[key]!r}: expected an integer >= 1")
    for key in ("window", "within_std", "between_std", "close_z"):
        if key in config and not MIN_SCALE <= number(config, key) < MAX_SCALE:
            raise ConfigError(f"config {key} = {config[key]!r}: expected a number in "
                              f"[{MIN_SCALE:g}, {MAX_SCALE:g})")  # fmt: skip
    if "p_new" in config and not 0 < number(config, "p_new") < 1:
        raise ConfigError(f"config p_new = {config['p_new']!r}: expected a probability in (0, 1)")
    for key, interval in (("travel_mean", "[0, "), ("travel_std", f"[{MIN_SCALE:g}, ")):
        if key not in config:
            continue
        v = array(config, key)
        above = v >= MIN_SCALE if key == "travel_std" else v >= 0
        if v.size == 0 or not np.all(above & (v < MAX_SCALE)):
            raise ConfigError(f"config {key} = {config[key]!r}: expected numbers in "
                              f"{interval}{MAX_SCALE:g})")  # fmt: skip
    if "close_z" in config and "stream_window" not in config:
        raise ConfigError("config close_z: applies to the streaming search; give stream_window too")


def _run_adf(ctx: RunContext, table, start, config: dict, fields: dict, cfg):
    import models
    from models.zajdel.api import one_per_step
    from models.zajdel.params import ZajdelParams, default_prior
    from models.zajdel.tracker import RunResult

    v = float(np.mean(np.diag(start.prior_cov))) * 2.0
    within = number(config, "within_std", np.sqrt(v / 2))
    between = number(config, "between_std", np.sqrt(v / 2))
    params = ZajdelParams(default_prior(start.mean, within, between), start.path, start.p_new)
    tracker = models.get("zajdel_adf").make(params=params, config=cfg)
    _, infos = tracker.fold(ctx.key(), one_per_step(table.obs), ctx.bar("observations"))
    stacked = [np.stack([np.asarray(x[i]) for x in infos]) for i in range(len(infos[0]))]
    res = RunResult(*stacked, counter=None, first_index=0)
    decode = text(config, "decode", "chain")
    labels = res.labels_chain() if decode == "chain" else res.labels_online()
    extra = {"decode": decode, "within_std": within, "between_std": between, **fields,
             "final_people_estimate": float(res.counter_mean[-1]),
             "log_likelihood": float(res.loglik.sum())}  # fmt: skip
    return labels, res.label_matrix(), extra


def _run_learnsearch(ctx: RunContext, table, start, config: dict, fields: dict, cfg):
    import models

    if "stream_window" in config:
        return _run_learnsearch_stream(ctx, table, start, config, fields, cfg)
    tracker = models.get("zajdel_learnsearch").make(params=start, config=cfg)
    k_init, k_step = jax.random.split(ctx.key())
    # one protocol step with every pass: one search over all of them (the adapter's
    # step takes one or more observations; one per step would search K times)
    state, info = tracker.step(k_step, tracker.init(k_init), table.obs)
    labels = np.asarray(state.labels)
    onehot = np.eye(int(labels.max()) + 1)[labels]
    return labels, onehot, {**fields, "best_log_score": float(info.log_score)}


def _run_learnsearch_stream(ctx: RunContext, table, start, config: dict, fields, cfg):
    """One protocol step per pass of the fixed-lag search; labels = committed + window."""
    import models
    from models.zajdel.data import take
    from models.zajdel.scores import canonical_labels

    window, close_z = integer(config, "stream_window"), number(config, "close_z", 5.0)
    tracker = models.get("zajdel_learnsearch").make(start, cfg, window=window, close_z=close_z)
    o = table.obs
    steps = [take(o, slice(i, i + 1)) for i in range(o.num_obs)]
    _, infos = tracker.fold(ctx.key(), steps, ctx.bar("passes"))
    info = infos[-1]
    labels = canonical_labels(np.concatenate([i.committed for i in infos] + [info.window_labels]))
    onehot = np.eye(int(labels.max()) + 1)[labels]
    extra = {**fields, "stream_window": window, "close_z": close_z}
    return labels, onehot, {**extra, "best_window_log_score": float(info.log_score)}


def check_config(name: str, config: dict) -> tuple[dict, object]:
    """The config of runner ``name`` checked (:class:`ConfigError` naming the key) before
    any file is read: its tracker-config fields and the tracker's config instance."""
    if name == "zajdel_adf":
        from models.zajdel.tracker import ADFConfig as Config
    else:
        from models.zajdel.learnsearch import LearnSearchConfig as Config
    return _split_config(config, Config, name)


def label_passes(ctx: RunContext, table, config: dict, path: str, checked=None):
    """Run tracker ``ctx.name`` on the passes of ``table`` (read from ``path``) with
    ``config`` (``checked``: :func:`check_config`'s result, else checked here). Returns
    the labels (n,), the label matrix (n, K), the run's parameters for the summary and
    the starting parameters (an :class:`~models.zajdel.learnsearch.LSParams`)."""
    fields, cfg = check_config(ctx.name, config) if checked is None else checked
    start = _path_and_start(table, config, path)
    run = _run_adf if ctx.name == "zajdel_adf" else _run_learnsearch
    return (*run(ctx, table, start, config, fields, cfg), start)


DEFAULT_PRIOR_STRENGTH = (1.0,)
"""``dbntrack fit``'s pseudo-observations per row where ``--prior-strength`` is not given
(:mod:`models.zajdel.fit`: one move spread uniformly over a row, one travel time at the
moments of every move), declared, not chosen on data: a plain fit (0) forbids every move
its training files never show."""


def fit(ctx: RunContext, train: list[str], validate: list[str], config: dict, seeds: int = 1,
        prior_strength=DEFAULT_PRIOR_STRENGTH, folds: int = 0,
        fold_by: str | None = None) -> dict:
    """``dbntrack fit``: the path model and appearance scales fitted on passes whose people
    are known (:mod:`models.track.zajdel_fit`)."""
    from models.track.zajdel_fit import fit as fit_files

    return fit_files(ctx, train, validate, config, seeds, prior_strength, folds, fold_by)


def fit_report(summary: dict) -> list[str]:
    """What ``dbntrack fit`` prints of ``summary`` (:mod:`models.track.zajdel_fit`)."""
    from models.track.zajdel_fit import fit_report as lines

    return lines(summary)


def track(ctx: RunContext, inputs: list[str], config: dict) -> dict:
    """Label every pass; write ``labels.csv``, ``partition.csv`` and ``labels.png``."""
    if len(inputs) != 1:
        raise InputError(f"{ctx.name} needs one input (OBSERVATIONS.csv), got {len(inputs)}")
    checked = check_config(ctx.name, config)
    with ctx.timed("read"):
        table = read_observations(inputs[0])
    with ctx.timed("track"):
        labels, matrix, extra, start = label_passes(ctx, table, config, inputs[0], checked)
    write_labels(ctx.outdir / "labels.csv", table, labels)
    write_partition(ctx.outdir / "partition.csv", table, labels)
    _plot(ctx, table, labels, matrix)
    params = {"num_passes": table.obs.num_obs, "num_cameras": start.path.num_cameras,
              "num_borders": start.path.num_borders, "window": float(start.path.window),
              "p_new": start.p_new, "num_tracks": int(np.unique(labels).size), **extra}  # fmt: skip
    return {"parameters": params, "outputs": ["labels.csv", "partition.csv", "labels.png"]}


def _plot(ctx: RunContext, table, labels: np.ndarray, matrix: np.ndarray) -> None:
    o = table.obs
    with ctx.figure("labels.png", ncols=2, figsize=(12, 4.5)) as (_, (ax0, ax1)):
        cmap = __import__("matplotlib").colormaps["tab20"]
        for te, tq, c, lab in zip(o.t_enter, o.t_quit, o.camera, labels):
            ax0.plot([te, tq], [c, c], lw=6, color=cmap(int(lab) % 20), solid_capstyle="butt")
            ax0.annotate(str(int(lab)), ((te + tq) / 2, c), ha="center", va="center", fontsize=7)
        ax0.set_yticks(range(int(o.camera.max()) + 1))
        ax0.set_xlabel("time")
        ax0.set_ylabel("camera")
        ax0.set_title("passes coloured by track label")
        ax1.imshow(matrix, aspect="auto", cmap="Greys", vmin=0, vmax=1, interpolation="nearest")
        ax1.set_xlabel("person / track")
        ax1.set_ylabel("pass (quit-time order)")
        ax1.set_title("label posterior" if ctx.name == "zajdel_adf" else "MAP partition")


def evaluate(result: str, truth: str) -> dict:
    """Partition accuracy q (seed 000, eqs. 7-8), pairwise precision/recall/F1 and the
    number of tracks, over the passes the truth labels (matched by pass id; a pass with
    an empty ``person`` is not scored). Every one of them must have a label in the result:
    a run labels every pass, so a result without some is another run's, or cut short."""
    from models.zajdel.metrics import num_objects, pairwise_prf, partition_accuracy

    pred = read_labels(result, "label")
    true = read_labels(truth, "person")
    missing = sorted(set(true) - set(pred))
    if missing:
        raise InputError(f"{result}: no label for {len(missing)} pass(es) that {truth} labels "
                         f"(first: {missing[:5]}); a run labels every pass")  # fmt: skip
    common = sorted(true)
    p = np.array([pred[i] for i in common])
    t = np.array([true[i] for i in common])
    prec, rec, f1 = pairwise_prf(p, t)
    return {"q": partition_accuracy(p, t), "pairwise_precision": prec, "pairwise_recall": rec,
            "pairwise_f1": f1, "num_tracks": num_objects(p), "num_people": num_objects(t),
            "num_compared": len(common)}  # fmt: skip


__all__ = ["INPUTS", "track", "evaluate", "fit", "fit_report", "label_passes",
           "check_config", "check_path_size", "DEFAULT_PRIOR_STRENGTH"]
