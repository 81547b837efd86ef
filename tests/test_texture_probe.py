"""scripts/texture_probe.py: the flat copy of a scene is the same scene without the target's speckle."""

from __future__ import annotations

import numpy as np
import pytest

from .conftest import load_script


def test_the_flat_copy_differs_only_on_the_objects_and_is_flat_inside_them():
    tp = load_script("texture_probe")
    frames, gt = tp.scene("simple", 7100, flat=False)
    flat, gt_flat = tp.scene("simple", 7100, flat=True)
    assert np.array_equal(gt, gt_flat)
    x, y, w, h = (int(round(v)) for v in gt[0])
    inner = (slice(y + h // 4, y + h // 2 - 2), slice(x + w // 3, x + 2 * w // 3))  # inside the upper half
    spread = lambda f: float(f[inner].astype(np.float64).std(axis=(0, 1)).mean())  # noqa: E731
    assert spread(flat[0]) < 0.5 * spread(frames[0])  # the speckle is gone; only the camera noise is left
    far = (slice(0, 20), slice(0, 20))  # the background away from the target is the same scene
    assert np.abs(flat[0][far].astype(int) - frames[0][far].astype(int)).mean() < 10
    with pytest.raises(KeyError):
        tp.scene("snow", 0, flat=True)


def test_the_probe_reads_a_tracker_on_both_copies():
    tp = load_script("texture_probe")
    r = tp.measure("pisc", ["simple"], [7100])
    assert set(r) == {"textured", "flat", "lost_off", "lost_on"}
    assert r["textured"] > 0.9 and r["flat"] < 0.6  # block matching needs texture: it drifts off the flat target
    assert r["lost_off"] == 0.0  # and says nothing (docs/robustness-cameras.md)
