"""Scenes cut from photographs (pftrack.synth.photo): exact boxes, visible fractions, hidden frames, the CLI, and
the lost flag of fusion-pf on a family it was not tuned on."""

from __future__ import annotations

import json

import numpy as np
import pytest

pytest.importorskip("skimage")

from pftrack.synth import HIDDEN_BELOW  # noqa: E402
from pftrack.synth.photo import (  # noqa: E402
    PhotoScene,
    Piece,
    _alpha,
    photo_exit_scene,
    photo_leave_scene,
    photo_vanish_scene,
    render_photo,
)

W, H = 320, 240


def _flat_scene(box, occluder=None, n_frames=1) -> PhotoScene:
    """A grey 100 background and a rectangular piece of 200 at ``box``: no noise, light or compression."""
    ph, pw = 30, 20
    piece = Piece(np.full((ph, pw, 3), 200, np.float32), np.ones((ph, pw), np.float32),
                  np.tile(np.asarray(box, np.float64), (n_frames, 1)))
    return PhotoScene(kind="test", seed=0, n_frames=n_frames, background=np.full((H + 2, W + 2, 3), 100, np.float32),
                      camera=np.zeros((n_frames, 2)), target=piece, lookalikes=[], occluder=occluder,
                      gain=np.ones((n_frames, 3)), lamp=None, gray=False, noise=0.0, jpeg=0)


@pytest.mark.parametrize("box", [(100.0, 80.0, 20.0, 30.0), (57.3, 101.6, 26.4, 41.2), (200.5, 30.25, 15.0, 22.5)])
def test_the_piece_covers_exactly_its_box(box):
    frame, visible = render_photo(_flat_scene(box), 0)
    cover = (frame[:, :, 0].astype(np.float64) - 100.0) / 100.0
    x, y, w, h = box
    assert cover.sum() == pytest.approx(w * h, rel=0.03)
    yy, xx = np.mgrid[0:H, 0:W] + 0.5  # pixel j spans [j, j + 1)
    assert (cover * xx).sum() / cover.sum() == pytest.approx(x + w / 2, abs=0.15)
    assert (cover * yy).sum() / cover.sum() == pytest.approx(y + h / 2, abs=0.15)
    assert visible == pytest.approx(1.0, abs=0.02)


def test_visible_fraction_counts_the_occluder_and_the_frame_edge():
    box = (100.0, 80.0, 20.0, 30.0)
    occ = (np.zeros((60, 10, 3), np.float32), (100, 60))  # covers the box's left half
    assert render_photo(_flat_scene(box, occ), 0)[1] == pytest.approx(0.5, abs=0.04)
    assert render_photo(_flat_scene((-10.0, 80.0, 20.0, 30.0)), 0)[1] == pytest.approx(0.5, abs=0.04)
    assert render_photo(_flat_scene((-30.0, 80.0, 20.0, 30.0)), 0)[1] == 0.0


def test_alpha_shapes_are_feathered_and_inside_the_piece():
    for ellipse, corner in ((True, 0.05), (False, 0.6)):
        a = _alpha(24, 40, ellipse)
        assert a.shape == (40, 24) and a.min() >= 0.0 and a.max() <= 1.0 + 1e-6
        assert a[20, 12] > 0.99 and a[0, 0] < corner
    assert _alpha(24, 40, True).sum() < _alpha(24, 40, False).sum()  # the ellipse leaves the corners out


def test_scenes_are_reproducible_and_vary_with_the_seed():
    a, b = photo_vanish_scene(5), photo_vanish_scene(5)
    for t in (0, 60, 119):
        assert np.array_equal(render_photo(a, t)[0], render_photo(b, t)[0])
    drawn = [photo_vanish_scene(s).nuisances for s in range(20)]
    assert len({d["background"] for d in drawn}) >= 4
    assert len({d["target"] for d in drawn}) >= 4
    assert len({d["lookalikes"] for d in drawn}) >= 3
    assert any(d["lamp"] for d in drawn) and not all(d["lamp"] for d in drawn)
    assert all(d["background"] != d["target"] for d in drawn)


@pytest.mark.parametrize("seed", [0, 7, 13])
def test_vanish_hides_the_target_once_for_the_drawn_frames(seed):
    sc = photo_vanish_scene(seed)
    vis = np.array([render_photo(sc, t)[1] for t in range(sc.n_frames)])
    occ, (ox, oy) = sc.occluder
    boxes = sc.target.boxes
    inside = ((boxes[:, 0] >= ox + 1) & (boxes[:, 0] + boxes[:, 2] <= ox + occ.shape[1] - 1)
              & (boxes[:, 1] >= oy + 1) & (boxes[:, 1] + boxes[:, 3] <= oy + occ.shape[0] - 1))
    assert np.all(vis[inside] == 0.0)  # wholly behind the band: nothing visible
    hidden = np.flatnonzero(vis < HIDDEN_BELOW)
    runs = np.split(hidden, np.flatnonzero(np.diff(hidden) > 1) + 1)
    longest = max(len(r) for r in runs)
    assert longest >= sc.nuisances["hidden_frames"]
    assert vis[0] > 0.5 and vis[-1] > 0.5  # seen at the start and the end


def test_leave_takes_the_target_out_of_the_frame_and_back():
    for seed in (1, 4):
        sc = photo_leave_scene(seed)
        boxes = sc.target.boxes
        out = (boxes[:, 0] + boxes[:, 2] <= 0) | (boxes[:, 0] >= W)
        assert out.sum() >= sc.nuisances["out_frames"]
        assert render_photo(sc, int(np.flatnonzero(out)[0]))[1] == 0.0
        x, y, w, h = boxes[-1]
        assert x >= 0 and x + w <= W and y >= 0 and y + h <= H


def test_exit_sends_a_flow_of_look_alikes_out_the_same_way_and_one_in_when_the_target_stays_out():
    kinds = set()
    for seed in range(8):
        sc = photo_exit_scene(seed)
        boxes = sc.target.boxes
        right = bool((boxes[:, 0] >= W).any())  # it leaves by the right edge (else the left)
        out = (boxes[:, 0] + boxes[:, 2] <= 0) | (boxes[:, 0] >= W)
        assert out.any() and render_photo(sc, int(np.flatnonzero(out)[0]))[1] == 0.0
        back = sc.nuisances["comes_back"]
        kinds.add(back)
        assert back == (not out[-1])  # back in view at the end exactly when it comes back
        flow = sc.lookalikes[:sc.nuisances["flow"]]
        assert 1 <= len(flow) <= 3 and len(sc.lookalikes) == len(flow) + (0 if back else 1)
        for piece in flow:  # heading for the target's exit edge (the slow ones may not reach it by the end)
            x = piece.boxes[:, 0]
            step = np.diff(x) if right else -np.diff(x)
            assert np.all(step >= -1e-9) and step.sum() > 0
        if not back:  # the one walking in starts outside that edge and ends inside
            b = sc.lookalikes[-1].boxes
            assert ((b[0, 0] >= W) if right else (b[0, 0] + b[0, 2] <= 0)) and 0 <= b[-1, 0] <= W - b[-1, 2]
    assert kinds == {True, False}


def test_cli_writes_otb_folders_with_hidden_frames_and_grey_on_request(tmp_path, capsys):
    from pftrack.cli import main
    from pftrack.io.datasets import read_sequence
    from pftrack.io.sources import read_image

    out = tmp_path / "scenes"
    assert main(["synth", "photo-vanish", "--seeds", "3", "--gray", "1", "--out", str(out)]) == 0
    folder = out / "photo-vanish-003"
    meta = json.loads((folder / "meta.json").read_text())
    assert meta["kind"] == "photo-vanish" and meta["gray"] is True and len(meta["hidden"]) >= 12
    seq = read_sequence(folder)
    assert len(seq.frames) == 120
    gt = seq.groundtruth
    vis = np.array(meta["visible"])
    assert np.all(np.isnan(gt[vis <= 0.0])) and np.all(np.isfinite(gt[vis > 0.0]))
    f = read_image(seq.frames[10])
    assert np.array_equal(f[:, :, 0], f[:, :, 2])
    capsys.readouterr()
    assert main(["synth", "photo-leave", "--seeds", "0", "--gray", "2", "--out", str(tmp_path / "x")]) == 2
    assert "--gray" in capsys.readouterr().err


def _lost_flag(scene, name, seed):
    import pftrack
    from pftrack.eval.metrics import lost_detection

    frames, vis = zip(*(render_photo(scene, t) for t in range(scene.n_frames)))
    gt = scene.target.boxes
    t = pftrack.create_tracker(name, seed=seed)
    t.init(frames[0], tuple(gt[0]))
    states = [t.update(f) for f in frames[1:]]
    return lost_detection(np.array([s.lost for s in states]), np.array([s.box for s in states]), gt[1:],
                          np.array(vis[1:]) < HIDDEN_BELOW, bounds=(W, H))


@pytest.mark.parametrize("kind, make", [("vanish", photo_vanish_scene), ("leave", photo_leave_scene)])
def test_fusion_pf_lost_flag_holds_on_photo_scenes(kind, make):
    """The issue's bars for the lost flag (raised on >= 70 % of the hidden frames, on <= 5 % of the covered ones) on
    a family the defaults were not chosen on (seeds 2000-2004; measured 0.96 / 0.006 on vanish, 0.996 / 0.038 on
    leave; docs/robustness.md has the evaluation over 40 scenes)."""
    res = [_lost_flag(make(seed), "fusion-pf", seed) for seed in range(2000, 2005)]
    recall = np.nanmean([r.recall for r in res])
    false = np.nanmean([r.false_rate for r in res])
    assert recall >= 0.7, recall
    assert false <= 0.05, false
    if kind == "leave":  # re-acquired within 15 frames in >= 75 % of the returns (measured 5 of 5); behind the band
        # the family falls short of that bar (docs/robustness.md: 48 and 41 of 63 on its two seed sets)
        events = sum(r.reappearances for r in res)
        assert events == 5 and sum(r.reacquired for r in res) >= 0.75 * events, [r.reacquired for r in res]


def test_photo_summary_script_splits_a_run_by_kind_and_nuisance(tmp_path, capsys):
    """scripts/photo_summary.py: the figures per kind and with / without each nuisance (docs/robustness.md)."""
    import csv
    import importlib.util
    from pathlib import Path

    spec = importlib.util.spec_from_file_location("photo_summary", Path(__file__).parents[1] / "scripts" /
                                                  "photo_summary.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    scenes = tmp_path / "scenes"
    for name, kind, lamp in (("photo-vanish-000", "photo-vanish", True), ("photo-leave-000", "photo-leave", False)):
        (scenes / name).mkdir(parents=True)
        nz = {"lamp": lamp, "lookalikes": 1, "gain_end": [1.0, 1.4, 1.0], "jpeg": 0}
        (scenes / name / "meta.json").write_text(json.dumps({"kind": kind, "gray": False, "nuisances": nz}))
    report = tmp_path / "report"
    report.mkdir()
    cols = ["tracker", "sequence", "auc", "lost_recall", "false_lost", "reacquired", "reappearances"]
    with open(report / "results.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(cols)
        w.writerow(["fusion-pf", "photo-vanish-000", 0.5, 1.0, 0.0, 0, 1])
        w.writerow(["fusion-pf", "photo-vanish-000", 0.7, 0.8, 0.1, 1, 1])
        w.writerow(["fusion-pf", "photo-leave-000", 0.9, 1.0, 0.0, 1, 1])
        w.writerow(["fusion-pf", "other-seq", 0.1, "", "", "", ""])  # not a scene of the folders: left out
    assert mod.main([str(report), str(scenes)]) == 0
    out = capsys.readouterr().out
    assert "photo-vanish  AUC 0.600, lost recall 0.900, false-lost 0.050, re-acquired 1 of 2 (1 scenes)" in out
    assert "photo-leave   AUC 0.900, lost recall 1.000, false-lost 0.000, re-acquired 1 of 1 (1 scenes)" in out
    assert "with: re-acquired 1 of 2, AUC 0.600 (2 runs); without: re-acquired 1 of 1, AUC 0.900 (1 runs)" in out
    assert mod.main([str(report)]) == 2
