"""The confirmation of a change on fresh training-side seeds (models/jorge/confirm.py)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from dbn.errors import InputError
from models.jorge import confirm
from models.jorge.network import NetworkConfig
from models.jorge.simulate import simulate_ground_truth
from models.jorge.strokes import build_strokes


def _small_sets(seed: int) -> list:
    """Two SIMULATED sequences of three walkers per seed (no shared data needed)."""
    return [build_strokes(seed, simulate_ground_truth(seed + k, num_people=3, num_frames=150)) for k in (0, 50)]


def test_a_network_against_itself_differs_by_nothing():
    res = confirm.compare(NetworkConfig(), [3, 4], sets=_small_sets)
    np.testing.assert_array_equal(res.candidate, res.incumbent)
    assert res.difference == 0.0 and res.standard_error == 0.0 and res.lower_on == 0
    assert all(a == b for a, b in res.per_set.values())
    assert res.seeds == (3, 4) and res.incumbent.shape == (2,)


def test_the_paired_figures_in_closed_form(monkeypatch):
    # per seed two sets with known errors (incumbent, candidate): the seed means, their
    # paired difference, its standard error and the per-set means follow by hand
    table = {(0, "a"): (0.2, 0.1), (0, "b"): (0.4, 0.4), (1, "a"): (0.3, 0.3), (1, "b"): (0.1, 0.2),
             (2, "a"): (0.5, 0.2), (2, "b"): (0.5, 0.4)}

    class Named:
        def __init__(self, seed, name):
            self.seed, self.name = seed, name

    monkeypatch.setattr(confirm, "_label_one", lambda job: (job[2].name, *table[job[2].seed, job[2].name]))
    res = confirm.compare(NetworkConfig(), [0, 1, 2], sets=lambda s: [Named(s, "a"), Named(s, "b")])
    np.testing.assert_allclose(res.incumbent, [0.3, 0.2, 0.5])
    np.testing.assert_allclose(res.candidate, [0.25, 0.25, 0.3])
    d = np.array([-0.05, 0.05, -0.2])
    assert res.difference == pytest.approx(d.mean())
    assert res.standard_error == pytest.approx(d.std(ddof=1) / np.sqrt(3))
    assert res.lower_on == 2
    assert res.per_set["a"] == pytest.approx((1.0 / 3, 0.2)) and res.per_set["b"] == pytest.approx((1.0 / 3, 1.0 / 3))
    summary = res.summary()
    assert summary["seeds"] == [0, 1, 2] and summary["num_seeds"] == 3 and json.dumps(summary)


@pytest.mark.parametrize("seeds", [[], [5, 5]])
def test_compare_needs_distinct_seeds(seeds):
    with pytest.raises(InputError, match="distinct seeds"):
        confirm.compare(NetworkConfig(), seeds, sets=_small_sets)


def test_a_seed_without_sets_is_refused_before_any_labelling():
    with pytest.raises(InputError, match="seed 7 has no set"):
        confirm.compare(NetworkConfig(), [6, 7], sets=lambda s: _small_sets(s) if s == 6 else [])


@pytest.mark.parametrize("name", ["no_such_field", "labels", "size_sigma", "palette_gain_table"])
def test_refit_refuses_unknown_or_fitted_fields(name):
    with pytest.raises(InputError, match=name):
        confirm.refit({name: 1})


def test_the_confirmation_sets_are_the_search_sets_and_the_meetings_at_7_fps(shared_data):
    from models.jorge.fit import MEETING_SIZES, TRAIN_SEQUENCES

    sets = confirm.confirmation_sets(800)
    assert len(sets) == len(TRAIN_SEQUENCES) + 2 * len(MEETING_SIZES)
    assert [s.fps for s in sets[-3:]] == [7.0] * 3 and [s.fps for s in sets[-6:-3]] == [25.0] * 3
    assert len({confirm._set_name(s) for s in sets}) == len(sets)


@pytest.mark.parametrize("bad", ["max_gap_frames", "=3", "max_gap_frames=sixty"])
def test_a_bad_change_names_itself(bad):
    with pytest.raises(InputError, match="--set"):
        confirm.main(["--set", bad, "--seeds", "880", "882"])


def test_an_empty_seed_range_is_refused_before_any_refit(monkeypatch):
    monkeypatch.setattr(confirm, "refit", lambda changes=None: pytest.fail("refitted"))
    with pytest.raises(InputError, match="--seeds 882 880"):
        confirm.main(["--seeds", "882", "880"])


def test_main_prints_the_summary_of_the_refitted_networks(monkeypatch, capsys):
    seen = {}

    def fake_refit(changes=None):
        seen.setdefault("refits", []).append(dict(changes or {}))
        return NetworkConfig(max_gap_frames=60) if changes else NetworkConfig()

    def fake_compare(candidate, seeds, incumbent=None, workers=1):
        seen.update(candidate=candidate, seeds=list(seeds), incumbent=incumbent, workers=workers)
        return confirm.Comparison(tuple(seeds), np.array([0.2, 0.3]), np.array([0.1, 0.3]), {"x": (0.25, 0.2)})

    monkeypatch.setattr(confirm, "refit", fake_refit)
    monkeypatch.setattr(confirm, "compare", fake_compare)
    confirm.main(["--set", "max_gap_frames=60", "--seeds", "880", "882", "--workers", "2"])
    out = json.loads(capsys.readouterr().out)
    assert seen["refits"] == [{"max_gap_frames": 60}, {}]
    assert seen["candidate"].max_gap_frames == 60 and seen["incumbent"] == NetworkConfig()
    assert seen["seeds"] == [880, 881] and seen["workers"] == 2
    assert out["changes"] == {"max_gap_frames": 60} and out["difference"] == pytest.approx(-0.05)
    assert out["lower_on"] == 1


def test_one_seed_has_no_standard_error():
    res = confirm.Comparison((9,), np.array([0.2]), np.array([0.1]), {})
    assert np.isnan(res.standard_error) and res.summary()["standard_error"] is None
    json.loads(json.dumps(res.summary()))  # strict JSON: no NaN
