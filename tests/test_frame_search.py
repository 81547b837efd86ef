"""The whole-frame search while lost of ``flow-pf``, ``cotrain-pf`` and the monitor (``lost_search``,
:mod:`pftrack.trackers.frame_search`)."""

from __future__ import annotations

import numpy as np
import pytest

import pftrack
from pftrack.eval.metrics import frame_ious
from pftrack.trackers.frame_search import Persistence, best_candidate, frame_candidate, local_grid, scan_centres

H, W = 180, 240
SIZE = (20, 28)
HIDE, BACK, END = 30, 42, 90


def test_scan_centres_keep_every_box_in_the_frame():
    c = scan_centres(240, 180, 20, 28, 5.0)
    assert (c[:, 0] - 10 >= 0).all() and (c[:, 0] + 10 <= 240).all()
    assert (c[:, 1] - 14 >= 0).all() and (c[:, 1] + 14 <= 180).all()
    xs, ys = np.unique(c[:, 0]), np.unique(c[:, 1])
    assert np.allclose(np.diff(xs), 5.0) and np.allclose(np.diff(ys), 5.0)
    assert len(c) == len(xs) * len(ys)
    assert xs[0] - 10 < 5 and 240 - (xs[-1] + 10) < 5  # the grid reaches both sides within a step
    one = scan_centres(30, 20, 40, 10, 4.0)  # wider than the frame: one column, in the middle
    assert np.allclose(np.unique(one[:, 0]), [15.0])


def test_best_candidate_reports_the_runner_up_one_box_away():
    c = np.array([[10.0, 10.0], [14.0, 10.0], [60.0, 10.0], [10.0, 80.0]])
    best, d, second, d2 = best_candidate(c, np.array([0.2, 0.1, 0.5, np.nan]), (20, 20))
    assert np.allclose(best, [14, 10]) and d == pytest.approx(0.1)
    assert np.allclose(second, [60, 10]) and d2 == pytest.approx(0.5)  # (10, 10) is within one box of the best
    assert best_candidate(c, np.full(4, np.inf), (20, 20)) is None
    alone = best_candidate(c[:2], np.array([0.3, 0.2]), (20, 20))
    assert alone[2] is None and alone[3] == np.inf


def test_the_candidates_are_refined_so_the_coarse_grid_favours_neither():
    """Two equal look-alikes, one on a coarse grid point and one between two: refined, both score alike."""
    targets = np.array([[40.0, 40.0], [123.0, 40.0]])

    def score(c):  # distance grows with the offset from the nearer target
        return np.min(np.hypot(c[:, None, 0] - targets[None, :, 0], c[:, None, 1] - targets[None, :, 1]), axis=1) / 10

    coarse = np.array([[x, 40.0] for x in np.arange(10.0, 200.0, 6.0)])  # 40 is on it, 123 falls between 118 and 124
    best = frame_candidate(score, coarse, (20, 20), 6.0)
    assert best.distance == pytest.approx(0.0) and best.runner_up <= 0.075  # refined to within 0.75 px
    raw = best_candidate(coarse, score(coarse), (20, 20))
    assert raw[3] == pytest.approx(0.1)  # unrefined, the runner-up looked 1 px worse
    grid = local_grid(np.array([5.0, 7.0]), 4.0)
    assert grid.shape == (25, 2) and np.allclose(grid.min(axis=0), [3, 5]) and np.allclose(grid.max(axis=0), [7, 9])


def test_persistence_needs_frames_in_one_place():
    p = Persistence(2, 5.0)
    assert not p.offer(np.array([10.0, 10.0]))
    assert not p.offer(np.array([40.0, 10.0]))  # moved: the streak starts again
    assert p.offer(np.array([42.0, 11.0]))
    assert not p.offer(np.array([42.0, 11.0]))  # taken: reset
    assert not p.offer(None) and p.streak == 0


def _box(t: int) -> tuple[float, float, float, float] | None:
    """A target that walks right, is hidden, and comes back far away (bottom right), walking left."""
    if t < HIDE:
        return 30.0 + t, 30.0, *SIZE
    if t < BACK:
        return None
    return 190.0 - (t - BACK), 130.0, *SIZE


def _frame(bg: np.ndarray, tex: np.ndarray, t: int, rng: np.random.Generator, twin: int = 0) -> np.ndarray:
    f = bg.astype(np.float32).copy()
    box = _box(t)
    if box is not None:
        x, y, w, h = (int(round(v)) for v in box)
        f[y:y + h, x:x + w] = tex
    if twin and box is None:  # ``twin`` look-alikes side by side, far from where the target was lost, while it is away
        for x in (15, 95)[:twin]:
            f[135:135 + SIZE[1], x:x + SIZE[0]] = tex
    f += rng.normal(0.0, 2.0, f.shape)
    return np.clip(f, 0, 255).astype(np.uint8)


def _scene(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """A bluish-green background and the target's texture, red (drawn from ``rng`` in this order)."""
    bg = np.clip(rng.normal(110, 25, (H, W, 3)), 0, 255)
    bg[..., 2] *= 0.4
    tex = np.zeros((SIZE[1], SIZE[0], 3))
    tex[..., 2] = 200 + rng.normal(0, 20, SIZE[::-1])
    tex[..., 1] = 40 + rng.normal(0, 15, SIZE[::-1])
    tex[..., 0] = 40
    return bg, tex


def _run(seed: int, twin: int = 0, name: str = "flow-pf", **params) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(300 + seed)
    bg, tex = _scene(rng)
    tracker = pftrack.create_tracker(name, seed=seed, **params)
    tracker.init(_frame(bg, tex, 0, rng, twin), _box(0))
    iou, lost = [], []
    for t in range(1, END):
        state = tracker.update(_frame(bg, tex, t, rng, twin))
        box = _box(t)
        iou.append(np.nan if box is None else frame_ious(np.array([state.box]), np.array([box]))[0])
        lost.append(state.lost)
    return np.array(iou), np.array(lost)


@pytest.mark.parametrize("name", ["flow-pf", "cotrain-pf"])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_target_back_far_away_is_found_by_the_frame_search(seed, name):
    iou, lost = _run(seed, name=name, lost_search="frame")
    before = iou[: HIDE - 1]
    assert (before >= 0.5).mean() > 0.9
    assert lost[HIDE + 3: BACK - 1].mean() > 0.9  # hidden: lost
    after = iou[BACK - 1 + 6:]  # found within 6 frames of its return and followed
    assert (after >= 0.5).mean() > 0.9
    assert lost[BACK - 1 + 6:].mean() < 0.1


@pytest.mark.parametrize("name", ["flow-pf", "cotrain-pf"])
@pytest.mark.parametrize("seed", [0, 1])
def test_without_the_search_the_far_return_is_missed(seed, name):
    iou, _ = _run(seed, name=name, lost_search="off")  # the negative control: the filter waits where it lost it
    assert (iou[BACK - 1 + 6:] >= 0.5).mean() < 0.2


@pytest.mark.parametrize("name", ["flow-pf", "cotrain-pf"])
@pytest.mark.parametrize("seed", [0, 1])
def test_two_look_alikes_are_not_taken(seed, name):
    iou, lost = _run(seed, twin=2, name=name, lost_search="frame")
    assert lost[HIDE + 3: BACK - 1].mean() > 0.9  # neither twin passes the uniqueness test
    assert (iou[BACK - 1 + 6:] >= 0.5).mean() > 0.9  # and the target is found when it is back
    # what the test guards against: a single look-alike is taken (colour cannot tell it from the target)
    _, lost_one = _run(seed, twin=1, name=name, lost_search="frame")
    assert lost_one[HIDE + 3: BACK - 1].mean() < 0.5

def test_sample_step_keeps_twelve_samples_across_the_box():
    from pftrack.trackers.frame_search import sample_step
    assert sample_step(20, 28) == 1 and sample_step(23, 100) == 1
    assert sample_step(50, 60) == 4 and sample_step(300, 36) == 3
    assert sample_step(12, 12, 640, 480) == 1 and sample_step(12, 12, 1920, 1080) == 2  # a million pixels at most
    assert sample_step(12, 12, 3840, 2160) == 3 and sample_step(50, 60, 1920, 1080) == 4


@pytest.mark.parametrize("value_only", [False, True])
def test_compiled_min_emd_matches_the_numpy_path(value_only):
    from pftrack._numba import numba_enabled, set_numba_enabled
    from pftrack.cues.emd import emd_circular, emd_linear, min_emd_hsv

    rng = np.random.default_rng(5)
    h, t = rng.random((300, 3, 10)), rng.random((4, 3, 10))
    h[7] = 0.0  # an empty box: uniform, as _normalise takes it
    want = []
    for tk in t:
        dv = emd_linear(h[:, 2], tk[2])
        want.append(dv if value_only else (emd_circular(h[:, 0], tk[0]) + emd_linear(h[:, 1], tk[1]) + dv) / 3)
    want = np.min(want, axis=0)
    previous = set_numba_enabled(True)
    try:
        got = min_emd_hsv(h, t, value_only=value_only)
        set_numba_enabled(False)
        ref = min_emd_hsv(h, t, value_only=value_only)
    finally:
        set_numba_enabled(previous)
    assert np.allclose(got, want, atol=1e-12) and np.allclose(ref, want, atol=1e-12)
    if numba_enabled():
        assert not np.allclose(min_emd_hsv(h, t[:1], value_only=value_only), want)  # the min over templates matters


@pytest.mark.parametrize("name", ["opencv-csrt", "template"])
def test_the_monitor_search_restarts_any_tracker_on_the_far_return(name):
    iou, lost = _run(0, name=name, monitor=True, monitor_search="frame")
    assert lost[HIDE + 3: BACK - 1].mean() > 0.9
    assert (iou[BACK - 1 + 6:] >= 0.5).mean() > 0.9 and lost[BACK - 1 + 6:].mean() < 0.1
    iou_off, lost_off = _run(0, name=name, monitor=True)  # the negative control: the monitor alone only flags
    assert (iou_off[BACK - 1 + 6:] >= 0.5).mean() < 0.2 and lost_off[BACK - 1 + 6:].mean() > 0.9


def test_the_monitor_search_takes_neither_of_two_look_alikes():
    _, lost = _run(1, twin=2, name="opencv-csrt", monitor=True, monitor_search="frame")
    assert lost[HIDE + 3: BACK - 1].mean() > 0.9
    _, lost_one = _run(1, twin=1, name="opencv-csrt", monitor=True, monitor_search="frame")
    assert lost_one[HIDE + 3: BACK - 1].mean() < 0.5  # a single look-alike is taken: colour cannot tell it


@pytest.mark.parametrize("case", ["one-pixel", "corner", "larger-than-frame", "bgra", "uint16", "small-frame"])
@pytest.mark.parametrize("name", ["meanshift+monitor", "cotrain-pf", "flow-pf"])
def test_the_searches_keep_the_protocol_on_awkward_starts(name, case):
    """The awkward starts of the protocol test, then the target gone for six frames (so every search runs) and back:
    a clean input error at init or valid states throughout, whatever the box and pixel type."""
    from pftrack.errors import InputError

    from .test_every_tracker import _check, _edge_frames

    frames, box = _edge_frames(case)
    h, w = frames[0].shape[:2]
    blank = np.full_like(frames[0], 90)
    seq = frames + [blank] * 6 + frames
    params = {"monitor": True, "monitor_search": "frame"} if name.endswith("+monitor") else {"lost_search": "frame"}
    tracker = pftrack.create_tracker(name.split("+")[0], seed=0, **params)
    try:
        state = tracker.init(seq[0], box)
    except InputError as exc:
        assert case in ("one-pixel", "larger-than-frame", "small-frame") and "\n" not in str(exc)
        return
    _check(state, w, h)
    for f in seq[1:]:
        _check(tracker.update(f), w, h)


def test_a_small_box_in_a_large_frame_widens_the_grid():
    c = scan_centres(1920, 1080, 8, 8, 2.0)  # 2 px would be about 510 000 centres
    assert 15_000 < len(c) <= 20_500
    assert len(scan_centres(1920, 1080, 8, 8, 2.0, max_centres=1000)) <= 1100
    assert len(scan_centres(640, 480, 20, 30, 6.25)) == len(scan_centres(640, 480, 20, 30, 6.25, max_centres=10**9))


def test_exit_side_and_band():
    from pftrack.trackers.frame_search import exit_band, exit_side

    assert exit_side((225, 80, 20, 28), 240, 180) == 1 and exit_side((2, 80, 20, 28), 240, 180) == 0
    assert exit_side((100, 3, 20, 28), 240, 180) == 2 and exit_side((100, 160, 20, 28), 240, 180) == 3
    assert exit_side((100, 80, 20, 28), 240, 180) is None and exit_side((205, 80, 20, 28), 240, 180) is None
    c = scan_centres(240, 180, 20, 28, 5.0)
    band = exit_band(c, 1, 240, 180, 20, 28)
    assert band.any() and (c[band, 0] >= 210).all() and (c[~band, 0] < 210).all()
    assert (c[exit_band(c, 2, 240, 180, 20, 28), 1] <= 42).all()


def _exit_box(t: int) -> tuple[float, float, float, float] | None:
    """A target that walks out through the right edge, stays away, and walks back in through it."""
    if t < 20:
        return 180.0 + 3 * t, 80.0, *SIZE  # gone past x = 240 by frame 20
    if t < 45:
        return None
    return 240.0 - 2 * (t - 45), 80.0, *SIZE


@pytest.mark.parametrize("name, params", [("cotrain-pf", {"lost_search_exit": True}),
                                          ("template", {"monitor": True, "monitor_search": "frame",
                                                        "monitor_search_exit": True})])
def test_a_target_that_left_by_an_edge_is_looked_for_there(name, params):
    """While it is away a look-alike stands in the middle of the view; the search keeps to the edge it left by, so
    the look-alike is not taken and the target is found when it walks back in."""
    rng = np.random.default_rng(11)
    bg, tex = _scene(rng)

    def frame(t):
        f = bg.copy()
        box = _exit_box(t)
        if box is not None:
            x, y, w, h = (int(round(v)) for v in box)
            f[y:y + h, max(x, 0):min(x + w, W)] = tex[:, : max(min(x + w, W) - max(x, 0), 0)]
        else:
            f[120:120 + SIZE[1], 60:60 + SIZE[0]] = tex  # the look-alike, far from that edge
        return np.clip(f + rng.normal(0.0, 2.0, f.shape), 0, 255).astype(np.uint8)

    def run(**extra):
        tracker = pftrack.create_tracker(name, seed=0, **{**params, **extra})
        tracker.init(frame(0), _exit_box(0))
        states = [tracker.update(frame(t)) for t in range(1, 90)]
        lost = np.array([s.lost for s in states])
        far = np.array([abs(s.box[0] + s.box[2] / 2 - 70) < 15 and abs(s.box[1] + s.box[3] / 2 - 134) < 15
                        for s in states])
        return lost, far

    lost, far = run()
    assert lost[25:43].mean() > 0.9 and not far.any()  # the look-alike is never taken
    assert lost[60:].mean() < 0.2  # the target, back through the edge, is found
    off = {"lost_search_exit": False} if name == "cotrain-pf" else {"monitor_search_exit": False}
    _, far_any = run(**off)
    assert far_any.any()  # the negative control: searched over the whole frame, the lone look-alike is taken


def _resident_frame(bg, tex, t, rng, lookalike_dx: float = 0.0):
    """The target of :func:`_exit_box` out through the right edge and back, and a look-alike in view all along
    (standing, or walking right at ``lookalike_dx`` px a frame), far from that edge."""
    f = bg.copy()
    box = _exit_box(t)
    if box is not None:
        x, y, w, h = (int(round(v)) for v in box)
        f[y:y + h, max(x, 0):min(x + w, W)] = tex[:, : max(min(x + w, W) - max(x, 0), 0)]
    lx = int(60 + lookalike_dx * t)
    f[120:120 + SIZE[1], lx:lx + SIZE[0]] = tex
    return np.clip(f + rng.normal(0.0, 2.0, f.shape), 0, 255).astype(np.uint8)


@pytest.mark.parametrize("name, on, off", [
    ("cotrain-pf", {"lost_search_resident": 15}, {"lost_search_resident": 0}),
    ("template", {"monitor_search": "frame", "monitor_search_resident": 15},
     {"monitor_search": "frame", "monitor_search_resident": 0})])
@pytest.mark.parametrize("dx", [0.0, 0.5])
def test_a_look_alike_in_view_all_along_is_not_taken_for_the_target_back(name, on, off, dx):
    """The resident veto: the look-alike in view while the target is out is refused and passed over, so the target
    walking back in is unique and found; without it, the look-alike is taken (the negative control)."""

    def run(params):
        rng = np.random.default_rng(11)
        bg, tex = _scene(rng)
        tracker = pftrack.create_tracker(name, seed=0, **params)
        tracker.init(_resident_frame(bg, tex, 0, rng, dx), _exit_box(0))
        states = [tracker.update(_resident_frame(bg, tex, t, rng, dx)) for t in range(1, 90)]
        lost = np.array([s.lost for s in states])
        on_lookalike = np.array([abs(s.box[1] + s.box[3] / 2 - 134) < 15 and not s.lost for s in states])
        back = np.array([abs(s.box[1] + s.box[3] / 2 - 94) < 15 and not s.lost for s in states[59:]])
        return lost, on_lookalike, back

    lost, on_lookalike, back = run(on)
    assert lost[25:43].mean() > 0.9 and not on_lookalike.any()
    assert back.mean() > 0.9  # the target, back through the edge, is found
    _, on_lookalike_off, back_off = run(off)
    assert on_lookalike_off.any() and back_off.mean() < 0.5


def test_residents_trace_and_follow():
    """Residents: a box that stayed inside the view through the kept frames is resident, one that came in through
    an edge is not; a refused resident is followed to the next frame and its neighbourhood passed over."""
    from pftrack.trackers.frame_search import Residents

    rng = np.random.default_rng(5)
    bg = np.clip(rng.normal(110, 25, (H, W)), 0, 255)
    patch = np.clip(rng.normal(128, 60, (28, 20)), 0, 255)

    def frame(x_in, x_out):
        f = bg.copy()
        f[100:128, x_in:x_in + 20] = patch  # walks right inside the view
        f[20:48, max(x_out, 0):x_out + 20] = patch[:, max(-x_out, 0):]  # walks in through the left edge
        return f.astype(np.uint8)

    r = Residents(5)
    for t in range(6):
        r.keep(t, frame(50 + 2 * t, -14 + 3 * t))
    assert len(r) == 5
    assert not r.resident((-14 + 15, 20, 20, 28))  # its trace reaches the edge
    assert r.resident((60, 100, 20, 28)) and len(r.vetoed) == 1
    r.keep(6, frame(62, 4))
    assert abs(r.vetoed[0][0] - 62) <= 1  # followed
    near = r.near(np.array([[72.0, 114.0], [20.0, 34.0]]), 20, 28)
    assert near.tolist() == [True, False]
    r.keep(8, frame(66, 10))  # a gap: everything forgotten
    assert len(r) == 1 and not r.vetoed


def test_exit_scan_keeps_the_band_and_the_store_only_after_an_exit():
    from pftrack.trackers.frame_search import Residents, exit_scan, scan_centres

    frame = np.zeros((180, 240, 3), np.uint8)
    every = scan_centres(240, 180, 20, 28, 6.0)
    store = Residents(5)
    centres, active = exit_scan(frame, (20, 28), 6.0, (100, 80, 20, 28), True, store, 3)  # mid-view: no exit
    assert active is None and len(store) == 0 and len(centres) == len(every)
    centres, active = exit_scan(frame, (20, 28), 6.0, (225, 80, 20, 28), True, store, 4)  # at the right edge
    assert active is store and len(store) == 1 and (centres[:, 0] >= 210).all() and len(centres) < len(every)
    centres, active = exit_scan(frame, (20, 28), 6.0, (225, 80, 20, 28), False, None, 5)  # no band, no store
    assert active is None and len(centres) == len(every)
