r"""Rao-Blackwellised particle filtering of conditionally linear-Gaussian DBNs.

A DBN is *conditionally linear-Gaussian* when, given its discrete variables, the
continuous ones form a linear-Gaussian system: every continuous variable has a
:class:`~dbn.cpds.LinearGaussianCPD` or :class:`~dbn.cpds.ConditionalLinearGaussianCPD`
(parameters selected by discrete parents), discrete variables have discrete parents only.
The switching linear dynamical system is the example: a switch ``s_t`` with a tabular
transition, ``x_t ~ N(A[s_t] x_{t-1} + b[s_t], Q[s_t])``, ``y_t ~ N(H x_t, R)``.

Each particle carries a sample of the discrete variables of the slice and, for the hidden
continuous variables :math:`z_t` (all of them, stacked in declaration order), the Gaussian
:math:`p(z_t \mid d_{0:t}^i, e_{0:t}) = N(m_t^i, P_t^i)` (Doucet, de Freitas, Murphy and
Russell 2000). One step:

1. draw the slice's hidden discrete variables from their CPDs given the particle's
   previous slice (observed ones are clamped and weigh the particle);
2. Kalman predict: the joint Gaussian of :math:`(z_{t-1}, z_t)` is built variable by
   variable in topological order (:math:`z_v = \sum_p W_p[k] z_p + b[k] + \epsilon`, the
   moments of a linear-Gaussian Bayes net), then :math:`z_{t-1}` is marginalised;
3. Kalman update with each observed continuous variable
   (:math:`y = H[k] z_t + c[k] + \nu`, :math:`\nu \sim N(0, R[k])`), Cholesky solves;
   the predictive density :math:`N(y; H m, H P H^T + R)` multiplies the weight;
4. resample (systematic, :mod:`inference.particle.resampling`) when the ESS falls below
   half the particles.

The per-particle Gaussian work is ``jax.vmap``-ed and the time loop is a ``lax.scan``.
Output: marginals of discrete variables, and mixture means and covariances of continuous
ones, in an :class:`~inference.results.DBNFilterResult` (``method="rbpf"``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from functools import partial
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array
from jax.scipy.special import logsumexp
from numpy.typing import ArrayLike

from dbn.bayesnet import BayesNet
from dbn.cpds import ConditionalLinearGaussianCPD, LinearGaussianCPD
from dbn.dbn import TwoSliceDBN, check_two_slice, is_prev, prev, unprev
from dbn.errors import CPDShapeError, InputError, ModelError
from dbn.variables import DiscreteVariable
from inference.evidence_columns import check_columns, check_query
from inference.model_cache import ModelCache
from inference.particle.dbn_adapter import _Node, check_not_collapsed
from inference.particle.filters import check_key, check_num_particles
from inference.particle.resampling import systematic
from inference.precision import scoped
from inference.results import DBNFilterResult

__all__ = ["RBPFState", "rbpf_filter_dbn"]


class RBPFState(NamedTuple):
    """Particles after a slice.

    Attributes
    ----------
    discrete : Array (num_particles, num_discrete) int32
        Sampled states of the discrete variables (declaration order).
    mean : Array (num_particles, state_dim)
        Conditional means of the hidden continuous variables, stacked.
    cov : Array (num_particles, state_dim, state_dim)
    log_weights : Array (num_particles,), normalised
    """

    discrete: Array
    mean: Array
    cov: Array
    log_weights: Array


class _Linear(NamedTuple):
    """A (conditional) linear-Gaussian CPD as arrays indexed by its discrete parents."""

    name: str
    dpa: tuple[str, ...]
    cpa: tuple[str, ...]
    weights: tuple[Array, ...]  # (*K, d, d_p)
    bias: Array  # (*K, d)
    cov: Array  # (*K, d, d)


def _linear(net: BayesNet, name: str) -> _Linear:
    cpd = net.cpd(name)
    if isinstance(cpd, ConditionalLinearGaussianCPD):
        return _Linear(
            name,
            cpd.discrete_parents,
            cpd.continuous_parents,
            tuple(jnp.asarray(w) for w in cpd.weights),
            jnp.asarray(cpd.bias),
            jnp.asarray(cpd.cov),
        )
    if isinstance(cpd, LinearGaussianCPD):
        return _Linear(
            name,
            (),
            cpd.parents,
            tuple(jnp.asarray(w) for w in cpd.weights),
            jnp.asarray(cpd.bias),
            jnp.asarray(cpd.cov),
        )
    raise ModelError(
        f"continuous variable {name!r} has a {type(cpd).__name__}: the Rao-Blackwellised "
        "filter needs LinearGaussianCPD or ConditionalLinearGaussianCPD (use particle_filter_dbn)"
    )


class _Slice:
    """What one slice's step needs, precompiled (initial or transition template)."""

    def __init__(self, model: _Model, net: BayesNet, first: bool) -> None:
        order = [n for n in net.topological_order() if not is_prev(n)]
        self.discrete = [_Node(net, n, model.cards, model.dims) for n in order if n in model.cards]
        self.hidden = [_linear(net, n) for n in order if n in model.offsets]
        self.observed = [_linear(net, n) for n in order if n in model.observed]
        for lin in self.hidden:
            for p in lin.cpa:
                if unprev(p) in model.observed or (first and is_prev(p)):
                    raise ModelError(
                        f"CPD of {lin.name!r}: continuous parent {p!r} must be a hidden "
                        "continuous variable"
                    )
        for lin in self.observed:
            for p in lin.cpa:
                if is_prev(p) or p not in model.offsets:
                    raise ModelError(
                        f"observed {lin.name!r}: its continuous parents must be hidden "
                        f"continuous variables of the same slice, got {p!r}"
                    )
        for lin in self.hidden + self.observed:
            for p, w in zip(lin.cpa, lin.weights):
                if (
                    w.shape[-1] != model.dims[unprev(p)]
                    or lin.bias.shape[-1] != model.dims[lin.name]
                ):
                    raise CPDShapeError(f"CPD of {lin.name!r}: weight of {p!r} has shape {w.shape}")


class _Model:
    """Layout of a conditionally linear-Gaussian DBN given which variables are observed."""

    def __init__(self, dbn: TwoSliceDBN, observed_continuous: Sequence[str]) -> None:
        self.dbn = dbn
        self.cards = {
            v.name: v.cardinality for v in dbn.variables if isinstance(v, DiscreteVariable)
        }
        self.dims = {v.name: v.dim for v in dbn.variables if v.name not in self.cards}
        self.observed = tuple(observed_continuous)
        self.offsets: dict[str, int] = {}
        D = 0
        for v in dbn.variables:
            if v.name in self.dims and v.name not in self.observed:
                self.offsets[v.name] = D
                D += self.dims[v.name]
        self.state_dim = D
        self.discrete_names = tuple(n for n in dbn.names if n in self.cards)
        self.slices = {
            True: _Slice(self, dbn.initial_net, True),
            False: _Slice(self, dbn.transition_net, False),
        }

    def block(self, name: str, current: bool) -> slice:
        """Rows of variable ``name`` in the joint ``(z_{t-1}, z_t)``."""
        a = self.offsets[unprev(name)] + (self.state_dim if current else 0)
        return slice(a, a + self.dims[unprev(name)])

    # --- per particle (vmapped) -----------------------------------------------------------
    def _select(self, lin: _Linear, disc: Mapping[str, Array]):
        k = tuple(disc[p] for p in lin.dpa)
        pick = (lambda a: a[k]) if k else (lambda a: a)
        return [pick(w) for w in lin.weights], pick(lin.bias), pick(lin.cov)

    def predict(self, first: bool, disc: Mapping[str, Array], m: Array, P: Array):
        """Moments of ``z_t`` given ``z_{t-1} ~ N(m, P)`` and the discrete values ``disc``."""
        D = self.state_dim
        mu = jnp.concatenate([m, jnp.zeros(D, m.dtype)])
        S = jnp.zeros((2 * D, 2 * D), m.dtype).at[:D, :D].set(P)
        for lin in self.slices[first].hidden:
            ws, b, Q = self._select(lin, disc)
            M = jnp.zeros((b.shape[-1], 2 * D), m.dtype)
            for p, w in zip(lin.cpa, ws):
                M = M.at[:, self.block(p, not is_prev(p))].add(w)
            rows = self.block(lin.name, True)
            MS = M @ S
            S = S.at[rows, :].set(MS).at[:, rows].set(MS.T)
            S = S.at[rows, rows].set(MS @ M.T + Q)
            mu = mu.at[rows].set(M @ mu + b)
        S = S[D:, D:]
        return mu[D:], 0.5 * (S + S.T)

    def update(self, first: bool, disc: Mapping[str, Array], m: Array, P: Array, obs: Mapping):
        """Kalman updates with each observed continuous variable; returns (m, P, log lik)."""
        D = self.state_dim
        ll = jnp.zeros((), m.dtype)
        for lin in self.slices[first].observed:
            y = obs[lin.name]
            seen = ~jnp.any(jnp.isnan(y))
            ws, c, R = self._select(lin, disc)
            H = jnp.zeros((c.shape[-1], D), m.dtype)
            for p, w in zip(lin.cpa, ws):
                H = H.at[:, self.block(p, False)].add(w)
            S = H @ P @ H.T + R
            L = jnp.linalg.cholesky(0.5 * (S + S.T))
            r = jnp.where(seen, y, 0.0) - H @ m - c
            z = jax.scipy.linalg.solve_triangular(L, r, lower=True)
            G = jax.scipy.linalg.solve_triangular(L, H @ P, lower=True)  # L^-1 H P
            m_new = m + G.T @ z  # P H^T S^-1 r
            P_new = P - G.T @ G
            lp = -0.5 * (
                z @ z + 2 * jnp.sum(jnp.log(jnp.diag(L))) + y.shape[0] * math.log(2 * math.pi)
            )
            m = jnp.where(seen, m_new, m)
            P = jnp.where(seen, 0.5 * (P_new + P_new.T), P)
            ll = ll + jnp.where(seen, lp, 0.0)
        return m, P, ll


_MODELS: ModelCache[dict] = ModelCache(maxsize=8)  # bounded: the layouts refer to the DBN


def _model(dbn: TwoSliceDBN, observed: tuple[str, ...]) -> _Model:
    """The compiled layout, cached per DBN and observed set (so jit reuses its code)."""
    per = _MODELS.get(dbn, dict)
    if observed not in per:
        per[observed] = _Model(dbn, observed)
    return per[observed]


def _step(model: _Model, first: bool, n: int, key: Array, state: RBPFState, inp: Mapping):
    """One slice for every particle: (new state, (log-likelihood estimate, ess))."""
    k_res, k_move = jax.random.split(key)
    lw = state.log_weights
    ess = jnp.exp(-logsumexp(2 * lw))
    do = ess < 0.5 * n
    anc = jnp.where(do, systematic(k_res, lw, n), jnp.arange(n, dtype=jnp.int32))
    base = jnp.where(do, jnp.full_like(lw, -math.log(n)), lw)
    old = {nm: state.discrete[anc, j] for j, nm in enumerate(model.discrete_names)}
    values: dict[str, Array] = {prev(k): v for k, v in old.items()}
    ll = jnp.zeros(n, lw.dtype)
    nodes = model.slices[first].discrete
    u = jax.random.uniform(k_move, (n, max(len(nodes), 1)), dtype=lw.dtype)
    for j, node in enumerate(nodes):
        draw = node.sample(u[:, j], values, n, False)
        if node.name in inp["discrete"]:
            obs = inp["discrete"][node.name]
            val = jnp.full((n,), jnp.maximum(obs, 0), dtype=jnp.int32)
            ll = ll + jnp.where(obs >= 0, node.log_prob(val, values, n), 0.0)
            draw = jnp.where(obs >= 0, val, draw)
        values[node.name] = draw
    disc = dict(values)  # current and previous slice: CLG parents may be either
    obs = inp["continuous"]

    def gauss(d, m, P):
        m, P = model.predict(first, d, m, P)
        return model.update(first, d, m, P, obs)

    m, P, llc = jax.vmap(gauss)(disc, state.mean[anc], state.cov[anc])
    log_w = base + ll + llc
    log_w = jnp.where(jnp.isnan(log_w), -jnp.inf, log_w)
    total = logsumexp(log_w)
    d_new = (
        jnp.stack([disc[nm] for nm in model.discrete_names], axis=1)
        if model.discrete_names
        else jnp.zeros((n, 0), jnp.int32)
    )
    new = RBPFState(d_new, m, P, log_w - total)
    return new, (total, jnp.exp(-logsumexp(2 * new.log_weights)))


def _summary(model: _Model, query: Sequence[str], state: RBPFState) -> dict[str, Any]:
    w = jnp.exp(state.log_weights)
    out = {}
    for q in query:
        if q in model.cards:
            j = model.discrete_names.index(q)
            out[q] = w @ jax.nn.one_hot(state.discrete[:, j], model.cards[q], dtype=w.dtype)
        else:
            sl = model.block(q, False)
            m, P = state.mean[:, sl], state.cov[:, sl, sl]
            mean = w @ m
            d = m - mean
            out[q] = (mean, jnp.einsum("i,ijk->jk", w, P) + (d * w[:, None]).T @ d)
    return out


@partial(jax.jit, static_argnums=(0, 1, 2))
def _run(model: _Model, query: tuple[str, ...], n: int, key: Array, inp: Mapping):
    k0, k_rest = jax.random.split(key)
    D = model.state_dim
    dt = jnp.float64
    state = RBPFState(
        jnp.zeros((n, len(model.discrete_names)), jnp.int32),
        jnp.zeros((n, D), dt),
        jnp.zeros((n, D, D), dt),
        jnp.full((n,), -math.log(n), dt),
    )
    first = jax.tree_util.tree_map(lambda a: a[0], inp)
    state, (ll0, ess0) = _step(model, True, n, k0, state, first)
    rest = jax.tree_util.tree_map(lambda a: a[1:], inp)
    T1 = jax.tree_util.tree_leaves(inp)[0].shape[0] - 1

    def body(st, x):
        k, slice_in = x
        st, (ll, ess) = _step(model, False, n, k, st, slice_in)
        return st, (ll, ess, _summary(model, query, st))

    s0 = _summary(model, query, state)
    _, (lls, esss, outs) = jax.lax.scan(body, state, (jax.random.split(k_rest, T1), rest))
    cat = jax.tree_util.tree_map(lambda a, b: jnp.concatenate([a[None], b]), s0, outs)
    return jnp.concatenate([ll0[None], lls]), jnp.concatenate([ess0[None], esss]), cat


@scoped(jnp.float64)
def rbpf_filter_dbn(
    key: Array,
    dbn: TwoSliceDBN,
    evidence: Mapping[str, ArrayLike],
    query: Sequence[str] | None = None,
    *,
    num_particles: int = 1000,
) -> DBNFilterResult:
    """Rao-Blackwellised particle filtering of a conditionally linear-Gaussian DBN.

    Parameters
    ----------
    key : jax PRNG key
    dbn : TwoSliceDBN
        Discrete variables with tabular CPDs; continuous ones with (conditional)
        linear-Gaussian CPDs (see the module docstring for the structure allowed).
    evidence : mapping name -> array
        Continuous: (num_timesteps, dim) floats, NaN rows = unobserved; these are the
        observed continuous variables, every other continuous variable is hidden.
        Discrete: (num_timesteps,) ints, -1 = unobserved (or state names, None =
        unobserved).
    query : sequence of str, optional
        Default: every variable without an evidence column.
    num_particles : int

    Returns
    -------
    DBNFilterResult
        ``method="rbpf"``: marginals of discrete query variables, mixture means (T, dim)
        and covariances (T, dim, dim) of continuous ones; ``log_likelihoods`` are the
        filter's estimates of ``log p(e_t | e_{0:t-1})``; ``info`` holds
        ``num_particles`` and ``ess`` (T,).

    Raises
    ------
    ModelError
        A continuous CPD that is not (conditional) linear-Gaussian, or an observed
        continuous variable whose continuous parents are not hidden in its slice.
    EvidenceError
        Bad evidence, or a slice where every particle got weight zero
        (:func:`~inference.particle.dbn_adapter.check_not_collapsed`).
    """
    check_two_slice(dbn, "the Rao-Blackwellised particle filter")
    num_particles = check_num_particles(num_particles)
    check_key(key)
    cols = check_columns(dbn, evidence)
    model = _model(dbn, tuple(cols.continuous))
    hidden = tuple(n for n in dbn.names if n not in cols.discrete and n not in cols.continuous)
    query = check_query(dbn, query, hidden)
    for q in query:
        if q in cols.continuous:
            raise InputError(f"query {q!r} is an observed continuous variable")
    inp = {
        "discrete": {n: jnp.asarray(a) for n, a in cols.discrete.items()},
        "continuous": {n: jnp.asarray(a) for n, a in cols.continuous.items()},
    }
    if not inp["discrete"] and not inp["continuous"]:
        inp["discrete"] = {}
    inp["_t"] = jnp.arange(cols.num_timesteps)  # gives the scan its length
    lls, ess, outs = _run(model, query, num_particles, key, inp)
    margs = {q: np.asarray(outs[q]) for q in query if q in model.cards}
    means = {q: np.asarray(outs[q][0]) for q in query if q not in model.cards}
    covs = {q: np.asarray(outs[q][1]) for q in query if q not in model.cards}
    check_not_collapsed(np.asarray(lls), "the Rao-Blackwellised particle filter", num_particles)
    info = {"num_particles": num_particles, "ess": np.asarray(ess)}
    return DBNFilterResult(margs, np.asarray(lls), "rbpf", means, covs, info)
