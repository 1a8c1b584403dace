"""World-metre tracks through the SIMULATED camera (models/jorge/eth.py), and the region
labels the stroke builder uses (models/jorge/strokes.py: region_labels)."""

from __future__ import annotations

import gzip
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dbn.errors import FileFormatError, InputError
from models.jorge import strokes as strokes_mod
from models.jorge.eth import ETH_FPS, ObliqueView, load_eth, read_obsmat
from models.jorge.strokes import build_strokes, pairwise_iou, region_labels, regions


# --- the view: closed form -------------------------------------------------------------
def test_view_boxes_closed_form():
    view = ObliqueView(tilt_deg=90.0, radius_m=0.25, height_m=1.75, px_per_m=10.0)
    box = view.boxes(np.array([[2.0, 3.0]]))[0]
    # straight down: a person is a 0.5 m square around the ground point, image y down
    np.testing.assert_allclose(box, [20.0, -30.0, 5.0, 5.0], atol=1e-12)
    low = ObliqueView(tilt_deg=1.0, px_per_m=1.0).boxes(np.array([0.0, 0.0]))
    assert low[3] == pytest.approx(0.5 * math.sin(math.radians(1)) + 1.75 * math.cos(math.radians(1)))
    assert np.isnan(view.boxes(np.array([[np.nan, np.nan]]))).all()


def test_view_overlap_depends_on_tilt():
    """One person 1 m behind another overlaps them in a 45 degree view, not from above."""
    ground = np.array([[[0.0, 0.0], [0.0, 1.0]]])
    assert pairwise_iou(ObliqueView(45.0).boxes(ground))[0, 0, 1] > 0.05
    assert pairwise_iou(ObliqueView(90.0).boxes(ground))[0, 0, 1] == 0.0


@pytest.mark.parametrize("field, value", [("tilt_deg", 0.0), ("tilt_deg", 91.0), ("radius_m", -1.0),
                                          ("height_m", float("nan")), ("px_per_m", "50"), ("tilt_deg", True)])
def test_view_rejects_bad_settings(field, value):
    with pytest.raises(InputError, match=f"ObliqueView.{field}"):
        ObliqueView(**{field: value})


def test_view_rejects_bad_shape():
    with pytest.raises(InputError, match="shape"):
        ObliqueView().boxes(np.zeros((3, 3)))


# --- the obsmat reader --------------------------------------------------------------------
ROWS = """\
   7.8000000e+02   1.0000000e+00   8.0   0.0   3.0   1.0   0.0   0.2
   7.8000000e+02   2.0000000e+00   8.2   0.0   3.5   1.0   0.0   0.2
   7.8600000e+02   1.0000000e+00   8.4   0.0   3.0   1.0   0.0   0.2
   8.1000000e+02   2.0000000e+00   9.0   0.0   3.5   1.0   0.0   0.2
"""


def _write(tmp_path, text: str, name="obsmat.txt.gz"):
    path = tmp_path / name
    with gzip.open(path, "wt") as fh:
        fh.write(text)
    return path


def test_load_eth_frames_rate_and_boxes(tmp_path):
    truth = load_eth(_write(tmp_path, ROWS), name="toy")
    # frames 780, 786, 810 every 6 video frames: indices 0, 1, 5, the empty 2-4 kept
    assert truth.frames.tolist() == [0, 1, 2, 3, 4, 5]
    assert truth.fps == ETH_FPS and truth.name == "toy" and truth.ids.tolist() == [1, 2]
    np.testing.assert_allclose(truth.boxes[0, 1], ObliqueView().boxes(np.array([8.2, 3.5])))
    assert np.isnan(truth.boxes[2:5]).all() and np.isnan(truth.boxes[1, 1]).all()


@pytest.mark.parametrize("text, line, what", [
    ("780 1 8.0 0.0\n", 1, "4 columns"),
    ("780 1 8.0 0.0 3.0\n780 1 8.0 0.0 x\n", 2, "y"),
    ("780.5 1 8.0 0.0 3.0\n", 1, "not an integer"),
    ("780 1 8.0 0.0 3.0\n780 1 8.1 0.0 3.0\n", 2, "twice"),
    ("780 1 inf 0.0 3.0\n", 1, "x"),
])
def test_read_obsmat_names_file_and_line(tmp_path, text, line, what):
    path = _write(tmp_path, text)
    with pytest.raises(FileFormatError, match=what) as err:
        read_obsmat(path)
    assert err.value.line == line and err.value.file == str(path)


@pytest.mark.parametrize("kwargs, what", [({"view": "45"}, "view"), ({"fps": 0.0}, "fps"),
                                          ({"fps": float("nan")}, "fps"), ({"fps": True}, "fps")])
def test_load_eth_rejects_bad_arguments(tmp_path, kwargs, what):
    with pytest.raises(InputError, match=f"load_eth: {what}"):
        load_eth(_write(tmp_path, ROWS), **kwargs)


def test_read_obsmat_empty_and_missing(tmp_path):
    with pytest.raises(FileFormatError, match="no rows"):
        read_obsmat(_write(tmp_path, "# nothing\n"))
    with pytest.raises(InputError, match="missing.obsmat"):
        load_eth(tmp_path / "missing.obsmat")


# --- region labels against the dense closure ---------------------------------------------
def _closure_labels(boxes: np.ndarray, thr: float) -> np.ndarray:
    """Oracle: breadth-first search over the overlap graph of each frame."""
    out = np.full(boxes.shape[:2], -1)
    adj = pairwise_iou(boxes) > thr
    for f in range(boxes.shape[0]):
        seen = set()
        for i in np.flatnonzero(~np.isnan(boxes[f, :, 0])):
            if i in seen:
                continue
            comp, todo = {int(i)}, [int(i)]
            while todo:
                j = todo.pop()
                for k in np.flatnonzero(adj[f, j]):
                    if int(k) not in comp:
                        comp.add(int(k))
                        todo.append(int(k))
            seen |= comp
            out[f, sorted(comp)] = min(comp)
    return out


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), frames=st.integers(0, 150), ids=st.integers(0, 9))
def test_region_labels_match_a_graph_search(seed, frames, ids):
    rng = np.random.default_rng(seed)
    boxes = np.concatenate([rng.uniform(0, 20, (frames, ids, 2)), rng.uniform(1, 6, (frames, ids, 2))], -1)
    boxes[rng.random((frames, ids)) < 0.3] = np.nan
    oracle = _closure_labels(boxes, 0.05)
    np.testing.assert_array_equal(region_labels(boxes, 0.05), oracle)
    same = regions(boxes, 0.05)  # the dense relation: two present boxes of one oracle region
    np.testing.assert_array_equal(same, (oracle[:, :, None] == oracle[:, None]) & (oracle >= 0)[:, :, None])


def test_region_labels_across_chunks(monkeypatch):
    """A region is the same whatever block of frames computes its overlaps."""
    rng = np.random.default_rng(3)
    boxes = np.concatenate([rng.uniform(0, 10, (20, 6, 2)), np.full((20, 6, 2), 3.0)], -1)
    whole = region_labels(boxes, 0.05)
    monkeypatch.setattr(strokes_mod, "_REGION_CHUNK", 3)
    np.testing.assert_array_equal(region_labels(boxes, 0.05), whole)


# --- the real sequence --------------------------------------------------------------------
def test_eth_seq_eth_makes_group_strokes(shared_data):
    path = shared_data / "eth" / "obsmat.txt.gz"
    if not path.is_file():
        pytest.skip(f"{path} is absent")
    truth = load_eth(path)
    assert truth.ids.size == 360 and truth.fps == ETH_FPS
    assert truth.num_frames == 1935  # 1448 annotated rows of frames, every 6th video frame, gaps kept
    sizes = np.array([len(s.truth) for s in build_strokes(0, truth)])
    # people walking together overlap in the oblique view: groups of three and more exist
    assert (sizes >= 3).sum() > 50 and (sizes == 1).sum() > (sizes >= 2).sum()
