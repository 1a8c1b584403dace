"""What a particle filter needs from a model: the state-space model declaration.

A model declares its laws; the algorithms (:mod:`inference.particle.filters`) turn any
such declaration into a filter, as in the ``particles`` library (a ``StateSpaceModel``
wrapped by ``Bootstrap`` / ``AuxiliaryPF``). Shapes use one vocabulary:
``num_particles``, ``state_dim``; an ``action`` (control input, e.g. odometry) and an
``observation`` are any pytrees of arrays for one time step (``None`` allowed).

A model class registered with :func:`register_model` is a jax pytree of its parameters:
:func:`inference.particle.filters.run_model` then traces them instead of baking them into
the compiled filter, so models of one class that differ only in their numbers share one
compilation (a parameter search compiles once per shape of its data).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import jax
from jax import Array

from dbn.errors import ModelError

__all__ = ["StateSpaceModel", "register_model", "is_registered_model"]


class StateSpaceModel:
    r"""Base class of a state-space model :math:`p(s_0)`, :math:`p(s_k|s_{k-1}, u_k)`, :math:`p(y_k|s_k)`.

    Subclasses implement :meth:`sample_initial`, :meth:`sample_transition` and
    :meth:`log_likelihood` (the bootstrap filter needs nothing more), and for the
    auxiliary filter either :meth:`transition_mean` (the default look-ahead point
    :math:`\mu_k^i`, seed 002 eq. 1.12), or their own :meth:`lookahead` or
    :meth:`log_eta`. All methods must be pure jax functions of their array arguments
    (they are traced under ``jax.jit``); model parameters are attributes fixed at
    construction, compiled into each filter unless the class is registered with
    :func:`register_model` (then :func:`~inference.particle.filters.run_model` traces them).
    """

    def sample_initial(self, key: Array, num_particles: int, dtype: Any) -> Array:
        """Draw ``num_particles`` states from :math:`p(s_0)`; shape ``(num_particles, state_dim)``."""
        raise NotImplementedError

    def sample_transition(self, key: Array, particles: Array, action: Any) -> Array:
        r"""Draw :math:`s_k^i \sim p(s_k | s_{k-1}^i, u_k)` for each row of ``particles``.

        ``particles`` has shape ``(num_particles, state_dim)``; returns the same shape/dtype.
        """
        raise NotImplementedError

    def log_likelihood(self, particles: Array, observation: Any) -> Array:
        r""":math:`\log p(y_k | s_k^i)` for each particle; shape ``(num_particles,)``.

        A model may return zeros for a skipped (e.g. outlier) observation: the filters
        then only propagate.
        """
        raise NotImplementedError

    def transition_mean(self, particles: Array, action: Any) -> Array:
        r""":math:`E[s_k | s_{k-1}^i, u_k]` per particle; shape ``(num_particles, state_dim)``."""
        raise NotImplementedError(
            f"{type(self).__name__} declares no transition_mean/lookahead: the auxiliary "
            "filter needs one (seed 002, eq. 1.12)"
        )

    def lookahead(self, particles: Array, action: Any) -> Array:
        r"""Look-ahead point :math:`\mu_k^i` of the auxiliary filter (seed 002, eq. 1.12).

        Defaults to :meth:`transition_mean`. Shape ``(num_particles, state_dim)``.
        """
        return self.transition_mean(particles, action)

    def log_eta(self, particles: Array, observation: Any, action: Any) -> Array:
        r"""First-stage log weight :math:`\log p(y_k | \mu_k^i)` of the auxiliary filter.

        Seed 002, eq. 1.12; defaults to :meth:`log_likelihood` at :meth:`lookahead`.
        ``particles`` are :math:`s_{k-1}`; returns shape ``(num_particles,)``.
        """
        return self.log_likelihood(self.lookahead(particles, action), observation)


def register_model(cls: type, data_fields: Sequence[str]) -> type:
    """Register the model class ``cls`` as a jax pytree whose leaves are ``data_fields``.

    ``data_fields`` name every attribute an instance holds (arrays, floats, or pytrees of
    them); its methods must then compute with them as jax values (``jnp.log``, not
    ``math.log``), as they may be traced. Unflattening sets the attributes without calling
    ``__init__`` (no checks run on traced values). Flattening an instance with an attribute
    outside ``data_fields`` is a :class:`~dbn.errors.ModelError` naming it. Returns ``cls``.
    """
    fields = tuple(data_fields)

    def flatten(model):
        extra = sorted(set(vars(model)) - set(fields))
        if extra:
            raise ModelError(f"{cls.__name__}: attribute(s) {extra} are not among the data "
                             f"fields {list(fields)} it was registered with")  # fmt: skip
        return tuple(getattr(model, f) for f in fields), None

    def unflatten(_aux, leaves):
        model = object.__new__(cls)
        model.__dict__.update(zip(fields, leaves, strict=True))
        return model

    jax.tree_util.register_pytree_node(cls, flatten, unflatten)
    cls._pytree_fields = fields
    return cls


def is_registered_model(model: Any) -> bool:
    """Whether ``model``'s own class was registered with :func:`register_model`."""
    return type(model).__dict__.get("_pytree_fields") is not None
