"""``models.zajdel.fit``: the path model and appearance scales fitted on passes whose people
are known, against a pass-by-pass count and against the simulator's parameters
(SIMULATED offices)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dbn.errors import InputError
from models.zajdel.data import Observations
from models.zajdel.fit import fit_counts, fit_passes, pass_counts
from models.zajdel.simulate import OfficeConfig, simulate_office


def _passes(rng: np.random.Generator, people: int, per: int, C: int, B: int, r: int = 2):
    """Random passes of ``people`` people (``per`` each, one after the other in time),
    shuffled into quit-time order: (obs, person)."""
    rows = []
    for p in range(people):
        t = rng.uniform(0, 50)
        for _ in range(per):
            te = t + rng.uniform(0, 20)
            tq = te + rng.uniform(0, 5)
            rows.append((te, tq, rng.integers(C), rng.integers(B), rng.integers(B), p))
            t = tq
    rows.sort(key=lambda x: x[1])
    te, tq, cam, be, bq, person = (np.array(c) for c in zip(*rows))
    obs = Observations(rng.normal(size=(len(rows), r)), cam.astype(np.int64), te, tq,
                       be.astype(np.int64), bq.astype(np.int64))  # fmt: skip
    return obs, person


def _by_loop(obs: Observations, person: np.ndarray, C: int, B: int, lam: float):
    """The module docstring's estimates, pass by pass (the oracle)."""
    trans, entry = np.zeros((C, B, C, B)), np.zeros((C, B))
    moves: dict = {}
    for p in np.unique(person):
        idx = sorted(np.flatnonzero(person == p), key=lambda i: obs.t_enter[i])
        entry[obs.camera[idx[0]], obs.border_enter[idx[0]]] += 1
        for j, k in zip(idx[:-1], idx[1:]):
            trans[obs.camera[j], obs.border_quit[j], obs.camera[k], obs.border_enter[k]] += 1
            moves.setdefault((obs.camera[j], obs.camera[k]), []).append(
                obs.t_enter[k] - obs.t_quit[j])
    people = np.unique(person).size
    for c in range(C):
        for b in range(B):
            n = trans[c, b].sum()
            trans[c, b] = (trans[c, b] + lam / (C * B)) / (n + lam) if n + lam else 1 / (C * B)
    entry = (entry + lam / (C * B)) / (people + lam)
    every = np.concatenate(list(moves.values()))
    d0, s0 = every.mean(), every.std()
    s0 = s0 if s0 > 0 else max(abs(d0), 1.0)  # one travel time only: a spread of its size
    mean, std = np.full((C, C), d0), np.full((C, C), s0)
    for (a, b), x in moves.items():
        x = np.asarray(x)
        mean[a, b] = (lam * d0 + x.sum()) / (lam + x.size)
        std[a, b] = np.sqrt((lam * s0**2 + np.sum((x - mean[a, b]) ** 2)) / (lam + x.size))
    std = np.maximum(std, 1e-6 * s0)  # a spread of 0 (one move, no prior) floored
    return trans, entry, mean, std, (people + lam / 2) / (person.size + lam)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), lam=st.sampled_from([0.0, 0.5, 1.0, 7.0]),
       C=st.integers(1, 3), B=st.integers(1, 2))  # fmt: skip
def test_fit_equals_the_pass_by_pass_count(seed, lam, C, B):
    rng = np.random.default_rng(seed)
    obs, person = _passes(rng, int(rng.integers(2, 6)), int(rng.integers(2, 5)), C, B)
    fit = fit_passes([(obs, person)], C, B, lam)
    trans, entry, mean, std, p_new = _by_loop(obs, person, C, B, lam)
    np.testing.assert_allclose(fit.trans, trans, atol=1e-12)
    np.testing.assert_allclose(fit.trans.sum(axis=(2, 3)), 1.0, atol=1e-12)
    np.testing.assert_allclose(fit.entry, entry, atol=1e-12)
    np.testing.assert_allclose(fit.travel_mean, mean, rtol=1e-9)
    np.testing.assert_allclose(fit.travel_std, std, rtol=1e-6)
    assert fit.p_new == pytest.approx(p_new)


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_two_files_fit_as_their_summed_counts(seed):
    """Two files' statistics add up: the fit equals the one on both files' passes side by
    side (the second's people renamed, its times shifted far after the first's)."""
    rng = np.random.default_rng(seed)
    (o1, p1), (o2, p2) = _passes(rng, 3, 3, 2, 2), _passes(rng, 4, 2, 2, 2)
    shift = o1.t_quit.max() + 1e3
    both = Observations(np.concatenate([o1.appearance, o2.appearance]),
                        np.concatenate([o1.camera, o2.camera]),
                        np.concatenate([o1.t_enter, o2.t_enter + shift]),
                        np.concatenate([o1.t_quit, o2.t_quit + shift]),
                        np.concatenate([o1.border_enter, o2.border_enter]),
                        np.concatenate([o1.border_quit, o2.border_quit]))  # fmt: skip
    one = fit_passes([(both, np.concatenate([p1, p2 + 100]))], 2, 2, 1.0)
    two = fit_passes([(o1, p1), (o2, p2)], 2, 2, 1.0)
    for a, b in zip(one, two):
        np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-12)


def test_many_passes_recover_the_simulators_parameters():
    """A SIMULATED office of 300 people (6000 passes): the fit is the generator's layout
    (its entrances, not the tracker's 10 % spread), the new-person rate and both appearance
    scales (the travel spread is not checked: the generator truncates travel times at 0
    and the fit takes plain moments, as EM does)."""
    cfg = OfficeConfig(num_people=300, num_obs=6000, arrival_window=3000.0)
    sc = simulate_office(1, cfg)
    fit = fit_passes([(sc.obs, sc.labels)], cfg.num_cameras, cfg.num_borders, 1.0)
    path = sc.params.path
    np.testing.assert_allclose(fit.trans, np.exp(path.log_trans), atol=0.06)
    entrances = np.exp(path.log_entry) > 0.1 / path.log_entry.size + 1e-12
    assert fit.entry[entrances].sum() > 0.99
    used = np.exp(path.log_trans).sum(axis=(1, 3)) > 0
    np.testing.assert_allclose(fit.travel_mean[used], path.travel_mean[used], rtol=0.15)
    assert fit.p_new == pytest.approx(300 / 6000, rel=0.01)
    assert fit.within_std == pytest.approx(cfg.within_std, rel=0.05)
    assert fit.between_std == pytest.approx(cfg.separability * cfg.within_std, rel=0.05)


def test_the_spread_of_peoples_means_is_told_from_their_noise():
    """3000 people seen twice each: the spread of their mean appearances holds half the
    within-person variance besides theirs (0.0004 + 0.0004 / 2); the fit takes it out."""
    cfg = OfficeConfig(num_people=3000, num_obs=6000, arrival_window=30000.0)
    sc = simulate_office(2, cfg)
    fit = fit_passes([(sc.obs, sc.labels)], cfg.num_cameras, cfg.num_borders)
    assert fit.within_std == pytest.approx(cfg.within_std, rel=0.05)
    assert fit.between_std == pytest.approx(cfg.separability * cfg.within_std, rel=0.05)


def test_bad_passes_are_refused_naming_them():
    rng = np.random.default_rng(0)
    obs, person = _passes(rng, 3, 3, 2, 2)
    late = obs._replace(t_enter=obs.t_enter.copy())
    j = int(np.flatnonzero(person == person[-1])[-1])  # the last person's last pass
    late.t_enter[j] = obs.t_enter[j] - 1e3  # now it enters before the person's others quit
    # the moved pass now comes first of its person's and quits after the next one enters
    with pytest.raises(InputError, match=rf"person {person[-1]}: pass 10\d enters at .*before "
                       rf"pass 10{j} quits .*one person in one camera at a time"):  # fmt: skip
        pass_counts(late, person, 2, 2, ids=np.arange(person.size) + 100)
    with pytest.raises(InputError, match=r"camera ids up to 1 .* do not fit 1 cameras x 2"):
        pass_counts(obs, person, 1, 2)
    with pytest.raises(InputError, match=r"person: expected shape"):
        pass_counts(obs, person[:-1], 2, 2)
    alone, nobody = _passes(rng, 1, 3, 2, 2)
    with pytest.raises(InputError, match=r"1 people over 3 passes: the fit needs two people"):
        fit_passes([(alone, nobody)], 2, 2)
    with pytest.raises(InputError, match=r"9 people over 9 passes: .*someone seen twice"):
        fit_passes([(obs, np.arange(person.size))], 2, 2)
    with pytest.raises(InputError, match=r"appearance dimensions differ: \[2, 3\]"):
        fit_passes([(obs, person), _passes(rng, 2, 2, 2, 2, r=3)], 2, 2)
    with pytest.raises(InputError, match=r"strength = -1.0: expected a finite number >= 0"):
        fit_counts(pass_counts(obs, person, 2, 2), -1.0)
    with pytest.raises(InputError, match="no passes to fit on"):
        fit_passes([], 2, 2)
