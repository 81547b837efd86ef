"""Synthetic scenes with exact ground truth (seeded)."""

from .scenes import (
                     HIDDEN_BELOW,
                     Occluder,
                     Scene,
                     SceneSpec,
                     Target,
                     Truth,
                     crossing_scene,
                     entering_scene,
                     export_otb,
                     illumination_scene,
                     occlusion_scene,
                     simple_scene,
                     waving_scene,
)
from .varied import (
                     VARIED_SCENES,
                     camouflage_scene,
                     draw_nuisances,
                     hidden_frames,
                     leave_scene,
                     teleport_scene,
                     vanish_scene,
                     varied_scene,
)

SCENES = {
    "simple": simple_scene,
    "occlusion": occlusion_scene,
    "full-occlusion": lambda seed=0, **kw: occlusion_scene(seed, full=True, **kw),
    "illumination": illumination_scene,
    "entering": entering_scene,
    "crossing": crossing_scene,
    "waving": waving_scene,
    **VARIED_SCENES,
}

__all__ = ["HIDDEN_BELOW", "SCENES", "VARIED_SCENES", "Occluder", "Scene", "SceneSpec", "Target", "Truth",
           "camouflage_scene", "crossing_scene", "draw_nuisances", "entering_scene", "export_otb", "hidden_frames",
           "illumination_scene", "teleport_scene",
           "leave_scene", "occlusion_scene", "simple_scene", "vanish_scene", "varied_scene", "waving_scene"]
