"""The registry of the seed trackers: ``models.available()``, ``models.get(name)``.

Entries are declared by module path and imported only when used, so ``import models``
stays cheap (no jax, no model code). Each entry's module (``models/<name>/api.py``)
provides ``make(**options) -> Tracker`` (the protocol adapter of
:mod:`models.protocol`) and ``example(key) -> Example`` (a tracker, a few steps of tiny
SIMULATED observations and one bad observation; for tests, docs and smoke runs).
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import Any

from dbn.errors import InputError

__all__ = ["Entry", "available", "get", "REGISTRY"]


@dataclass(frozen=True)
class Entry:
    """One registered tracker.

    Attributes
    ----------
    name : registry key
    seed_paper : the seed paper (``shared/seeds``) it implements
    tracks : what it tracks, in a sentence
    input_formats : what one ``step`` observation is, and the data it reads
    module : the adapter module (imported lazily)
    demo_module : the module whose ``run_demo(quick)`` the CLI's ``demo`` runs
    """

    name: str
    seed_paper: str
    tracks: str
    input_formats: tuple[str, ...]
    module: str
    demo_module: str | None = None

    def _api(self):
        return importlib.import_module(self.module)

    def make(self, *args: Any, **options: Any):
        """The tracker (protocol adapter), built from the module's ``make(*args, **options)``."""
        return self._api().make(*args, **options)

    def example(self, key):
        """:class:`models.protocol.Example`: a small tracker, a few SIMULATED steps, a bad one."""
        return self._api().example(key)


_ENTRIES = (
    Entry(
        "zajdel_adf",
        "002 (Zajdel, Cemgil & Krose: online multi-camera tracking, ADF, sec. 1.4)",
        "identities of people re-appearing across non-overlapping cameras, unknown count",
        ("zajdel.Observations, one observation per step (appearance, camera, times, borders)",),
        "models.zajdel.api",
        "models.zajdel.demo",
    ),
    Entry(
        "zajdel_learnsearch",
        "000 (Zajdel & Krose: learn-search over partitions with EM)",
        "the most probable partitions of observations into people, with learned parameters",
        ("zajdel.Observations, one observation per step",),
        "models.zajdel.api_learnsearch",
        "models.zajdel.demo_learnsearch",
    ),
    Entry(
        "jorge",
        "004 (Jorge et al.: online labelling of groups of people with a BN of strokes)",
        "group/person labels of video 'strokes' (tracks between splits and merges)",
        ("jorge.Stroke, one stroke per step in start order (CAVIAR / PETS2009 or simulated)",),
        "models.jorge.api",
        "models.jorge.demo",
    ),
    Entry(
        "localization",
        "002 (robot localisation with an auxiliary particle filter, sec. 1.3)",
        "a robot's pose (x, y, heading) from odometry and a sensor",
        (
            "(odometry (4,), RangeBearingObservation) per step (MRCLAM or simulated)",
            "(odometry (4,), raw scan (obs_dim,)) per step for the k-NN sensor model",
        ),
        "models.localization.api",
        "models.localization.demo",
    ),
    Entry(
        "pathrecovery",
        "001 (Lev-Tov & Moses: path recovery in a large camera network)",
        "the path of one target through a camera network, visible and hidden (gaps)",
        ("(obs_cam (n,), obs_feat (n, d)) per time step, sorted by camera (simulated)",),
        "models.pathrecovery.api",
        "models.pathrecovery.demo",
    ),
    Entry(
        "rjmcmc3d",
        "003 (Yao & Odobez: multi-camera 3-D people tracking with RJ-MCMC)",
        "3-D positions, heights and identities of people seen by calibrated cameras",
        ("rjmcmc3d.Frame per step (foreground maps, colour images, detections; simulated)",),
        "models.rjmcmc3d.api",
        "models.rjmcmc3d.demo",
    ),
)

REGISTRY: dict[str, Entry] = {e.name: e for e in _ENTRIES}


def available() -> tuple[str, ...]:
    """The names of the registered trackers, in registry order."""
    return tuple(REGISTRY)


def get(name: str) -> Entry:
    """The registry entry of ``name``.

    Raises
    ------
    InputError
        Unknown name (the message lists the valid ones).
    """
    try:
        return REGISTRY[name]
    except (KeyError, TypeError):
        raise InputError(f"unknown tracker {name!r}; available: {', '.join(available())}") from None
