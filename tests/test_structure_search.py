"""Whole-frame proposals of the structural cue (pftrack.cues.structure_search)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from pftrack.cues.structure import StructureCue
from pftrack.cues.structure_search import map_peaks, ncc_map, propose_centres


def _zncc(a: np.ndarray, b: np.ndarray) -> float:
    a = a - a.mean()
    b = b - b.mean()
    return float((a * b).sum() / np.sqrt((a * a).sum() * (b * b).sum()))


def test_ncc_map_is_the_zero_mean_ncc_at_every_position(rng):
    img = rng.uniform(0, 255, (30, 40)).astype(np.float32)
    t1 = rng.uniform(0, 255, (6, 8)).astype(np.float32)
    t2 = img[10:16, 20:28] * 0.5 + 30.0  # a gain and an offset of a window of the image
    m = ncc_map(img, np.stack([t1, t2]))
    assert m.shape == (25, 33)
    for r, c in [(0, 0), (3, 17), (24, 32), (10, 20)]:
        want = max(_zncc(img[r:r + 6, c:c + 8], t1), _zncc(img[r:r + 6, c:c + 8], t2))
        assert m[r, c] == pytest.approx(want, abs=1e-4)
    assert m[10, 20] == pytest.approx(1.0, abs=1e-5)  # NCC ignores the gain and the offset


def test_map_peaks_suppresses_neighbours():
    s = np.zeros((20, 20), np.float32)
    s[5, 5], s[5, 6], s[15, 14], s[2, 17] = 0.9, 0.85, 0.8, 0.3
    pos, val = map_peaks(s, 3, (3, 3))
    assert pos.tolist() == [[5, 5], [15, 14], [2, 17]]  # (5, 6) lies within the first peak's window
    np.testing.assert_allclose(val, [0.9, 0.8, 0.3])
    assert map_peaks(s, 0, (3, 3))[0].shape == (0, 2)


@pytest.mark.parametrize("colour", [False, True])
def test_proposals_find_the_reference_elsewhere_in_the_frame_under_a_gain(rng, colour):
    """The target's patch planted at another place with half the light is the best proposal."""
    frame = rng.integers(60, 200, (240, 320)).astype(np.float32)
    frame = (frame + np.roll(frame, 1, 0) + np.roll(frame, 1, 1)) / 3.0  # a little spatial correlation
    blobs = cv2.GaussianBlur(rng.normal(0, 1, (44, 24)).astype(np.float32), (0, 0), 3.0)
    target = 128.0 + 100.0 * blobs / np.abs(blobs).max()  # smooth structure, as an object's at its own scale
    frame[100:144, 40:64] = target  # box (40, 100, 24, 44): centre (52, 122)
    img = np.clip(frame, 0, 255).astype(np.uint8)
    cue = StructureCue(template_pixels=256)
    bgr = np.repeat(img[..., None], 3, axis=2) if colour else img
    cue.init(bgr, (52.0, 122.0, 12.0, 22.0))
    moved = np.clip(rng.integers(60, 200, (240, 320)).astype(np.float32), 0, 255)
    moved[150:194, 250:274] = target * 0.5 + 20.0  # elsewhere, darker
    moved = moved.astype(np.uint8)
    centres, ncc = cue.proposals(np.repeat(moved[..., None], 3, axis=2) if colour else moved, (12.0, 22.0), 4)
    assert centres.shape == (4, 2)
    assert np.hypot(*(centres[0] - (262.0, 172.0))) < 3.0
    assert ncc[0] > 0.8 > ncc[1]
    assert np.all(np.diff(ncc) <= 0)


def test_no_proposals_when_the_frame_is_smaller_than_a_box():
    c, v = propose_centres(np.zeros((10, 10), np.uint8), np.ones((1, 8, 8), np.float32), (20.0, 20.0), 3)
    assert c.shape == (0, 2) and v.shape == (0,)
