"""Shared fixtures: paths to the optional development data and cached synthetic scenes."""

from __future__ import annotations

import functools
import os
from pathlib import Path

import numpy as np
import pytest

from pftrack.synth import Scene

REPO = Path(__file__).resolve().parents[1]
SHARED_DATA = Path(os.environ.get("PFTRACK_SHARED_DATA", REPO.parent / "shared" / "data"))


def pytest_configure(config):
    """With several workers on a checkout whose kernels were never compiled (a fresh clone): compile them first,
    the shares of ``tests/_prewarm.py`` side by side, so that the workers load them from Numba's cache instead of
    each compiling the same kernels. Best effort: a share that fails or hangs leaves its kernels to the workers."""
    import subprocess
    import sys

    workers = getattr(config.option, "numprocesses", None)
    if hasattr(config, "workerinput") or not isinstance(workers, int) or workers < 2:
        return
    from pftrack._numba import numba_enabled

    if not numba_enabled() or next((REPO / "pftrack").rglob("*.nbi"), None) is not None:
        return
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(REPO), os.environ.get("PYTHONPATH")]))}
    procs = [subprocess.Popen([sys.executable, str(REPO / "tests" / "_prewarm.py"), str(k), str(workers)], env=env,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL) for k in range(workers)]
    for p in procs:
        try:
            p.wait(timeout=300)
        except subprocess.TimeoutExpired:
            p.kill()


def load_script(name: str):
    """The module of ``scripts/NAME.py`` (the scripts are not a package)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(name, REPO / "scripts" / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def shared_sequence(name: str) -> Path:
    """Path of a development sequence, or skip the test when ../shared/data is absent."""
    path = SHARED_DATA / name
    if not path.is_dir():
        pytest.skip(f"development data {name} not available (../shared/data)")
    return path


def bundled_clip() -> tuple[list[np.ndarray], np.ndarray]:
    """The frames of the demo's bundled real clip (OTB 'Crossing', a tune-split sequence) and its ground truth."""
    import cv2

    from pftrack.cli.track import demo_clip

    video, gt_path = demo_clip()
    cap = cv2.VideoCapture(str(video))
    frames = []
    while True:
        ok, f = cap.read()
        if not ok:
            break
        frames.append(f)
    return frames, np.loadtxt(gt_path)


@functools.lru_cache(maxsize=32)
def _render(spec):
    scene = Scene(spec)
    frames, truths = zip(*(scene.render(t) for t in range(len(scene))))
    for f in frames:
        f.setflags(write=False)
    return scene, frames, truths


def render_scene(spec):
    """Rendered frames and per-frame truth of a scene spec (cached across tests)."""
    return _render(spec)


class _CachedScene:
    """A :class:`pftrack.synth.Scene` whose frames and truth come from :func:`render_scene`'s cache."""

    def __init__(self, spec):
        self._scene, self._frames, self._truths = _render(spec)

    def render(self, t: int):
        if not 0 <= t < len(self._frames):
            raise IndexError(t)
        return self._frames[t], self._truths[t]

    def frames(self) -> list:
        return list(self._frames)

    def __len__(self) -> int:
        return len(self._frames)

    def __iter__(self):
        return iter(zip(self._frames, self._truths))

    def __getattr__(self, name):  # spec, groundtruth, truth, ...
        return getattr(self._scene, name)


def cached_scene(spec) -> _CachedScene:
    """The scene of ``spec`` as :class:`pftrack.synth.Scene` gives it, its frames and truth from the cache of
    :func:`render_scene` (the same values; the frames read-only): for tests that run several trackers or settings on
    one scene."""
    return _CachedScene(spec)


def grey_frames(frames):
    """BGR frames as a grey camera gives them: three equal channels (OpenCV's grey levels)."""
    import cv2

    return [cv2.cvtColor(cv2.cvtColor(f, cv2.COLOR_BGR2GRAY), cv2.COLOR_GRAY2BGR) for f in frames]


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


def lost_flag_run(spec, tracker: str = "color-pf", seed: int = 0, **params):
    """A tracker's lost flag scored as a detector (:func:`pftrack.eval.metrics.lost_detection`) on a synthetic
    scene spec whose hidden frames are the absent ones."""
    import pftrack
    from pftrack.eval.metrics import lost_detection
    from pftrack.synth import hidden_frames

    scene, frames, _ = render_scene(spec)
    gt = scene.groundtruth(0)
    hid = hidden_frames(spec)
    t = pftrack.create_tracker(tracker, seed=seed, **params)
    t.init(frames[0], tuple(gt[0]))
    boxes, lost = [gt[0]], [False]
    for k in range(1, spec.n_frames):
        st = t.update(frames[k])
        boxes.append(st.box)
        lost.append(st.lost)
    return lost_detection(np.array(lost[1:]), np.array(boxes[1:]), gt[1:], hid[1:])


def face_proxy_run(name: str, seed: int, frames: int = 150, *, dim: tuple[float, float] | None = None, **params):
    """Mean IoU and the raised lost flags of a tracker (run seed = scene seed) on the grey face proxy
    (:func:`pftrack.synth.face.face_scene`; skipped without scikit-image, which provides the portrait).

    ``dim=(gain, noise)``: every frame darkened by that gain, with Gaussian noise of that spread, as
    ``scripts/grey_face_proxy.py --dark GAIN --noise SD`` (a dim, noisy camera)."""
    pytest.importorskip("skimage")
    import pftrack
    from pftrack.eval.metrics import frame_ious
    from pftrack.synth.face import face_scene

    imgs, gt = face_scene(seed, frames)
    if dim is not None:
        rng = np.random.default_rng(seed)
        imgs = [np.clip(f.astype(np.float32) * dim[0] + rng.normal(0.0, dim[1], f.shape), 0, 255).astype(np.uint8)
                for f in imgs]
    t = pftrack.create_tracker(name, seed=seed, **params)
    t.init(imgs[0], tuple(gt[0]))
    states = [t.update(f) for f in imgs[1:]]
    iou = frame_ious(np.array([s.box for s in states]), gt[1:])
    return float(iou.mean()), [bool(s.lost) for s in states]


#: :func:`hidden_box_frame`'s cycle: the box is seen for ``HIDDEN_PERIOD - HIDDEN_FRAMES`` frames, then hidden
HIDDEN_PERIOD, HIDDEN_FRAMES = 400, 100
#: its box at frame 0 (x, y, w, h)
HIDDEN_BOX_START = (70.0, 70.0, 16.0, 24.0)


def hidden_box(t: int) -> tuple[int, int, int, int] | None:
    """:func:`hidden_box_frame`'s box at frame ``t`` (x, y, w, h), None while it is hidden."""
    if t % HIDDEN_PERIOD >= HIDDEN_PERIOD - HIDDEN_FRAMES:
        return None
    return int(70 + 40 * np.sin(t / 30.0)), int(50 + 20 * np.cos(t / 45.0)), 16, 24


def hidden_box_frame(bg: np.ndarray, t: int, noise: float = 0.0, rng: np.random.Generator | None = None
                     ) -> np.ndarray:
    """Frame ``t`` of a red box of one flat colour (16 x 24) circling over the 120 x 160 background ``bg``, hidden
    on the last :data:`HIDDEN_FRAMES` frames of every :data:`HIDDEN_PERIOD`; with Gaussian noise of spread ``noise``
    (drawn from ``rng``) on every pixel."""
    f = bg.astype(np.float32)
    box = hidden_box(t)
    if box is not None:
        x, y, w, h = box
        f[y:y + h, x:x + w] = (30, 40, 220)
    if noise:
        f += rng.normal(0.0, noise, f.shape).astype(np.float32)
    return np.clip(f, 0, 255).astype(np.uint8)
