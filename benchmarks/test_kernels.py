"""Micro-benchmarks of the compiled kernels against their NumPy reference paths."""

import numpy as np
import pytest

import pftrack
from pftrack._numba import set_numba_enabled
from pftrack.cues.color import ellipse_histograms, ellipse_rho
from pftrack.cues.histogram_cue import ColorCue
from pftrack.cues.quantize import make_lut, quantize
from pftrack.filtering.kernels import normalize_and_estimate, propagate_cv_scale
from pftrack.synth import Scene, SceneSpec, Target

BACKENDS = ["numba", "numpy"]


@pytest.fixture(scope="module")
def clip():
    spec = SceneSpec(width=640, height=480, n_frames=60, seed=0,
                     targets=(Target(path=((0, 200.0, 240.0), (59, 440.0, 240.0)), size=(50.0, 50.0)),))
    scene = Scene(spec)
    return scene.frames(), scene.groundtruth(0)


@pytest.fixture(scope="module")
def region(clip):
    frames, gt = clip
    cue = ColorCue()
    cx, cy = gt[0][0] + 25, gt[0][1] + 25
    feats = cue.prepare(frames[0], (int(cx) - 70, int(cy) - 70, int(cx) + 70, int(cy) + 70))
    rng = np.random.default_rng(0)
    ell = np.column_stack([rng.normal(cx, 5, 100), rng.normal(cy, 5, 100), np.full(100, 25.0), np.full(100, 25.0)])
    q = cue.histogram(frames[0], [cx, cy, 25, 25])
    return frames[0], feats, ell, np.sqrt(q)


@pytest.mark.parametrize("backend", BACKENDS)
def test_quantize_roi(benchmark, region, backend):
    frame = region[0]
    lut = make_lut("rgb", (8, 8, 8))
    roi = frame[170:310, 250:390]
    out = np.empty(roi.shape[:2], np.uint16)
    prev = set_numba_enabled(backend == "numba")
    try:
        benchmark(quantize, roi, lut, out)
    finally:
        set_numba_enabled(prev)


@pytest.mark.parametrize("backend", BACKENDS)
def test_rho_100_particles_50x50(benchmark, region, backend):
    _, feats, ell, sq = region
    benchmark(ellipse_rho, feats.bins, feats.x0, feats.y0, ell, sq, backend=backend)


@pytest.mark.parametrize("backend", BACKENDS)
def test_histograms_100_particles_50x50(benchmark, region, backend):
    _, feats, ell, _ = region
    benchmark(ellipse_histograms, feats.bins, feats.x0, feats.y0, ell, 512, backend=backend)


@pytest.mark.parametrize("backend", BACKENDS)
def test_propagate_and_normalize(benchmark, backend):
    rng = np.random.default_rng(0)
    states = np.tile([320.0, 240, 1, 0, 25, 25, 0], (100, 1))
    noise = rng.standard_normal(states.shape)
    std = np.array([5.0, 5, 2.5, 2.5, 0, 0, 0.005])
    ll = -rng.random(100) * 10
    lw, w, mean = np.empty(100), np.empty(100), np.empty(7)
    prev = set_numba_enabled(backend == "numba")

    def step():
        propagate_cv_scale(states, noise, std, width=640, height=480)
        normalize_and_estimate(ll, states, lw, w, mean)

    try:
        benchmark(step)
    finally:
        set_numba_enabled(prev)


@pytest.mark.parametrize("backend", BACKENDS)
def test_color_pf_update(benchmark, clip, backend):
    frames, gt = clip
    prev = set_numba_enabled(backend == "numba")
    try:
        tr = pftrack.create_tracker("color-pf", seed=0)
        tr.init(frames[0], gt[0])
        it = iter(frames[1:] * 1000)
        benchmark(lambda: tr.update(next(it)))
    finally:
        set_numba_enabled(prev)


# ---------------------------------------------------------------------------- book ch. 2: batched SSIM

def _ssim_inputs():
    rng = np.random.default_rng(0)
    return rng.uniform(0, 255, (100, 64, 64)).astype(np.float32), rng.uniform(0, 255, (64, 64))


def test_ssim_batch_100x64x64(benchmark):
    from pftrack.cues.ssim import ssim_batch

    patches, tmpl = _ssim_inputs()
    benchmark(lambda: ssim_batch(patches, tmpl))


def test_ssim_reference_loop_100x64x64(benchmark):
    """The per-particle loop the batch replaces (Wang's formula, one pair per call)."""
    from pftrack.cues.ssim import ssim_reference

    patches, tmpl = _ssim_inputs()
    benchmark.pedantic(lambda: [ssim_reference(p, tmpl) for p in patches], rounds=5, iterations=1)


def test_skimage_loop_100x64x64(benchmark):
    skm = pytest.importorskip("skimage.metrics")
    patches, tmpl = _ssim_inputs()
    p64 = patches.astype(np.float64)
    benchmark.pedantic(lambda: [skm.structural_similarity(p, tmpl, gaussian_weights=True, sigma=1.5,
                                                          use_sample_covariance=False, data_range=255) for p in p64],
                       rounds=3, iterations=1)


# ---------------------------------------------------------------------------- book ch. 14: matching criteria

@pytest.mark.parametrize("method", ["sad", "morph", "mi"])
def test_match_surface_compiled(benchmark, method):
    from pftrack.cues.template import match_surface

    rng = np.random.default_rng(0)
    search, tmpl = rng.uniform(0, 255, (64, 64)), rng.uniform(0, 255, (24, 24))
    match_surface(search, tmpl, method)
    benchmark(lambda: match_surface(search, tmpl, method))


@pytest.mark.parametrize("method", ["sad", "morph", "mi"])
def test_match_surface_numpy_loop(benchmark, method):
    from pftrack.cues.template import match_surface_reference

    rng = np.random.default_rng(0)
    search, tmpl = rng.uniform(0, 255, (64, 64)), rng.uniform(0, 255, (24, 24))
    benchmark.pedantic(lambda: match_surface_reference(search, tmpl, method), rounds=3, iterations=1)


# ---------------------------------------------------------------------------- fusion-pf's structural cue

@pytest.mark.parametrize("levels", ["uint8", "float64"])
def test_structure_ncc_100_boxes(benchmark, region, levels):
    """The compiled NCC of 100 boxes on a reduced region read as 8-bit levels or as their float64 copy (the
    cue reads the copy when the region is small next to the samples; the numbers are the same)."""
    from pftrack.cues.structure import StructureCue, _grid, _ncc_boxes, reduce_region

    frame, _, ell, _ = region
    cue = StructureCue(256, weighting="uniform")
    cue.init(frame, ell.mean(axis=0))
    red = reduce_region(frame, (150, 150, 420, 330), 2)
    gray = red.gray if levels == "uint8" else red.gray.astype(np.float64)
    u, v = _grid(cue.shape)
    tw, w = cue._prepared
    out = np.empty(ell.shape[0])
    benchmark(_ncc_boxes, gray, ell, float(red.x0), float(red.y0), float(red.k), u, v, tw, w, 1.0, out)


def test_fusion_pf_update(benchmark, clip):
    frames, gt = clip
    tr = pftrack.create_tracker("fusion-pf", seed=0)
    tr.init(frames[0], gt[0])
    it = iter(frames[1:] * 1000)
    benchmark(lambda: tr.update(next(it)))


@pytest.mark.parametrize("tracker", ["fusion-pf", "color-pf"])
@pytest.mark.parametrize("size", ["160x120", "320x240"])
def test_update_small_frames(benchmark, tracker, size):
    """One tracking update on small frames with a small target (20 x 30 px at 160 x 120, 30 x 60 px at 320 x 240):
    the per-frame cost that does not shrink with the target, where CSRT is fastest (docs/performance.md)."""
    w, h = (int(v) for v in size.split("x"))
    box = (w // 2 - 10, h // 2 - 15, 20, 30) if w == 160 else (140, 100, 30, 60)
    rng = np.random.default_rng(0)
    frames = [np.clip(rng.normal(120, 30, (h, w, 3)), 0, 255).astype(np.uint8) for _ in range(5)]
    for f in frames:
        f[box[1]:box[1] + box[3], box[0]:box[0] + box[2]] = (200, 50, 50)
    tr = pftrack.create_tracker(tracker, seed=0)
    tr.init(frames[0], box)
    for k in range(50):
        tr.update(frames[k % 5])
    state = {"k": 0}

    def step():
        state["k"] += 1
        tr.update(frames[state["k"] % 5])

    benchmark(step)


@pytest.mark.parametrize("grey_check", ["structure", "off"])
def test_color_pf_update_grey(benchmark, clip, grey_check):
    """One color-pf update on grey frames (the synthetic clip in grey, 640 x 480, a 50 x 50 target), with and
    without the structural check at re-acquisition (``grey_check``): on tracked frames it adds the estimate's NCC
    and, every 5th frame, the running reference's refresh (docs/robustness.md)."""
    frames, gt = clip
    grey = [np.repeat(f.mean(axis=2, keepdims=True).astype(np.uint8), 3, axis=2) for f in frames]
    tr = pftrack.create_tracker("color-pf", seed=0, grey_check=grey_check)
    tr.init(grey[0], gt[0])
    it = iter(grey[1:] * 1000)
    benchmark(lambda: tr.update(next(it)))


# -- book ch. 6, C6.3: the Log-Euclidean mean against the affine-invariant (Karcher) mean -------------
@pytest.fixture(scope="module")
def covariances():
    """T = 10 SPD matrices (d = 9) of the kind a track produces: one covariance, slightly perturbed."""
    rng = np.random.default_rng(0)
    A = rng.normal(size=(9, 40))
    base = A @ A.T / 40 + 0.1 * np.eye(9)
    out = []
    for _ in range(10):
        E = rng.normal(scale=0.15, size=(9, 9))
        out.append(base + 0.5 * (E @ base + base @ E.T) + 0.01 * np.eye(9))
    return np.stack(out)


@pytest.mark.benchmark(group="spd-mean")
@pytest.mark.parametrize("mean", ["log-euclidean", "affine-invariant", "pyriemann-riemann"])
def test_spd_means(benchmark, covariances, mean):
    from pftrack.cues import covariance as cv

    if mean == "log-euclidean":
        fn = cv.le_mean
    elif mean == "affine-invariant":
        fn = cv.airm_mean
    else:
        riemann = pytest.importorskip("pyriemann.utils.mean")
        fn = riemann.mean_riemann
    fn(covariances)          # compiled kernels load before timing (otherwise the first call sets the rounds)
    M = benchmark(fn, covariances)
    assert np.all(np.linalg.eigvalsh(M) > 0)


@pytest.fixture(scope="module")
def walkway():
    """768x576 frames of six upright movers crossing a horizontal line (the PETS frame size)."""
    rng = np.random.default_rng(0)
    bg = np.clip(rng.normal(110, 10, (576, 768, 3)), 0, 255).astype(np.uint8)
    frames = []
    for k in range(80):
        f = bg.copy()
        for i in range(6):
            x = int(60 + 110 * i + 2 * k) % 740
            y = int(180 + (k * (2 + i % 3)) % 220)
            f[y:y + 80, x:x + 26] = (40 + 30 * i, 200 - 20 * i, 90)
        frames.append(f)
    return frames


@pytest.mark.parametrize("feet", [True, False])
def test_tripwire_frame_768x576(benchmark, walkway, feet):
    """One processed frame of the trackerless tripwire (one line, decode excluded), with and without the blobs'
    foot points."""
    from pftrack.events.tripwire import TrackerlessTripwire, TripwireParams

    tw = TrackerlessTripwire(np.array([[150.0, 300.0], [700.0, 300.0]]), walkway[0].shape[:2], 7.0,
                             TripwireParams(radius=12.0, feet=feet))
    state = {"n": 0}

    def step():
        n = state["n"] = state["n"] + 1
        tw.process(walkway[n % len(walkway)], n)

    benchmark(step)


@pytest.mark.parametrize("how", ["pftrack", "opencv"])
def test_blob_boxes(benchmark, walkway, how):
    """Boxes and areas of the labelled blobs: from the labelled pixels, or OpenCV's statistics."""
    import cv2

    from pftrack.events.blobs import label_stats

    m = (np.abs(walkway[10].astype(np.int16) - walkway[0]).max(axis=2) > 30).astype(np.uint8)
    if how == "pftrack":
        labels = cv2.connectedComponents(m, connectivity=8)[1]
        benchmark(label_stats, labels)
    else:
        benchmark(cv2.connectedComponentsWithStats, m, connectivity=8)


@pytest.fixture(scope="module")
def lit_frames():
    """Two 854 x 480 colour frames of one textured view, the second with the light times 1.3 (a lamp switched on)."""
    import cv2

    rng = np.random.default_rng(5)
    base = cv2.resize(rng.integers(30, 200, (60, 107, 3), dtype=np.uint8), (854, 480), interpolation=cv2.INTER_LINEAR)
    return base, np.clip(base.astype(np.float32) * 1.3, 0, 255).astype(np.uint8)


@pytest.mark.parametrize("reading", ["steady", "jump", "still"])
def test_light_readings_854x480(benchmark, lit_frames, reading):
    """The per-frame readings of the light (docs/performance.md, the nineteenth look): the jump against the previous
    frame (``cast_jump``, ``light_jump``; a steady view, and a lamp switched on or off at every frame) and the gain
    against the first frame (``color_normalize="still"``), each on a lattice of every 16th pixel."""
    from pftrack.cues.still_gain import JUMP_MAX_MAD, JumpReader, reference_lattice, still_gain

    first, lit = lit_frames
    if reading in ("steady", "jump"):  # "jump": the frames in turn, each read compares one with the other
        reader = JumpReader(min_chroma=0.2, max_mad=JUMP_MAX_MAD, min_light=0.18)
        reader.read(first)
        frames = {"n": 0}

        def step():
            frames["n"] += 1
            reader.read(lit if reading == "jump" and frames["n"] % 2 else first)

        benchmark(step)
    else:
        ref = reference_lattice(first)
        benchmark(still_gain, ref, lit)
