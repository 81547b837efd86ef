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
