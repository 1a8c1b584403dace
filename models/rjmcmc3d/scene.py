"""A calibrated multi-camera scene, rendered (SIMULATED data) for the seed 003 tracker.

Real multi-camera video is not available to this project, so the observations of seed 003
(section 3.3: foreground maps ``D_v`` and colour images ``I_v``; section 3.4: a per-view
person detector) are rendered from a calibrated model:

- pinhole cameras (three by default, with partial overlap as in the seed's metro scene:
  most of the floor is seen by one camera, a minority by two or more; people appear at
  very different image sizes across views; each camera has its own colour shift), images
  rectified by the vertical-vanishing-point homography of seed 003, section 2;
- a loader for Tsai calibration XML (PETS2009 ``View_001.xml``), so a real camera can be
  read and rectified;
- people as three elliptic cylinders (legs, torso, head; seed 003, fig. 3) with height
  and orientation, projected to axis-aligned boxes in the rectified views;
- foreground maps ``D(x)`` in [0, 1] with noise, silhouettes that do not fill their boxes
  and false-alarm blobs; colour images with per-person region colours;
- a noisy per-view detector (misses, foot-position noise, false alarms);
- Langevin walkers (seed 003, eq. 7) entering and leaving the floor.

The scene is split into rooms that hold one job; this module re-exports their names
(the former single module's API): :mod:`~models.rjmcmc3d.types` (Scene, Frame, Truth),
:mod:`~models.rjmcmc3d.calibration` (Tsai loader, default scene),
:mod:`~models.rjmcmc3d.projection` (body model and part boxes),
:mod:`~models.rjmcmc3d.walkers` (simulated walkers), :mod:`~models.rjmcmc3d.rendering`
(foreground and colour images) and :mod:`~models.rjmcmc3d.detection` (the detector).
"""

from models.rjmcmc3d.calibration import default_scene, load_tsai_xml, scene_from_cameras
from models.rjmcmc3d.detection import detect
from models.rjmcmc3d.projection import (
    BODY_HALF_AXES,
    BODY_Z,
    BoxProjector,
    coverage_fractions,
    depths,
    part_boxes,
    visible_views,
)
from models.rjmcmc3d.rendering import render_frame
from models.rjmcmc3d.types import Frame, FrameTruth, Scene, Truth
from models.rjmcmc3d.walkers import simulate_walkers

__all__ = [
    "BODY_HALF_AXES",
    "BODY_Z",
    "BoxProjector",
    "Frame",
    "FrameTruth",
    "Scene",
    "Truth",
    "coverage_fractions",
    "default_scene",
    "depths",
    "detect",
    "load_tsai_xml",
    "part_boxes",
    "render_frame",
    "scene_from_cameras",
    "simulate_walkers",
    "visible_views",
]
