"""Path recovery of a disappearing target in a large camera network (seed 001, Lev-Tov &
Moses 2010): a modified particle filter over visible and hidden states (first phase) and
dynamic programming over each step's k best states (second phase), with the simulator of
sec. 7.1 and the confusion measure of sec. 6.

Typical use (SIMULATED data)::

    from models.pathrecovery import (FilterConfig, make_model, manhattan_grid,
                                     path_score, recover_path, run_filter, simulate_scene)
    net = manhattan_grid(0)
    scene = simulate_scene(1, net, num_objects=2000, num_timesteps=100, cm=0.17)
    model = make_model(net, scene.c0, scene.f0, scene.sigma, FilterConfig())
    lists = run_filter(2, model, scene.odb)               # first phase: k-best lists
    path = recover_path(model, lists, scene.odb.feat, k=7)  # second phase
    print(path_score(path.kind, path.obs, scene.true_obs[1:]))
"""

from models.pathrecovery.filter import (
    FilterConfig,
    KBestLists,
    ParticleState,
    PathFilterModel,
    PathParticles,
    StepInfo,
    init,
    make_model,
    observation_support,
    run_filter,
    step,
)
from models.pathrecovery.metrics import PathScore, correct_states, kbest_score, path_score
from models.pathrecovery.model import CameraNetwork, propagate
from models.pathrecovery.recover import RecoveredPath, legal_transitions, recover_path
from models.pathrecovery.simulate import (
    ObservationDB,
    Scene,
    confusion_measure,
    manhattan_grid,
    similarity,
    simulate_scene,
    street,
)

__all__ = [
    "CameraNetwork",
    "FilterConfig",
    "KBestLists",
    "ObservationDB",
    "ParticleState",
    "PathFilterModel",
    "PathParticles",
    "PathScore",
    "RecoveredPath",
    "Scene",
    "StepInfo",
    "confusion_measure",
    "correct_states",
    "init",
    "kbest_score",
    "legal_transitions",
    "make_model",
    "manhattan_grid",
    "observation_support",
    "path_score",
    "propagate",
    "recover_path",
    "run_filter",
    "similarity",
    "simulate_scene",
    "step",
    "street",
]
