"""scripts/first_box_grabcut.py: a first box snapped to the object by GrabCut, measured on SRE's starts."""

from __future__ import annotations

import numpy as np

from pftrack.synth import export_otb, simple_scene

from .conftest import load_script


def _frame():
    rng = np.random.default_rng(3)
    img = np.clip(rng.normal(110, 25, (160, 200, 3)), 0, 255).astype(np.uint8)  # a noisy grey background
    img[50:110, 80:120] = (30, 40, 220)  # the object: a red block, 40 x 60 at (80, 50)
    return img, (80.0, 50.0, 40.0, 60.0)


def test_a_tight_or_loose_box_snaps_to_the_block():
    fb = load_script("first_box_grabcut")
    img, truth = _frame()
    for scale in (0.8, 1.2):
        w, h = 40 * scale, 60 * scale
        box = (100 - w / 2, 80 - h / 2, w, h)
        assert fb.box_iou(box, truth) < 0.85
        assert fb.box_iou(fb.snap_box(img, box), truth) > 0.9, scale
    far = (0.0, 0.0, 30.0, 30.0)  # no block under it: what GrabCut finds overlaps it little, so it is kept
    assert fb.snap_box(img, far) == far


def test_probe_rows_and_the_command(tmp_path, capsys):
    fb = load_script("first_box_grabcut")
    img, truth = _frame()
    res = fb.probe([(img, truth)])
    assert [k for k, _ in fb.KINDS] == list(res)
    assert res["truth"].shape == (1, 2) and res["shift"].shape == (8, 2)
    assert res["truth"][0, 0] == 1.0 and res["scale 0.8"][0, 0] < res["scale 0.8"][0, 1]
    export_otb(simple_scene(0, n_frames=6), tmp_path / "simple-000")
    assert fb.main([str(tmp_path / "simple-000"), "--step", "5"]) == 0
    out = capsys.readouterr().out
    assert "2 frames" in out and out.count("\n") == 2 + len(fb.KINDS)
