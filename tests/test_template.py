"""Book ch. 14: the six matching criteria, sub-pixel peaks, and the ``template`` tracker."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

import pftrack
from pftrack.cues import template as T
from pftrack.geometry import center_error
from pftrack.synth import Scene, camouflage_scene, simple_scene


def _texture(seed, shape=(120, 140)):
    rng = np.random.default_rng(seed)
    return cv2.GaussianBlur(rng.uniform(0, 255, shape), (0, 0), 2.0) * 3 - 250


@pytest.mark.parametrize("method", T.METHODS)
def test_every_criterion_equals_its_definition(method):
    rng = np.random.default_rng(1)
    search, tmpl = rng.uniform(0, 255, (20, 23)), rng.uniform(0, 255, (7, 9))
    got = T.match_surface(search, tmpl, method)
    ref = T.match_surface_reference(search, tmpl, method)
    tol = 1e-4 * np.abs(ref).max() if method in ("ssd", "ccorr", "ncc", "ncc_uncentred") else 1e-9
    assert got.shape == ref.shape and np.max(np.abs(got - ref)) <= tol


def test_sad_and_morphological_correlation_identities():
    rng = np.random.default_rng(2)
    search = rng.integers(0, 256, (18, 21)).astype(float)
    tmpl = rng.integers(0, 256, (6, 8)).astype(float)
    sad = -T.match_surface(search, tmpl, "sad")
    morph = T.match_surface(search, tmpl, "morph")
    win = np.lib.stride_tricks.sliding_window_view(search, tmpl.shape).sum(axis=(2, 3))
    assert np.array_equal(sad, tmpl.sum() + win - 2 * morph)  # |a - b| = a + b - 2 min(a, b), exactly
    mn = T.match_surface(search, tmpl, "morph_normed")
    assert np.allclose(mn, 1 - sad / (tmpl.sum() + win), atol=1e-12)


def test_mutual_information_properties():
    rng = np.random.default_rng(3)
    r = rng.integers(0, 256, (12, 12)).astype(float)
    q = T.quantize_levels(r, 32)
    p = np.bincount(q.ravel(), minlength=32) / q.size
    e = -np.sum(p[p > 0] * np.log(p[p > 0]))
    assert T.match_surface(r, r, "mi")[0, 0] == pytest.approx(e, abs=1e-12)  # C_V(R, R) = E(R)
    assert T.match_surface(np.full((12, 12), 77.0), r, "mi")[0, 0] == pytest.approx(0.0, abs=1e-12)
    inverted = 255.0 - r  # a relabelling of the bins: the information is unchanged
    assert T.match_surface(inverted, r, "mi")[0, 0] == pytest.approx(e, abs=1e-9)


@pytest.mark.parametrize("method", [m for m in T.METHODS if m != "ccorr"])
def test_exact_recovery_of_a_known_shift(method):
    """Raw correlation (4) is left out: it grows with the window's brightness, so a brighter window can
    beat the template's own position (the reason the chapter prefers the normalised measures)."""
    img = np.clip(_texture(4), 0, 255)
    k0, l0 = 37, 52
    tmpl = img[k0:k0 + 16, l0:l0 + 20]
    peak = T.best_offset(T.match_surface(img, tmpl, method))
    assert (round(peak.k), round(peak.l)) == (k0, l0) and not peak.on_border
    assert abs(peak.k - k0) < 0.5 and abs(peak.l - l0) < 0.5


def test_sub_pixel_peak_and_border_flag():
    img = _texture(5).astype(np.float32)
    shifted = cv2.warpAffine(img, np.float32([[1, 0, 0.4], [0, 1, -0.3]]), img.shape[::-1], flags=cv2.INTER_CUBIC)
    tmpl = img[40:64, 50:80]
    peak = T.best_offset(T.match_surface(shifted, tmpl, "ncc"))
    assert abs(peak.l - 50.4) < 0.15 and abs(peak.k - 39.7) < 0.15
    small = shifted[35:70, 47:85]  # the true offset (5, 3) is inside; a window cut at the target's edge is not
    assert not T.best_offset(T.match_surface(small, tmpl, "ncc")).on_border
    edge = shifted[40:66, 52:84]
    assert T.best_offset(T.match_surface(edge, tmpl, "ncc")).on_border


def test_batch_scores_match_the_surface():
    img = _texture(6)
    tmpl = img[30:46, 40:60]
    patches = np.stack([img[30 + d:46 + d, 40 - d:60 - d] for d in range(5)])
    for m in ("ncc", "ncc_uncentred", "ssd", "sad", "ccorr", "morph", "morph_normed"):
        surf = T.match_surface(img, tmpl, m)
        expected = [surf[30 + d, 40 - d] for d in range(5)]
        assert np.allclose(T.batch_scores(patches, tmpl, m), expected, rtol=1e-4, atol=1e-6), m


@pytest.mark.parametrize("metric", ["ncc", "mi", "sad"])
def test_template_tracker_follows_a_textured_target(metric):
    """A camouflaged target (structure only) under a light drift: the normalised criteria follow it."""
    scene = Scene(camouflage_scene(3, n_frames=60))
    frames, gt = scene.frames(), scene.groundtruth(0)
    t = pftrack.create_tracker("template", metric=metric)
    t.init(frames[0], tuple(gt[0]))
    err = center_error(np.array([gt[0]] + [t.update(f).box for f in frames[1:]]), gt)
    if metric in ("ncc", "mi"):
        assert err.mean() < 1.0
    else:  # SAD is not invariant to the falling light (the chapter: normalised measures are best)
        assert err.mean() > 5.0


def test_template_tracker_is_deterministic_and_registered():
    scene = Scene(simple_scene(2, n_frames=20))
    frames, gt = scene.frames(), scene.groundtruth(0)
    runs = []
    for _ in range(2):
        t = pftrack.create_tracker("template", metric="sad")
        t.init(frames[0], tuple(gt[0]))
        runs.append([t.update(f).box for f in frames[1:]])
    assert runs[0] == runs[1]
    assert "template" in pftrack.tracker_names()


def _vessels(seed=0, size=256):
    """A grey image with dark branching curves on a smooth bright background (angiography-like)."""
    rng = np.random.default_rng(seed)
    img = np.full((size, size), 170.0) + cv2.GaussianBlur(rng.normal(0, 25, (size, size)), (0, 0), 20)
    for _ in range(14):
        pts = np.cumsum(rng.normal(0, 9, (30, 2)), axis=0) + rng.uniform(40, size - 40, 2)
        cv2.polylines(img, [pts.astype(np.int32)], False, float(rng.uniform(60, 110)), int(rng.integers(2, 6)),
                      cv2.LINE_AA)
    return np.clip(cv2.GaussianBlur(img, (0, 0), 1.0), 0, 255).astype(np.uint8)


def test_xray_like_sequence_ncc_keeps_the_segment():
    """Ch. 14's setting: known heart-like motion, contrast drift and noise; NCC within 2 px, no failure."""
    from pftrack.synth.xray import structured_box, warped_sequence

    errs, fails = [], {"ncc": 0, "ssd": 0}
    for seed in range(3):
        src = _vessels(seed)
        frames, shifts = warped_sequence(src, seed, n_frames=30, amplitude=15.0)
        box = structured_box(src, margin=40)
        truth = np.array([box[0] + 16, box[1] + 16]) + shifts
        for metric in ("ncc", "ssd"):
            t = pftrack.create_tracker("template", metric=metric, search_margin=1.0)
            t.init(frames[0], box)
            for k, f in enumerate(frames[1:], 1):
                st = t.update(f)
                e = np.hypot(st.box[0] + 16 - truth[k, 0], st.box[1] + 16 - truth[k, 1])
                fails[metric] += int(e > 10)
                if metric == "ncc":
                    errs.append(e)
    assert np.mean(errs) <= 2.0, np.mean(errs)
    assert fails["ncc"] <= fails["ssd"]


def test_particle_filter_mode_scores_particles_with_the_criterion():
    """ssim-pf[cue=ncc]: the template criterion as a particle likelihood (D = (1 - NCC)/2, eq. 29)."""
    scene = Scene(camouflage_scene(2, n_frames=40))
    frames, gt = scene.frames(), scene.groundtruth(0)
    t = pftrack.create_tracker("ssim-pf", seed=0, cue="ncc")
    t.init(frames[0], tuple(gt[0]))
    err = center_error(np.array([gt[0]] + [t.update(f).box for f in frames[1:]]), gt)
    assert err.mean() < 2.0


def test_synth_xray_writes_sequences_with_exact_truth(tmp_path):
    from pftrack.cli import main
    from pftrack.io.datasets import read_sequence

    src = tmp_path / "frame.png"
    cv2.imwrite(str(src), _vessels(4))
    assert main(["synth", "xray", "--source", str(src), "--seeds", "0-1", "--out", str(tmp_path / "x")]) == 0
    seq = read_sequence(tmp_path / "x" / "xray-001")
    assert len(seq.frames) == 50 and np.all(np.isfinite(seq.groundtruth))
    assert main(["synth", "xray", "--seeds", "0", "--out", str(tmp_path / "y")]) == 2  # no --source
