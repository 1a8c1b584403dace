"""The simulated calibrated scene (seed 003): coverage, rendering, detector, walkers, metrics."""

from __future__ import annotations

import numpy as np
import pytest

from dbn.errors import InputError
from models.rjmcmc3d.metrics import evaluate
from models.rjmcmc3d.scene import (
    BoxProjector,
    coverage_fractions,
    default_scene,
    part_boxes,
    render_frame,
    simulate_walkers,
)
from models.rjmcmc3d.tracker import FrameResult


@pytest.fixture(scope="module")
def scene():
    return default_scene(0, width=192, height=144)


def test_partial_overlap_like_the_metro_scene() -> None:
    frac = coverage_fractions(default_scene(0), step=0.2)
    assert frac.sum() == pytest.approx(1.0)
    assert frac[1] > 0.5, f"most of the floor should be seen by exactly one camera: {frac}"
    assert 0.1 < frac[2] + frac[3] < 0.45, f"a minority by two or more: {frac}"


def test_people_sizes_differ_across_views() -> None:
    sc = default_scene(0)
    boxes = part_boxes(sc.P, np.array([[11.0, 4.0]]), np.array([1.75]), np.array([0.0]), 384, 288)
    heights = boxes[:, 0, :, 3].max(-1) - boxes[:, 0, :, 1].min(-1)
    seen = heights[heights > 0]
    assert len(seen) >= 2 and seen.max() > 1.5 * seen.min()


def test_fast_projector_equals_part_boxes(scene) -> None:
    proj = BoxProjector(scene)
    rng = np.random.default_rng(0)
    for _ in range(200):
        x, y = rng.uniform(-1, 21), rng.uniform(-1, 9)
        h, a = rng.uniform(1.4, 2.0), rng.uniform(-np.pi, np.pi)
        boxes, bbox, depth = proj.one(x, y, h, a)
        ref = part_boxes(
            scene.P, np.array([[x, y]]), np.array([h]), np.array([a]), scene.width, scene.height
        )[:, 0]
        assert np.array_equal(np.array(boxes), ref)
        for v in range(3):
            ne = [b for b in ref[v] if b[2] > b[0] and b[3] > b[1]]
            if ne:
                ne = np.array(ne)
                assert bbox[v] == [ne[:, 0].min(), ne[:, 1].min(), ne[:, 2].max(), ne[:, 3].max()]
        assert np.allclose(depth, np.hypot(x - scene.centers[:, 0], y - scene.centers[:, 1]))


def test_walkers_enter_and_leave(scene) -> None:
    truth = simulate_walkers(1, scene, 200, 5)
    counts = [len(f.ids) for f in truth.frames]
    assert 3 <= np.mean(counts) <= 6
    all_ids = np.unique(np.concatenate([f.ids for f in truth.frames]))
    assert len(all_ids) > 5  # some left and new ones came in
    for f in truth.frames:
        assert np.all((f.u[:, 0] >= 0) & (f.u[:, 0] <= 20) & (f.u[:, 1] >= 0) & (f.u[:, 1] <= 8))
    with pytest.raises(InputError, match="num_frames"):
        simulate_walkers(1, scene, 0, 5)


def test_render_and_detector(scene) -> None:
    truth = simulate_walkers(4, scene, 30, 6)
    errs, n_det, n_true = [], 0, 0
    for t in range(0, 30, 3):
        fr = render_frame(5, scene, truth, t)
        assert fr.D.shape == (3, scene.height, scene.width)
        assert fr.D.min() >= 0 and fr.D.max() <= 1 and fr.image.min() >= 0 and fr.image.max() <= 1
        a = render_frame(5, scene, truth, t)
        assert np.array_equal(a.D, fr.D) and np.array_equal(a.det_px, fr.det_px)
        u = truth.frames[t].u
        n_true += len(u)
        for g in fr.det_ground:
            d = np.hypot(*(u - g).T).min() if len(u) else np.inf
            errs.append(d)
        n_det += len(fr.det_ground)
    errs = np.array(errs)
    assert np.mean(errs < 1.0) > 0.6  # most detections are near a person (some are false alarms)
    assert n_det > 0.5 * n_true


def test_metrics_through_motmetrics() -> None:
    sc = default_scene(0, width=192, height=144)
    truth = simulate_walkers(2, sc, 20, 3)
    perfect = [
        FrameResult(
            f.ids + 100,
            np.c_[f.u, np.zeros((len(f.ids), 4))],
            np.ones(len(f.ids)),
            np.zeros(6),
            0.0,
        )
        for f in truth.frames
    ]
    m = evaluate(truth.frames, perfect)
    assert m["mota"] == pytest.approx(1.0) and m["idf1"] == pytest.approx(1.0)
    assert m["id_switches"] == 0
    # swap two hypothesis identities half-way: switches are counted
    swapped = []
    for t, r in enumerate(perfect):
        ids = r.ids.copy()
        if t >= 10 and len(ids) >= 2:
            ids[[0, 1]] = ids[[1, 0]]
        swapped.append(r._replace(ids=ids))
    m2 = evaluate(truth.frames, swapped)
    assert m2["id_switches"] >= 2 and m2["idf1"] < 1.0
    # positions off by more than 0.5 m are misses plus false positives
    off = [r._replace(X=r.X + np.array([0.6, 0, 0, 0, 0, 0])) for r in perfect]
    m3 = evaluate(truth.frames, off)
    assert m3["mota"] < 0 and m3["misses"] == m3["num_objects"]
    with pytest.raises(InputError, match="frames"):
        evaluate(truth.frames, perfect[:-1])
    for bad in (float("nan"), 0.0, -1.0, "0.5", float("inf")):  # nan ran
        with pytest.raises(InputError, match="must be a positive number"):
            evaluate(truth.frames, perfect, threshold=bad)


def _cam():
    from models.rjmcmc3d.geometry import look_at_camera

    return look_at_camera(np.array([0.0, -5, 5]), np.array([0.0, 5, 0]), 500.0, 320, 240)


@pytest.mark.parametrize(("args", "needle"), [
    (dict(floor=[10, 0, 0, 10]), "floor = [10.0, 0.0, 0.0, 10.0]: need [x_min, x_max"),
    (dict(floor=np.array([0, 10, 0, 10]) + 0j), "floor holds complex numbers"),
    (dict(floor=["a"] * 4), "floor must be numbers"),
    (dict(sigma_px=[-1.0]), "sigma_px = [-1.0]: every number must be >= 1e-100"),
    (dict(sigma_px=["x"]), "sigma_px must be numbers"),
    (dict(colour_gain=np.ones((2, 3))), "colour_gain has 6 numbers"),
    (dict(colour_gain=[[1.0, -1.0, 1.0]]), "colour_gain = [1.0, -1.0, 1.0]"),
    (dict(cameras=[]), "cameras must be a non-empty list of Camera"),
    (dict(cameras=[5]), "cameras[0] must be an instance of Camera, got int"),
])  # fmt: skip
def test_scene_from_cameras_checks_its_arguments(args, needle) -> None:
    """An inverted floor, a negative noise or gain, or a gain per view of the wrong shape
    built a scene that tracked garbage; text raised numpy's ValueError."""
    from dbn.errors import DBNError
    from models.rjmcmc3d.calibration import scene_from_cameras

    kw = dict(cameras=[_cam()], floor=[0, 10, 0, 10], colour_gain=np.ones((1, 3)),
              sigma_px=np.ones(1))  # fmt: skip
    with pytest.raises(DBNError) as exc:
        scene_from_cameras(0, **{**kw, **args})
    assert needle in str(exc.value)


def test_camera_geometry_refuses_complex_and_text() -> None:
    """look_at_camera and the homographies cast complex positions to their real parts."""
    from models.rjmcmc3d.geometry import ground_homography, look_at_camera, projection_matrix

    with pytest.raises(InputError, match="position holds complex numbers"):
        look_at_camera(np.array([0.0, -5, 5]) + 0j, np.array([0.0, 5, 0]), 500.0, 320, 240)
    with pytest.raises(InputError, match="target is not an array of numbers"):
        look_at_camera(np.array([0.0, -5, 5]), ["a"] * 3, 500.0, 320, 240)
    with pytest.raises(InputError, match="P holds complex numbers"):
        ground_homography(projection_matrix(_cam()) + 0j)
