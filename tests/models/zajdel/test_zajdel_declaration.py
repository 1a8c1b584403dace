"""The dbn declaration of the Zajdel slice model: the tracker reads it, and its discrete
part (label, counter, pointers) encodes exactly the tracker's label prior."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from dbn.bayesnet import BayesNet
from dbn.variables import DiscreteVariable
from inference.exact import variable_elimination
from models.zajdel.data import take
from models.zajdel.model import declare_model
from models.zajdel.scores import canonical_labels, label_prior_log_prob
from models.zajdel.simulate import simulate_office
from models.zajdel.tracker import ADFConfig, ZajdelADF


def discrete_part(bn: BayesNet) -> BayesNet:
    names = [n for n, v in bn.variables.items() if isinstance(v, DiscreteVariable)]
    return BayesNet([bn.variables[n] for n in names], [bn.cpds[n] for n in names])


@pytest.mark.parametrize("p_new", [None, 0.2])
def test_unrolled_label_prior_equals_tracker_prior(p_new):
    sc = simulate_office(0)
    model = declare_model(sc.params._replace(p_new=p_new), max_people=4, max_slices=4)
    assert model.to_params().p_new == (None if p_new is None else pytest.approx(p_new))
    T = 4
    bn = discrete_part(model.dbn.unroll(T))
    q = [f"label_{t}" for t in range(T)]
    joint = variable_elimination(bn, q)
    vals = np.exp(joint.log_values)
    axes = [joint.variables.index(n) for n in q]
    vals = np.transpose(vals, axes)
    for seq in itertools.product(range(4), repeat=T):
        seq = np.array(seq)
        canonical = np.array_equal(canonical_labels(seq), seq)
        want = np.exp(label_prior_log_prob(seq, p_new)) if canonical else 0.0
        assert vals[tuple(seq)] == pytest.approx(want, abs=1e-12)


def test_unrolled_pointers_point_at_last_slice():
    sc = simulate_office(0)
    model = declare_model(sc.params, max_people=3, max_slices=4)
    bn = discrete_part(model.dbn.unroll(4))
    # labels 0, 1, 0, 1: at slice 3, person 0 was last seen at slice 2 (1-based 3)
    ev = {"label_0": 0, "label_1": 1, "label_2": 0}
    post = variable_elimination(bn, ["pointer_0_3", "pointer_1_3", "counter_2"], evidence=ev)
    vals = np.exp(post.log_values)
    idx = np.unravel_index(np.argmax(vals), vals.shape)
    got = dict(zip(post.variables, idx))
    assert got == {"pointer_0_3": 3, "pointer_1_3": 2, "counter_2": 2}
    assert vals.max() == pytest.approx(1.0)


def test_tracker_reads_the_declaration():
    sc = simulate_office(1)
    obs = take(sc.obs, slice(0, 10))
    cfg = ADFConfig(max_open=12, persons_per_slot=8, init_persons=32, chunk=8, link_out=12, label_out=12)
    _, a = ZajdelADF(declare_model(sc.params), cfg).run(obs)
    _, b = ZajdelADF(sc.params, cfg).run(obs)
    np.testing.assert_array_equal(a.link_prob, b.link_prob)
