"""Detections of ``dbntrack track rjmcmc3d`` whose feet are above a view's horizon.

A foreground blob above the horizon maps through the ground homography to a point behind
the camera (on the ray's backward extension), which the default floor (the span of the
camera centres) can contain: such a blob used to become a detection there.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from models.io.rjmcmc3d import read_view
from models.rjmcmc3d.calibration import scene_from_cameras
from models.rjmcmc3d.geometry import camera_center, in_front, look_at_camera
from models.track.rjmcmc3d import _ground

DATA = Path(__file__).resolve().parents[2] / "data" / "rjmcmc3d"


@settings(max_examples=40, deadline=None)
@given(
    pos=st.tuples(st.floats(-20, 20), st.floats(-20, 20), st.floats(1, 10)),
    target=st.tuples(st.floats(-20, 20), st.floats(-20, 20)),
    pts=st.lists(st.tuples(st.floats(-50, 50), st.floats(-50, 50)), min_size=1, max_size=8),
)
def test_in_front_is_the_side_of_the_optical_axis(pos, target, pts):
    """Oracle: a point is in front when its offset from the camera centre has a positive
    component along the optical axis (the camera's looking direction)."""
    position, aim = np.array(pos), np.array([*target, 0.0])
    if np.linalg.norm(aim[:2] - position[:2]) < 0.5:
        aim[0] += 1.0
    cam = look_at_camera(position, aim, 500.0, 320, 240)
    axis = (aim - position) / np.linalg.norm(aim - position)
    g = np.array(pts)
    offset = np.c_[g, np.zeros(len(g))] - camera_center(cam)
    along = offset @ axis
    sure = np.abs(along) > 1e-6
    assert np.array_equal(in_front(cam, g)[sure], (along > 0)[sure])


def _scene():
    cams = [read_view(DATA / f"view{v}", 1.0).camera for v in range(3)]
    return scene_from_cameras(0, cams, np.array([0.0, 20, 0, 8]), np.ones((3, 3)),
                              np.full(3, 4.0))  # fmt: skip


def _pixel(scene, v: int, g: np.ndarray) -> np.ndarray:
    x = scene.P[v] @ np.array([g[0], g[1], 0.0, 1.0])
    return x[:2] / x[2]


def test_feet_behind_a_camera_are_not_detections():
    """Per view: a foot on the floor is kept at its ground point; the pixel of a ground
    point 30 m behind the camera (above the horizon: it maps back there) is dropped."""
    scene = _scene()
    for v, cam in enumerate(scene.cameras):
        c = camera_center(cam)[:2]
        ahead = np.array([10.0, 4.0])
        look = cam.R[2, :2] / np.linalg.norm(cam.R[2, :2])  # the optical axis on the ground
        behind = c - 30.0 * look
        assert in_front(cam, ahead[None])[0] and not in_front(cam, behind[None])[0]
        dpx = np.array([_pixel(scene, v, ahead), _pixel(scene, v, behind)])
        dv, kept_px, ground = _ground(scene, np.array([v, v]), dpx)
        assert dv.tolist() == [v], f"view {v}: kept {dv.tolist()}"
        assert np.allclose(kept_px, dpx[:1]) and np.allclose(ground, ahead[None], atol=1e-6)


def test_feet_on_the_horizon_are_not_detections():
    """A pixel on the horizon maps to infinity (or beyond MAX_METRES): dropped, and no
    numpy warning or NonFiniteError escapes from the frame check."""
    scene = _scene()
    v = 0
    Hg_inv = np.linalg.inv(scene.P[v][:, [0, 1, 3]])
    # the horizon: pixels x with (Hg_inv x)_3 = 0; take the one at the image's centre column
    a, b, c = Hg_inv[2]
    x = scene.width / 2
    horizon = np.array([x, -(a * x + c) / b])
    dv, _, ground = _ground(scene, np.array([0, 0]), np.array([horizon, horizon + [0, 1e-9]]))
    assert dv.size == 0 and ground.shape == (0, 2)
