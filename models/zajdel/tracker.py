r"""The switching state-space tracker with assumed-density filtering (seed 002, section
1.4.3; the pointer update and projection written out in ``../shared/spec/zajdel_adf.md``).

After observation k the belief is the product of (eq. 1.22 of seed 002)

* ``q_k(c)``: the counter (number of people so far);
* ``q_k(z^(n) = j)``: the pointers, probability that slice j is the latest observation
  of person n (a sparse table: ``max_open`` slots, one per open track end j, each
  holding its ``persons_per_slot`` most probable persons);
* one NIW(theta_{j,k}) per open slice j, over that slice's appearance state x_j.

The model lives here; the algorithm in :mod:`inference.adf.driver` (chunked
``lax.scan``, capacity growth, fixed-lag revision), which runs the model's hooks
(:mod:`models.zajdel.adf_hooks`: predict = link prior x Student-t x path model,
condition = normalise, project = labels, counter, pointers and the KL projection of
the new slice's NIW mixture). Old slices follow the seed's marginal
``w_j NIW(theta_j (+) o_k) + (1 - w_j) NIW(theta_j)`` projected (``old_update="seed"``,
for the ``old_update_top`` most probable links) or stay unchanged
(``old_update="keep"``, the conditional alternative, :data:`DEFAULT_OLD_UPDATE`).

Memory and time per observation are bounded: pointer entries below ``prune_eps`` are
dropped, and when all ``max_open`` slots are taken the track end seen longest ago is
closed. Dropped pointer mass is kept per person as a "closed end" entry, so every
person's pointer row (never seen + closed + open slots) still sums to 1. With
``ADFConfig(slot_mass_eps=..., min_open=...)`` slots whose open mass is below the
threshold are closed too and the table is sized by the open slots, ``max_open`` only
a cap (:mod:`models.zajdel.adf_prune`): the cost per observation then follows the
number of track ends that carry mass, not the cap.

Decodings (:mod:`models.zajdel.decode`): on-line MAP labels and chain decoding.
Fixed-lag revision (``lag = L``, :mod:`models.zajdel.adf_lag`); ``lag = 0`` is the
plain filter.

Precision: float64 throughout, without any global jax setting: every entry point runs
inside ``jax.enable_x64(True)`` (the driver's :func:`~inference.adf.driver.x64_context`).
A run resumed from a saved state gives bit-identical results.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from dbn.checks import check_size, check_type
from dbn.errors import InputError, ModelError
from inference.adf.checkpoint import load_state, save_state
from inference.adf.driver import adf_filter, adf_filter_lag, adf_step, x64_context
from inference.adf.niw import niw_predictive_lognorm, niw_sum_digamma
from models.zajdel.adf_hooks import CLOSE_EPS
from models.zajdel.adf_lag import lag_revision
from models.zajdel.adf_prune import grow_slots, overflow_slots, tracker_hooks
from models.zajdel.adf_types import DEFAULT_OLD_UPDATE, ADFConfig, ADFInfo, ADFParams, ADFState
from models.zajdel.data import Observations, validate_observations
from models.zajdel.decode import RunResult, chain_decode
from models.zajdel.params import ZajdelParams, check_params
from models.zajdel.path import PathModel, continuation_horizon, stay_table, travel_log_norm

__all__ = [
    "ADFConfig",
    "ADFState",
    "ADFInfo",
    "RunResult",
    "ZajdelADF",
    "chain_decode",
    "DEFAULT_OLD_UPDATE",
]

_FORMAT = "zajdel-adf-state-v2"  # v2: slot_lognorm and slot_psi_next cached in the state
STAY_TABLE_SIZE = 1024  # birth-leave filtering form: log g tabulated at this many times
_NEG_INF = ("last_tq",)  # -inf: no observation yet (log-space fields are finite)


_path_lognorm = jax.jit(travel_log_norm)
"""The path's travel-time normalisers as one compiled program: op by op, each of their
few dozen operations on (num_cameras, num_cameras) arrays compiles on its own for every
new camera count (about 2 s on a CPU). The same numbers bit for bit on every model tested
(7 and 20 cameras, with and without the birth-leave prior). The prior's normaliser and
digamma sum stay op by op: scalars, compiled once per process, and compiled together
they round differently in the last bit."""


def _adf_params(params: ZajdelParams) -> ADFParams:
    """The hooks' parameter pytree (float64; call inside an x64 context)."""
    r = params.obs_dim
    pr = params.prior
    C0 = np.asarray(pr.C, float)
    L = np.linalg.cholesky(C0)
    Linv = np.linalg.solve(L, np.eye(r))
    f64 = np.float64
    path = PathModel(*(jnp.asarray(np.asarray(v, float)) for v in params.path))
    k0, e0 = jnp.asarray(f64(pr.kappa)), jnp.asarray(f64(pr.eta))
    logdet0 = jnp.asarray(f64(2.0 * np.log(np.diag(L)).sum()))
    horizon = continuation_horizon(params.path, CLOSE_EPS)
    if np.isfinite(params.path.leave_prob):
        table, step = stay_table(params.path, float(np.max(horizon)), STAY_TABLE_SIZE)
    else:
        table, step = np.zeros((1, 1, 2)), 1.0
    return ADFParams(
        a0=jnp.asarray(np.asarray(pr.a, f64)),
        k0=k0,
        e0=e0,
        C0=jnp.asarray(C0),
        Cinv0=jnp.asarray(Linv.T @ Linv),
        logdet0=logdet0,
        lognorm0=niw_predictive_lognorm(k0, e0, logdet0, r),
        psi0_next=niw_sum_digamma(e0 + 1.0, r),
        path=path,
        path_lognorm=_path_lognorm(path),
        p_new=jnp.asarray(f64(0.5 if params.p_new is None else params.p_new)),
        close_horizon=jnp.asarray(horizon),
        stay_table=jnp.asarray(table),
        stay_step=jnp.asarray(f64(step)),
    )


def _empty_info(cfg: ADFConfig) -> ADFInfo:
    return ADFInfo(
        np.zeros((0, cfg.link_out), int),
        np.zeros((0, cfg.link_out)),
        np.zeros(0),
        np.zeros((0, cfg.label_out), int),
        np.zeros((0, cfg.label_out)),
        np.zeros(0),
        np.zeros(0),
        np.zeros(0),
        np.zeros(0, int),
        np.zeros(0, bool),
    )


class ZajdelADF:
    r"""Assumed-density filter of the multi-camera tracking DBN (seed 002, section 1.4).

    Parameters
    ----------
    params : ZajdelParams (NIW prior theta_0, path model, label prior), or a
        :class:`models.zajdel.model.ZajdelModel` declaration (read for its parameters)
    config : ADFConfig (static sizes and switches)

    The trio of the house style: :meth:`init` -> state, :meth:`step` (one
    observation) -> (state, info), :meth:`run` (many observations, optional fixed lag)
    -> (state, :class:`RunResult`). States are immutable pytrees; a rejected
    observation raises before anything is computed and the state handed in is
    unchanged. :meth:`save` / :meth:`load` write a state to ``.npz`` (no pickle).
    """

    def __init__(self, params, config: ADFConfig | None = None):
        if hasattr(params, "to_params"):  # a models.zajdel.model.ZajdelModel declaration
            params.check_structure()
            params = params.to_params()
        check_params(params)
        self.params: ZajdelParams = params
        self.config = ADFConfig() if config is None else check_type("config", config, ADFConfig)
        cfg = self.config
        cfg.validate()
        if cfg.birth_leave and not (
            np.all(np.isfinite(params.path.new_rate)) and np.isfinite(params.path.leave_prob)
        ):
            raise ModelError("birth_leave: set path.new_rate and path.leave_prob first")
        self.obs_dim = params.obs_dim
        self._uniform = params.p_new is None
        self._hooks = tracker_hooks(cfg, self._uniform)
        with x64_context():
            self._model = _adf_params(params)
        empty = self.init(1, 1)._asdict()
        self._blank = {f: v[0] for f, v in empty.items() if f.startswith("slot_")}

    # -- state ---------------------------------------------------------------------
    def init(self, num_persons: int | None = None, num_slots: int | None = None) -> ADFState:
        """Empty belief (no observation yet): q_0(c = 0) = 1, no open track; a table of
        ``num_slots`` slots (default ``max_open``, or ``min_open`` when set)."""
        cfg = self.config
        N = int(num_persons or cfg.init_persons)
        S = cfg.max_open if cfg.min_open <= 0 else min(cfg.min_open, cfg.max_open)
        S, W, r = int(num_slots or S), cfg.persons_per_slot, self.obs_dim
        m = self._model
        counter = np.zeros(N + 1)
        counter[0] = 1.0
        f64, i64 = np.float64, np.int64

        def rows(value, shape, dtype=f64):  # on the host: no compiled op per new shape
            return np.broadcast_to(np.asarray(value, dtype), shape)

        host = ADFState(
            k=np.int64(0),
            last_tq=f64(-np.inf),
            counter=counter,
            never=np.ones(N),
            closed=np.zeros(N),
            slot_valid=np.zeros(S, bool),
            slot_obs=-np.ones(S, i64),
            slot_cam=np.zeros(S, i64),
            slot_bq=np.zeros(S, i64),
            slot_tq=np.zeros(S),
            slot_a=rows(m.a0, (S, r)),
            slot_kappa=rows(m.k0, (S,)),
            slot_eta=rows(m.e0, (S,)),
            slot_C=rows(m.C0, (S, r, r)),
            slot_Cinv=rows(m.Cinv0, (S, r, r)),
            slot_logdetC=rows(m.logdet0, (S,)),
            slot_lognorm=rows(m.lognorm0, (S,)),
            slot_psi_next=rows(m.psi0_next, (S,)),
            slot_person=np.zeros((S, W), i64),
            slot_pprob=np.zeros((S, W)),
        )
        with x64_context():
            return ADFState(*(jnp.asarray(v) for v in host))

    def _grow(self, st: ADFState, margin: int) -> ADFState:
        """Double the person capacity while the counter could reach it within ``margin``
        steps (the counter grows by at most one per observation); with ``min_open``,
        resize the pointer table to its open slots
        (:func:`models.zajdel.adf_prune.grow_slots`)."""
        st = grow_slots(self.config, st, self._blank)
        N = st.never.shape[0]
        top = np.flatnonzero(np.asarray(st.counter) > 0)
        cmax = int(top[-1]) if top.size else 0
        newN = N
        while cmax + margin + 1 >= newN:
            newN *= 2
        if newN == N:
            return st
        pad = newN - N
        with x64_context():  # padded on the host: no compiled op per new size
            return st._replace(
                counter=jnp.asarray(np.concatenate([np.asarray(st.counter), np.zeros(pad)])),
                never=jnp.asarray(np.concatenate([np.asarray(st.never), np.ones(pad)])),
                closed=jnp.asarray(np.concatenate([np.asarray(st.closed), np.zeros(pad)])),
            )

    def _validate(self, obs: Observations, st: ADFState) -> Observations:
        p = self.params.path
        return validate_observations(
            obs, self.obs_dim, p.num_cameras, p.num_borders, float(st.last_tq)
        )

    @staticmethod
    def _xs(obs: Observations) -> tuple:
        return (
            obs.appearance,
            obs.camera,
            obs.border_enter,
            obs.border_quit,
            obs.t_enter,
            obs.t_quit,
        )

    # -- the trio ------------------------------------------------------------------
    def step(self, state: ADFState, obs: Observations) -> tuple[ADFState, ADFInfo]:
        """One ADF update with one observation (fields scalars or length-1 arrays).

        Raises a :mod:`dbn.errors` error for bad input before any computation."""
        o = self._validate(obs, state)
        if o.num_obs != 1:
            raise InputError(f"step: expected one observation, got {o.num_obs}")
        state = self._grow(state, 1)
        x = tuple(np.asarray(v)[0] for v in self._xs(o))
        state, info = adf_step(self._hooks, self._model, state, x)
        if self._hooks.prune is not None:
            info, rep = info
            info = info._replace(num_open=rep.num_open)
        return state, info

    def run(
        self,
        obs: Observations,
        state: ADFState | None = None,
        lag: int = 0,
        progress: bool = False,
    ) -> tuple[ADFState, RunResult]:
        """Filter a batch of observations (all validated first).

        Parameters
        ----------
        obs : Observations (num_obs,)
        state : belief to continue from (default: :meth:`init`)
        lag : fixed-lag revision L >= 0 (0 = the plain filter)
        progress : tqdm bar

        Returns
        -------
        (final state, RunResult)
        """
        state = self.init() if state is None else state
        lag = check_size("lag", lag)
        o = self._validate(obs, state)
        first = int(state.k)
        cfg = self.config
        common = dict(
            chunk=cfg.chunk,
            grow=self._grow,
            empty_info=_empty_info(cfg),
            progress=progress,
            overflow=self._overflow,
        )
        if lag > 0:
            out = adf_filter_lag(
                self._hooks, self._model, state, self._xs(o), int(lag), self._reviser(o), **common
            )
        else:
            out = adf_filter(self._hooks, self._model, state, self._xs(o), **common)
        return out.state, self._result(out.infos, out.records, first, out.reports)

    def _overflow(self, before: ADFState, after: ADFState, reports):
        """The driver's ``overflow`` hook (:func:`models.zajdel.adf_prune.overflow_slots`)."""
        return overflow_slots(self.config, self._blank, before, reports)

    def _reviser(self, o: Observations):
        """The fixed-lag ``revise`` hook over the run's observations ``o``."""

        def revise(state, k, n, scores):
            logw, logw0, lp_win = scores
            idx = np.arange(k, k + n)
            w, w0, lz = lag_revision(
                self.params, self.config, state, o, idx, logw[:n], logw0[:n], float(lp_win)
            )
            # host arrays: the driver's compiled projection takes them as they are (the
            # same float64 / bool types jnp.asarray gave, without an eager op for each)
            return (
                np.asarray(w, np.float64),
                np.float64(w0),
                np.float64(lz),
                np.bool_(not np.isfinite(lz)),
            )

        return revise

    def _result(self, infos: ADFInfo, records: list, first: int, reports=None) -> RunResult:
        counter = None
        if records:
            width = max(np.shape(c)[1] for c in records)
            counter = np.concatenate(
                [np.pad(c, ((0, 0), (0, width - np.shape(c)[1]))) for c in records]
            )
        pruned = None
        if reports is not None:
            infos = infos._replace(num_open=np.asarray(reports.num_open, int))
            pruned = np.asarray(reports.pruned_mass)
        return RunResult(*(np.asarray(v) for v in infos), counter, first, pruned)

    # -- persistence ---------------------------------------------------------------
    def save(self, state: ADFState, path) -> None:
        """Write a state to an ``.npz`` file (arrays, config, version, checksum; no pickle)."""
        save_state(path, state, _FORMAT, config=self._checkpoint_config(), neg_inf=_NEG_INF)

    def load(self, path) -> ADFState:
        """Read a state written by :meth:`save`; a file saved under another configuration
        (or obs_dim), damaged, or holding NaN/inf is a :class:`~dbn.errors.CheckpointError`."""
        cfg = self._checkpoint_config()
        return load_state(path, ADFState, _FORMAT, config=cfg, neg_inf=_NEG_INF)

    def _checkpoint_config(self) -> dict:
        """What a saved state must match (the config and the appearance dimension)."""
        return {"config": self.config._asdict(), "obs_dim": int(self.obs_dim)}
