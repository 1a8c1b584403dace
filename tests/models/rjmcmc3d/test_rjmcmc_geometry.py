"""Rectification H = G R T of seed 003, section 2, and the camera / Tsai geometry."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dbn.errors import FileFormatError, InputError, ShapeError
from models.rjmcmc3d.geometry import (
    Camera,
    apply_homography,
    ground_homography,
    homography_jacobian,
    look_at_camera,
    projection_matrix,
    rectification,
    rectified_projection,
    vertical_vanishing_point,
)
from models.rjmcmc3d.scene import default_scene, load_tsai_xml


def _numeric_jacobian(H: np.ndarray, x: np.ndarray, eps: float = 1e-5) -> np.ndarray:
    J = np.zeros((2, 2))
    for k in range(2):
        d = np.zeros(2)
        d[k] = eps
        J[:, k] = (apply_homography(H, x + d) - apply_homography(H, x - d)) / (2 * eps)
    return J


@settings(max_examples=60, deadline=None)
@given(
    vx=st.floats(-3000, 3000),
    vy=st.floats(-3000, 3000),
    x0=st.floats(0, 800),
    y0=st.floats(0, 600),
)
def test_vanishing_point_goes_to_infinity_and_g_is_rigid(vx, vy, x0, y0) -> None:
    v = np.array([vx, vy, 1.0])
    if math.hypot(vx - x0, vy - y0) < 50:
        return
    rect = rectification(v, np.array([x0, y0]))
    image = rect.H @ v
    scale = np.linalg.norm(image)
    assert abs(image[2]) < 1e-9 * scale, "vanishing point not at infinity"
    assert abs(image[0]) < 1e-9 * scale, "image of the vertical direction is not vertical"
    # G has identity Jacobian at the origin (seed 003, sec. 2) ...
    assert np.allclose(homography_jacobian(rect.G, np.zeros(2)), np.eye(2), atol=1e-12)
    assert np.allclose(_numeric_jacobian(rect.G, np.zeros(2)), np.eye(2), atol=1e-6)
    # ... so H acts at x0 as the rotation R: no linear distortion there.
    J = homography_jacobian(rect.H, np.array([x0, y0]))
    assert np.allclose(J, rect.R[:2, :2], atol=1e-9)
    assert np.allclose(J.T @ J, np.eye(2), atol=1e-9)
    assert np.allclose(_numeric_jacobian(rect.H, np.array([x0, y0])), J, atol=1e-5)
    assert np.allclose(apply_homography(rect.H, np.array([x0, y0])), [x0, y0], atol=1e-9)


def test_jacobian_identity_when_vanishing_point_below_x0() -> None:
    rect = rectification(np.array([320.0, 2500.0, 1.0]), np.array([320.0, 240.0]))
    assert np.allclose(rect.R, np.eye(3))
    assert np.allclose(homography_jacobian(rect.H, np.array([320.0, 240.0])), np.eye(2))
    # the closed form of the seed: y_inf / (y - y_inf)^2 [[y_inf - y, x], [0, y_inf]]
    x, y, yi = 12.0, -30.0, rect.y_inf
    closed = yi / (y - yi) ** 2 * np.array([[yi - y, x], [0.0, yi]])
    assert np.allclose(homography_jacobian(rect.G, np.array([x, y])), closed)


def test_negative_homogeneous_scale_does_not_flip_the_image() -> None:
    v = np.array([320.0, 2500.0, 1.0])
    a = rectification(v, np.array([320.0, 240.0])).H
    b = rectification(-v, np.array([320.0, 240.0])).H
    assert np.allclose(a / a[2, 2], b / b[2, 2])


@pytest.mark.parametrize("view", [0, 1, 2])
def test_rectified_verticals_are_vertical(view: int) -> None:
    scene = default_scene(0)
    P = scene.P[view]
    rng = np.random.default_rng(view)
    for _ in range(20):
        x, y = rng.uniform(0, 20), rng.uniform(0, 8)
        pts = np.array([[x, y, z, 1.0] for z in (0.0, 0.9, 1.8)]) @ P.T
        px = pts[:, 0] / pts[:, 2]
        assert np.ptp(px) < 1e-6
        py = pts[:, 1] / pts[:, 2]
        assert py[0] > py[1] > py[2], "the head must be above the feet"


def test_unrectified_camera_has_slant_and_ground_homography() -> None:
    cam = look_at_camera(np.array([0.0, -5.0, 6.0]), np.array([3.0, 4.0, 0.0]), 400, 640, 480)
    P = projection_matrix(cam)
    pts = np.array([[6.0, 6.0, z, 1.0] for z in (0.0, 1.8)]) @ P.T
    assert abs(pts[0, 0] / pts[0, 2] - pts[1, 0] / pts[1, 2]) > 1.0  # slanted before
    Pr, rect = rectified_projection(cam)
    assert np.allclose(Pr, rect.H @ P)
    Hg = ground_homography(Pr)
    g = np.array([6.0, 6.0])
    img = apply_homography(Hg, g)
    assert np.allclose(apply_homography(np.linalg.inv(Hg), img), g)
    with pytest.raises(ShapeError, match="P"):
        vertical_vanishing_point(np.zeros((3, 3)))
    with pytest.raises(InputError, match="v_perp"):
        rectification(np.array([10.0, 10.0, 1.0]), np.array([10.0, 10.0]))


_EXAMPLE = Path(__file__).resolve().parents[2] / "data" / "rjmcmc3d" / "view0" / "calibration.xml"


@pytest.mark.parametrize(("attr", "value", "needle"), [
    ("rx", "143.6", "<Extrinsic rx='143.6'>: beyond one turn: angles are radians (degrees?)"),
    ("tz", "-1e200", "<Extrinsic tz='-1e200'>: beyond 1e9 mm"),
    ("cx", "1e200", "<Intrinsic cx='1e200'>: beyond 1e6 pixels"),
    ("width", "1e200", "<Geometry width='1e200'>: beyond 1e5 pixels"),
    ("dpx", "1e200", "focal length sx focal / dpx = 3e-198 pixels, outside [1, 1e+06]"),
    ("focal", "1e200", "focal length sx focal / dpx = 1e+200 pixels"),
    ("dpy", "1e-200", "focal length focal / dpy = 3e+202 pixels"),
])
def test_tsai_values_out_of_range_name_the_file_and_attribute(tmp_path, attr, value, needle):
    """dpx, cx or sx of 1e200 ended in numpy's "Singular matrix" traceback; a rotation of
    1e200 rad or a focal length of 1e200 ran to rc 0 (found by a mutation probe)."""
    text = _EXAMPLE.read_text()
    path = tmp_path / "calibration.xml"
    path.write_text(re.sub(rf' {attr}="[^"]*"', f' {attr}="{value}"', text, count=1))
    with pytest.raises(FileFormatError) as exc:
        load_tsai_xml(path)
    assert str(path) in str(exc.value) and needle in str(exc.value), str(exc.value)


def test_tsai_values_at_their_bounds_are_read(tmp_path) -> None:
    """The bounds themselves: a turn, 1e9 mm, 1e6 px principal point, 1 px focal length."""
    text = _EXAMPLE.read_text()
    for attr, value in (("rx", f"{2 * np.pi!r}"), ("tz", "1e9"), ("cx", "-1e6"),
                        ("dpx", "300.0"), ("width", "1e5")):  # fmt: skip
        path = tmp_path / f"{attr}.xml"
        path.write_text(re.sub(rf' {attr}="[^"]*"', f' {attr}="{value}"', text, count=1))
        cam, _ = load_tsai_xml(path)
        assert np.isfinite(cam.K).all()


def test_a_camera_looking_straight_down_is_named() -> None:
    """rx = 0 gave "v_perp=[192.0, 144.0, 1.0] coincides with x0=[192.0, 144.0]"."""
    cam = Camera(np.array([[300.0, 0, 192], [0, 300, 144], [0, 0, 1]]), np.eye(3),
                 np.array([0.0, 0.0, 8.0]), 384, 288)  # fmt: skip
    with pytest.raises(InputError, match="looks straight down"):
        rectified_projection(cam)


def test_pets2009_tsai_camera(shared_data) -> None:
    path = shared_data / "pets2009" / "View_001.xml"
    if not path.exists():
        pytest.skip(f"{path} absent")
    cam, kappa1 = load_tsai_xml(path)
    assert (cam.width, cam.height) == (768, 576)
    assert kappa1 > 0
    centre = -cam.R.T @ cam.t
    assert 2.0 < centre[2] < 30.0, f"camera height {centre[2]} m is implausible"
    assert np.allclose(cam.R @ cam.R.T, np.eye(3), atol=1e-9)
    # The ground in front of the camera projects into the image, in front of it.
    P = projection_matrix(cam)
    ahead = centre[:2] + 15.0 * (cam.R[2, :2] / np.linalg.norm(cam.R[2, :2]))
    p = P @ np.array([ahead[0], ahead[1], 0.0, 1.0])
    assert p[2] > 0 and 0 <= p[0] / p[2] < 768 and 0 <= p[1] / p[2] < 576
    # Rectified, the real camera's verticals become vertical.
    Pr, rect = rectified_projection(cam)
    q = np.array([[ahead[0], ahead[1], z, 1.0] for z in (0.0, 1.7)]) @ Pr.T
    assert abs(q[0, 0] / q[0, 2] - q[1, 0] / q[1, 2]) < 1e-6
