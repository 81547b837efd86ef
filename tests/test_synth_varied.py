"""Synthetic scenes whose nuisances vary with the seed, and their meta.json."""

from __future__ import annotations

import json

import cv2
import numpy as np

from pftrack.cues.intensity import is_gray
from pftrack.io.datasets import read_sequence
from pftrack.synth import Scene, export_otb, hidden_frames, leave_scene, vanish_scene, varied_scene
from pftrack.synth.varied import exit_scene


def test_nuisances_vary_with_the_seed():
    specs = [vanish_scene(s) for s in range(12)]
    nz = [dict(s.nuisances) for s in specs]
    assert len({n["colors"] for n in nz}) == 12
    assert len({round(n["size"][0], 3) for n in nz}) == 12
    assert {n["gray"] for n in nz} == {True, False}
    assert {n["illumination"] is None for n in nz} == {True, False}
    assert len({n["distractors"] for n in nz}) > 1
    assert vanish_scene(3) == vanish_scene(3)  # and are reproducible


def test_vanish_scenes_hide_the_target_and_show_it_again():
    for seed in range(8):
        hid = hidden_frames(vanish_scene(seed))
        assert 12 <= hid.sum() <= 45, (seed, hid.sum())
        assert not hid[:5].any() and not hid[-10:].any()
        assert np.count_nonzero(np.diff(hid.astype(int)) == 1) == 1  # one hidden run


def test_leave_scene_target_leaves_the_frame():
    spec = leave_scene(4)
    scene = Scene(spec)
    present = [scene.truth(t).present[0] for t in range(spec.n_frames)]
    assert present[0] and present[-1] and not all(present)


def test_a_scenes_truth_without_its_frame_is_the_rendered_truth():
    """Scene.truth (what hidden_frames reads) gives the very numbers render gives with the frame: several targets
    hiding one another, occluders, a target leaving the view, the light on the target only."""
    from pftrack.synth import crossing_scene, illumination_scene

    specs = [vanish_scene(203), leave_scene(4), exit_scene(1), crossing_scene(2), illumination_scene(0)]
    assert any(len(s.targets) > 2 for s in specs) and any(s.illumination_target_only for s in specs)
    partly = 0
    for spec in specs:
        scene = Scene(spec)
        for t in range(spec.n_frames):
            a, b = scene.truth(t), scene.render(t)[1]
            np.testing.assert_array_equal(a.boxes, b.boxes)
            np.testing.assert_array_equal(a.visible, b.visible)
            np.testing.assert_array_equal(a.present, b.present)
            partly += int(np.any((b.visible > 0) & (b.visible < 1)))
    assert partly > 20  # the occlusions are exercised, not only whole targets


def test_exit_scene_look_alikes_head_for_the_edge_the_target_leaves_by():
    backs = set()
    for seed in range(8):
        spec = exit_scene(seed)
        assert spec == exit_scene(seed)
        nz = dict(spec.nuisances)
        backs.add(nz["comes_back"])
        scene = Scene(spec)
        truths = [scene.truth(t) for t in range(spec.n_frames)]
        present = np.array([tr.present[0] for tr in truths])
        gone = int(np.argmin(present))  # the first frame out
        assert present[:gone].all() and gone > 5
        assert present[-1] == nz["comes_back"]
        tgt = spec.targets[0]
        side = np.sign(tgt.center(gone)[0] - tgt.center(0)[0])
        followers = spec.targets[1:1 + len(spec.targets) - 1 - (not nz["comes_back"])]
        assert 1 <= len(followers) <= 3
        for f in followers:  # behind the target at the start, walking its way, and out by the end
            assert side * (f.center(0)[0] - tgt.center(0)[0]) < 0
            assert side * (f.center(spec.n_frames - 1)[0] - f.center(0)[0]) > 0
        if not nz["comes_back"]:  # a look-alike walks in through the exit edge after the target left
            walker = spec.targets[-1]
            t_in = next(t for t in range(spec.n_frames) if truths[t].present[len(spec.targets) - 1])
            assert t_in > gone
            assert side * (walker.center(spec.n_frames - 1)[0] - walker.center(t_in)[0]) < 0
    assert backs == {True, False}


def test_export_writes_hidden_frames_and_grey_frames(tmp_path):
    spec = vanish_scene(0, gray=1.0, n_frames=90)
    export_otb(spec, tmp_path / "v")
    meta = json.loads((tmp_path / "v" / "meta.json").read_text())
    assert meta["gray"] and meta["kind"] == "vanish" and len(meta["visible"]) == 90
    seq = read_sequence(tmp_path / "v")
    assert seq.absent is not None and seq.absent.sum() == len(meta["hidden"]) > 0
    assert list(np.nonzero(seq.absent)[0] + 1) == meta["hidden"]
    import cv2

    assert is_gray(cv2.imread(str(seq.frames[0])))
    assert len(varied_scene(1).targets) >= 1


def test_eval_reports_both_lost_flag_rates(tmp_path, capsys):
    import csv

    from pftrack.cli import main

    assert main(["synth", "leave", "--seeds", "0", "--out", str(tmp_path / "s")]) == 0
    rep = tmp_path / "rep"
    assert main(["eval", str(tmp_path / "s"), "--trackers", "color-pf", "--workers", "1", "--quiet",
                 "--report", str(rep)]) == 0
    out = capsys.readouterr().out
    assert "lost recall" in out and "false-lost rate" in out
    with open(rep / "results.csv", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    assert rows and rows[0]["lost_recall"] != "" and rows[0]["false_lost"] != ""
    assert float(rows[0]["absent_frames"]) > 0
    assert "lost recall" in (rep / "index.html").read_text(encoding="utf-8")


def test_synth_gray_option_greys_each_seed_and_keeps_its_other_nuisances(tmp_path, capsys):
    from pftrack.cli import main

    assert main(["synth", "vanish", "--seeds", "0-2", "--gray", "1", "--out", str(tmp_path / "g")]) == 0
    assert main(["synth", "vanish", "--seeds", "0-2", "--out", str(tmp_path / "d")]) == 0
    changed = 0
    for s in range(3):
        g = json.loads((tmp_path / "g" / f"vanish-{s:03d}" / "meta.json").read_text())
        d = json.loads((tmp_path / "d" / f"vanish-{s:03d}" / "meta.json").read_text())
        assert g["gray"] is True
        ng, nd = dict(g["nuisances"]), dict(d["nuisances"])
        assert {k for k in ng if ng[k] != nd[k]} <= {"gray"}
        changed += not d["gray"]
        seq = read_sequence(tmp_path / "g" / f"vanish-{s:03d}")
        assert is_gray(cv2.imread(str(seq.frames[0])))
    assert changed >= 1  # at least one seed was in colour by default
    assert main(["synth", "camouflage", "--gray", "1", "--out", str(tmp_path / "c")]) == 2
    assert main(["synth", "vanish", "--gray", "1.5", "--out", str(tmp_path / "c")]) == 2


def test_synth_length_writes_scenes_of_that_many_frames_for_the_untimed_kinds(tmp_path):
    from pftrack.cli import main

    assert main(["synth", "varied", "--seeds", "7", "--length", "40", "--out", str(tmp_path / "v")]) == 0
    seq = read_sequence(tmp_path / "v" / "varied-007")
    assert len(seq.frames) == 40 and len(seq.groundtruth) == 40
    spec = varied_scene(7, n_frames=40)
    np.testing.assert_allclose(seq.groundtruth, np.array([tr.boxes[0] for _, tr in Scene(spec)]), atol=1e-3)
    assert main(["synth", "simple", "--seeds", "1", "--length", "25", "--out", str(tmp_path / "s")]) == 0
    assert len(read_sequence(tmp_path / "s" / "simple-001").frames) == 25
    assert main(["synth", "vanish", "--length", "40", "--out", str(tmp_path / "x")]) == 2  # timed: not free
    assert main(["synth", "varied", "--length", "1", "--out", str(tmp_path / "x")]) == 2


def test_grey_frames_given_as_one_channel_or_three_give_the_same_track():
    """A one-channel grey source is kept as such inside (pftrack.frames.grey_origin): the same levels and the same
    track as its three-channel copy, for both colour trackers, through a loss and a search."""
    import pftrack

    spec = vanish_scene(2, gray=1.0, n_frames=45)
    pairs = [(f, tr.boxes[0]) for f, tr in Scene(spec)]
    grey = [cv2.cvtColor(f, cv2.COLOR_BGR2GRAY) for f, _ in pairs]
    for name in ("color-pf", "fusion-pf"):
        runs = []
        for frames in (grey, [cv2.cvtColor(g, cv2.COLOR_GRAY2BGR) for g in grey]):
            t = pftrack.create_tracker(name, seed=4)
            states = [t.init(frames[0], pairs[0][1])] + [t.update(f) for f in frames[1:]]
            runs.append([(s.box, s.score, s.lost) for s in states])
        assert runs[0] == runs[1], name
        assert any(lost for _, _, lost in runs[0])  # the hidden frames were searched through
