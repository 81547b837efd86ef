"""scripts/split_summary.py: re-acquisitions split by the synthetic scenes' drawn grey/colour nuisance."""

from __future__ import annotations

import csv
import json
import subprocess
import sys
from pathlib import Path

SCRIPT = Path(__file__).resolve().parents[1] / "scripts" / "split_summary.py"
FIELDS = ["tracker", "sequence", "seed", "auc", "lost_recall", "false_lost", "fps", "reappearances", "reacquired"]


def _scene(root: Path, kind: str, name: str, gray: bool) -> None:
    d = root / kind / name
    d.mkdir(parents=True)
    (d / "meta.json").write_text(json.dumps({"kind": kind, "nuisances": {"gray": gray}}))


def test_reacquisitions_are_split_by_scene_colour(tmp_path):
    scenes = tmp_path / "synth"
    _scene(scenes, "vanish", "vanish-000", True)
    _scene(scenes, "vanish", "vanish-001", False)
    _scene(scenes, "leave", "leave-000", False)
    rows = [
        ("color-pf", "vanish-000", 0, 1, 0), ("color-pf", "vanish-000", 1, 1, 1),
        ("color-pf", "vanish-001", 0, 1, 1), ("color-pf", "leave-000", 0, 2, 1),
        ("color-pf", "tld_pedestrian2", 0, 3, 2), ("color-pf", "otb_couple", 0, "", ""),
    ]
    results = tmp_path / "results.csv"
    with results.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(FIELDS)
        for tracker, seq, seed, reapp, reacq in rows:
            w.writerow([tracker, seq, seed, 0.5, "", "", 100, reapp, reacq])
    out = subprocess.run([sys.executable, str(SCRIPT), str(results), "--scenes", str(scenes)],
                         capture_output=True, text=True, check=True).stdout
    table = out.split("by the scenes' colour")[1]
    line = next(ln for ln in table.splitlines() if ln.startswith("color-pf"))
    # grey: vanish-000 (1 of 2); colour: vanish-001 and leave-000 (2 of 3); other: the real sequence (2 of 3)
    assert line.split()[1:] == ["1", "/", "2", "2", "/", "3", "2", "/", "3"]
    # without --scenes the table is not printed
    plain = subprocess.run([sys.executable, str(SCRIPT), str(results)], capture_output=True, text=True,
                           check=True).stdout
    assert "by the scenes' colour" not in plain


def test_reacquisitions_are_split_by_scene_light(tmp_path):
    scenes = tmp_path / "synth"
    for name, nz in [("vanish-000", {"gray": False, "illumination": None}),
                     ("vanish-001", {"gray": False, "illumination": [0.5, 0.5, 0.5],
                                     "illumination_target_only": False}),
                     ("vanish-002", {"gray": True, "illumination": [1.4, 1.3, 1.5], "illumination_target_only": True})]:
        d = scenes / "vanish" / name
        d.mkdir(parents=True)
        (d / "meta.json").write_text(json.dumps({"kind": "vanish", "nuisances": nz}))
    results = tmp_path / "results.csv"
    with results.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(FIELDS)
        for seq, reacq in [("vanish-000", 1), ("vanish-001", 0), ("vanish-002", 1)]:
            w.writerow(["fusion-pf", seq, 0, 0.5, "", "", 100, 1, reacq])
    out = subprocess.run([sys.executable, str(SCRIPT), str(results), "--scenes", str(scenes)],
                         capture_output=True, text=True, check=True).stdout
    table = out.split("by the scenes' colour and light")[1]
    header = next(ln for ln in table.splitlines() if ln.startswith("tracker"))
    assert header.split()[1:] == ["colour", "none", "colour", "frame", "colour", "objects", "grey", "none", "grey",
                                  "frame", "grey", "objects"]
    line = next(ln for ln in table.splitlines() if ln.startswith("fusion-pf"))
    # colour none 1 of 1, colour frame 0 of 1, grey objects 1 of 1, the rest empty
    assert line.split()[1:] == ["1", "/", "1", "0", "/", "1", "0", "/", "0", "0", "/", "0", "0", "/", "0", "1", "/",
                                "1"]


def _results(path: Path, rows: list[tuple]) -> None:
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(FIELDS)
        for tracker, seq, auc in rows:
            w.writerow([tracker, seq, 0, auc, "", "", 100, "", ""])


def test_scenes_of_other_kinds_are_not_counted_as_real_sequences(tmp_path):
    results = tmp_path / "results.csv"
    _results(results, [("color-pf", "otb_couple", 0.4), ("color-pf", "simple-7800", 0.9),
                       ("color-pf", "photo-vanish-3", 0.7), ("color-pf", "vanish-001", 0.6)])
    out = subprocess.run([sys.executable, str(SCRIPT), str(results)], capture_output=True, text=True,
                         check=True).stdout
    header, line = out.splitlines()[:2]
    cells = dict(zip(header.split()[1:12], line.split()[1:12]))
    assert cells["real"] == "0.400" and cells["vanish"] == "0.600" and cells["othersynth"] == "0.800"


def test_by_kind_gives_the_mean_auc_and_the_boxes_size_per_scene_kind(tmp_path):
    import cv2
    import numpy as np

    scenes = tmp_path / "synth"
    for name in ("simple-001", "simple-002"):
        d = scenes / "simple" / name
        (d / "img").mkdir(parents=True)
        for k in range(1, 13):
            cv2.imwrite(str(d / "img" / f"{k:04d}.png"), np.zeros((60, 80, 3), np.uint8))
        (d / "groundtruth_rect.txt").write_text("\n".join(["10,10,20,40"] * 12) + "\n")
        (d / "meta.json").write_text(json.dumps({"kind": "", "nuisances": {}}))
    results = tmp_path / "report" / "results.csv"
    (tmp_path / "report" / "runs").mkdir(parents=True)
    _results(results, [("fusion-pf", "simple-001", 0.8), ("fusion-pf", "simple-002", 0.6),
                       ("fusion-pf", "tld_pedestrian2", 0.5)])
    # simple-001: the box at half the true area over the second half (sqrt 0.707); simple-002: the true box, and a
    # frame without a box (5 of its second half's 6 frames count)
    half = [10, 10, 10, 40]
    for name, late in (("simple-001", half), ("simple-002", [10, 10, 20, 40])):
        boxes = [[10, 10, 20, 40]] * 6 + [late] * 6
        flat = [v for b in boxes for v in b]
        if name == "simple-002":
            flat[-4:] = [None] * 4
        rec = {"tracker": "fusion-pf", "sequence": name, "boxes": flat}
        (tmp_path / "report" / "runs" / f"ope__{name}__fusion-pf__s0__x.json").write_text(json.dumps(rec))
    out = subprocess.run([sys.executable, str(SCRIPT), str(results), "--scenes", str(scenes), "--by-kind"],
                         capture_output=True, text=True, check=True).stdout
    table = out.split("mean AUC by kind")[1].splitlines()
    simple = next(ln for ln in table if ln.startswith("simple"))
    real = next(ln for ln in table if ln.startswith("real"))
    # the mean AUC 0.7; the size the median of the two runs' medians (0.707 and 1.0)
    assert simple.split()[1:] == ["0.700", "(0.85)"]
    assert real.split()[1:] == ["0.500"]
    assert "mean AUC by kind" not in subprocess.run([sys.executable, str(SCRIPT), str(results)], capture_output=True,
                                                    text=True, check=True).stdout


def test_by_kind_columns_of_long_tracker_names_are_lettered():
    sys.path.insert(0, str(SCRIPT.parent))
    try:
        from split_summary import column_labels
    finally:
        sys.path.pop(0)
    assert column_labels(["color-pf", "fusion-pf"]) == ["color-pf", "fusion-pf"]
    long = ["fusion-pf", "fusion-pf[velocity_step=0.25;velocity_noise=0]", "fusion-pf[velocity_step=0.25]"]
    assert column_labels(long) == ["A", "B", "C"]


def test_by_kind_pools_the_lost_flag_over_the_frames(tmp_path):
    """--by-kind also prints lost recall / false-lost per kind, each run's rate weighted by its frames."""
    results = tmp_path / "results.csv"
    fields = ["tracker", "sequence", "seed", "auc", "lost_recall", "false_lost", "absent_frames", "covered_frames"]
    rows = [("lk-rls", "leave-300", 0, 0.3, 1.0, 0.0, 30, 50),       # 30 of 30 absent frames flagged
            ("lk-rls", "leave-301", 0, 0.4, 0.5, 0.1, 10, 100),      # 5 of 10; 10 of 100 covered frames
            ("lk-rls", "simple-300", 0, 0.9, "", 0.0, 0, 80)]        # no absent frame: recall undefined
    with open(results, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(fields)
        w.writerows(rows)
    out = subprocess.run([sys.executable, str(SCRIPT), str(results), "--by-kind"], capture_output=True, text=True,
                         check=True).stdout
    table = out.split("lost recall / false-lost by kind")[1].splitlines()
    leave = next(ln for ln in table if ln.startswith("leave"))
    simple = next(ln for ln in table if ln.startswith("simple"))
    assert leave.split()[1:] == ["0.88", "/", "0.07"]     # 35 / 40 and 10 / 150
    assert simple.split()[1:] == ["-", "/", "0.00"]
