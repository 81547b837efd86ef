"""Book ch. 6 §3 and §5: feature selection, back-projection mean shift, fs-meanshift and switching
(ch06.md §5.1 tests 1-4 and 8, §5.2)."""

import cv2
import numpy as np
import pytest

import pftrack
from pftrack.cues import feature_selection as fs
from pftrack.filtering.running_threshold import RunningThreshold
from pftrack.geometry import iou
from pftrack.synth import Scene, camouflage_scene, teleport_scene


def test_llr_and_variance_ratio_worked_example():
    zf = np.array([0.6, 0.4, 0.0, 0.0])
    zb = np.array([0.0, 0.4, 0.6, 0.0])
    L, zf2, zb2 = fs.log_likelihood_ratio(zf * 100, zb * 100, delta=1e-3)
    np.testing.assert_allclose(L, [1.0, 0.0, -1.0, 0.0])
    np.testing.assert_allclose(zf2, zf)
    assert fs._var(L, zf) == pytest.approx(0.24)
    assert fs._var(L, zb) == pytest.approx(0.24)
    assert fs._var(L, 0.5 * (zf + zb)) == pytest.approx(0.6)
    assert fs.variance_ratio(L, zf, zb) == pytest.approx(1.25)


def test_variance_ratio_guards():
    L, zf, zb = fs.log_likelihood_ratio(np.array([10.0, 0.0]), np.array([0.0, 10.0]))
    assert fs.variance_ratio(L, zf, zb) >= 1e6  # disjoint supports: the denominator guard
    L, zf, zb = fs.log_likelihood_ratio(np.array([3.0, 7.0]), np.array([3.0, 7.0]))
    assert fs.variance_ratio(L, zf, zb) == 0.0  # identical distributions


def test_ranking_prefers_the_discriminative_channels():
    rng = np.random.default_rng(0)
    img = np.empty((120, 160, 3), np.uint8)
    img[:] = (40, 160, 40)  # BGR green background
    img[40:80, 60:100] = (40, 40, 200)  # red target
    img = np.clip(img + rng.normal(0, 3, img.shape), 0, 255).astype(np.uint8)
    bins = fs.bin_images(img)
    box = (60, 40, 40, 40)
    obj, ring = fs.ring_masks(img.shape[:2], box)
    ranking, vr = fs.rank_features(bins, obj, ring)
    assert set(ranking[:2]) <= {"R", "G", "H", "r", "g"}
    assert ranking.index("B") >= 2 and ranking.index("orient") >= 2


@pytest.mark.parametrize("previous, ranking, expected", [
    (("R", "G"), ("H", "R", "G"), ("R", "H")),
    (("R", "G"), ("R", "S", "G"), ("R", "S")),
    (("B", "G"), ("R", "S", "G"), ("B", "R")),
    (None, ("S", "R", "G"), ("S", "R")),
])
def test_only_the_second_feature_is_replaced(previous, ranking, expected):
    assert fs.select_pair(previous, ranking) == expected
    if previous is not None:
        assert fs.select_pair(previous, ranking)[0] == previous[0]
        assert fs.select_pair(previous, ranking, replace="all") == ranking[:2]


def test_partner_ranking_skips_a_copy_of_the_first_feature():
    """On grey frames R = G = B: Eq. 12 alone ranks the copies first and second; the joint ranking
    (partner="joint") pairs the first feature with one that adds information."""
    rng = np.random.default_rng(1)
    h, w = 60, 80
    obj = np.zeros((h, w), bool)
    obj[20:40, 30:50] = True
    ring = ~obj
    inten = np.where(obj, rng.integers(2, 5, (h, w)), rng.integers(3, 10, (h, w)))  # overlapping ranges
    other = np.where(obj, rng.integers(0, 6, (h, w)), rng.integers(0, 12, (h, w)))  # weaker alone, independent
    bins = np.stack([inten, inten, other], axis=-1).astype(np.uint8)
    names = ("R", "G", "S")
    ranking, vr = fs.rank_features(bins, obj, ring, names)
    assert ranking[:2] == ("R", "G")  # the copy ranks second alone
    partners, pvr = fs.rank_partners(bins, obj, ring, names, "R")
    assert partners[0] == "S" and list(pvr) == sorted(pvr, reverse=True)
    assert pvr[partners.index("G")] == pytest.approx(vr[0])  # a copy adds nothing to the pair


def test_refine_centre_moves_to_the_best_matching_window():
    """The local rho search returns the window whose kernel histogram matches the model, from a start
    two grid steps off, and stays put where no grid point is better."""
    rng = np.random.default_rng(4)
    joint = rng.integers(0, 16, (120, 160)).astype(np.int32)  # clutter of 16 bins
    joint[40:80, 60:100] = rng.integers(16, 24, (40, 40))  # the target: its own 8 bins, 40 x 40 at (80, 60)
    size = np.array([40.0, 40.0])
    true = np.array([80.0, 60.0])
    i0, j0, i1, j1, cx, cy = fs.kernel_window(joint.shape, *true, *size)
    model = fs.kernel_histogram(joint, 24, (i0, j0, i1, j1), cx, cy, 20.0, 20.0)
    got = fs.refine_centre(joint, model, (0, 0), true + [4.0, -4.0], size, radius=2, step=0.05)
    np.testing.assert_allclose(got, true)
    np.testing.assert_allclose(fs.refine_centre(joint, model, (0, 0), true, size), true)
    far = true + [30.0, 0.0]  # beyond the grid: the best reachable point is two steps towards the target
    np.testing.assert_allclose(fs.refine_centre(joint, model, (0, 0), far, size), far - [4.0, 0.0])


@pytest.mark.experiment
def test_joint_partner_keeps_grey_camouflaged_targets():
    """Grey camouflage scenes (target textured like the background): with the partner ranked alone the
    pair is two intensities and the window slides off; ranked jointly it holds (ch06.md §1.2)."""
    rates = {"single": [], "joint": []}
    for seed in (1, 2, 3):
        frames = list(Scene(camouflage_scene(seed, gray=1.0, n_frames=60)))
        for partner in rates:
            t = pftrack.create_tracker("switching", partner=partner)
            t.init(frames[0][0], tuple(frames[0][1].boxes[0]))
            hits = [iou(np.array(t.update(f).box), tr.boxes[0]) >= 0.5 for f, tr in frames[1:]
                    if tr.present[0] and tr.visible[0] > 0.9]
            rates[partner].append(np.mean(hits))
    assert min(rates["joint"]) >= 0.8, rates
    assert np.mean(rates["joint"]) >= np.mean(rates["single"]) + 0.3, rates


def test_weighted_meanshift_finds_a_gaussian_blob():
    yy, xx = np.mgrid[0:200, 0:200] + 0.5
    w = np.exp(-((xx - 100.3) ** 2 + (yy - 80.7) ** 2) / (2 * 10.0 ** 2)).astype(np.float32)
    c, it, mass = fs.weighted_meanshift(w, (112.0, 71.0), (20.0, 20.0), max_iter=15, eps=0.05)
    assert np.hypot(c[0] - 100.3, c[1] - 80.7) < 0.3
    assert 3 <= it <= 15


def test_damping_halves_the_first_step():
    yy, xx = np.mgrid[0:100, 0:100] + 0.5
    w = np.exp(-((xx - 50) ** 2 + (yy - 50) ** 2) / 200.0)
    full, _, _ = fs.weighted_meanshift(w, (58.0, 45.0), (15.0, 15.0), max_iter=1, damping=1.0)
    half, _, _ = fs.weighted_meanshift(w, (58.0, 45.0), (15.0, 15.0), max_iter=1, damping=0.5)
    np.testing.assert_allclose(half - [58.0, 45.0], 0.5 * (full - [58.0, 45.0]), atol=1e-9)


def test_equalised_intensity_is_invariant_to_a_gain():
    from pftrack.cues.intensity import equalization_lut

    rng = np.random.default_rng(1)
    g = rng.integers(20, 120, (60, 80)).astype(np.uint8)
    img = np.repeat(g[..., None], 3, axis=2)
    bright = np.clip(img.astype(np.float32) * 1.8, 0, 255).astype(np.uint8)
    b0 = fs.bin_images(img, ("Ieq",), eq_lut=equalization_lut(img))
    b1 = fs.bin_images(bright, ("Ieq",), eq_lut=equalization_lut(bright))
    assert np.mean(b0 == b1) > 0.9
    assert np.mean(fs.bin_images(img, ("R",)) == fs.bin_images(bright, ("R",))) < 0.5


def test_running_threshold():
    t = RunningThreshold(window=5, seed=3, k=2.0, sd_floor=0.1)
    assert not t.exceeds(100.0)  # not ready: nothing is flagged
    for v in (1.0, 1.0, 1.0):
        t.push(v)
    assert t.threshold == pytest.approx(1.2)
    assert t.exceeds(1.3) and not t.exceeds(1.1)


def _run(name, spec, **params):
    scene = Scene(spec)
    t = pftrack.create_tracker(name, **params)
    frames = list(scene)
    t.init(frames[0][0], tuple(frames[0][1].boxes[0]))
    out = [t.update(f) for f, _ in frames[1:]]
    truth = [tr for _, tr in frames[1:]]
    return out, truth


@pytest.mark.parametrize("name", ["fs-meanshift", "switching"])
def test_deterministic(name):
    spec = teleport_scene(3, n_frames=40)
    a, _ = _run(name, spec)
    b, _ = _run(name, spec)
    assert [s.box for s in a] == [s.box for s in b]
    assert all(np.all(np.isfinite(s.box)) for s in a)


@pytest.mark.experiment
def test_switching_recovers_teleports_that_local_mean_shift_loses():
    """ch06.md §5.2 on varied teleport scenes (seeds drawn colours, light, grey frames)."""
    wins, sw_rates, fs_rates = 0, [], []
    for seed in range(4):
        spec = teleport_scene(seed)
        jump = dict(spec.nuisances)["jump_at"]
        sw, truth = _run("switching", spec)
        lo, _ = _run("fs-meanshift", spec)
        vis = [tr.visible[0] > 0.9 and tr.present[0] for tr in truth]
        after = [k for k in range(len(truth)) if k + 1 > jump + 3 and vis[k]]

        def rate(states):
            return np.mean([iou(np.array(states[k].box), truth[k].boxes[0]) >= 0.5 for k in after])

        sw_rates.append(rate(sw))
        fs_rates.append(rate(lo))
        wins += sw_rates[-1] > fs_rates[-1]
    assert np.mean(sw_rates) >= np.mean(fs_rates) + 0.3, (sw_rates, fs_rates)
    assert wins >= 3


@pytest.mark.parametrize("name", ["fs-meanshift", "switching"])
def test_working_resolution_reports_frame_coordinates(name):
    """max_pixels: a tracker run on reduced frames reports boxes in the frame's coordinates and follows the
    target about as well as at full resolution."""
    spec = teleport_scene(5, n_frames=30)
    full, truth = _run(name, spec, max_pixels=0)
    small, _ = _run(name, spec, max_pixels=250)
    w, h = truth[0].boxes[0][2:]
    assert w * h > 4 * 250  # the reduced run works on 2 x 2 block means
    assert np.allclose([s.box[2:] for s in small[:5]], [s.box[2:] for s in full[:5]], rtol=0.1)
    vis = [k for k, tr in enumerate(truth[:10]) if tr.visible[0] > 0.9 and tr.present[0]]
    assert len(vis) >= 5
    assert np.mean([iou(np.array(small[k].box), truth[k].boxes[0]) for k in vis]) > 0.5


def test_compiled_kernel_histogram_and_mean_shift_equal_the_numpy_reference():
    from pftrack._numba import set_numba_enabled

    rng = np.random.default_rng(2)
    joint = rng.integers(0, 144, (60, 80))
    weights = rng.uniform(0, 1, (60, 80))
    weights[20:35, 30:50] += 3.0
    cases = [((5, 4, 50, 41), 21.3, 17.8, 20.0, 15.5), ((0, 0, 80, 60), 70.0, 3.0, 12.0, 30.0)]
    compiled = [fs.kernel_histogram(joint, 144, *c) for c in cases]
    ms = fs.weighted_meanshift(weights, (45.0, 22.0), (8.0, 6.0), origin=(0, 0))
    ms_off = fs.weighted_meanshift(weights, (145.0, 222.0), (8.0, 6.0), origin=(100, 200), max_iter=3)
    model = fs.kernel_histogram(joint, 144, (10, 10, 40, 40), 15.0, 15.0, 15.0, 15.0)
    # centres inside, across the border, outside (NaN) and on the half-pixel grid
    centres = np.array([[30.0, 25.0], [2.5, 58.5], [-40.0, 10.0], [79.5, 0.5], [41.25, 33.75]])
    rhos = fs.kernel_rhos_at(joint, model, centres, 17.0, 23.0)
    previous = set_numba_enabled(False)
    try:
        ref = fs.kernel_rhos_at(joint, model, centres, 17.0, 23.0)
        assert np.array_equal(np.isnan(rhos), np.isnan(ref)) and np.isnan(rhos[2])
        assert np.allclose(rhos[~np.isnan(rhos)], ref[~np.isnan(ref)], rtol=0, atol=1e-12)
        for c, h in zip(cases, compiled):
            assert np.array_equal(h, fs.kernel_histogram(joint, 144, *c))
        for got, kw in ((ms, {}), (ms_off, {"origin": (100, 200), "max_iter": 3})):
            ref = fs.weighted_meanshift(weights, (45.0, 22.0) if not kw else (145.0, 222.0), (8.0, 6.0), **kw)
            assert np.allclose(got[0], ref[0], rtol=0, atol=1e-9) and got[1] == ref[1]
            assert got[2] == pytest.approx(ref[2], rel=1e-12)
    finally:
        set_numba_enabled(previous)
    assert ms[0][0] < 45.0 and ms[0][1] > 22.0  # moved towards the heavy block


def test_search_prior_prefers_the_passing_candidate_near_the_prediction():
    """search_prior: of two global candidates that both pass the local test (two copies of the target), the
    chapter's rule takes the first by covariance distance; with the prior, the one near the prediction."""
    from pftrack.cues import covariance_search as cs

    rng = np.random.default_rng(0)
    img = cv2.GaussianBlur(rng.uniform(0, 255, (240, 320, 3)).astype(np.float32), (0, 0), 3).astype(np.uint8)
    patch = np.zeros((40, 24, 3), np.uint8)
    patch[:20] = (30, 60, 200)
    patch[20:] = (200, 160, 40)
    img[40:80, 40:64] = patch
    img[150:190, 220:244] = patch
    boxes = [(40.0, 40.0, 24.0, 40.0), (220.0, 150.0, 24.0, 40.0)]
    res = cs.SearchResult(boxes[0], 0.1, 2, np.array([(*boxes[0], 0.1), (*boxes[1], 0.2)]))
    picks = []
    for eps in (0.0, 0.05):
        t = pftrack.create_tracker("switching", search_prior=eps)
        t.init(img, boxes[0])
        t.update(img)
        t._seen = (t.frame_index, np.array([232.0, 170.0]), np.zeros(2))  # the target was last seen near B
        found = t._verify(img, res)
        assert found is not None
        picks.append(found[0])
    assert np.hypot(*(picks[0] - [52.0, 60.0])) < 6 and np.hypot(*(picks[1] - [232.0, 170.0])) < 6, picks


def test_the_switch_rule_of_each_alarm():
    """ch06.md §1.10: on an occlusion alarm a near candidate always takes over; a far one, with
    occlusion_take='closer', only when its covariance distance beats the local window's ('any': always).
    A sudden-motion alarm needs a higher rho; a distraction check a far candidate better on both."""
    from pftrack.trackers.switching import takes_over

    common = dict(global_rho=0.9, local_rho=0.7)
    assert takes_over("occlusion", far=False, global_le=2.0, local_le=1.0, **common)
    assert not takes_over("occlusion", far=True, global_le=2.0, local_le=1.0, **common)  # a look-alike elsewhere
    assert takes_over("occlusion", far=True, global_le=0.5, local_le=1.0, **common)
    assert takes_over("occlusion", far=True, global_le=2.0, local_le=1.0, occlusion_take="any", **common)
    assert takes_over("motion", far=True, global_le=2.0, local_le=1.0, global_rho=0.8, local_rho=0.7)
    assert not takes_over("motion", far=True, global_le=0.1, local_le=1.0, global_rho=0.6, local_rho=0.7)
    assert takes_over(None, far=True, global_le=0.5, local_le=1.0, distraction_bar=0.3, **common)
    assert not takes_over(None, far=True, global_le=0.8, local_le=1.0, distraction_bar=0.3, **common)
    assert not takes_over(None, far=False, global_le=0.1, local_le=1.0, **common)


def test_ratio_test_on_look_alikes():
    """``ambiguity``: a far candidate is refused when another window one box side or more away is nearly as
    close to the covariance model (or closer); windows overlapping the candidate do not count."""
    from pftrack.trackers.switching import ambiguous

    size = (20.0, 40.0)
    chosen = (100.0, 100.0)                      # centre of the candidate; its distance is 1.0
    cand = np.array([[90.0, 80.0, 20.0, 40.0, 1.0],     # the candidate itself
                     [93.0, 80.0, 20.0, 40.0, 1.02],    # 3 px away: the same place
                     [150.0, 80.0, 20.0, 40.0, 1.5]])   # a window 60 px away, clearly worse
    assert not ambiguous(cand, chosen, size, 1.0, 0.1)
    twin = np.vstack([cand, [[200.0, 80.0, 20.0, 40.0, 1.08]]])  # a look-alike 110 px away, within 10 %
    assert ambiguous(twin, chosen, size, 1.0, 0.1)
    assert not ambiguous(twin, chosen, size, 1.0, 0.05)
    assert not ambiguous(twin, chosen, size, 1.0, 0.0)          # off
    better = np.vstack([cand, [[200.0, 80.0, 20.0, 40.0, 0.7]]])  # a closer window that failed verification
    assert ambiguous(better, chosen, size, 1.0, 0.1)
