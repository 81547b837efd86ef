"""Synthetic scenes with exact ground truth (seeded)."""

from .scenes import (SCENES, Occluder, Scene, SceneSpec, Target, Truth, crossing_scene, entering_scene, export_otb,
                     illumination_scene, occlusion_scene, simple_scene, waving_scene)

__all__ = ["SCENES", "Occluder", "Scene", "SceneSpec", "Target", "Truth", "crossing_scene", "entering_scene",
           "export_otb", "illumination_scene", "occlusion_scene", "simple_scene", "waving_scene"]
