"""Yao & Odobez multi-camera multi-person 3-D tracker with RJ-MCMC (seed 003).

- :mod:`~models.rjmcmc3d.geometry`: pinhole cameras, ground homographies and the
  slant-removing rectification ``H = G R T`` (section 2);
- :mod:`~models.rjmcmc3d.types`: Scene, Frame, Truth;
- :mod:`~models.rjmcmc3d.calibration`: the Tsai XML loader and the default scene;
- :mod:`~models.rjmcmc3d.projection`: the body model projected to part boxes;
- :mod:`~models.rjmcmc3d.walkers`, :mod:`~models.rjmcmc3d.rendering`,
  :mod:`~models.rjmcmc3d.detection`: the SIMULATED walkers, foreground maps and colour
  images, and detector (:mod:`~models.rjmcmc3d.scene` re-exports all of these);
- :mod:`~models.rjmcmc3d.model`: parameters, dynamics (eq. 7 with ``C(u)``), priors;
- :mod:`~models.rjmcmc3d.likelihood`: eqs. 8-10, incremental and from scratch;
- :mod:`~models.rjmcmc3d.chain`: one frame's chain, its target and six moves (eqs. 2, 5-7,
  11);
- :mod:`~models.rjmcmc3d.tracker`: the RJ-MCMC filter over frames: the state carried
  between frames and each frame's posterior summary;
- :mod:`~models.rjmcmc3d.metrics`: MOTA / IDF1 / ID switches through py-motmetrics.
"""

from models.rjmcmc3d.calibration import default_scene
from models.rjmcmc3d.frames import check_frame, unit_image
from models.rjmcmc3d.model import TrackerParams
from models.rjmcmc3d.rendering import render_frame
from models.rjmcmc3d.tracker import FrameResult, RJMCMCTracker, TrackState
from models.rjmcmc3d.walkers import simulate_walkers

__all__ = [
    "FrameResult",
    "RJMCMCTracker",
    "TrackState",
    "TrackerParams",
    "check_frame",
    "default_scene",
    "render_frame",
    "simulate_walkers",
    "unit_image",
]
