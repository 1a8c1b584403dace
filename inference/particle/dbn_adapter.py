r"""Any declared two-slice DBN as a particle filter's state-space model.

:class:`DBNStateSpaceModel` turns a :class:`~dbn.dbn.TwoSliceDBN` into a
:class:`~inference.particle.model.StateSpaceModel`, so the existing bootstrap and auxiliary
filters (:mod:`inference.particle.filters`) run on declarations. One particle is one
joint assignment of a slice; one move samples the slice's variables in topological order
from their CPDs given the particle's previous slice (likelihood weighting): a variable
observed at that slice is clamped to its value and contributes
:math:`\log P(e_v \mid \mathrm{pa}(v))` to the particle's weight, so

.. math:: w_t^i \propto w_{t-1}^i \prod_{v \text{ observed at } t}
    P(e_{v,t} \mid \mathrm{pa}(x_{v,t})^i)

(seed 002, eqs. 1.8-1.9, with the slice's hidden variables drawn from the prior).

Particle layout, shape ``(num_particles, state_dim)``: one column per discrete variable
(its state, stored as a float), ``dim`` columns per continuous variable, in declaration
order, and a last column holding the log-likelihood of the slice's evidence computed
during the move (an observation's parents may lie in the previous slice, which the new
particle no longer holds). The per-step input (``observation`` and ``action``, the same
pytree, from :meth:`DBNStateSpaceModel.inputs`) carries the evidence of the slice and a
flag for slice 0, whose move samples from the initial CPDs; ``sample_initial`` returns a
placeholder that slice 0's move ignores.

CPDs: tabular and deterministic ones are table lookups vectorised over particles;
linear-Gaussian and conditional linear-Gaussian ones are jax code; any other continuous
CPD is called through its ``sample(key, parent_values)`` / ``log_prob(value,
parent_values)`` with parent values batched over particles (shape ``(num_particles,
dim)``); the filter then runs step by step without ``jit`` so numpy-based CPDs work.

:func:`particle_filter_dbn` runs a whole sequence and returns a
:class:`~inference.results.DBNFilterResult`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array
from numpy.typing import ArrayLike

from dbn.bayesnet import BayesNet
from dbn.cpds import (
    ConditionalLinearGaussianCPD,
    DeterministicCPD,
    LinearGaussianCPD,
    TabularCPD,
)
from dbn.dbn import TwoSliceDBN, check_two_slice, is_prev, prev, unprev
from dbn.errors import CPDShapeError, EvidenceError, InputError, ModelError
from dbn.variables import DiscreteVariable
from inference.evidence_columns import check_columns, check_query
from inference.model_cache import ModelCache
from inference.particle.filters import (
    auxiliary_filter,
    bootstrap_filter,
    check_key,
    check_num_particles,
    ess,
    run,
)
from inference.particle.model import StateSpaceModel
from inference.precision import scoped
from inference.results import DBNFilterResult

__all__ = ["DBNStateSpaceModel", "particle_filter_dbn"]

_NATIVE = (TabularCPD, DeterministicCPD, LinearGaussianCPD, ConditionalLinearGaussianCPD)


def _gauss_logpdf(value: Array, mean: Array, chol: Array) -> Array:
    """``log N(value; mean, L L^T)`` batched: value, mean (..., d); chol (..., d, d) or (d, d)."""
    r = value - mean
    L = jnp.broadcast_to(chol, (*r.shape, r.shape[-1]))
    z = jax.scipy.linalg.solve_triangular(L, r[..., None], lower=True)[..., 0]
    logdet = 2.0 * jnp.sum(jnp.log(jnp.diagonal(L, axis1=-2, axis2=-1)), axis=-1)
    return -0.5 * (jnp.sum(z**2, axis=-1) + logdet + r.shape[-1] * math.log(2 * math.pi))


class _Node:
    """Sampler and log density of one CPD, vectorised over particles."""

    def __init__(self, net: BayesNet, name: str, cards: Mapping[str, int], dims) -> None:
        self.name = name
        self.cpd = cpd = net.cpd(name)
        self.parents = tuple(cpd.parents)
        self.discrete = name in cards
        if self.discrete:
            table = np.asarray(net.table(name), dtype=np.float64)
            pc = table.shape[:-1]
            self.strides = np.array([int(np.prod(pc[i + 1 :])) for i in range(len(pc))], int)
            rows = table.reshape(-1, table.shape[-1])
            with np.errstate(divide="ignore"):
                self.log_rows = jnp.asarray(np.log(rows))
            # inner cumulative sums for inverse-CDF sampling with one uniform per particle
            self.cum_rows = jnp.asarray(np.cumsum(rows, axis=1)[:, :-1])
        elif isinstance(cpd, LinearGaussianCPD | ConditionalLinearGaussianCPD):
            if cpd.dim != dims[name]:
                raise CPDShapeError(
                    f"CPD of {name!r}: dimension {cpd.dim}, the variable has dim {dims[name]}"
                )
            clg = isinstance(cpd, ConditionalLinearGaussianCPD)
            dpa = cpd.discrete_parents if clg else ()
            for p, k in zip(dpa, cpd.discrete_cardinalities if clg else ()):
                if cards.get(unprev(p)) != k:
                    raise CPDShapeError(
                        f"CPD of {name!r}: discrete parent {p!r} needs {k} states, "
                        f"the model gives it {cards.get(unprev(p))}"
                    )
            cpa = cpd.continuous_parents if clg else cpd.parents
            for p, w in zip(cpa, cpd.weights):
                if unprev(p) in cards or w.shape[-1] != dims[unprev(p)]:
                    raise CPDShapeError(
                        f"CPD of {name!r}: parent {p!r} must be continuous of dim {w.shape[-1]}"
                    )
            self.dpa, self.cpa = dpa, cpa
            self.weights = [jnp.asarray(w) for w in cpd.weights]
            self.bias, self.chol = jnp.asarray(cpd.bias), jnp.asarray(cpd.chol)

    def _index(self, values: Mapping[str, Array], names: Sequence[str]):
        return tuple(values[p] for p in names)

    def _rows(self, values: Mapping[str, Array], n: int, table=None) -> Array:
        table = self.log_rows if table is None else table
        if not self.parents:
            return jnp.broadcast_to(table[0], (n, table.shape[1]))
        flat = sum(values[p] * int(s) for p, s in zip(self.parents, self.strides))
        return table[flat]

    def _gauss(self, values: Mapping[str, Array], n: int) -> tuple[Array, Array]:
        k = self._index(values, self.dpa)
        mean = jnp.broadcast_to(self.bias[k] if k else self.bias, (n, self.bias.shape[-1]))
        for p, w in zip(self.cpa, self.weights):
            wk = w[k] if k else w
            mean = mean + jnp.einsum("...ij,...j->...i", wk, values[p])
        return mean, self.chol[k] if k else self.chol

    def sample(self, noise: Any, values: Mapping[str, Array], n: int, deterministic: bool):
        """A draw per particle given parent values: (n,) int or (n, d) float.

        ``noise``: uniforms (n,) for a discrete CPD, standard normals (n, d) for a
        (conditional) linear-Gaussian one, a jax key for any other CPD.
        """
        if self.discrete:
            if deterministic:
                return jnp.argmax(self._rows(values, n), axis=-1)
            cum = self._rows(values, n, self.cum_rows)
            return jnp.sum(noise[:, None] >= cum, axis=1).astype(jnp.int32)
        if isinstance(self.cpd, _NATIVE):
            mean, chol = self._gauss(values, n)
            if deterministic:
                return mean
            return mean + jnp.einsum("...ij,...j->...i", chol, noise.astype(mean.dtype))
        pv = {p: values[p] for p in self.parents}
        if deterministic:
            mean = getattr(self.cpd, "mean", None)
            if not callable(mean):
                raise ModelError(
                    f"CPD of {self.name!r} has no mean(parent_values): the auxiliary filter "
                    "needs one for its look-ahead"
                )
            return jnp.asarray(mean(pv))
        return jnp.asarray(self.cpd.sample(noise, pv))

    def log_prob(self, value: Array, values: Mapping[str, Array], n: int) -> Array:
        """``log P(value | parents)`` per particle, shape (n,)."""
        if self.discrete:
            rows = self._rows(values, n)
            return jnp.take_along_axis(rows, value[:, None], axis=1)[:, 0]
        if isinstance(self.cpd, _NATIVE):
            mean, chol = self._gauss(values, n)
            return _gauss_logpdf(value, mean, chol)
        pv = {p: values[p] for p in self.parents}
        return jnp.broadcast_to(jnp.asarray(self.cpd.log_prob(value, pv)), (n,))


class DBNStateSpaceModel(StateSpaceModel):
    """A :class:`~dbn.dbn.TwoSliceDBN` as a particle-filter model (see the module docstring).

    Parameters
    ----------
    dbn : TwoSliceDBN
        Discrete variables with tabular/deterministic CPDs; continuous ones with
        linear-Gaussian, conditional linear-Gaussian or any CPD with sample/log_prob.

    Attributes
    ----------
    columns : dict name -> slice
        Where each variable lives in a particle row.
    state_dim : int
        Number of columns (the last one is the slice's evidence log-likelihood).
    jittable : bool
        False when a CPD is neither tabular, deterministic, linear-Gaussian nor
        conditional linear-Gaussian (its methods may be numpy code).
    """

    def __init__(self, dbn: TwoSliceDBN) -> None:
        self.dbn = dbn
        self.cards = {
            v.name: v.cardinality for v in dbn.variables if isinstance(v, DiscreteVariable)
        }
        self.dims = {v.name: v.dim for v in dbn.variables if v.name not in self.cards}
        self.columns: dict[str, slice] = {}
        start = 0
        for v in dbn.variables:
            width = 1 if v.name in self.cards else self.dims[v.name]
            self.columns[v.name] = slice(start, start + width)
            start += width
        self.state_dim = start + 1
        self._order = {
            first: [n for n in net.topological_order() if not is_prev(n)]
            for first, net in ((True, dbn.initial_net), (False, dbn.transition_net))
        }
        self._nodes = {
            first: {n: _Node(net, n, self.cards, self.dims) for n in self._order[first]}
            for first, net in ((True, dbn.initial_net), (False, dbn.transition_net))
        }
        self._static_first: bool | None = None
        self.jittable = all(
            isinstance(node.cpd, _NATIVE)
            for nodes in self._nodes.values()
            for node in nodes.values()
        )

    # --- inputs -------------------------------------------------------------------------
    def inputs(
        self,
        evidence: Mapping[str, ArrayLike] | None,
        soft_evidence: Mapping[str, ArrayLike] | None = None,
    ) -> dict[str, Any]:
        """Validated columnar evidence as the per-step input pytree (leading axis T).

        ``{"first": (T,) bool, "discrete": {name: (T,) int}, "continuous": {name: (T, d)},
        "soft": {name: (T, K) log-likelihoods}}``; pass it as both ``observations`` and
        ``actions`` to :func:`inference.particle.run`.
        """
        cols = check_columns(self.dbn, evidence, soft_evidence)
        first = np.zeros(cols.num_timesteps, bool)
        first[0] = True
        with np.errstate(divide="ignore"):
            soft = {n: jnp.asarray(np.log(a)) for n, a in cols.soft.items()}
        return {
            "first": jnp.asarray(first),
            "discrete": {n: jnp.asarray(a) for n, a in cols.discrete.items()},
            "continuous": {n: jnp.asarray(a) for n, a in cols.continuous.items()},
            "soft": soft,
        }

    # --- the state-space model ----------------------------------------------------------
    def _unpack(self, particles: Array) -> dict[str, Array]:
        out = {}
        for n, sl in self.columns.items():
            col = particles[:, sl]
            out[n] = jnp.round(col[:, 0]).astype(jnp.int32) if n in self.cards else col
        return out

    def _pack(self, values: Mapping[str, Array], loglik: Array, dtype) -> Array:
        cols = []
        for n in self.columns:
            v = values[n]
            cols.append(v[:, None].astype(dtype) if n in self.cards else v.astype(dtype))
        cols.append(loglik[:, None].astype(dtype))
        return jnp.concatenate(cols, axis=1)

    def _move(self, key: Array, particles: Array, inp: Mapping[str, Any], first: bool, det: bool):
        n = particles.shape[0]
        old = self._unpack(particles)
        values: dict[str, Array] = {prev(k): v for k, v in old.items()}
        loglik = jnp.zeros(n, dtype=particles.dtype)
        noise = self._noise(key, n, first, particles.dtype) if not det else {}
        for name in self._order[first]:
            node = self._nodes[first][name]
            draw = node.sample(noise.get(name), values, n, det)
            obs = inp["discrete"].get(name)
            if obs is None and name in inp["continuous"]:
                obs = inp["continuous"][name]
            if obs is not None:
                if name in self.cards:
                    seen = obs >= 0
                    val = jnp.full((n,), jnp.maximum(obs, 0), dtype=jnp.int32)
                else:
                    seen = ~jnp.any(jnp.isnan(obs))
                    val = jnp.broadcast_to(jnp.where(seen, obs, 0.0), draw.shape)
                lp = node.log_prob(val, values, n)
                loglik = loglik + jnp.where(seen, lp, 0.0)
                draw = jnp.where(seen, val, draw)
            if name in inp["soft"]:
                loglik = loglik + inp["soft"][name][draw]
            values[name] = draw
        return self._pack(values, loglik, particles.dtype)

    def _noise(self, key: Array, n: int, first: bool, dtype) -> dict[str, Any]:
        """All the randomness of one move in three draws (few RNG calls: fast to compile)."""
        nodes = list(self._nodes[first].values())
        disc = [nd.name for nd in nodes if nd.discrete]
        gauss = [nd for nd in nodes if not nd.discrete and isinstance(nd.cpd, _NATIVE)]
        other = [nd.name for nd in nodes if not nd.discrete and not isinstance(nd.cpd, _NATIVE)]
        k_u, k_n, k_o = jax.random.split(key, 3)
        out: dict[str, Any] = {}
        if disc:
            u = jax.random.uniform(k_u, (n, len(disc)), dtype=dtype)
            out.update({name: u[:, j] for j, name in enumerate(disc)})
        if gauss:
            dims = [self.dims[nd.name] for nd in gauss]
            eps = jax.random.normal(k_n, (n, sum(dims)), dtype=dtype)
            starts = np.cumsum([0, *dims])
            out.update({nd.name: eps[:, a:b] for nd, a, b in zip(gauss, starts, starts[1:])})
        if other:
            out.update(zip(other, jax.random.split(k_o, len(other))))
        return out

    def at_slice(self, first: bool) -> DBNStateSpaceModel:
        """A view whose moves are always slice 0's (``first=True``) or always a later
        slice's: no run-time branch, half the code to compile."""
        view = object.__new__(DBNStateSpaceModel)
        view.__dict__.update(self.__dict__)
        view._static_first = bool(first)
        return view

    def _either(self, key: Array, particles: Array, inp: Any, det: bool) -> Array:
        if self._static_first is not None:
            return self._move(key, particles, inp, self._static_first, det)
        if not self.jittable:  # eager: a Python branch
            return self._move(key, particles, inp, bool(inp["first"]), det)
        return jax.lax.cond(
            inp["first"],
            lambda: self._move(key, particles, inp, True, det),
            lambda: self._move(key, particles, inp, False, det),
        )

    def sample_initial(self, key: Array, num_particles: int, dtype: Any) -> Array:
        """A placeholder (zeros): slice 0's move draws from the initial CPDs."""
        return jnp.zeros((num_particles, self.state_dim), dtype=dtype)

    def sample_transition(self, key: Array, particles: Array, action: Any) -> Array:
        """Draw slice ``t`` given slice ``t - 1`` (``action`` = this slice's input)."""
        return self._either(key, particles, action, det=False)

    def log_likelihood(self, particles: Array, observation: Any) -> Array:
        """The slice's evidence log-likelihood, computed during the move (last column)."""
        return particles[:, -1]

    def lookahead(self, particles: Array, action: Any) -> Array:
        """A deterministic move (most probable state of discrete CPDs, mean of continuous
        ones), evidence clamped: the auxiliary filter's look-ahead point (seed 002, eq. 1.12)."""
        return self._either(None, particles, action, det=True)

    def log_eta(self, particles: Array, observation: Any, action: Any) -> Array:
        return self.lookahead(particles, action)[:, -1]

    # --- summaries ----------------------------------------------------------------------
    def summary(self, query: Sequence[str]):
        """``ParticleState -> dict`` of weighted marginals (discrete) and mean/cov
        (continuous) of the query variables."""

        def summarise(state):
            w = jnp.exp(state.log_weights)
            vals = self._unpack(state.particles)
            out = {"_ess": ess(state.log_weights)}
            for q in query:
                if q in self.cards:
                    onehot = jax.nn.one_hot(vals[q], self.cards[q], dtype=w.dtype)
                    out[q] = w @ onehot
                else:
                    x = vals[q]
                    m = w @ x
                    d = x - m
                    out[q] = (m, (d * w[:, None]).T @ d)
            return out

        return summarise


#: per DBN: its state-space model and its compiled filters (bounded: the values refer to
#: the DBN, a weak-key cache would keep every DBN alive)
_CACHE: ModelCache[dict] = ModelCache(maxsize=8)


def _filters(dbn, model, num_particles: int, method: str, query: tuple[str, ...]):
    """(slice-0 filter, later-slice filter, summary), cached per DBN so that ``run``'s
    compiled code is reused by later calls with the same sizes."""
    per = _CACHE.get(dbn, dict)
    per["model"] = model
    key = (num_particles, method, query)
    if key not in per:
        make = bootstrap_filter if method == "bootstrap" else auxiliary_filter
        pf0 = make(model.at_slice(True), num_particles, dtype=jnp.float64)
        step0 = jax.jit(pf0.step) if model.jittable else pf0.step
        per[key] = (
            pf0._replace(step=step0),
            make(model.at_slice(False), num_particles, dtype=jnp.float64),
            model.summary(query),
        )
    return per[key]


def check_not_collapsed(log_likelihoods: np.ndarray, engine: str, num_particles: int) -> None:
    """Raise :class:`~dbn.errors.EvidenceError` naming the first slice whose estimate
    :math:`\\log \\hat p(y_t | y_{0:t-1})` is not finite: every particle got weight zero
    there, and every marginal from that slice on would be the resampler's uniform
    fallback, not a posterior (the exact engines and Boyen-Koller raise at that slice too).
    """
    bad = ~np.isfinite(log_likelihoods)
    if bad.any():
        t = int(np.argmax(bad))
        raise EvidenceError(
            f"slice {t}: every one of the {num_particles:,} particles of {engine} has weight "
            "zero (the evidence is impossible under all of them: impossible evidence, or too "
            "few particles for it)"
        )


@scoped(jnp.float64)
def particle_filter_dbn(
    key: Array,
    dbn: TwoSliceDBN,
    evidence: Mapping[str, ArrayLike],
    query: Sequence[str] | None = None,
    *,
    num_particles: int = 1000,
    method: str = "bootstrap",
    soft_evidence: Mapping[str, ArrayLike] | None = None,
) -> DBNFilterResult:
    """Particle filtering of a declared DBN over a whole sequence.

    Parameters
    ----------
    key : jax PRNG key
    dbn : TwoSliceDBN
    evidence : mapping name -> array
        Discrete: int (num_timesteps,), -1 = unobserved (or state names, None =
        unobserved); continuous: float (num_timesteps, dim), NaN rows = unobserved.
    query : sequence of str, optional
        Default: every variable without an evidence column.
    num_particles : int
    method : {"bootstrap", "auxiliary"}
    soft_evidence : mapping name -> (num_timesteps, cardinality), optional

    Returns
    -------
    DBNFilterResult
        ``method="particle"``; marginals of discrete, means and covariances of continuous
        query variables; ``log_likelihoods`` are the filter's estimates;
        ``info`` holds ``num_particles``, ``filter`` and ``ess`` (T,), the effective
        sample size of the filtered weights at each slice.

    Raises
    ------
    EvidenceError
        Bad evidence, or a slice where every particle got weight zero
        (:func:`check_not_collapsed`).
    """
    if method not in ("bootstrap", "auxiliary"):
        raise InputError(f"method must be 'bootstrap' or 'auxiliary', got {method!r}")
    check_two_slice(dbn, "the particle filter")
    num_particles = check_num_particles(num_particles)
    check_key(key)
    model = _CACHE.get(dbn, dict).get("model") or DBNStateSpaceModel(dbn)
    inp = model.inputs(evidence, soft_evidence)
    hidden = tuple(n for n in dbn.names if n not in inp["discrete"] and n not in inp["continuous"])
    query = check_query(dbn, query, hidden)
    pf0, pf1, summary = _filters(dbn, model, num_particles, method, query)
    T = int(inp["first"].shape[0])
    k0, k_first, k_rest = jax.random.split(key, 3)
    at = [
        jax.tree_util.tree_map(lambda a, t=t: a[t], inp) for t in range(1 if model.jittable else T)
    ]
    state, info = pf0.step(k_first, pf0.init(k0), at[0], at[0])
    rows, lls = [summary(state)], [info.log_likelihood]
    if T > 1 and model.jittable:
        rest = jax.tree_util.tree_map(lambda a: a[1:], inp)
        _, infos, outs = run(k_rest, pf1, rest, rest, initial_state=state, summary=summary)
        rows.append(outs)
        lls.append(infos.log_likelihood)
    elif T > 1:  # eager, step by step: CPDs may be numpy code
        for t, k in enumerate(jax.random.split(k_rest, T - 1), start=1):
            state, info = pf1.step(k, state, at[t], at[t])
            rows.append(summary(state))
            lls.append(info.log_likelihood)
    stack = [rows[0]] + (rows[1:] if not model.jittable else [])
    outs = jax.tree_util.tree_map(lambda *a: jnp.stack(a), *stack)
    if model.jittable and T > 1:
        outs = jax.tree_util.tree_map(lambda a, b: jnp.concatenate([a, b]), outs, rows[1])
    lls = np.concatenate([np.atleast_1d(np.asarray(x)) for x in lls])
    margs = {q: np.asarray(outs[q]) for q in query if q in model.cards}
    means = {q: np.asarray(outs[q][0]) for q in query if q not in model.cards}
    covs = {q: np.asarray(outs[q][1]) for q in query if q not in model.cards}
    check_not_collapsed(lls, f"the {method} particle filter", num_particles)
    info = {"num_particles": num_particles, "filter": method, "ess": np.asarray(outs["_ess"])}
    return DBNFilterResult(margs, lls, "particle", means, covs, info)
