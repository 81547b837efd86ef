"""The multi-target filter's per-frame colour features: regions cut from a track's own region are exactly what a
fresh quantisation gives, and the model updates read the estimate's own features."""

import numpy as np
import pytest

from pftrack.cues.histogram_cue import ColorCue
from pftrack.multi import create_multi_tracker
from pftrack.multi.track_state import cut_features as _cut

from .conftest import render_scene
from .test_mot import movers


@pytest.mark.parametrize("pitch", [1, 2, 3])
def test_a_cut_region_equals_a_fresh_quantisation(pitch):
    rng = np.random.default_rng(pitch)
    frame = rng.integers(0, 256, (97, 131, 3), dtype=np.uint8)
    cue = ColorCue("rgb", (8, 8, 8), "nummiaro", 1000)
    shape = frame.shape[:2]
    big = cue.prepare(frame, (5, 7, 120, 90), pitch)
    big = type(big)(big.bins.copy(), big.x0, big.y0, big.pitch)
    inside = outside = 0
    for _ in range(200):
        x0, y0 = int(rng.integers(0, 125)), int(rng.integers(0, 92))
        roi = (x0, y0, x0 + int(rng.integers(1, 40)), y0 + int(rng.integers(1, 40)))
        cut = _cut(big, roi, pitch, shape)
        fresh = cue.prepare(frame, roi, pitch)
        if cut is None:
            outside += 1
            continue
        inside += 1
        assert (cut.x0, cut.y0, cut.pitch) == (fresh.x0, fresh.y0, fresh.pitch)
        assert cut.bins.flags.c_contiguous
        np.testing.assert_array_equal(cut.bins, fresh.bins)
    assert inside > 20 and outside > 20
    assert _cut(big, (10, 10, 20, 20), pitch + 1, shape) is None  # another lattice is never cut


def test_the_contrast_model_learns_from_the_estimates_own_region(monkeypatch):
    """The colour-model update quantises the estimate's ellipse again: the counts of the object/surround model
    must still be taken on the estimate's region, not on what that quantisation left in a shared buffer."""
    _, frames, _ = render_scene(movers(2))
    mt = create_multi_tracker("multi-pf", seed=0, detector="mog2")
    seen = []
    original = type(mt)._contrast_model

    def check(self, feats, tr, box, rate):
        if rate is not None:
            bins = feats.bins.copy()  # before the fresh quantisation below, which writes the cue's buffer
            fresh = self.cue.prepare(self._frame, feats.roi, feats.pitch)
            np.testing.assert_array_equal(bins, fresh.bins[: bins.shape[0], : bins.shape[1]])
            seen.append(1)
        return original(self, feats, tr, box, rate)

    monkeypatch.setattr(type(mt), "_contrast_model", check)
    for f in frames:
        mt._frame = f
        mt.update(f)
    assert len(seen) > 10
