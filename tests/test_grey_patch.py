"""Grey levels of the part of a frame a cue reads (cues.grey_patch) and the flow computed on such parts."""

import math

import cv2
import numpy as np
import pytest

import pftrack
from pftrack._numba import NUMBA_INSTALLED, set_numba_enabled
from pftrack.cues.grey_patch import GreyPatch, grey_patch
from pftrack.cues.motion import (LocalMotionCue, lattice_min_eigenvalues, lk_reach, lucas_kanade_flow,
                                 motion_likelihood, shi_tomasi_features, similarities)
from pftrack.frames import as_bgr_uint8, grey_origin


def textured_bgr(rng, h=240, w=320):
    base = rng.integers(0, 256, (h // 4, w // 4, 3), dtype=np.uint8)
    return cv2.GaussianBlur(cv2.resize(base, (w, h), interpolation=cv2.INTER_CUBIC), (0, 0), 1.0)


def shifted(img, dx, dy):
    m = np.float32([[1, 0, dx], [0, 1, dy]])
    return cv2.warpAffine(img, m, (img.shape[1], img.shape[0]), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)


def test_patch_levels_are_the_whole_conversion_s(rng):
    frame = textured_bgr(rng)
    whole = cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
    p = grey_patch(frame, (100, 50, 180, 120), margin=30)
    assert (p.x0, p.y0, p.img.shape) == (70, 20, (130, 140))
    assert np.array_equal(p.img, whole[20:150, 70:210])
    # cut to the frame
    p = grey_patch(frame, (5, 200, 60, 240), margin=30)
    assert (p.x0, p.y0, p.x0 + p.img.shape[1], p.y0 + p.img.shape[0]) == (0, 170, 90, 240)
    assert np.array_equal(p.img, whole[170:240, 0:90])
    assert p.covers(0, 170, 90, 240) and not p.covers(0, 169, 90, 240)
    assert np.array_equal(p.view(10, 180, 20, 200), whole[180:200, 10:20])
    # the whole frame
    p = grey_patch(frame)
    assert (p.x0, p.y0, p.frame_w, p.frame_h) == (0, 0, 320, 240) and np.array_equal(p.img, whole)


def test_a_grey_source_is_not_converted(rng):
    grey = cv2.cvtColor(textured_bgr(rng), cv2.COLOR_BGR2GRAY)
    bgr = as_bgr_uint8(grey)  # remembers the grey image it was made from
    p = grey_patch(bgr, (10, 10, 50, 50), margin=4)
    assert np.shares_memory(p.img, grey_origin(bgr)) and np.array_equal(p.img, grey[6:54, 6:54])
    assert np.array_equal(p.img, cv2.cvtColor(bgr, cv2.COLOR_BGR2GRAY)[6:54, 6:54])
    p = grey_patch(grey, (10, 10, 50, 50), margin=4)  # a 2-D frame
    assert np.shares_memory(p.img, grey)


@pytest.mark.parametrize("pitch", [1, 4])
def test_lattice_on_a_patch_is_the_whole_frame_s(rng, pitch):
    grey = cv2.cvtColor(textured_bgr(rng), cv2.COLOR_BGR2GRAY)
    roi = (0, 30, 140, 200)  # touches the frame's left border
    patch = grey_patch(grey, roi, margin=2)
    for flag in ([True, False] if NUMBA_INSTALLED else [False]):
        prev = set_numba_enabled(flag)
        try:
            whole = lattice_min_eigenvalues(grey, roi, pitch)
            part = lattice_min_eigenvalues(patch, roi, pitch)
            with pytest.raises(ValueError):
                lattice_min_eigenvalues(grey_patch(grey, roi, margin=1), roi, pitch)
        finally:
            set_numba_enabled(prev)
        for a, b in zip(whole, part):
            assert np.array_equal(a, b)
    assert np.array_equal(shi_tomasi_features(grey, roi, max_features=60),
                          shi_tomasi_features(patch, roi, max_features=60))


def test_flow_on_patches_matches_the_whole_frames(rng):
    prev_bgr = textured_bgr(rng)
    cur_bgr = shifted(prev_bgr, 1.7, -1.2)
    prev, cur = cv2.cvtColor(prev_bgr, cv2.COLOR_BGR2GRAY), cv2.cvtColor(cur_bgr, cv2.COLOR_BGR2GRAY)
    roi = (100, 60, 240, 190)
    margin = lk_reach() + 32
    pts = shi_tomasi_features(cur, roi, max_features=120)
    assert len(pts) > 30
    whole = lucas_kanade_flow(prev, cur, pts)
    part = lucas_kanade_flow(grey_patch(prev_bgr, roi, margin), grey_patch(cur_bgr, roi, margin), pts)
    assert part.n == whole.n and np.array_equal(part.x, whole.x) and np.array_equal(part.y, whole.y)
    # the same flow up to the float rounding of other coordinates (LK iterates in float32)
    assert np.abs(part.vx - whole.vx).max() < 0.05 and np.abs(part.vy - whole.vy).max() < 0.05
    assert np.median(part.vx) == pytest.approx(1.7, abs=0.1) and np.median(part.vy) == pytest.approx(-1.2, abs=0.1)


def test_a_feature_beyond_the_previous_patch_gets_no_flow(rng):
    prev_bgr = textured_bgr(rng)
    cur_bgr = shifted(prev_bgr, 1.0, 0.5)
    cur = grey_patch(cur_bgr, (40, 40, 280, 200), lk_reach())
    pts = np.float32([[60, 100], [150, 100], [260, 100]])
    prev = grey_patch(prev_bgr, (40, 40, 200, 200), lk_reach())  # holds the first two points' reach only
    flow = lucas_kanade_flow(prev, cur, pts)
    assert flow.n == 2 and np.all(flow.x < 200)
    assert np.allclose(flow.vx, 1.0, atol=0.1) and np.allclose(flow.vy, 0.5, atol=0.1)
    empty = GreyPatch(np.zeros((10, 10), np.uint8), 300, 220, 320, 240)
    assert lucas_kanade_flow(empty, cur, pts).n == 0


@pytest.mark.parametrize("v_obs", [(2.0, 0.5), (-1.0, 3.0), (0.004, 0.0), (0.0, -2.5)])
@pytest.mark.parametrize("v_est", [(1.5, 0.2), (0.0, 0.0), (-2.0, -2.0)])
def test_adaptation_in_scalars_follows_eqs_7_to_9(v_obs, v_est):
    cue = LocalMotionCue()
    v_ref = np.array([1.0, 1.0])
    g_t, g_r = similarities(np.array([v_obs]), np.array(v_est), eps=cue.eps)
    a_t = float(motion_likelihood(g_t[0], 0.0, sigma_theta=cue.sigma_theta, sigma_r=cue.sigma_r,
                                  w_noise=cue.w_noise))
    a_r = float(motion_likelihood(0.0, g_r[0], sigma_theta=cue.sigma_theta, sigma_r=cue.sigma_r,
                                  w_noise=cue.w_noise))
    th_ref, th_obs = math.atan2(1.0, 1.0), math.atan2(v_obs[1], v_obs[0])
    r_obs = math.hypot(*v_obs)
    th = th_ref if r_obs <= cue.eps else th_ref + a_t * math.atan2(math.sin(th_obs - th_ref),
                                                                      math.cos(th_obs - th_ref))
    r = (1 - a_r) * math.sqrt(2.0) + a_r * r_obs
    assert cue.adapt(v_ref, np.array(v_est), np.array(v_obs)) == pytest.approx([r * math.cos(th), r * math.sin(th)],
                                                                             abs=1e-12)


def test_local_motion_pf_converts_only_near_its_particles(rng):
    """On a large frame with a small target the tracker's grey patch is a small part of the frame, and the
    motion likelihood still steers it (the tracker follows a textured target on textured ground)."""
    h, w = 480, 640
    ground = textured_bgr(rng, h, w)
    target = textured_bgr(np.random.default_rng(7), 40, 30)
    target[:, :, 2] = np.clip(target[:, :, 2].astype(int) + 80, 0, 255)
    frames, boxes = [], []
    for k in range(30):
        x, y = 100 + 4 * k, 200 + 2 * k
        f = ground.copy()
        f[y:y + 40, x:x + 30] = target
        frames.append(f)
        boxes.append((x, y, 30, 40))
    t = pftrack.create_tracker("local-motion-pf", seed=0)
    t.init(frames[0], boxes[0])
    ious = []
    for f, b in zip(frames[1:], boxes[1:]):
        s = t.update(f)
        assert t._prev_gray.img.size < 0.25 * h * w
        bx, by, bw, bh = s.box
        iw = max(0.0, min(bx + bw, b[0] + b[2]) - max(bx, b[0]))
        ih = max(0.0, min(by + bh, b[1] + b[3]) - max(by, b[1]))
        ious.append(iw * ih / (bw * bh + b[2] * b[3] - iw * ih))
    assert t.v_ref is not None and np.mean(ious) > 0.6
