"""Large frames cost what the target needs: the background statistics quantise only what their ellipses read
(``ColorCue.prepare_cells``: the same bins where they are written, the same coefficients as the whole frame's
features, the same tracks), and a rectangle of a frame reaches OpenCV's conversions without a copy (``bgr_view``)."""

import cv2
import numpy as np
import pytest

import pftrack
from pftrack._numba import NUMBA_INSTALLED, set_numba_enabled
from pftrack.cues.histogram_cue import ColorCue
from pftrack.cues.quantize import make_lut, quantize, quantize_cells
from pftrack.frames import bgr_view
from pftrack.geometry import background_grid

BACKENDS = [False, True] if NUMBA_INSTALLED else [False]


@pytest.mark.parametrize("compiled", BACKENDS)
@pytest.mark.parametrize("pitch", [1, 2, 3])
def test_cells_get_the_whole_lattices_bins_and_nothing_else_is_written(compiled, pitch):
    rng = np.random.default_rng(pitch)
    img = rng.integers(0, 256, (101, 157, 3)).astype(np.uint8)
    lut = make_lut("rgb", (8, 8, 8))
    whole = quantize(np.ascontiguousarray(img[::pitch, ::pitch]), lut)
    cells = np.array([[0, 3, 0, 5], [10, 20, 7, 30], [15, 25, 25, 40], [30, 34, 48, 53], [5, 5, 2, 9]])
    cells[:, :2] = np.minimum(cells[:, :2], whole.shape[0])
    cells[:, 2:] = np.minimum(cells[:, 2:], whole.shape[1])
    out = np.full(whole.shape, 65535, np.uint16)
    previous = set_numba_enabled(compiled)
    try:
        quantize_cells(img, pitch, cells, lut, out)
    finally:
        set_numba_enabled(previous)
    written = np.zeros(whole.shape, bool)
    for r0, r1, c0, c1 in cells:
        written[r0:r1, c0:c1] = True
    assert np.array_equal(out[written], whole[written])
    assert np.all(out[~written] == 65535)


def _frame(h=720, w=1280, seed=0):
    rng = np.random.default_rng(seed)
    f = rng.integers(0, 256, (h // 8 + 1, w // 8 + 1, 3)).astype(np.uint8).repeat(8, 0).repeat(8, 1)[:h, :w]
    return np.ascontiguousarray(f)


@pytest.mark.parametrize("max_pixels", [0, 200])
def test_a_small_targets_background_grid_scores_as_on_the_whole_frames_features(max_pixels):
    frame = _frame()
    cue = ColorCue("rgb", (8, 8, 8), "nummiaro", max_pixels)
    cue.adapt_to(frame)
    ell = background_grid(1280, 720, 12.0, 30.0, 100, np.array([300.0, 200.0, 12.0, 30.0]))
    ref = cue.histogram(frame, (300.0, 200.0, 12.0, 30.0))
    sqrt_q = np.sqrt(ref)
    pitch = cue.step_for(ell)
    whole = cue.prepare(frame, (0, 0, 1280, 720), pitch)
    rho_a, tot_a = (a.copy() for a in cue.rho(whole, ell, sqrt_q))
    cells = cue.prepare_cells(frame, pitch, ell)
    assert cells is not None and cells.bins.shape == whole.bins.shape and cells.pitch == pitch
    rho_b, tot_b = cue.rho(cells, ell, sqrt_q)
    assert np.array_equal(rho_a, rho_b) and np.array_equal(tot_a, tot_b)


def test_where_it_would_save_nothing_or_cannot_apply_it_declines():
    frame = _frame(240, 320)
    cue = ColorCue("rgb", (8, 8, 8), "nummiaro", 0)
    cue.adapt_to(frame)
    dense = background_grid(320, 240, 30.0, 40.0, 100)  # target-sized ellipses covering the frame
    assert cue.prepare_cells(frame, 1, dense) is None
    grey = ColorCue("gray", None, "nummiaro", 0)
    grey.adapt_to(frame[..., 0])
    assert grey.prepare_cells(np.dstack([frame[..., 0]] * 3), 1, background_grid(320, 240, 5.0, 5.0, 20)) is None


def test_fusion_pf_tracks_a_small_target_in_a_large_frame_as_before(monkeypatch):
    """The whole state of every frame is the same with the whole frame quantised for the background statistics."""
    rng = np.random.default_rng(5)
    base = _frame(540, 960, seed=3)
    frames = []
    for n in range(24):
        f = base.copy()
        x, y = 400 + 3 * n, 250 + int(2 * np.sin(n / 3.0) * 5)
        f[y:y + 40, x:x + 20] = (30, 60, 220)
        f[y + 10:y + 20, x + 4:x + 16] = (200, 200, 40)
        frames.append(np.clip(f + rng.normal(0, 3, f.shape), 0, 255).astype(np.uint8))

    def run():
        t = pftrack.create_tracker("fusion-pf", seed=0)
        states = [t.init(frames[0], (400.0, 250.0, 20.0, 40.0))] + [t.update(f) for f in frames[1:]]
        return [(s.box, s.score, s.lost, s.particles.copy(), s.weights.copy()) for s in states]

    used = []
    original = ColorCue.prepare_cells

    def spy(self, *a, **k):
        r = original(self, *a, **k)
        used.append(r is not None)
        return r

    monkeypatch.setattr(ColorCue, "prepare_cells", spy)
    now = run()
    assert any(used)  # the background statistics took the cells
    monkeypatch.setattr(ColorCue, "prepare_cells", lambda self, *a, **k: None)
    before = run()
    for a, b in zip(now, before):
        assert a[0] == b[0] and a[1] == b[1] and a[2] == b[2]
        assert np.array_equal(a[3], b[3]) and np.array_equal(a[4], b[4])


def test_a_rectangle_of_a_frame_reaches_opencv_without_a_copy_and_converts_the_same():
    frame = _frame(120, 160)
    rect = frame[7:90, 11:150]
    assert bgr_view(rect) is rect
    assert np.array_equal(cv2.cvtColor(bgr_view(rect), cv2.COLOR_BGR2GRAY),
                          cv2.cvtColor(np.ascontiguousarray(rect), cv2.COLOR_BGR2GRAY))
    for odd in (frame[::2, ::3], frame[::-1], frame[..., ::-1], np.asfortranarray(frame)):
        v = bgr_view(odd)
        assert v.flags.c_contiguous and np.array_equal(v, odd)
