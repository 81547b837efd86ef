"""The mog2 detector on a dark camera (``dark_stretch``): its frames are brought to the levels' full range before
MOG2, whose floor on each pixel's variance would hide a person's contrast in the dark; a noisy camera's frames are
smoothed first (``dark_denoise``)."""

from __future__ import annotations

import numpy as np

from pftrack.multi.detectors import MOG2Detector, MOG2DetectorParams


def _frames(gain: float, n: int = 40, seed: int = 0):
    """A textured ground and a box walking across it, times ``gain``, with noise of 2 levels."""
    rng = np.random.default_rng(seed)
    ground = rng.integers(90, 150, (120, 160, 3)).astype(np.float32)
    out = []
    for t in range(n):
        f = ground.copy()
        x = 10 + 3 * t
        f[40:90, x:x + 24] += np.array([-45.0, -20.0, 10.0], np.float32)  # a person in other colours than the ground
        f = f * gain + rng.normal(0, 2, f.shape)
        out.append(np.clip(np.rint(f), 0, 255).astype(np.uint8))
    return out


def _found(frames, **params) -> tuple[int, float]:
    det = MOG2Detector(MOG2DetectorParams(downscale=1, min_area=200, **params))
    hits = sum(len(det(f)) > 0 for f in frames[10:])
    return hits, det.gain


def test_a_dark_camera_is_stretched_before_mog2_and_an_ordinary_one_is_not():
    dark = _frames(0.2)
    plain_hits, plain_gain = _found(dark, dark_stretch=0.0)
    stretch_hits, gain = _found(dark, dark_stretch=2.0)
    assert plain_gain == 1.0 and 4.0 < gain <= 8.0
    assert stretch_hits > plain_hits + 5, (plain_hits, stretch_hits)
    ordinary = _frames(1.0)
    hits, gain = _found(ordinary, dark_stretch=2.0)
    assert gain == 1.0 and hits == _found(ordinary, dark_stretch=0.0)[0] and hits >= 15


def test_noise_sigma_reads_the_added_noise_and_little_of_smooth_structure():
    from pftrack.cues.foreground import noise_sigma

    rng = np.random.default_rng(1)
    flat = np.full((120, 160), 100.0)
    for sd in (2.0, 5.0, 10.0):
        noisy = np.clip(np.rint(flat + rng.normal(0, sd, flat.shape)), 0, 255).astype(np.uint8)
        assert abs(noise_sigma(noisy) - sd) < 0.1 * sd, (sd, noise_sigma(noisy))
    yy, xx = np.mgrid[0:120, 0:160]
    ramp = np.dstack([(xx + yy).astype(np.uint8)] * 3)  # a smooth colour frame: the two Laplacians cancel
    assert noise_sigma(ramp) < 0.5
    assert noise_sigma(np.zeros((2, 2), np.uint8)) == 0.0


def _still_dark(sd: float, n: int = 40, seed: int = 3):
    """A textured, still ground at gain 0.2 with noise of ``sd`` levels: every detection is a false positive."""
    rng = np.random.default_rng(seed)
    ground = rng.integers(60, 200, (30, 40, 3)).astype(np.float32)
    ground = np.kron(ground, np.ones((4, 4, 1), np.float32))  # patches of 4 x 4 pixels
    return [np.clip(np.rint(ground * 0.2 + rng.normal(0, sd, ground.shape)), 0, 255).astype(np.uint8)
            for _ in range(n)]


def test_dark_denoise_smooths_only_a_noisy_stretched_camera():
    def run(frames, denoise):
        """Mean share of the still ground taken for foreground, the smoothing decision, the gain."""
        det = MOG2Detector(MOG2DetectorParams(downscale=1, min_area=30, dark_stretch=2.0, dark_denoise=denoise))
        share = []
        for f in frames:
            det(f)
            share.append(float((det.foreground[0] > 0).mean()))
        return float(np.mean(share[5:])), det.denoise, det.gain

    noisy = _still_dark(6.0)
    plain, flag0, gain = run(noisy, 0.0)
    smoothed, flag1, _ = run(noisy, 8.66)
    assert gain > 4 and not flag0 and flag1
    # stretched, the noise passes MOG2's test on most of the still ground; smoothed first, on almost none
    assert plain > 0.3 and smoothed < 0.05, (plain, smoothed)
    quiet = _still_dark(1.0)
    assert not run(quiet, 8.66)[1]  # low noise: frames as before
    bright = [np.clip(f.astype(np.int32) * 5, 0, 255).astype(np.uint8) for f in quiet]
    assert run(bright, 8.66)[1:] == (False, 1.0)  # no stretch, no smoothing
    # a person still found under the smoothing (the walking box of _frames, noise 2 at gain 0.2)
    hits, gain = _found(_frames(0.2), dark_stretch=2.0, dark_denoise=1.0)
    assert gain > 4 and hits >= 15
