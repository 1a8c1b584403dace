r"""Configuration, belief, step report and parameters of the Zajdel ADF tracker
(seed 002, section 1.4.3; ``../shared/spec/zajdel_adf.md``). The step maths is in
:mod:`models.zajdel.adf_hooks`, the driver in :mod:`inference.adf.driver`."""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp
import numpy as np

from dbn.checks import check_number_fields
from dbn.errors import ModelError
from models.zajdel.path import PathModel

__all__ = ["ADFConfig", "ADFState", "ADFInfo", "ADFParams", "DEFAULT_OLD_UPDATE"]

#: Old-slice update kept by default. Measured against the exact filtering oracle on the
#: first 8 observations of 80 default office scenarios (seeds 1000-1079, 640
#: observations): "keep" agreed with the exact MAP link on 96.3 % of observations, mean
#: total-variation distance of the link posteriors 0.029; the seed's projection 95.8 %,
#: 0.032. "keep" is the more accurate here, costs no extra projections, and gave the
#: higher pairwise F1 on the default scenario (0.84 vs 0.76), so it is the default. The
#: benchmark reports both (``oracle_*`` and ``oracle_*_seed_update``).
DEFAULT_OLD_UPDATE = "keep"

#: What the factorised belief costs against the exact oracle (issue 17; K = 8, the 80
#: scenarios above, "keep"): MAP links agree on 96.25 % (94.4 % on the first 20
#: scenarios), exact at k = 0, 1; the link-posterior distance grows with k (mean TV
#: 0.010 at k = 2, 0.033 at k = 4, 0.069 at k = 7): each step's projection (the new
#: slice's NIW mixture onto one NIW, labels and pointers onto independent persons)
#: compounds. Disagreements are mostly near ties (exact margin between the two best
#: links <= 0.2: 81 % agreement; > 0.2: 97.9 %; > 0.3: 98.6 %). Coupling the open ends
#: with the count (after every step, each person's pointer row rescaled to the
#: counter's q(c > n), so that "person n exists" and "n has an open end" agree, which
#: the independent-person update breaks) changed nothing measurable: 96.25 % on 80
#: scenarios, 93.75 % on 20 (one observation flips), mean TV 0.0291 both, counter mean
#: within 0.161 of the exact one both; it was not kept. The disagreement at k = 2
#: (where only the first NIW projection acts) points at the appearance projection.


class ADFConfig(NamedTuple):
    """Static configuration (sizes that shape arrays and switches).

    Attributes
    ----------
    max_open : number of slots of the pointer table (cap on open track ends)
    persons_per_slot : persons kept per slot (sparse pointer row width)
    prune_eps : pointer entries below this are dropped
    slot_mass_eps : slots whose open mass (sum of their pointer entries) is below this
        are closed after each step (0: off); see :mod:`models.zajdel.adf_prune`
    min_open : 0 (the table always has ``max_open`` slots) or the smallest table size:
        the table then follows the number of open slots, ``max_open`` only a cap
        (:mod:`models.zajdel.adf_prune`)
    old_update : "seed" or "keep" (see :data:`DEFAULT_OLD_UPDATE`)
    old_update_top : number of most probable links whose slices get the seed update
    mix_top : links (most probable first) whose components enter the new slice's NIW
        mixture (the others' weights are negligible and dropped; exact when
        ``max_open <= mix_top``)
    link_out, label_out : how many top links / labels are recorded per observation
    chunk : observations per compiled scan chunk in :meth:`ZajdelADF.run`
    init_persons : initial person capacity (grows by doubling, each growth recompiles)
    lag_branch : links per observation enumerated by the fixed-lag revision
    record_counter : also record the full counter distribution of every step
    birth_leave : False (default, the spec's label prior: uniform or ``p_new``), True
        or "filter": the birth-leave link prior of :mod:`models.zajdel.adf_hooks` (new
        people arrive at ``path.new_rate`` per unit time, a pass is a person's last
        with probability ``path.leave_prob``, a track end that can no longer be
        continued is closed), in its joint (True) or filtering ("filter") form
        (:mod:`models.zajdel.birth_leave`)
    """

    max_open: int = 256
    persons_per_slot: int = 16
    prune_eps: float = 1e-10
    slot_mass_eps: float = 0.0
    min_open: int = 0
    old_update: str = DEFAULT_OLD_UPDATE
    old_update_top: int = 8
    mix_top: int = 32
    link_out: int = 16
    label_out: int = 16
    chunk: int = 128
    init_persons: int = 512
    lag_branch: int = 5
    record_counter: bool = False
    birth_leave: bool | str = False

    def validate(self) -> None:
        """Raise :class:`~dbn.errors.ModelError` naming the first field the filter cannot
        run with (sizes, thresholds, switches); called by the tracker and the CLI."""
        check_number_fields(self, ModelError)
        if self.old_update not in ("seed", "keep"):
            raise ModelError(f"old_update = {self.old_update!r}: must be 'seed' or 'keep'")
        for name in ("max_open", "persons_per_slot", "chunk", "init_persons", "mix_top",
                     "link_out", "label_out", "lag_branch"):
            if getattr(self, name) < 1:
                raise ModelError(f"{name} = {getattr(self, name)!r}: must be >= 1")
        for name in ("min_open", "old_update_top"):
            if getattr(self, name) < 0:
                raise ModelError(f"{name} = {getattr(self, name)!r}: must be >= 0")
        for name in ("prune_eps", "slot_mass_eps"):  # probabilities: 1 or more drops all
            v = getattr(self, name)
            if not (np.isfinite(v) and 0 <= v < 1):
                raise ModelError(f"{name} = {v!r}: must be in [0, 1)")
        if self.birth_leave not in (False, True, "filter"):
            raise ModelError(f"birth_leave = {self.birth_leave!r}: must be False, True or 'filter'")


class ADFState(NamedTuple):
    """The factorised belief after ``k`` observations (a jax pytree; immutable; float64).

    Shapes: ``S = max_open``, ``W = persons_per_slot``, ``N`` = person capacity,
    ``r = obs_dim``.

    k () int, last_tq () float, counter (N + 1,) q(c), never (N,) q(z^(n) = 0),
    closed (N,) probability that person n's latest slice is a closed track end (pruned
    or evicted from the table; such a slice is never continued),
    slot_valid (S,) bool, slot_obs (S,) int (observation index j of the slot),
    slot_cam, slot_bq (S,) int, slot_tq (S,), slot_a (S, r), slot_kappa (S,),
    slot_eta (S,), slot_C (S, r, r), slot_Cinv (S, r, r), slot_logdetC (S,),
    slot_lognorm (S,) the data-free part of each slot's Student-t predictive
    (:func:`inference.adf.niw.niw_predictive_lognorm`, cached: it needs log-gamma),
    slot_psi_next (S,) :func:`inference.adf.niw.niw_sum_digamma` of ``slot_eta + 1``
    (the digamma sum of the slot's NIW once updated with an observation, cached for
    the projection),
    slot_person (S, W) int, slot_pprob (S, W) q(z^(person) = slot's j).
    """

    k: jnp.ndarray
    last_tq: jnp.ndarray
    counter: jnp.ndarray
    never: jnp.ndarray
    closed: jnp.ndarray
    slot_valid: jnp.ndarray
    slot_obs: jnp.ndarray
    slot_cam: jnp.ndarray
    slot_bq: jnp.ndarray
    slot_tq: jnp.ndarray
    slot_a: jnp.ndarray
    slot_kappa: jnp.ndarray
    slot_eta: jnp.ndarray
    slot_C: jnp.ndarray
    slot_Cinv: jnp.ndarray
    slot_logdetC: jnp.ndarray
    slot_lognorm: jnp.ndarray
    slot_psi_next: jnp.ndarray
    slot_person: jnp.ndarray
    slot_pprob: jnp.ndarray


class ADFInfo(NamedTuple):
    """What one step reports (arrays; batch axes in front when stacked over steps).

    link_obs (link_out,) int: earlier observations y_k may continue (-1: unused);
    link_prob (link_out,): their posterior probabilities; new_prob (): P(new person);
    label_person (label_out,) int, label_prob (label_out,): top of q_k(l_k = n);
    counter_mean (), counter_std (): of q_k(c); loglik (): log p(y_k | y_1..y_{k-1})
    under the ADF; num_open (): open slots after the step; impossible (): no link and
    no new person had positive density (treated as new).
    """

    link_obs: jnp.ndarray
    link_prob: jnp.ndarray
    new_prob: jnp.ndarray
    label_person: jnp.ndarray
    label_prob: jnp.ndarray
    counter_mean: jnp.ndarray
    counter_std: jnp.ndarray
    loglik: jnp.ndarray
    num_open: jnp.ndarray
    impossible: jnp.ndarray


class ADFParams(NamedTuple):
    """The model's parameters as the hooks use them (a pytree of float64 arrays).

    a0 (r,), k0 (), e0 (), C0 (r, r), Cinv0 (r, r), logdet0 (): theta_0 with its
    cached inverse and log-determinant; lognorm0 (): its predictive's data-free part;
    psi0_next (): the digamma sum of ``e0 + 1``;
    path: PathModel; path_lognorm (C, C): :func:`models.zajdel.path.travel_log_norm`;
    p_new (): P(new) (0.5 placeholder under the uniform label prior);
    close_horizon (C, B): birth-leave model, time after a pass at (camera, quit border)
    beyond which the track end is closed
    (:func:`models.zajdel.path.continuation_horizon`; inf when unused);
    stay_table (C, B, G), stay_step (): birth-leave filtering form, log g_j tabulated
    (:func:`models.zajdel.path.stay_table`; a dummy when unused).
    """

    a0: jnp.ndarray
    k0: jnp.ndarray
    e0: jnp.ndarray
    C0: jnp.ndarray
    Cinv0: jnp.ndarray
    logdet0: jnp.ndarray
    lognorm0: jnp.ndarray
    psi0_next: jnp.ndarray
    path: PathModel
    path_lognorm: jnp.ndarray
    p_new: jnp.ndarray
    close_horizon: jnp.ndarray | None = None
    stay_table: jnp.ndarray | None = None
    stay_step: jnp.ndarray | None = None
