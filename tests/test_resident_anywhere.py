"""``resident_anywhere``: after a loss inside the view, a look-alike that stayed in view all the while is not taken
for the target (:meth:`pftrack.trackers.vetoes.VetoMixin._resident`)."""

from __future__ import annotations

import numpy as np
import pytest

import pftrack

H, W = 180, 240
SIZE = (20, 28)


def _box(t: int, back: int) -> tuple[float, float, float, float] | None:
    """The target walks right, vanishes in mid-view at frame 30 and comes back there at frame ``back``."""
    if t < 30:
        return 40.0 + 2 * t, 40.0, *SIZE
    if t < back:
        return None
    return 100.0 + 2 * (t - back), 40.0, *SIZE


def _run(back: int, seed: int, **params) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(21)
    bg = np.clip(rng.normal(110, 25, (H, W, 3)), 0, 255)
    bg[..., 2] *= 0.4
    tex = np.zeros((SIZE[1], SIZE[0], 3))
    tex[..., 2] = 200 + rng.normal(0, 20, SIZE[::-1])
    tex[..., 1] = 40 + rng.normal(0, 15, SIZE[::-1])
    tex[..., 0] = 40

    def frame(t: int) -> np.ndarray:
        f = bg.copy()
        b = _box(t, back)
        if b is not None:
            x, y, w, h = (int(round(v)) for v in b)
            f[y:y + h, x:x + w] = tex
        lx = int(30 + 40 * abs(((t / 40.0) % 2) - 1))  # a look-alike walking to and fro far below, all along
        f[130:130 + SIZE[1], lx:lx + SIZE[0]] = tex
        return np.clip(f + rng.normal(0.0, 2.0, f.shape), 0, 255).astype(np.uint8)

    tracker = pftrack.create_tracker("fusion-pf", seed=seed, **params)
    tracker.init(frame(0), _box(0, back))
    states = [tracker.update(frame(t)) for t in range(1, 100)]
    lost = np.array([s.lost for s in states])
    on_lookalike = np.array([abs(s.box[1] + s.box[3] / 2 - 144) < 15 and not s.lost for s in states])
    on_target = np.array([abs(s.box[1] + s.box[3] / 2 - 54) < 15 and not s.lost for s in states])
    return lost, on_lookalike, on_target


@pytest.mark.parametrize("trace", ["ncc", "colour"])
@pytest.mark.parametrize("back", [40, 60])  # a loss shorter and longer than the 15 frames the trace covers
def test_a_look_alike_in_view_all_the_while_is_not_taken_and_the_target_is(back, trace):
    lost, on_lookalike, on_target = _run(back, 0, resident_anywhere=1.0, resident_trace=trace)
    assert lost[31:back - 2].mean() > 0.9 and not on_lookalike.any()  # refused, then followed and refused again
    assert on_target[back + 5:].mean() > 0.9  # the target, back where it vanished, is taken
    # the negative control: without it the walking look-alike is taken and the target is not found again
    lost0, on_lookalike0, on_target0 = _run(back, 0)
    assert on_lookalike0.sum() > 30 and on_target0[back + 5:].mean() < 0.1


def test_off_by_default_and_needs_reenter_resident():
    p = pftrack.create_tracker("fusion-pf").params
    assert p.resident_anywhere == 0.0 and p.reenter_resident > 0
    lost, on_lookalike, _ = _run(40, 0, resident_anywhere=1.0, reenter_resident=0)  # no trace: nothing refused
    assert on_lookalike.sum() > 30


def test_the_colour_trace_follows_a_walker_whose_limbs_change_and_is_lost_on_another_colour():
    """trace_back_colour: a two-colour walker moving 6 px a frame with its lower half redrawn each frame (the legs)
    is followed back to where it was; a box on a patch of other colours is lost at once."""
    from pftrack.cues.colour_trace import trace_back_colour

    rng = np.random.default_rng(3)
    bg = np.clip(rng.normal(120, 30, (120, 200, 3)), 0, 255).astype(np.uint8)

    def frame(t: int) -> np.ndarray:
        f = bg.copy()
        x = 40 + 6 * t
        f[30:55, x:x + 16] = (40, 40, 200)  # the body
        legs = np.zeros((25, 16, 3), np.uint8)
        for c in range(16):  # the legs: dark columns that move between frames
            legs[:, c] = (30, 90, 30) if (c + 3 * t) % 8 < 4 else (150, 150, 150)
        f[55:80, x:x + 16] = legs
        return f

    frames = [frame(t) for t in range(6)]
    out = list(trace_back_colour(frames[4::-1], frames[5], (70.0, 30.0, 16.0, 50.0), 12))
    assert all(b is not None for b in out) and len(out) == 5
    assert abs(out[-1][0] - 40.0) <= 3  # six px a frame, back to where it was five frames before
    other = frames[5].copy()
    other[30:80, 150:166] = (200, 200, 40)
    lost = list(trace_back_colour(frames[4::-1], other, (150.0, 30.0, 16.0, 50.0), 12))
    assert lost == [None]
