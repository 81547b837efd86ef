"""The grey face scene under changing light (``pftrack synth face``) and the trackers' light handling on it."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

import pftrack
from pftrack.eval.metrics import frame_ious

pytest.importorskip("skimage")

from pftrack.synth.face import ASTRONAUT_FACE, face_scene, turned_face  # noqa: E402


def _normalised_crop(img: np.ndarray, box, size=(48, 60)) -> np.ndarray:
    """The box resampled to ``size``, divided by its smoothed copy (the light cancels), zero-mean, unit norm."""
    x, y, w, h = box
    m = np.float32([[size[0] / w, 0, -x * size[0] / w], [0, size[1] / h, -y * size[1] / h]])
    c = cv2.warpAffine(img.astype(np.float32), m, size, flags=cv2.INTER_AREA)
    c = c / (cv2.GaussianBlur(c, (0, 0), 6) + 1.0)
    c -= c.mean()
    return c / (np.linalg.norm(c) + 1e-9)


def test_face_scene_is_seeded_and_its_boxes_follow_the_face():
    frames, boxes = face_scene(3, 60)
    again, boxes2 = face_scene(3, 60)
    assert all(np.array_equal(a, b) for a, b in zip(frames, again)) and np.array_equal(boxes, boxes2)
    assert frames[0].shape == (240, 320) and frames[0].dtype == np.uint8
    # a camera zoom keeps the face's aspect; the face stays in view
    assert np.allclose(boxes[:, 2] / boxes[:, 3], ASTRONAUT_FACE[2] / ASTRONAUT_FACE[3])
    assert (boxes[:, 0] >= 0).all() and (boxes[:, 0] + boxes[:, 2] <= 320).all()
    # the exact box holds the same face in every frame (the light divided out); a box a quarter-width aside does not
    ref = _normalised_crop(frames[0], boxes[0])
    on = [float((_normalised_crop(frames[k], boxes[k]) * ref).sum()) for k in range(10, 60, 10)]
    off = [float((_normalised_crop(frames[k], boxes[k] + [0.25 * boxes[k][2], 0, 0, 0]) * ref).sum())
           for k in range(10, 60, 10)]
    assert min(on) > 0.9 and max(off) < 0.3, (on, off)  # measured: 0.96-0.98 and below 0
    # the light changes strongly: the darkest frame is under half the brightest
    means = [f.mean() for f in frames]
    assert min(means) < 0.5 * max(means)


def test_a_turning_face_changes_only_the_face_box():
    """``turn``: the face box is redrawn as a cylinder seen turned; the rest of the image, the boxes and the scene
    without a turn are unchanged."""
    rng = np.random.default_rng(0)
    base = rng.uniform(0, 255, (200, 300)).astype(np.float32)
    face = (100.0, 50.0, 60.0, 80.0)
    assert np.array_equal(turned_face(base, face, 0.0), base)
    out = turned_face(base, face, np.radians(40))
    inside = np.zeros(base.shape, bool)
    inside[50:130, 100:160] = True
    assert np.array_equal(out[~inside], base[~inside]) and not np.array_equal(out[inside], base[inside])
    # each row of the box is the same resampling of the same row: one side foreshortened, the other widened
    ramp = np.tile(np.arange(300, dtype=np.float32), (200, 1))
    cols = turned_face(ramp, face, np.radians(40))[60, 100:160]
    assert np.all(np.diff(cols) >= -1e-3)
    assert cols[-1] < 159.5 - 5.0 and np.allclose(cols[:5], 99.5)  # one edge turned out of view, the other in
    frames, boxes = face_scene(1, 20)
    turned, tboxes = face_scene(1, 20, turn=50)
    assert np.array_equal(boxes, tboxes)
    assert all(np.array_equal(a, b) for a, b in zip(frames, face_scene(1, 20, turn=0.0)[0]))
    assert any(not np.array_equal(a, b) for a, b in zip(frames, turned))


@pytest.mark.parametrize("seed", [0, 1])
def test_quotient_illumination_follows_a_grey_face_without_false_alarms(seed):
    """fusion-pf with illumination='quotient' (docs/robustness.md): the face is always visible, so no frame may be
    called lost.  Measured on 100 frames: mean IoU 0.82 and 0.80, no lost frame (the default raises lost on 60 and
    29 frames of these two seeds)."""
    frames, gt = face_scene(seed, 100)
    t = pftrack.create_tracker("fusion-pf", seed=seed, illumination="quotient")
    t.init(frames[0], tuple(gt[0]))
    states = [t.update(f) for f in frames[1:]]
    iou = frame_ious(np.array([s.box for s in states]), gt[1:])
    assert iou.mean() >= 0.65, iou.mean()
    assert not any(s.lost for s in states)


def test_synth_face_writes_otb_folders(tmp_path):
    from pftrack.cli import main
    from pftrack.io.datasets import read_sequence

    assert main(["synth", "face", "--seeds", "4", "--out", str(tmp_path / "f")]) == 0
    seq = read_sequence(tmp_path / "f" / "face-004")
    frames, boxes = face_scene(4)
    assert len(seq.frames) == len(frames) and np.allclose(seq.groundtruth, boxes, atol=0.01)
    assert np.array_equal(cv2.imread(str(seq.frames[7]), cv2.IMREAD_GRAYSCALE), frames[7])
    assert main(["synth", "face", "--seeds", "4", "--turn", "45", "--out", str(tmp_path / "t")]) == 0
    turned = read_sequence(tmp_path / "t" / "face-004")
    assert np.array_equal(cv2.imread(str(turned.frames[7]), cv2.IMREAD_GRAYSCALE), face_scene(4, turn=45)[0][7])


def test_the_second_portrait_gives_its_own_scene(tmp_path):
    """``--portrait camera``: the cameraman's head, in a scene drawn with the same seeded camera and light."""
    from pftrack.cli import main
    from pftrack.io.datasets import read_sequence
    from pftrack.synth.face import CAMERA_FACE, portrait

    image, box = portrait("camera")
    assert image.shape == (512, 512) and image.dtype == np.uint8 and box == CAMERA_FACE
    with pytest.raises(ValueError):
        portrait("nobody")
    assert main(["synth", "face", "--portrait", "camera", "--seeds", "4", "--out", str(tmp_path / "c")]) == 0
    seq = read_sequence(tmp_path / "c" / "face-004")
    frames, boxes = face_scene(4, image=image, face=box)
    assert np.allclose(seq.groundtruth, boxes, atol=0.01)
    assert np.array_equal(cv2.imread(str(seq.frames[7]), cv2.IMREAD_GRAYSCALE), frames[7])
    assert not np.array_equal(frames[7], face_scene(4)[0][7])
    assert np.allclose(boxes[:, 2] / boxes[:, 3], CAMERA_FACE[2] / CAMERA_FACE[3])


@pytest.mark.parametrize("name", ["fusion-pf", "color-pf"])
def test_the_colour_trackers_follow_the_second_face_without_false_alarms(name):
    """The defaults were checked on the astronaut's face; the cameraman's (a profile beside a dark coat, under the
    same kind of light) was never used for a choice.  Both colour trackers follow it with the flag down (measured on
    this seed: mean IoU 0.842 and 0.837, no lost frame)."""
    from pftrack.synth.face import portrait

    frames, gt = face_scene(2, 100, image=portrait("camera")[0], face=portrait("camera")[1])
    t = pftrack.create_tracker(name, seed=0)
    t.init(frames[0], tuple(gt[0]))
    states = [t.update(f) for f in frames[1:]]
    iou = frame_ious(np.array([s.box for s in states]), gt[1:])
    assert iou.mean() >= 0.7, iou.mean()
    assert sum(s.lost for s in states) <= 2


@pytest.mark.parametrize("seed", [0, 1])
def test_local_motion_pf_follows_a_grey_face_with_color_pf_grey_model(seed):
    """local-motion-pf's defaults for grey video since its second grey rule (docs/local-motion.md): color-pf's grey
    model, grey search and loss counts. Measured on 100 frames: mean IoU 0.919 and 0.904, no lost frame (the former
    defaults, grey_check="off" with the plain grey histogram: 0.611 with 56 lost frames, and 0.360)."""
    frames, gt = face_scene(seed, 100)
    t = pftrack.create_tracker("local-motion-pf", seed=seed)
    p = t.params
    assert (p.grey_check, p.grey_histogram, p.grey_search_structure) == ("fused", "both", True)
    t.init(frames[0], tuple(gt[0]))
    states = [t.update(f) for f in frames[1:]]
    iou = frame_ious(np.array([s.box for s in states]), gt[1:])
    assert iou.mean() >= 0.8, iou.mean()
    assert not any(s.lost for s in states)
