"""models.jorge.checkpoint: the on-line labeller saved part way and resumed labels the rest
exactly as the labeller that never stopped (SIMULATED walkers, models.jorge.simulate)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from dbn.errors import CheckpointError
from inference.checkpoint import load_arrays, save_arrays
from models.jorge.checkpoint import _NAMES, FORMAT, load_labeller, save_labeller
from models.jorge.online import OnlineConfig, OnlineLabeller
from models.jorge.simulate import simulate_ground_truth
from models.jorge.strokes import build_strokes


@pytest.fixture(scope="module")
def strokes():
    return build_strokes(4, simulate_ground_truth(4, num_people=6, num_frames=500))


def _state(lab: OnlineLabeller) -> tuple:
    """Everything the labeller decides (without wall times)."""
    g = lab.graph
    return ({k: sorted(v) for k, v in lab.labels.items()},
            {k: b.tolist() for k, b in lab.beliefs.items()},
            [(nd.parents, nd.domain, nd.frozen) for nd in g.nodes],
            [(r.frame, r.num_active, r.max_domain, r.log_prob) for r in lab.records],
            lab._next_inference, sorted(lab._inferred), lab.instant_pruned_mass)


@pytest.mark.parametrize("cut", [0, 1, 17, 40])
def test_a_resumed_labeller_labels_the_rest_as_the_one_that_never_stopped(strokes, tmp_path, cut):
    cfg = OnlineConfig()
    whole, part = OnlineLabeller(cfg, strokes.fps), OnlineLabeller(cfg, strokes.fps)
    for s in strokes.strokes[:cut]:
        whole.add_stroke(s)
        part.add_stroke(s)
    save_labeller(tmp_path / "lab.npz", part)
    resumed = load_labeller(tmp_path / "lab.npz", cfg, strokes.fps)
    assert _state(resumed) == _state(part)
    for s in strokes.strokes[cut:]:
        whole.add_stroke(s)
        resumed.add_stroke(s)
    assert _state(resumed) == _state(whole)
    assert resumed.finish() == whole.finish()
    assert [nd.stroke.truth for nd in resumed.graph.nodes] == [s.truth for s in strokes.strokes]


def test_given_links_sizes_and_kept_windows_come_back(strokes, tmp_path):
    """Links given from outside (not the rule's), strokes without a size, kept windows."""
    rule = OnlineLabeller(OnlineConfig(), strokes.fps)
    for s in strokes.strokes[:12]:
        rule.add_stroke(s)
    k = next(nd.stroke.index for nd in rule.graph.nodes if nd.parents)  # the rule links it
    lab = OnlineLabeller(OnlineConfig(), strokes.fps, keep_windows=True)
    for s in strokes.strokes[:12]:
        bare = dataclasses.replace(s, extent=None) if s.index % 2 else s
        lab.add_stroke(bare, () if s.index == k else None)  # stroke k: no links, given
    assert lab.graph.nodes[k].parents == () and lab.graph.nodes[1].stroke.extent is None
    save_labeller(tmp_path / "lab.npz", lab)
    back = load_labeller(tmp_path / "lab.npz", OnlineConfig(), strokes.fps)
    assert _state(back) == _state(lab) and back.keep_windows
    assert back.graph.nodes[k].parents == ()
    assert back.graph.nodes[1].stroke.extent is None
    extent = back.graph.nodes[2].stroke.extent
    np.testing.assert_array_equal(extent, lab.graph.nodes[2].stroke.extent)


def test_another_configuration_rate_or_labeller_is_refused(strokes, tmp_path):
    cfg = OnlineConfig()
    lab = OnlineLabeller(cfg, strokes.fps)
    for s in strokes.strokes[:20]:
        lab.add_stroke(s)
    path = tmp_path / "lab.npz"
    save_labeller(path, lab)
    with pytest.raises(CheckpointError, match="lab.npz"):
        load_labeller(path, dataclasses.replace(cfg, period_s=cfg.period_s * 2), strokes.fps)
    with pytest.raises(CheckpointError, match="lab.npz"):
        load_labeller(path, cfg, strokes.fps / 2)
    # a file whose labels the replay does not give back (another labeller saved it)
    arrays, header = load_arrays(path, FORMAT, _NAMES, {"online": cfg, "fps": strokes.fps})
    relabelled = dict(arrays, labels=arrays["labels"] + 1000)
    extra = {k: header[k] for k in ("keep_windows", "num_inferences")}
    save_arrays(tmp_path / "other.npz", relabelled, FORMAT, {"online": cfg, "fps": strokes.fps},
                extra)
    with pytest.raises(CheckpointError, match="labels otherwise"):
        load_labeller(tmp_path / "other.npz", cfg, strokes.fps)
    # nor the inference count (an inference run from outside add_stroke): refused at saving
    extra_run = dict(extra, num_inferences=extra["num_inferences"] + 1)
    save_arrays(tmp_path / "ran.npz", arrays, FORMAT, {"online": cfg, "fps": strokes.fps},
                extra_run)
    with pytest.raises(CheckpointError, match="inferences run from outside"):
        load_labeller(tmp_path / "ran.npz", cfg, strokes.fps)
    assert len(lab.records) > 0  # the periodic inferences of add_stroke are saved
    lab.infer(strokes.strokes[19].start)
    with pytest.raises(CheckpointError, match="inferences run from outside add_stroke"):
        save_labeller(tmp_path / "after.npz", lab)
    assert not (tmp_path / "after.npz").exists()
    # links the replay cannot take (a later stroke as a parent), a file that is not one
    parents = arrays["parents"].copy()
    parents[0] = 15
    save_arrays(tmp_path / "links.npz", dict(arrays, parents=parents), FORMAT,
                {"online": cfg, "fps": strokes.fps}, extra)
    with pytest.raises(CheckpointError, match=r"links.npz.*stroke \d+"):
        load_labeller(tmp_path / "links.npz", cfg, strokes.fps)
    counts = arrays["num_frames"].copy()
    counts[-1] += 1  # the rows do not add up to the frames array
    save_arrays(tmp_path / "rows.npz", dict(arrays, num_frames=counts), FORMAT,
                {"online": cfg, "fps": strokes.fps}, extra)
    with pytest.raises(CheckpointError, match="'frames' does not hold 20 strokes"):
        load_labeller(tmp_path / "rows.npz", cfg, strokes.fps)
    (tmp_path / "bad.npz").write_bytes(b"not a zip")
    with pytest.raises(CheckpointError, match="bad.npz"):
        load_labeller(tmp_path / "bad.npz", cfg, strokes.fps)
