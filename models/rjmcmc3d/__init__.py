"""Yao & Odobez multi-camera multi-person 3-D tracker with RJ-MCMC (seed 003).

- :mod:`~models.rjmcmc3d.geometry`: pinhole cameras, ground homographies and the
  slant-removing rectification ``H = G R T`` (section 2);
- :mod:`~models.rjmcmc3d.scene`: the calibrated scene (Tsai XML loader) and the
  SIMULATED observations (foreground maps, colour images, detector, walkers);
- :mod:`~models.rjmcmc3d.model`: parameters, dynamics (eq. 7 with ``C(u)``), priors;
- :mod:`~models.rjmcmc3d.likelihood`: eqs. 8-10, incremental and from scratch;
- :mod:`~models.rjmcmc3d.tracker`: the six-move RJ-MCMC filter (eqs. 2, 5, 11);
- :mod:`~models.rjmcmc3d.metrics`: MOTA / IDF1 / ID switches through py-motmetrics.
"""

from models.rjmcmc3d.model import TrackerParams
from models.rjmcmc3d.scene import default_scene, render_frame, simulate_walkers
from models.rjmcmc3d.tracker import FrameResult, RJMCMCTracker, TrackState

__all__ = [
    "FrameResult",
    "RJMCMCTracker",
    "TrackState",
    "TrackerParams",
    "default_scene",
    "render_frame",
    "simulate_walkers",
]
