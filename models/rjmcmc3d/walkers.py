"""SIMULATED ground truth: Langevin walkers (seed 003, eq. 7) entering and leaving the
floor, each with its own region colours.
"""

from __future__ import annotations

import math

import numpy as np

from dbn.checks import make_rng
from dbn.errors import InputError
from models.rjmcmc3d.types import FrameTruth, Scene, Truth

__all__ = ["simulate_walkers"]


_TORSO_PALETTE = np.array(
    [
        [0.85, 0.15, 0.15],
        [0.15, 0.35, 0.85],
        [0.15, 0.7, 0.25],
        [0.9, 0.8, 0.15],
        [0.9, 0.9, 0.9],
        [0.1, 0.1, 0.12],
        [0.6, 0.2, 0.7],
        [0.95, 0.5, 0.1],
        [0.2, 0.75, 0.8],
    ]
)
_LEGS_PALETTE = np.array(
    [[0.12, 0.12, 0.3], [0.2, 0.2, 0.2], [0.45, 0.35, 0.2], [0.7, 0.7, 0.65], [0.05, 0.05, 0.05]]
)


def _random_boundary_point(rng: np.random.Generator, floor: np.ndarray) -> tuple[np.ndarray, int]:
    side = int(rng.integers(4))
    lx, hx, ly, hy = floor
    if side == 0:
        return np.array([lx, rng.uniform(ly, hy)]), side
    if side == 1:
        return np.array([hx, rng.uniform(ly, hy)]), side
    if side == 2:
        return np.array([rng.uniform(lx, hx), ly]), side
    return np.array([rng.uniform(lx, hx), hy]), side


def _goal_for(rng: np.random.Generator, floor: np.ndarray, start_side: int) -> np.ndarray:
    lx, hx, ly, hy = floor
    # people mostly walk along the hall; exit through the opposite end or a side
    if start_side in (0, 1) or rng.random() < 0.7:
        if start_side == 0 or (start_side > 1 and rng.random() < 0.5):
            return np.array([hx + 1.0, rng.uniform(ly, hy)])
        if start_side == 1 or start_side > 1:
            return np.array([lx - 1.0, rng.uniform(ly, hy)])
    return np.array([rng.uniform(lx, hx), ly - 1.0 if start_side == 3 else hy + 1.0])


def simulate_walkers(
    seed: int,
    scene: Scene,
    num_frames: int,
    num_people: int,
    tau: float = 0.2,
    speed: float = 1.2,
    beta: float = 0.5,
) -> Truth:
    """SIMULATED walkers: Langevin motion (seed 003, eq. 7) with a drift to an exit.

    About ``num_people`` people are on the floor at any time: each enters at the edge,
    walks towards an exit with velocity ``v_t = a v_{t-1} + (1 - a) v_goal + b w_t``
    (``a = exp(-beta tau)``, ``b = 0.3 speed sqrt(1 - a^2)``), ``u_t = u_{t-1} + tau v_t``,
    and leaves when outside the floor; a new walker then enters after a short delay.

    Parameters
    ----------
    seed : int
    scene : Scene
    num_frames, num_people : int
    tau : float
        Frame interval (s).
    speed : float
        Preferred walking speed (m/s).
    beta : float
        Velocity damping (1/s).

    Returns
    -------
    Truth
    """
    if num_frames < 1 or num_people < 1:
        raise InputError(f"num_frames={num_frames} and num_people={num_people} must be >= 1")
    rng = make_rng(seed)
    a = math.exp(-beta * tau)
    b = 0.3 * speed * math.sqrt(1 - a * a)
    floor = scene.floor
    colours: list[np.ndarray] = []
    walkers = [_new_walker(rng, floor, speed, i, True, colours) for i in range(num_people)]
    next_id = num_people
    pending: list[int] = []  # frames at which new walkers enter
    frames = []
    for t in range(num_frames):
        while pending and pending[0] <= t:
            pending.pop(0)
            walkers.append(_new_walker(rng, floor, speed, next_id, False, colours))
            next_id += 1
        for w in walkers:
            d = w["goal"] - w["u"]
            vgoal = w["pref"] * d / max(np.linalg.norm(d), 1e-9)
            w["v"] = a * w["v"] + (1 - a) * vgoal + b * rng.normal(size=2)
            w["u"] = w["u"] + tau * w["v"]
        alive = []
        for w in walkers:
            inside = floor[0] <= w["u"][0] <= floor[1] and floor[2] <= w["u"][1] <= floor[3]
            if inside:
                alive.append(w)
            else:
                pending.append(t + 1 + int(rng.geometric(0.25)))
        pending.sort()
        walkers = alive
        frames.append(_frame_truth(walkers))
    return Truth(frames, np.stack(colours), tau)


def _new_walker(
    rng: np.random.Generator,
    floor: np.ndarray,
    speed: float,
    walker_id: int,
    inside: bool,
    colours: list,
) -> dict:
    """A walker starting inside the floor or at its edge, heading to an exit; its region
    colours (legs, torso, skin) are appended to ``colours``."""
    if inside:
        start = np.array(
            [rng.uniform(floor[0] + 1, floor[1] - 1), rng.uniform(floor[2] + 1, floor[3] - 1)]
        )
        side = int(rng.integers(4))
    else:
        start, side = _random_boundary_point(rng, floor)
    goal = _goal_for(rng, floor, side)
    d = goal - start
    v = speed * rng.uniform(0.8, 1.2) * d / np.linalg.norm(d)
    skin = np.array([0.55, 0.4, 0.3]) + rng.normal(0, 0.06, 3)
    legs = _LEGS_PALETTE[rng.integers(len(_LEGS_PALETTE))] + rng.normal(0, 0.05, 3)
    torso = _TORSO_PALETTE[rng.integers(len(_TORSO_PALETTE))] + rng.normal(0, 0.05, 3)
    colours.append(np.clip(np.stack([legs, torso, skin]), 0, 1))
    return {
        "id": walker_id,
        "u": start,
        "v": v,
        "goal": goal,
        "pref": np.linalg.norm(v),
        "h": float(np.clip(rng.normal(1.72, 0.08), 1.5, 1.95)),
    }


def _frame_truth(walkers: list[dict]) -> FrameTruth:
    ids = np.array([w["id"] for w in walkers], dtype=np.int64)
    u = np.array([w["u"] for w in walkers]).reshape(-1, 2)
    hh = np.array([w["h"] for w in walkers])
    al = np.array([math.atan2(w["v"][1], w["v"][0]) for w in walkers])
    return FrameTruth(ids, u, hh, al)
