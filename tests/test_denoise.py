"""A noisy camera (``denoise`` of the colour particle filters, pftrack.cues.noise): the noise estimates, and the gate
that smooths every frame when the first two frames differ by more noise than the limit."""

from __future__ import annotations

import numpy as np
import pytest

import pftrack
from pftrack.cues.noise import noise_sigma, smooth, temporal_noise
from pftrack.errors import ParameterError


def _scene(noise: float, n: int = 12, seed: int = 0, texture: float = 0.0):
    """A ground (flat, or with fine static texture of deviation ``texture``), a red box walking across it, and
    white noise of ``noise`` levels drawn afresh on every frame."""
    rng = np.random.default_rng(seed)
    ground = np.full((120, 160, 3), 110.0, np.float32) + rng.normal(0, texture, (120, 160, 1)).astype(np.float32)
    frames, boxes = [], []
    for t in range(n):
        f = ground.copy()
        x = 20 + 4 * t
        f[40:80, x:x + 24] = (40.0, 50.0, 200.0)
        f += rng.normal(0, noise, f.shape).astype(np.float32)
        frames.append(np.clip(np.rint(f), 0, 255).astype(np.uint8))
        boxes.append((x, 40, 24, 40))
    return frames, boxes


@pytest.mark.parametrize("sd", [3.0, 8.0, 16.0])
def test_temporal_noise_reads_the_noise_and_not_the_static_texture(sd):
    frames, _ = _scene(sd, n=2, texture=12.0)
    grey_sd = sd * np.sqrt(0.114 ** 2 + 0.587 ** 2 + 0.299 ** 2)  # independent noise in B, G, R, seen in grey
    assert abs(temporal_noise(frames[0], frames[1]) - grey_sd) < 0.1 * grey_sd
    clean, _ = _scene(0.0, n=2, texture=12.0)
    assert temporal_noise(clean[0], clean[1]) < 0.5  # the texture stays put: nothing reads as noise
    assert noise_sigma(clean[0]) > 5.0  # while one frame alone takes the texture for noise


def test_temporal_noise_edge_cases_and_smooth():
    a = np.zeros((2, 2), np.uint8)
    assert temporal_noise(a, a) == 0.0
    with pytest.raises(ValueError):
        temporal_noise(np.zeros((8, 8), np.uint8), np.zeros((9, 8), np.uint8))
    f = np.random.default_rng(1).integers(0, 255, (20, 20, 3), dtype=np.uint8)
    assert smooth(f, 1) is f
    assert smooth(f, 5).std() < f.std()


def _run(frames, box, **params):
    tr = pftrack.create_tracker("fusion-pf", seed=3, **params)
    states = [tr.init(frames[0], box)] + [tr.update(f) for f in frames[1:]]
    return tr, np.array([s.box for s in states])


def test_a_noisy_camera_is_tracked_as_if_its_frames_were_smoothed_from_the_start():
    frames, boxes = _scene(14.0)
    tr, got = _run(frames, boxes[0], denoise=7.5)
    assert tr.denoised and tr.noise_level > 7.5
    _, want = _run([smooth(f, 5) for f in frames], boxes[0])
    np.testing.assert_array_equal(got, want)
    _, raw = _run(frames, boxes[0])
    assert not np.array_equal(got, raw)


def test_a_clean_camera_is_left_as_it_is():
    frames, boxes = _scene(2.0, texture=12.0)
    tr, got = _run(frames, boxes[0], denoise=7.5)
    assert not tr.denoised and tr.noise_level < 7.5
    _, off = _run(frames, boxes[0])
    np.testing.assert_array_equal(got, off)
    tr, _ = _run(frames, boxes[0])
    assert tr.noise_level is None and not tr.denoised  # off by default: nothing read


def test_denoise_kernel_must_be_odd():
    with pytest.raises(ParameterError):
        pftrack.create_tracker("color-pf", denoise=7.5, denoise_kernel=4)
