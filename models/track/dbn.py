"""``dbntrack track dbn MODEL.bif EVIDENCE.csv``: per-slice marginals of any discrete
two-slice DBN (formats in :mod:`models.io.dbn`).

Every method goes to the generic engines of :func:`inference.filter`, which returns the
filtered marginal of every hidden variable: ``method = "exact"`` (default) is its
structured exact filter (:class:`inference.exact.structured_filter.StructuredFilter`:
tables over the slice's frontier, never the whole interface, so ten coupled chains run
where the dense :class:`inference.exact.DBNFilter`, which this command ran before, refused
a 2^30-entry slice table; config key ``max_size``); ``auto``, ``bk``, ``particle`` and
``rbpf`` as :func:`inference.filter` says.
"""

from __future__ import annotations

import numpy as np

from dbn.dbn import TwoSliceDBN
from dbn.errors import ConfigError, FrontierTooLargeError, InputError
from models.io.dbn import read_evidence, read_states, read_two_slice_bif, write_marginals
from models.track.context import RunContext

INPUTS = ("MODEL.bif: a two-slice BIF file (variables X_0 / X_1)",
          "EVIDENCE.csv: one row per slice, one column per observed variable")  # fmt: skip
METHODS = ("exact", "auto", "bk", "particle", "rbpf")


def _filter(ctx: RunContext, dbn: TwoSliceDBN, ev: dict[str, np.ndarray], method: str, hidden,
            options: dict) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """:func:`inference.filter` of the evidence columns: ``name -> (T, K)`` filtered
    marginals of ``hidden`` and the ``(T,)`` per-slice log-likelihoods."""
    from inference import filter as generic_filter

    try:
        res = generic_filter(dbn, ev, method, list(hidden), key=ctx.key(), **options)
    except TypeError as exc:  # an option the engine does not take
        raise ConfigError(f"method {method!r}: {exc}") from None
    except FrontierTooLargeError as exc:  # its remedies name Python calls: add the CLI's
        raise FrontierTooLargeError(
            f"{exc}; from dbntrack: --method bk (Boyen-Koller), particle, rbpf or auto, or "
            '"max_size" in the --config JSON'
        ) from None
    return {n: np.asarray(res.marginals[n]) for n in hidden}, np.asarray(res.log_likelihoods)


def _check_options(method: str, config: dict) -> None:
    """A :class:`~dbn.errors.ConfigError` (``dbntrack track`` names the config file) for a
    key ``method`` does not take (:func:`inference.api.method_options`), before any
    reading; the values are the engines' to check."""
    from inference.api import method_options

    known = method_options(method)
    unknown = sorted(set(config) - known)
    if unknown:
        raise ConfigError(f"unknown config key(s) {unknown} for method {method!r}; "
                          f"valid: {sorted(known)}")  # fmt: skip


def track(ctx: RunContext, inputs: list[str], config: dict) -> dict:
    """Filter the evidence; write ``marginals.csv`` and ``marginals.png``."""
    if len(inputs) != 2:
        raise InputError(f"dbn needs 2 inputs (MODEL.bif EVIDENCE.csv), got {len(inputs)}")
    method = config.pop("method", None) or "exact"
    if method not in METHODS:
        raise InputError(f"method = {method!r}; valid: {', '.join(METHODS)}")
    _check_options(method, config)
    with ctx.timed("read"):
        dbn = read_two_slice_bif(inputs[0])
        ev = read_evidence(inputs[1], dbn, model=inputs[0])
    T = len(next(iter(ev.values())))
    hidden = [n for n in dbn.names if n not in ev or (ev[n] < 0).any()]
    with ctx.timed("filter"):
        marg, loglik = _filter(ctx, dbn, ev, method, hidden, config)
    write_marginals(ctx.outdir / "marginals.csv", dbn, marg)
    if marg:  # every variable observed at every slice: the log-likelihood, no heat map
        _plot(ctx, dbn, marg)
    summary = {
        "parameters": {"method": method, "num_slices": T, "hidden": hidden, **config},
        "outputs": ["marginals.csv", "marginals.png"] if marg else ["marginals.csv"],
        "log_likelihood": float(np.sum(loglik)),
    }
    return summary


def _plot(ctx: RunContext, dbn: TwoSliceDBN, marg: dict[str, np.ndarray]) -> None:
    names = list(marg)[:8]
    with ctx.figure("marginals.png", nrows=len(names), figsize=(8, 1.2 + 1.1 * len(names)),
                    squeeze=False, layout="constrained") as (fig, axes):  # fmt: skip
        states = {v.name: v.state_names for v in dbn.variables}
        for ax, n in zip(axes[:, 0], names):
            im = ax.imshow(marg[n].T, aspect="auto", origin="lower", vmin=0, vmax=1,
                           cmap="viridis", interpolation="nearest")  # fmt: skip
            ax.set_yticks(range(len(states[n])), states[n])
            ax.set_ylabel(n)
        axes[-1, 0].set_xlabel("slice")
        fig.colorbar(im, ax=axes[:, 0].tolist(), label="P(state | evidence so far)")


def evaluate(result: str, truth: str, model: str | None = None) -> dict:
    """Label error rate (argmax of the marginal vs the true state) and mean log-loss, over
    the slices and variables the truth CSV gives."""
    from models.io.dbn import read_marginals, row_slices
    from models.io.table import read_rows

    marg = read_marginals(result)
    header, rows = read_rows(truth, what="truth CSV", keep_blank=True)
    if not marg:
        raise InputError(f"{result}: no marginals to score")
    header, slices = row_slices(header, rows, marg)
    num_slices = min(m.shape[0] for _, m in marg.values())
    beyond = [i for i, t in enumerate(slices) if t >= num_slices]
    if beyond:  # another recording's truth: a silent partial score otherwise
        raise rows[beyond[0]].fail(f"truth has {slices[-1] + 1} slices, {result} has {num_slices}")
    errors, losses = [], []
    for col in header:
        if col not in marg:
            raise InputError(f"{truth}:1: column {col!r} has no marginals in {result}")
        states, m = marg[col]
        for t, row in zip(slices, rows):
            if row[col] == "":
                continue
            if row[col] not in states:
                raise row.fail(f"{col} = {row[col]!r} is not a state of {states}")
            k = states.index(row[col])
            errors.append(int(np.argmax(m[t]) != k))
            losses.append(-np.log(max(m[t, k], 1e-300)))
    if not errors:
        raise InputError(f"{truth}: no slice with a true state to compare")
    return {"label_error_rate": float(np.mean(errors)), "mean_log_loss": float(np.mean(losses)),
            "num_compared": len(errors)}  # fmt: skip


__all__ = ["INPUTS", "METHODS", "track", "evaluate", "read_states"]
