r"""A SIMULATED world with perceptual aliasing for the k-NN localisation of seed 002, section 1.3.

Everything here is simulated (no real images): a 12 m x 6 m floor with a row of five
identical pillars along its middle and walls painted in stripes that repeat every 2 m.
The robot carries a panoramic range sensor (``num_rays`` rays, maximum range 3 m) that
also reads the colour of the surface each ray hits, so one observation has
``2 * num_rays`` dimensions (default 144). Away from the end walls, places 2 m apart along
the corridor look the same: the perceptual aliasing of seed 002, section 1.3.

Occlusion outliers (a person next to the robot hiding a block of 20-40% of the rays) are
injected at a set rate. The training set is a grid of poses (cell ``cell_xy`` metres,
``num_orientations`` headings) with noise-free scans, from which :class:`KNNSensor` is
fitted; the outlier threshold is the ``threshold_quantile`` quantile of the nearest-
neighbour distances of clean noisy scans at random poses (a separate calibration draw).
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import NamedTuple

import numpy as np

from dbn.checks import check_count, check_numbers, make_rng
from dbn.errors import InputError, ModelError
from models.localization.model import (
    KNNLocalizationModel,
    KNNSensor,
    MotionNoise,
    compose,
    wrap_angle,
)

__all__ = [
    "World",
    "make_world",
    "cast_scans",
    "SyntheticRun",
    "simulate_run",
    "TrainedWorld",
    "build_trained_world",
    "knn_model_for",
    "odometry_only",
    "training_grid",
    "free_space",
    "SIM_NOISE",
]

MAX_RANGE = 3.0
#: odometry noise of the simulated robot (the filter assumes the same law)
SIM_NOISE = MotionNoise(0.02, 0.1, 0.02, 0.1)


class World(NamedTuple):
    """Floor plan: wall segments ``(num_segments, 2, 2)``, their colours ``(num_segments,)``,
    the pillar boxes ``(num_pillars, 4)`` as (xmin, ymin, xmax, ymax) and the outer size."""

    segments: np.ndarray
    colours: np.ndarray
    pillars: np.ndarray
    width: float
    height: float


MAX_STRIPES = 10_000
"""Most wall stripes a simulated world has (a width of 1e100 m looped for ever)."""


def make_world(width: float = 12.0, height: float = 6.0, period: float = 2.0) -> World:
    """The aliased floor plan (simulated): striped walls and identical pillars every ``period`` m.

    Raises
    ------
    ModelError, NonFiniteError
        A size not finite and > 0 (NaN raised numpy's "cannot convert float NaN to
        integer", a negative width ran), or more than :data:`MAX_STRIPES` wall stripes.
    """
    sizes = {"width": width, "height": height, "period": period}
    width, height, period = (float(check_numbers(k, v, 1)[0]) for k, v in sizes.items())
    if not min(width, height, period) > 0:
        raise ModelError(f"make_world: width, height and period must be > 0, got {width}, "
                         f"{height}, {period}")  # fmt: skip
    if width / (period / 2) > MAX_STRIPES:
        raise ModelError(f"make_world: width / (period / 2) = {width / (period / 2):g} wall "
                         f"stripes, more than {MAX_STRIPES}")  # fmt: skip
    segs, cols = [], []
    n = int(round(width / (period / 2)))
    for i in range(n):  # bottom and top walls, stripes of period/2 alternating colours
        x0, x1 = i * period / 2, (i + 1) * period / 2
        segs.append(((x0, 0.0), (x1, 0.0)))
        cols.append(0.3 if i % 2 == 0 else 0.7)
        segs.append(((x0, height), (x1, height)))
        cols.append(0.1 if i % 2 == 0 else 0.5)
    segs.append(((0.0, 0.0), (0.0, height)))
    cols.append(0.9)
    segs.append(((width, 0.0), (width, height)))
    cols.append(0.0)
    pillars = []
    half = 0.3
    for cx in np.arange(period, width - period / 2, period):
        cy = height / 2
        box = (cx - half, cy - half, cx + half, cy + half)
        pillars.append(box)
        a, b, c, d = (box[0], box[1]), (box[2], box[1]), (box[2], box[3]), (box[0], box[3])
        for p, q in ((a, b), (b, c), (c, d), (d, a)):
            segs.append((p, q))
            cols.append(0.6)
    return World(np.array(segs), np.array(cols), np.array(pillars), width, height)


def free_space(world: World, xy: np.ndarray, margin: float = 0.3) -> np.ndarray:
    """Boolean mask ``(n,)``: the points ``(n, 2)`` at least ``margin`` from walls and pillars."""
    x, y = xy[:, 0], xy[:, 1]
    ok = (x > margin) & (x < world.width - margin) & (y > margin) & (y < world.height - margin)
    for x0, y0, x1, y1 in world.pillars:
        ok &= ~((x > x0 - margin) & (x < x1 + margin) & (y > y0 - margin) & (y < y1 + margin))
    return ok


def cast_scans(
    world: World, poses: np.ndarray, num_rays: int = 72, chunk: int = 2048
) -> np.ndarray:
    """Noise-free panoramic scans ``(n, 2 * num_rays)``: depth / MAX_RANGE, then colour.

    Ray ``d`` leaves pose ``(x, y, theta)`` at angle ``theta + 2 pi d / num_rays``; rays that
    hit nothing within ``MAX_RANGE`` read depth 1 (normalised) and colour 0.5. Vectorised
    over poses x rays x segments, in chunks of poses.
    """
    poses = np.atleast_2d(np.asarray(poses, dtype=np.float64))
    a0 = world.segments[:, 0]  # (S, 2)
    e = world.segments[:, 1] - a0  # (S, 2)
    out = np.empty((len(poses), 2 * num_rays))
    offsets = 2 * math.pi * np.arange(num_rays) / num_rays
    for s in range(0, len(poses), chunk):
        p = poses[s : s + chunk]
        ang = p[:, 2:3] + offsets[None]  # (P, D)
        rx, ry = np.cos(ang)[..., None], np.sin(ang)[..., None]  # (P, D, 1)
        wx = a0[None, None, :, 0] - p[:, None, None, 0]
        wy = a0[None, None, :, 1] - p[:, None, None, 1]
        den = rx * e[None, None, :, 1] - ry * e[None, None, :, 0]
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (wx * e[None, None, :, 1] - wy * e[None, None, :, 0]) / den
            u = (wx * ry - wy * rx) / den
        hit = (np.abs(den) > 1e-12) & (t > 1e-9) & (u >= 0) & (u <= 1) & (t < MAX_RANGE)
        t = np.where(hit, t, np.inf)
        j = np.argmin(t, axis=2)
        depth = np.take_along_axis(t, j[..., None], axis=2)[..., 0]
        colour = np.where(np.isfinite(depth), world.colours[j], 0.5)
        depth = np.where(np.isfinite(depth), depth, MAX_RANGE) / MAX_RANGE
        out[s : s + chunk, :num_rays] = depth
        out[s : s + chunk, num_rays:] = colour
    return out


def _occlude(rng: np.random.Generator, scan: np.ndarray, num_rays: int) -> np.ndarray:
    """A person close to the robot hides a block of 20-40% of the panorama (an outlier)."""
    width = int(rng.integers(int(0.2 * num_rays), int(0.4 * num_rays) + 1))
    start = int(rng.integers(num_rays))
    idx = (start + np.arange(width)) % num_rays
    scan = scan.copy()
    scan[idx] = rng.uniform(0.3, 1.0) / MAX_RANGE
    scan[num_rays + idx] = rng.uniform(0.0, 1.0)
    return scan


class SyntheticRun(NamedTuple):
    """One simulated run.

    Attributes
    ----------
    poses : (num_timesteps + 1, 3) true poses, ``poses[0]`` the start
    actions : (num_timesteps, 4) odometry ``(dx, dy, dtheta, dt)`` in the robot frame
    observations : (num_timesteps, obs_dim) noisy scans at ``poses[1:]``
    outlier : (num_timesteps,) bool, which scans were occluded
    """

    poses: np.ndarray
    actions: np.ndarray
    observations: np.ndarray
    outlier: np.ndarray


def _waypoints(world: World) -> np.ndarray:
    lo, hi = 1.0, world.width - 1.0
    y0, y1 = world.height / 4, 3 * world.height / 4
    return np.array([[hi, y0], [hi, y1], [lo, y1], [lo, y0]])


def simulate_run(
    seed: int,
    world: World,
    num_timesteps: int,
    *,
    outlier_rate: float = 0.1,
    noise: MotionNoise = SIM_NOISE,
    step_length: float = 0.25,
    scan_noise: float = 0.02,
    num_rays: int = 72,
) -> SyntheticRun:
    """Simulate a robot looping around the pillar row (SIMULATED data).

    The true motion is the odometry plus Gaussian noise drawn from the same
    :class:`MotionNoise` law the filter assumes; scans get Gaussian noise ``scan_noise``
    and, with probability ``outlier_rate``, an occlusion.

    Parameters
    ----------
    seed : int
        Seed of a local ``numpy.random.Generator``.
    world : World
    num_timesteps : int

    Raises
    ------
    InputError, ModelError, NonFiniteError
        A count that is not an int >= 1, ``outlier_rate`` outside [0, 1], a negative or
        non-finite ``step_length``, ``scan_noise`` or noise term (NaN ran; 2.5 steps
        raised Python's TypeError).
    """
    check_count("num_timesteps", num_timesteps)
    check_count("num_rays", num_rays)
    rate = float(check_numbers("outlier_rate", outlier_rate, 1, low=0.0)[0])
    if rate > 1:
        raise ModelError(f"outlier_rate = {rate} must be a probability in [0, 1]")
    check_numbers("step_length", step_length, 1, low=0.0)
    check_numbers("scan_noise", scan_noise, 1, low=0.0)
    noise = MotionNoise(*check_numbers("noise", noise, len(MotionNoise._fields), low=0.0))
    rng = make_rng(seed)
    wps = _waypoints(world)
    start_x = rng.uniform(1.0, world.width - 3.0)
    pose = np.array([start_x, world.height / 4, 0.0])
    target = 0
    poses, actions = [pose], []
    for _ in range(num_timesteps):
        to = wps[target] - pose[:2]
        if np.hypot(*to) < 0.4:
            target = (target + 1) % len(wps)
            to = wps[target] - pose[:2]
        dth = float(np.clip(wrap_angle(math.atan2(to[1], to[0]) - pose[2]), -0.6, 0.6))
        d = min(step_length, float(np.hypot(*to))) * (1.0 if abs(dth) < 0.5 else 0.4)
        act = np.array([d, 0.0, dth, 1.0])
        sxy = noise.a_xy + noise.b_xy * d
        sth = noise.a_theta + noise.b_theta * abs(dth)
        new = compose(pose, act[:3]) + rng.normal(size=3) * np.array([sxy, sxy, sth])
        new[2] = wrap_angle(new[2])
        if not free_space(world, new[None, :2], margin=0.15)[0]:
            new[:2] = pose[:2]  # bumped: stays (the odometry still reports the command)
        poses.append(new)
        actions.append(act)
        pose = new
    poses = np.array(poses)
    scans = cast_scans(world, poses[1:], num_rays)
    scans = scans + scan_noise * rng.normal(size=scans.shape)
    outlier = rng.uniform(size=num_timesteps) < outlier_rate
    for k in np.flatnonzero(outlier):
        scans[k] = _occlude(rng, scans[k], num_rays)
    return SyntheticRun(poses, np.array(actions), scans, outlier)


def training_grid(
    world: World, cell_xy: float, num_orientations: int, num_rays: int
) -> tuple[np.ndarray, np.ndarray]:
    """Training poses ``(K, 3)`` on a grid and their noise-free scans ``(K, 2 num_rays)``.

    Rays are cast once per position at heading 0; the scan at heading
    ``2 pi o / num_orientations`` is a circular shift (requires ``num_rays`` to be a multiple
    of ``num_orientations``).
    """
    if num_rays % num_orientations:
        raise InputError(
            f"num_rays {num_rays} must be a multiple of num_orientations {num_orientations}"
        )
    xs = np.arange(cell_xy / 2, world.width, cell_xy)
    ys = np.arange(cell_xy / 2, world.height, cell_xy)
    xy = np.stack(np.meshgrid(xs, ys, indexing="ij"), -1).reshape(-1, 2)
    xy = xy[free_space(world, xy, margin=0.1)]
    base = cast_scans(world, np.column_stack([xy, np.zeros(len(xy))]), num_rays)
    shift = num_rays // num_orientations
    poses, scans = [], []
    for o in range(num_orientations):
        th = wrap_angle(2 * math.pi * o / num_orientations)
        poses.append(np.column_stack([xy, np.full(len(xy), th)]))
        depth = np.roll(base[:, :num_rays], -o * shift, axis=1)
        col = np.roll(base[:, num_rays:], -o * shift, axis=1)
        scans.append(np.hstack([depth, col]))
    return np.vstack(poses), np.vstack(scans)


class TrainedWorld(NamedTuple):
    """The simulated world with its fitted k-NN sensor model."""

    world: World
    sensor: KNNSensor
    num_rays: int
    scan_noise: float


@lru_cache(maxsize=4)
def build_trained_world(
    seed: int = 0,
    *,
    cell_xy: float = 0.2,
    num_orientations: int = 24,
    num_rays: int = 72,
    feature_dim: int = 16,
    num_neighbours: int = 10,
    scan_noise: float = 0.02,
    threshold_quantile: float = 0.99,
) -> TrainedWorld:
    """Fit the k-NN sensor of seed 002, eq. 1.14 on the simulated training grid.

    The outlier threshold is the ``threshold_quantile`` quantile of first-neighbour feature
    distances of 400 clean noisy scans at random free poses (drawn with ``seed``).
    """
    world = make_world()
    poses, scans = training_grid(world, cell_xy, num_orientations, num_rays)
    sensor = KNNSensor(
        poses,
        scans,
        feature_dim=feature_dim,
        num_neighbours=num_neighbours,
        cell_xy=cell_xy,
        cell_theta=2 * math.pi / num_orientations,
    )
    rng = make_rng(seed)
    cand = np.column_stack([rng.uniform(0, world.width, 2000), rng.uniform(0, world.height, 2000)])
    cand = cand[free_space(world, cand)][:400]
    cal = np.column_stack([cand, rng.uniform(-math.pi, math.pi, len(cand))])
    cal_scans = cast_scans(world, cal, num_rays) + scan_noise * rng.normal(
        size=(len(cal), 2 * num_rays)
    )
    sensor.threshold = float(np.quantile(sensor.nearest_distance(cal_scans), threshold_quantile))
    return TrainedWorld(world, sensor, num_rays, scan_noise)


def knn_model_for(trained: TrainedWorld, run: SyntheticRun, *, initial_std=(0.3, 0.3, 0.2)):
    """The :class:`KNNLocalizationModel` of a run: Gaussian initial belief at the true start."""
    return KNNLocalizationModel(trained.sensor, run.poses[0], np.asarray(initial_std), SIM_NOISE)


def odometry_only(start: np.ndarray, actions: np.ndarray) -> np.ndarray:
    """Dead reckoning: compose the odometry from ``start``; poses ``(num_timesteps, 3)``."""
    out, pose = [], np.asarray(start, dtype=np.float64)
    for a in actions:
        pose = compose(pose, a[:3])
        out.append(pose)
    return np.array(out)
