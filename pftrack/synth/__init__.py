"""Synthetic scenes with exact ground truth (seeded)."""

from .scenes import (Occluder, Scene, SceneSpec, Target, Truth, crossing_scene, entering_scene, illumination_scene,
                     occlusion_scene, simple_scene)

__all__ = ["Occluder", "Scene", "SceneSpec", "Target", "Truth", "crossing_scene", "entering_scene",
           "illumination_scene", "occlusion_scene", "simple_scene"]
