r"""The slice model of the multi-camera tracker declared with :mod:`dbn` (seed 002,
section 1.4.2, fig. 1.2; eqs. 1.15-1.19).

Variables of slice k (a two-slice template; ``P = max_people`` and ``T = max_slices``
bound the finite cardinalities of the declaration only, the tracker grows past them):

=================  ==========================================  =============================
variable           CPD                                         seed 002
=================  ==========================================  =============================
``clock``          deterministic: ``clock_k = clock_{k-1}+1``  (slice index, for pointers)
``label``          tabular, parent ``counter[t-1]``: uniform   eq. 1.16
                   over 1..c+1, or ``p_new`` for the new one
``counter``        deterministic: ``c_k = c_{k-1} + [l_k new]``  eq. 1.17
``pointer_n``      deterministic: ``z^(n) = k-1 if l_{k-1}=n``   "pointers" (Zajdel 2004)
                   else ``z^(n)_{k-1}``; 0 = never seen
``state``          NIW(theta_0) if new, else a copy of          eqs. 1.15, 1.18
                   ``x_{z^(l)}`` (the non-Markov edge of fig. 1.2)
``appearance``     ``N(m_k, V_k)``                              eq. 1.19
``where_when``     ``p_delta(d_k | d_{z^(l)})`` or               eq. 1.19, seed 000 eq. 2
                   ``p_delta0(d_k)``
=================  ==========================================  =============================

The copy of a past state and the path term's dependence on the observation at the
pointer's slice reach back more than one slice; the template records them as CPDs whose
parents are the label and the pointers (the structure), with the parameters inside
(theta_0, the path model); :class:`~models.zajdel.tracker.ZajdelADF` reads the
parameters from :meth:`ZajdelModel.to_params` and checks the structure with
:meth:`ZajdelModel.check_structure`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from dbn.cpds import DeterministicCPD, TabularCPD
from dbn.dbn import TwoSliceDBN, prev
from dbn.errors import ModelError
from dbn.variables import ContinuousVariable, DiscreteVariable
from inference.adf.niw import NIW, niw_predictive_logpdf_np
from models.zajdel.params import ZajdelParams, check_params
from models.zajdel.path import PathModel, log_p_delta, log_p_delta0

__all__ = [
    "NIWStateCPD",
    "AppearanceCPD",
    "PathCPD",
    "ZajdelModel",
    "declare_model",
    "label_prior_table",
]


def label_prior_table(max_people: int, p_new: float | None) -> np.ndarray:
    """Table (max_people + 1, max_people) of P(l_k = n | c_{k-1} = c) (seed 002, eq. 1.16).

    Row c: uniform over persons 0..c (c = the new one), or ``p_new`` on person c and
    ``(1 - p_new) / c`` on each known one (row 0: the first person is new). Row
    ``max_people`` (no room for a new person) spreads over the known ones."""
    P = int(max_people)
    t = np.zeros((P + 1, P))
    for c in range(P + 1):  # a small declaration table (P + 1 rows)
        known = min(c, P)
        if c >= P:
            t[c, :P] = 1.0 / P
        elif p_new is None or c == 0:
            t[c, : c + 1] = 1.0 / (c + 1)
        else:
            t[c, :known] = (1.0 - p_new) / known
            t[c, c] = p_new
    return t


class NIWStateCPD:
    """``x_k = (m_k, V_k)``: a fresh draw from NIW(theta_0) for a new person, else the copy
    of the person's last state (seed 002, eqs. 1.15 and 1.18)."""

    def __init__(self, variable: str, parents, prior: NIW):
        self.variable = variable
        self.parents = tuple(parents)
        self.prior = prior

    def renamed(self, variable: str, parents):
        return NIWStateCPD(variable, parents, self.prior)

    def sample(self, key: Any, parent_values: dict[str, Any]):
        """(m, V) from NIW(theta_0) (``key``: a numpy Generator or an int seed), or the
        ``"copy"`` entry of ``parent_values`` when the person has been seen."""
        if parent_values.get("copy") is not None:
            return parent_values["copy"]
        from scipy.stats import invwishart

        rng = np.random.default_rng(key)
        a, kappa, eta, C = (np.asarray(x, float) for x in self.prior)
        V = np.atleast_2d(invwishart(df=float(eta), scale=C).rvs(random_state=rng))
        m = rng.multivariate_normal(a, V / float(kappa))
        return m, V

    def log_prob(self, value, parent_values: dict[str, Any]):
        """log NIW density of (m, V) under theta_0 (a new person)."""
        from scipy.stats import invwishart, multivariate_normal

        m, V = value
        a, kappa, eta, C = (np.asarray(x, float) for x in self.prior)
        return float(
            invwishart(df=float(eta), scale=C).logpdf(V)
            + multivariate_normal(a, V / float(kappa)).logpdf(m)
        )


class AppearanceCPD:
    """``o_k ~ N(m_k, V_k)`` (seed 002, eq. 1.19); marginally over a NIW state, the
    Student-t predictive of :func:`inference.adf.niw.niw_predictive_logpdf_np`."""

    def __init__(self, variable: str, parents):
        self.variable = variable
        self.parents = tuple(parents)

    def renamed(self, variable: str, parents):
        return AppearanceCPD(variable, parents)

    def sample(self, key: Any, parent_values: dict[str, Any]):
        m, V = parent_values[self.parents[0]]
        return np.random.default_rng(key).multivariate_normal(m, V)

    def log_prob(self, value, parent_values: dict[str, Any]):
        from scipy.stats import multivariate_normal

        m, V = parent_values[self.parents[0]]
        return float(multivariate_normal(m, V).logpdf(value))

    @staticmethod
    def predictive_log_prob(value, theta: NIW) -> np.ndarray:
        """log of the appearance marginalised over a NIW(theta) state."""
        return niw_predictive_logpdf_np(value, theta)


class PathCPD:
    """``d_k ~ p_delta(d_k | d_j)`` for a returning person last seen at slice j, else
    ``p_delta0(d_k)`` (seed 002, eq. 1.19; seed 000, eq. 2). Value: (camera, t_enter,
    t_quit, border_enter, border_quit)."""

    def __init__(self, variable: str, parents, path: PathModel):
        self.variable = variable
        self.parents = tuple(parents)
        self.path = path

    def renamed(self, variable: str, parents):
        return PathCPD(variable, parents, self.path)

    def sample(self, key: Any, parent_values: dict[str, Any]):
        raise ModelError("where_when: sample paths with models.zajdel.simulate")

    def log_prob(self, value, parent_values: dict[str, Any]):
        """``parent_values["previous"]``: the d of the person's last slice, or None."""
        cam, te, _tq, be, _bq = value
        last = parent_values.get("previous")
        if last is None:
            return float(log_p_delta0(self.path, int(cam), int(be)))
        lcam, _lte, ltq, _lbe, lbq = last
        return float(log_p_delta(self.path, int(lcam), int(lbq), ltq, int(cam), int(be), te))


class ZajdelModel:
    """A declared tracking model: the :class:`~dbn.dbn.TwoSliceDBN` and its parameters.

    Attributes
    ----------
    dbn : TwoSliceDBN
    max_people, max_slices : the bounds of the declaration's finite cardinalities
    """

    def __init__(self, dbn: TwoSliceDBN, max_people: int, max_slices: int):
        self.dbn = dbn
        self.max_people = max_people
        self.max_slices = max_slices
        self.check_structure()

    def _cpd(self, name: str):
        for c in self.dbn.transition_cpds:
            if c.variable == name:
                return c
        raise ModelError(f"the declaration has no variable {name!r}")

    def check_structure(self) -> None:
        """Raise :class:`~dbn.errors.ModelError` unless the declaration has the structure
        the ADF implements (label <- counter[t-1]; counter <- counter[t-1], label; the
        state, appearance and path CPDs of this module)."""
        want = {
            "label": (TabularCPD, (prev("counter"),)),
            "counter": (DeterministicCPD, (prev("counter"), "label")),
            "state": (NIWStateCPD, None),
            "appearance": (AppearanceCPD, ("state",)),
            "where_when": (PathCPD, None),
        }
        for name, (kind, parents) in want.items():
            c = self._cpd(name)
            if not isinstance(c, kind):
                raise ModelError(f"{name}: expected a {kind.__name__}, got {type(c).__name__}")
            if parents is not None and tuple(c.parents) != parents:
                raise ModelError(f"{name}: expected parents {parents}, got {tuple(c.parents)}")

    def to_params(self) -> ZajdelParams:
        """The tracker's parameters read from the declaration: theta_0 from the state
        CPD, the path model from the path CPD, the label prior from the label table
        (uniform rows -> ``p_new = None``, else ``p_new`` = P(new | one known person))."""
        table = np.asarray(self._cpd("label").table)
        P = self.max_people
        uniform = np.allclose(table[: P], label_prior_table(P, None)[: P], atol=1e-12)
        p_new = None if uniform else float(table[1, 1]) if P > 1 else None
        params = ZajdelParams(self._cpd("state").prior, self._cpd("where_when").path, p_new)
        check_params(params)
        return params


def declare_model(params: ZajdelParams, max_people: int = 4, max_slices: int = 6) -> ZajdelModel:
    """Declare the slice model of seed 002, section 1.4.2 with :mod:`dbn`.

    Parameters
    ----------
    params : ZajdelParams (theta_0, path model, label prior)
    max_people, max_slices : bounds of the finite cardinalities of the declaration (the
        discrete part can be unrolled and solved exactly for small bounds)

    Returns
    -------
    ZajdelModel
    """
    check_params(params)
    P, T = int(max_people), int(max_slices)
    r = params.obs_dim
    clock = DiscreteVariable("clock", T + 1)
    label = DiscreteVariable("label", P)
    counter = DiscreteVariable("counter", P + 1)
    pointers = [DiscreteVariable(f"pointer_{n}", T + 1) for n in range(P)]
    state = ContinuousVariable("state", r + r * r)
    appearance = ContinuousVariable("appearance", r)
    where_when = ContinuousVariable("where_when", 5)
    table = label_prior_table(P, params.p_new)

    def count(cp, lab):
        return np.minimum(cp + (lab == cp), P)

    def make_pointer(n):
        def fn(zp, lp, kp):  # z^(n)_k = k - 1 (1-based slice index kp + 1) if l_{k-1} = n
            return np.where(lp == n, np.minimum(kp + 1, T), zp)

        return fn

    initial = [
        DeterministicCPD("clock", [], lambda: np.int64(0)),
        TabularCPD("label", [], table[0]),
        DeterministicCPD("counter", ["label"], lambda lab: np.minimum(lab + 1, P)),
        *[DeterministicCPD(f"pointer_{n}", [], lambda: np.int64(0)) for n in range(P)],
        NIWStateCPD("state", ["label"], params.prior),
        AppearanceCPD("appearance", ["state"]),
        PathCPD("where_when", ["label"], params.path),
    ]
    transition = [
        DeterministicCPD("clock", [prev("clock")], lambda kp: np.minimum(kp + 1, T)),
        TabularCPD("label", [prev("counter")], table),
        DeterministicCPD("counter", [prev("counter"), "label"], count),
        *[
            DeterministicCPD(f"pointer_{n}", [prev(f"pointer_{n}"), prev("label"), prev("clock")], make_pointer(n))
            for n in range(P)
        ],
        NIWStateCPD("state", ["label", *[f"pointer_{n}" for n in range(P)]], params.prior),
        AppearanceCPD("appearance", ["state"]),
        PathCPD("where_when", ["label", *[f"pointer_{n}" for n in range(P)]], params.path),
    ]
    dbn = TwoSliceDBN(
        [clock, label, counter, *pointers, state, appearance, where_when], initial, transition
    )
    return ZajdelModel(dbn, P, T)
