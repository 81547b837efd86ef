"""The structural cue on histograms of oriented gradients (pftrack.cues.structure_hog)."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

import pftrack
from pftrack.cues.structure import StructureCue
from pftrack.cues.structure_hog import (
    BestStructure,
    HogStructure,
    _atan2_numpy,
    cell_grid,
    hog_descriptors,
    hog_ncc,
    orientation_integrals,
    standardize_descriptors,
)
from pftrack.cues.structure_light import LitStructure
from pftrack.eval.metrics import frame_ious


def _texture(seed: int = 0, size=(240, 320)) -> np.ndarray:
    """A smooth random grey texture, levels 40-200 (float32)."""
    rng = np.random.default_rng(seed)
    g = cv2.GaussianBlur(rng.uniform(0, 255, size).astype(np.float32), (0, 0), 3)
    return 40 + 160 * (g - g.min()) / (g.max() - g.min())


def _bgr(g: np.ndarray) -> np.ndarray:
    return cv2.cvtColor(np.clip(g, 0, 255).astype(np.uint8), cv2.COLOR_GRAY2BGR)


TARGET = np.array([160.0, 120.0, 40.0, 40.0])  # an 80 x 80 box


def test_the_octant_arctangent_is_within_its_stated_error():
    rng = np.random.default_rng(0)
    y, x = rng.normal(size=50_000), rng.normal(size=50_000)
    ref = np.mod(np.arctan2(y, x), math.pi)
    err = np.abs(_atan2_numpy(y, x) - ref)
    err = np.minimum(err, math.pi - err)  # 0 and pi are the same orientation
    assert err.max() < 3e-4


def test_orientation_integrals_put_each_edge_in_its_bins_and_both_backends_agree():
    e = np.zeros((20, 20), np.uint8)
    e[:, 10:] = 200  # a vertical edge: horizontal gradient, orientation 0, halfway between bins 8 and 0
    tot = orientation_integrals(e, 9)[-1, -1]
    assert tot[0] == pytest.approx(tot[8]) and tot[0] == pytest.approx(20 * 2 * 200 / 2)  # 2 columns of 20 rows
    assert np.all(tot[1:8] == 0)
    h = e.T.copy()  # a horizontal edge: orientation pi/2, the centre of bin 4
    tot = orientation_integrals(h, 9)[-1, -1]
    assert tot[4] == pytest.approx(tot.sum()) and tot.sum() > 0
    # unsigned orientations: the negated image (every gradient reversed) gives the same channels
    g = _texture(1, (40, 50)).astype(np.uint8)
    a = orientation_integrals(g, 9, backend="numba")
    np.testing.assert_allclose(a, orientation_integrals(255 - g, 9, backend="numba"), rtol=1e-9, atol=1e-6)
    np.testing.assert_allclose(a, orientation_integrals(g, 9, backend="numpy"), rtol=1e-9, atol=1e-6)
    with pytest.raises(ValueError):
        orientation_integrals(np.zeros((4, 4, 3)))



def _integrals_every_pixel(gray: np.ndarray, bins: int) -> np.ndarray:
    """The compiled kernel's sums written out pixel by pixel, flat pixels included (their shares are zeros)."""
    from pftrack.cues.structure_hog import _unsigned_angle

    h, w = gray.shape
    out = np.zeros((h + 1, w + 1, bins))
    for j in range(h):
        row = np.zeros(bins)
        for i in range(w):
            gx = float(gray[j, i + 1]) - float(gray[j, i - 1]) if 0 < i < w - 1 else 0.0
            gy = float(gray[j + 1, i]) - float(gray[j - 1, i]) if 0 < j < h - 1 else 0.0
            mag = math.sqrt(gx * gx + gy * gy)
            t = getattr(_unsigned_angle, "py_func", _unsigned_angle)(gy, gx) * (bins / math.pi) - 0.5
            b0 = math.floor(t)
            f = t - b0
            i0 = int(b0) % bins
            row[i0] += mag * (1.0 - f)
            row[(i0 + 1) % bins] += mag * f
            out[j + 1, i + 1] = row + out[j, i + 1]
    return out


def test_orientation_integrals_skip_flat_pixels_without_changing_a_bit():
    g = _texture(3, (23, 31)).astype(np.uint8)
    g[:8] = 90  # a flat band: pixels without gradient, skipped by the compiled kernel
    g[12:, 20:] = 150
    ref = _integrals_every_pixel(g, 9)
    assert np.array_equal(orientation_integrals(g, 9, backend="numba"), ref)

def test_descriptors_and_ncc_agree_between_backends_and_a_box_matches_itself():
    rng = np.random.default_rng(2)
    ii = orientation_integrals(_texture(2, (60, 80)).astype(np.uint8), 9)
    boxes = rng.uniform(0, 40, (9, 4))
    boxes[:, 2:] = boxes[:, :2] + rng.uniform(8, 30, (9, 2))
    boxes[0] = (-5.0, -5.0, 20.0, 20.0)  # partly outside the region: its outer cells are empty
    d = hog_descriptors(ii, boxes, 3, 4, backend="numba")
    np.testing.assert_allclose(d, hog_descriptors(ii, boxes, 3, 4, backend="numpy"), atol=1e-12)
    assert d.shape == (9, 3 * 4 * 9) and np.all(d >= -1e-9)  # integral differences: rounding only
    refs = standardize_descriptors(d[1:3])
    best, per = hog_ncc(ii, boxes, 3, 4, refs, backend="numba")
    best_np, per_np = hog_ncc(ii, boxes, 3, 4, refs, backend="numpy")
    np.testing.assert_allclose(per, per_np, atol=1e-12)
    np.testing.assert_allclose(best, best_np, atol=1e-12)
    assert per[1, 0] == pytest.approx(1.0) and per[2, 1] == pytest.approx(1.0)
    assert np.all(best <= 1.0 + 1e-12) and np.all(best >= -1.0 - 1e-12)


@pytest.mark.parametrize(("w", "h", "grid"), [(80, 80, (4, 4)), (27, 116, (2, 8)), (300, 100, (7, 2)), (5, 5, (4, 4))])
def test_the_cell_grid_follows_the_box_aspect(w, h, grid):
    assert cell_grid(w, h, 16) == grid


def _grey_ncc(a: np.ndarray, b: np.ndarray) -> float:
    a, b = a - a.mean(), b - b.mean()
    return float((a * b).sum() / math.sqrt((a * a).sum() * (b * b).sum()))


def test_a_light_across_the_target_keeps_the_gradient_cue_where_the_grey_ncc_falls():
    """The cue's purpose: a lamp from one side (gain 1.6 to 0.4 across the frame) changes the layout of the grey
    levels more than the contrast-normalised edges. Measured: HOG NCC 0.95, grey-patch NCC 0.70."""
    g = _texture(0)
    x = np.linspace(1.0, -1.0, g.shape[1])[None, :]
    lit = g * (1.0 + 0.6 * np.sin(0.5 * np.pi * x))
    hog = HogStructure()
    hog.init(_bgr(g), TARGET)
    grey = StructureCue(256, weighting="uniform")
    grey.init(_bgr(g), TARGET)
    grey.new_frame()
    e = TARGET.reshape(1, 4)
    r_hog = float(hog.scores(_bgr(lit), None, e)[0])
    r_grey = float(grey.scores(_bgr(lit), None, e)[0])
    assert r_hog > 0.9 and r_grey < r_hog - 0.15, (r_hog, r_grey)
    # a gain and an offset over the whole frame change little (cells normalised, gradients offset-free; the
    # 8-bit rounding of the darker copy is all that is left)
    hog.new_frame()
    assert float(hog.scores(_bgr(0.5 * g + 30), None, e)[0]) > 0.97
    # and the cue still tells the target from the texture beside it
    hog.new_frame()
    aside = (TARGET + [60.0, 0, 0, 0]).reshape(1, 4)
    assert float(hog.scores(_bgr(lit), None, aside)[0]) < r_hog - 0.5


def test_the_cue_keeps_an_anchor_and_a_gated_running_reference():
    g0, g1 = _texture(3), _texture(4)
    hog = HogStructure()
    assert not hog.ready
    hog.init(_bgr(g0), TARGET)
    assert hog.ready and hog.grid == (4, 4) and hog.shape == (32, 32)
    e = TARGET.reshape(1, 4)
    assert float(hog.scores(_bgr(g0), None, e)[0]) == pytest.approx(1.0)
    # a different texture in the box: the anchor gate refuses to learn it
    hog.new_frame()
    assert not hog.update(_bgr(g1), TARGET, 0.5, anchor_gate=0.5)
    assert hog.update(_bgr(g1), TARGET, 0.5)  # no gate: blended
    hog.new_frame()
    # the anchor still matches the first texture exactly (the better of the two references)
    assert float(hog.scores(_bgr(g0), None, e)[0]) == pytest.approx(1.0)
    # the size search's three sizes peak at the true one
    hog.new_frame()
    lo, mid, hi = hog.size_scores(_bgr(g0), TARGET, (1 / 1.2, 1.0, 1.2))
    assert mid > max(lo, hi) + 0.1
    assert hog.proposals(_bgr(g0), (40.0, 40.0), 3)[0].shape == (0, 2)


def test_the_best_of_several_cues_scores_the_larger_and_updates_each():
    g = _texture(5)
    f = _bgr(g)
    a, b = StructureCue(256, weighting="uniform"), HogStructure()
    best = BestStructure(a, b)
    best.init(f, TARGET)
    best.new_frame()
    assert best.ready and best.primary is a and best.shape == a.shape
    ell = np.array([TARGET, TARGET + [20.0, 0, 0, 0], TARGET + [0, 30.0, 0, 0]])
    np.testing.assert_allclose(best.scores(f, None, ell), np.maximum(a.scores(f, None, ell), b.scores(f, None, ell)))
    sizes = best.size_scores(f, TARGET, (0.9, 1.0, 1.1))
    assert sizes == [max(x, y) for x, y in zip(a.size_scores(f, TARGET, (0.9, 1.0, 1.1)),
                                                 b.size_scores(f, TARGET, (0.9, 1.0, 1.1)))]
    with pytest.raises(ValueError):
        BestStructure()


@pytest.mark.parametrize(("features", "gray", "kind"), [
    ("hog", True, HogStructure), ("hog", False, HogStructure), ("both", True, BestStructure),
    ("both", False, BestStructure), ("hog-on-grey", True, HogStructure), ("hog-on-grey", False, StructureCue),
    ("ncc", True, LitStructure)])
def test_fusion_pf_builds_the_structural_cue_its_parameter_names_and_tracks(features, gray, kind):
    g = _texture(6)
    to = _bgr if gray else (lambda a: cv2.merge([a.astype(np.uint8), (255 - a).astype(np.uint8), a.astype(np.uint8)]))
    box = (120.0, 80.0, 80.0, 80.0)
    t = pftrack.create_tracker("fusion-pf", seed=0, structure_features=features)
    t.init(to(g), box)
    assert type(t.structure) is kind
    if kind is BestStructure:  # the grey NCC (on grey input the quotient/levels pair) and the gradients
        assert type(t.structure.cues[1]) is HogStructure
        assert isinstance(t.structure.primary, LitStructure if gray else StructureCue)
    boxes = []
    for dx in range(3, 31, 3):  # the whole scene moves right, 3 px a frame
        st = t.update(to(np.roll(g, dx, axis=1)))
        boxes.append(st.box)
        assert not st.lost
    truth = np.array([[box[0] + dx, box[1], box[2], box[3]] for dx in range(3, 31, 3)])
    assert frame_ious(np.array(boxes), truth).mean() > 0.7


def test_color_pf_builds_its_grey_check_on_gradients_when_asked():
    from pftrack.filtering.loss import LossDetector
    from pftrack.trackers.structure_check import StructureCheck

    assert type(StructureCheck(LossDetector(), fused=True, features="hog").cue) is HogStructure
    assert type(StructureCheck(LossDetector(), fused=True).cue) is LitStructure
    assert type(StructureCheck(LossDetector(), fused=False, features="hog").cue) is StructureCue  # re-acquisition only
    with pytest.raises(ValueError):
        StructureCheck(LossDetector(), features="sift")
    g = _texture(7)
    box = (120.0, 80.0, 80.0, 80.0)
    t = pftrack.create_tracker("color-pf", seed=0, grey_check_features="hog")
    t.init(_bgr(g), box)
    assert type(t._structure_check.cue) is HogStructure
    assert t._grey_shared()  # no structural quotient: the histogram's own starts from the one grey conversion
    for dx in range(3, 16, 3):
        st = t.update(_bgr(np.roll(g, dx, axis=1)))
        assert not st.lost
    assert frame_ious(np.array([st.box]), np.array([[box[0] + 15, box[1], box[2], box[3]]]))[0] > 0.7
    colour = cv2.merge([g.astype(np.uint8), (255 - g).astype(np.uint8), g.astype(np.uint8)])
    t = pftrack.create_tracker("color-pf", seed=0, grey_check_features="hog")
    t.init(colour, box)
    assert t._structure_check is None


def test_color_pf_grey_check_on_both_features_scores_the_better():
    from pftrack.filtering.loss import LossDetector
    from pftrack.trackers.structure_check import StructureCheck

    check = StructureCheck(LossDetector(), fused=True, features="both")
    assert type(check.cue) is BestStructure
    assert type(check.cue.primary) is LitStructure and type(check.cue.cues[1]) is HogStructure
    g = _bgr(_texture(7))
    ell = np.array([[160.0, 120.0, 40.0, 40.0]])
    check.init(g, ell)
    moved = _bgr(np.roll(_texture(7), 6, axis=1))
    boxes = np.array([[166.0, 120.0, 40.0, 40.0], [100.0, 60.0, 40.0, 40.0]])
    check.new_frame()
    both = check.scores(moved, boxes)
    each = [StructureCheck(LossDetector(), fused=True, features=f) for f in ("ncc", "hog")]
    for c in each:
        c.init(g, ell)
        c.new_frame()
    ncc, hog = (c.scores(moved, boxes) for c in each)
    assert np.allclose(both, np.maximum(ncc, hog))
    assert not np.allclose(ncc, hog)
    t = pftrack.create_tracker("color-pf", seed=0, grey_check_features="both")
    box = (120.0, 80.0, 80.0, 80.0)
    t.init(g, box)
    for dx in range(3, 16, 3):
        st = t.update(_bgr(np.roll(_texture(7), dx, axis=1)))
        assert not st.lost
    assert frame_ious(np.array([st.box]), np.array([[box[0] + 15, box[1], box[2], box[3]]]))[0] > 0.7


def test_fusion_pf_passes_its_cell_count_to_the_gradient_cue():
    t = pftrack.create_tracker("fusion-pf", seed=0, hog_cells=36)
    t.init(_bgr(_texture(8)), (120.0, 80.0, 80.0, 80.0))
    assert type(t.structure) is HogStructure and t.structure.grid == (6, 6) and t.structure.shape == (48, 48)


def test_the_correlations_can_bring_the_descriptors_they_were_computed_from():
    rng = np.random.default_rng(9)
    ii = orientation_integrals(_texture(9, (60, 80)).astype(np.uint8), 9)
    boxes = rng.uniform(0, 40, (5, 4))
    boxes[:, 2:] = boxes[:, :2] + rng.uniform(8, 30, (5, 2))
    refs = standardize_descriptors(hog_descriptors(ii, boxes[:2], 3, 4))
    for backend in ("numba", "numpy"):
        best, per = hog_ncc(ii, boxes, 3, 4, refs, backend=backend)
        best_k, per_k, desc = hog_ncc(ii, boxes, 3, 4, refs, backend=backend, keep=True)
        assert np.array_equal(best, best_k) and np.array_equal(per, per_k)
        assert np.array_equal(desc, hog_descriptors(ii, boxes, 3, 4, backend=backend))
