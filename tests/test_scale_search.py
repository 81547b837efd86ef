"""The NCC scale search (``pftrack.cues.scale_search``) and ``cotrain-pf``'s size estimate built on it."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

import pftrack
from pftrack.cues.scale_search import aspect_factor, best_ratio, scale_candidates, search_scale, vertex_ratio
from pftrack.cues.structure import StructureCue


def test_candidates_scale_the_half_axes_and_shift_in_scaled_units():
    ell = scale_candidates((50.0, 40.0, 10.0, 20.0), [0.5, 1.0, 2.0], np.array([[0.0, 0.0], [0.1, -0.1]]))
    assert ell.shape == (6, 4)
    np.testing.assert_allclose(ell[0], [50, 40, 5, 10])
    np.testing.assert_allclose(ell[1], [50.5, 39.0, 5, 10])  # shift 0.1 of the scaled half-axes
    np.testing.assert_allclose(ell[5], [52.0, 36.0, 20, 40])


def test_best_ratio_takes_the_best_shift_and_needs_the_margin():
    ratios = np.array([0.9, 1.0, 1.1])
    s = np.array([0.1, 0.5, 0.60, 0.2, 0.3, 0.58])  # 3 ratios x 2 shifts; per ratio: 0.5, 0.6, 0.58
    assert best_ratio(s, ratios, 2) == (1.0, 0.6, 0.6)
    s2 = np.array([0.2, 0.3, 0.5, 0.55, 0.7, 0.1])  # per ratio: 0.3, 0.55, 0.7
    assert best_ratio(s2, ratios, 2) == (1.1, 0.7, 0.55)
    assert best_ratio(s2, ratios, 2, margin=0.2)[0] == 1.0  # 0.7 does not beat 0.55 by more than 0.2


def test_vertex_ratio_interpolates_in_log_scale():
    # one shift per ratio; scores at 1/1.05, 1, 1.05
    r, best, at1 = vertex_ratio(np.array([0.5, 0.7, 0.6]), 0.05, 1)
    assert r == pytest.approx(1.05 ** (1 / 6)) and (best, at1) == (0.7, 0.7)  # vertex at x = 1/6 of a step
    assert vertex_ratio(np.array([0.6, 0.7, 0.6]), 0.05, 1)[0] == 1.0  # symmetric: no change
    assert vertex_ratio(np.array([0.2, 0.5, 0.9]), 0.05, 1)[0] == pytest.approx(1.05)  # vertex beyond: clipped
    assert vertex_ratio(np.array([0.5, 0.4, 0.7]), 0.05, 1)[0] == pytest.approx(1.05)  # convex: the better end
    assert vertex_ratio(np.array([0.5, 0.4, 0.7]), 0.05, 1, margin=0.5)[0] == 1.0  # ... only beyond the margin
    # the best shift of each ratio counts (2 shifts per ratio)
    assert vertex_ratio(np.array([0.1, 0.5, 0.7, 0.0, 0.2, 0.6]), 0.05, 2)[0] == pytest.approx(1.05 ** (1 / 6))


def _textured_frame(rng, scale: float, size=(240, 320), centre=(160.0, 120.0), half=(24.0, 36.0)):
    """A smooth random texture target of half-axes ``half * scale`` on a textured background."""
    h, w = size
    bg = cv2.GaussianBlur(rng.uniform(0, 255, (h, w)).astype(np.float32), (0, 0), 3)
    tex = cv2.GaussianBlur(np.random.default_rng(99).uniform(0, 255, (96, 64)).astype(np.float32), (0, 0), 2)
    tw, th = int(round(2 * half[0] * scale)), int(round(2 * half[1] * scale))
    sprite = cv2.resize(tex, (tw, th), interpolation=cv2.INTER_LINEAR)
    x0, y0 = int(round(centre[0] - tw / 2)), int(round(centre[1] - th / 2))
    img = bg.copy()
    img[y0:y0 + th, x0:x0 + tw] = sprite
    return cv2.cvtColor(np.clip(img, 0, 255).astype(np.uint8), cv2.COLOR_GRAY2BGR)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_search_scale_recovers_a_five_percent_size_change(seed):
    rng = np.random.default_rng(seed)
    ell = (160.0, 120.0, 24.0, 36.0)
    cue = StructureCue(template_pixels=256, anchor=True)
    cue.init(_textured_frame(rng, 1.0), ell)
    for true, expect in ((1.05, 1.05), (1 / 1.05, 1 / 1.05), (1.0, 1.0)):
        cue.new_frame()
        r, best, at1 = search_scale(cue, _textured_frame(rng, true), ell, step=0.05)
        assert r == pytest.approx(expect), (true, r, best, at1)
        assert best >= at1


def _growing_scene(seed: int, n: int = 50):
    """A textured, distinctly coloured target drifting right while it grows from 30 x 40 to 45 x 60 px."""
    rng = np.random.default_rng(seed)
    h, w = 200, 260
    bg = cv2.GaussianBlur(rng.uniform(60, 200, (h, w, 3)).astype(np.float32), (0, 0), 4)
    tex = rng.uniform(0, 255, (60, 45)).astype(np.float32)
    tex = cv2.GaussianBlur(tex, (0, 0), 1.5)
    frames, boxes = [], []
    for t in range(n):
        s = 1.0 + 0.5 * t / (n - 1)
        tw, th = int(round(30 * s)), int(round(40 * s))
        cx, cy = 90 + 60 * t / (n - 1), 100.0
        sprite = cv2.resize(tex, (tw, th))
        col = np.stack([0.3 * sprite, 0.5 * sprite, 0.4 * sprite + 120], axis=-1)  # reddish, textured
        x0, y0 = int(round(cx - tw / 2)), int(round(cy - th / 2))
        img = bg.copy()
        img[y0:y0 + th, x0:x0 + tw] = col
        img += rng.normal(0, 2.0, img.shape)
        frames.append(np.clip(img, 0, 255).astype(np.uint8))
        boxes.append((x0, y0, tw, th))
    return frames, np.array(boxes, float)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_cotrain_pf_size_follows_a_growing_target(seed):
    """With the particles' own scale frozen, the size follows only through the NCC search."""
    frames, gt = _growing_scene(seed)
    sizes = {}
    for mode in ("ncc", "none"):
        t = pftrack.create_tracker("cotrain-pf", seed=seed, scale_search=mode, scale_noise=0.0)
        t.init(frames[0], gt[0])
        states = [t.update(f) for f in frames[1:]]
        sizes[mode] = np.sqrt(states[-1].box[2] * states[-1].box[3])
    true = np.sqrt(gt[-1, 2] * gt[-1, 3])  # 1.5 x the first size
    assert abs(sizes["ncc"] / true - 1.0) < 0.15, (sizes, true)
    assert sizes["none"] == pytest.approx(np.sqrt(gt[0, 2] * gt[0, 3]))


def test_vertex_offset_is_vertex_ratios_step_fraction():
    from pftrack.cues.scale_search import vertex_offset

    for lo, mid, hi in [(0.5, 0.7, 0.6), (0.6, 0.7, 0.6), (0.2, 0.5, 0.9), (0.5, 0.4, 0.7), (0.9, 0.5, 0.2)]:
        x = vertex_offset(lo, mid, hi)
        assert -1.0 <= x <= 1.0
        assert np.exp(x * np.log1p(0.05)) == pytest.approx(vertex_ratio(np.array([lo, mid, hi]), 0.05, 1)[0])
    assert vertex_offset(0.5, 0.7, 0.6) == pytest.approx(1 / 6)
    assert vertex_offset(0.5, 0.4, 0.7, margin=0.5) == 0.0


@pytest.mark.parametrize("lit", [False, True])
def test_size_scores_equal_the_batch_scores(lit):
    """The per-size compiled path gives the batch's numbers (grey levels, and the quotient/levels pair)."""
    from pftrack.cues.structure_light import LitStructure

    rng = np.random.default_rng(3)
    ell = (160.0, 120.0, 24.0, 36.0)
    cue = LitStructure(256, weighting="uniform") if lit else StructureCue(template_pixels=256, anchor=True)
    cue.init(_textured_frame(rng, 1.0), ell)
    frame = _textured_frame(rng, 1.04)
    ratios = (1 / 1.03, 1.0, 1.03)
    cue.new_frame()
    got = cue.size_scores(frame, ell, ratios)
    cue.new_frame()
    want = cue.scores(frame, None, scale_candidates(ell, np.array(ratios), np.zeros((1, 2))))
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-9)



@pytest.mark.parametrize("seed", [0, 1, 2])
def test_aspect_factor_moves_the_shape_toward_the_target(seed):
    """A target stretched 5 % wider and 5 % shorter (the same texture, about the same area) moves the width up and
    the height down; the reverse moves them the other way; the unchanged target leaves the shape (almost) alone."""
    rng = np.random.default_rng(seed)
    ell = (160.0, 120.0, 24.0, 36.0)
    cue = StructureCue(template_pixels=256, anchor=True)
    cue.init(_textured_frame(rng, 1.0), ell)
    got = {}
    for name, (fx, fy) in {"wider": (1.05, 1 / 1.05), "taller": (1 / 1.05, 1.05), "same": (1.0, 1.0)}.items():
        cue.new_frame()
        frame = _textured_frame(rng, 1.0, half=(24.0 * fx, 36.0 * fy))
        got[name] = aspect_factor(cue, frame, ell, 0.05, 1.0)
    assert got["wider"] > 1.02 and got["taller"] < 1 / 1.02, got
    assert abs(np.log(got["same"])) < 0.25 * np.log(1.05), got
    cue.new_frame()  # a box reaching past the frame's edge at the widest shape: no change
    assert aspect_factor(cue, _textured_frame(rng, 1.0), (12.0, 120.0, 24.0, 36.0), 0.05, 1.0) == 1.0


def test_size_scores_of_shapes_equal_the_batch_scores():
    """A ratio given per half-axis ``(rx, ry)`` scores the box of those half-axes, as the batch does."""
    rng = np.random.default_rng(4)
    ell = (160.0, 120.0, 24.0, 36.0)
    cue = StructureCue(template_pixels=256, anchor=True)
    cue.init(_textured_frame(rng, 1.0), ell)
    frame = _textured_frame(rng, 1.0, half=(25.0, 34.0))
    pairs = ((1 / 1.05, 1.05), (1.0, 1.0), (1.05, 1 / 1.05))
    cue.new_frame()
    got = cue.size_scores(frame, ell, pairs)
    cue.new_frame()
    want = cue.scores(frame, None, np.array([[160.0, 120.0, 24.0 * rx, 36.0 * ry] for rx, ry in pairs]))
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-9)

def test_particle_columns_and_mean_scale_together():
    from pftrack.filtering.particles import ParticleSet

    ps = ParticleSet(np.arange(12.0).reshape(3, 4), np.log(np.array([0.2, 0.3, 0.5])))
    before = ps.mean().copy()
    ps.scale_columns(2, 4, 1.5)
    np.testing.assert_allclose(ps.states[:, 2:], 1.5 * np.arange(12.0).reshape(3, 4)[:, 2:])
    np.testing.assert_allclose(ps.states[:, :2], np.arange(12.0).reshape(3, 4)[:, :2])
    np.testing.assert_allclose(ps.mean(), np.r_[before[:2], 1.5 * before[2:]])


@pytest.mark.parametrize("seed", [0, 1])
def test_fusion_pf_scale_search_follows_a_growing_target(seed):
    """With the particles' own scale frozen, fusion-pf's size follows a target growing 1.5x only through the
    NCC scale search (``scale_search``), at most (1 + s)^rate a frame. The size read from the map's mass
    (``mass_size``, fusion-pf's default since) is off here: it follows the growth too."""
    frames, gt = _growing_scene(seed)
    sizes = {}
    for s in (0.03, 0.0):
        t = pftrack.create_tracker("fusion-pf", seed=seed, scale_search=s, scale_rate_noise=0.0, mass_size=0.0)
        t.init(frames[0], gt[0])
        states = [t.update(f) for f in frames[1:]]
        sizes[s] = np.sqrt(states[-1].box[2] * states[-1].box[3])
    true = np.sqrt(gt[-1, 2] * gt[-1, 3])
    assert abs(sizes[0.03] / true - 1.0) < 0.15, (sizes, true)
    assert sizes[0.0] == pytest.approx(np.sqrt(gt[0, 2] * gt[0, 3]), rel=0.02)


@pytest.mark.parametrize("kind", ["ncc", "ncc-numpy", "hog"])
def test_the_size_search_can_compare_sizes_with_the_anchor_alone(kind):
    """``anchor_only``: the sizes are compared with the first frame's reference alone, the running mean ignored, so
    a cue whose running mean learnt another box scores them as a cue that learnt nothing."""
    from pftrack._numba import set_numba_enabled
    from pftrack.cues.structure_hog import HogStructure

    rng = np.random.default_rng(3)
    ell, ratios = (160.0, 120.0, 24.0, 36.0), (1 / 1.05, 1.0, 1.05)
    first, later = _textured_frame(rng, 1.0), _textured_frame(rng, 0.95)  # the target shrank by 5 %
    make = (lambda: HogStructure()) if kind == "hog" else (lambda: StructureCue(template_pixels=256, anchor=True))
    previous = set_numba_enabled(kind != "ncc-numpy")
    try:
        learnt, fresh = make(), make()
        learnt.init(first, ell)
        fresh.init(first, ell)
        assert learnt.update(later, ell, 1.0)  # the running mean learnt the shrunken target at the old size
        learnt.new_frame()
        fresh.new_frame()
        both = learnt.size_scores(later, ell, ratios)
        anchor = learnt.size_scores(later, ell, ratios, anchor_only=True)
        assert anchor == pytest.approx(fresh.size_scores(later, ell, ratios), abs=1e-6)
        assert both[1] > anchor[1] + 0.01  # with it, the old size matches its own patch best
    finally:
        set_numba_enabled(previous)
