"""scripts/views_summary.py: the lost flag on the PETS views pooled over absent frames, by window share."""

from __future__ import annotations

import csv
import math
import subprocess
import sys
from pathlib import Path

from .conftest import load_script

SCRIPT = Path(__file__).resolve().parents[1] / "scripts" / "views_summary.py"
FIELDS = ["tracker", "sequence", "seed", "auc", "lost_recall", "absent_frames", "reappearances", "reacquired",
          "error"]
ROWS = [
    # tracker, sequence, seed, auc, lost recall, absent frames, reappearances, re-acquired, error
    ("fusion-pf", "pets09_left_f1-200_id9", 0, 0.5, 0.2, 100, 1, 1, ""),
    ("fusion-pf", "pets09_right_f1-200_id12", 0, 0.3, 1.0, 10, 0, 0, ""),
    ("fusion-pf", "pets09_top40_f1-200_id9", 0, 0.7, 0.5, 40, 1, 0, ""),
    ("fusion-pf", "pets09_bottom70_f1-200_id13", 0, 0.1, "", 0, "", "", ""),
    ("fusion-pf", "pets09_left_f1-200_id15", 0, "", "", "", "", "", "ValueError: broken"),
    ("color-pf", "pets09_left_f1-200_id9", 0, 0.4, 0.0, 100, 1, 0, ""),
]


def _load():
    return load_script("views_summary")


def test_share_of_reads_the_window_from_the_name():
    mod = _load()
    assert mod.share_of("pets09_left_f1-200_id9") == "55"
    assert mod.share_of("pets09_bottom70_f1-200_id13") == "70"
    assert mod.share_of("otb_crossing_right40_f1-120_id1") == "40"
    assert mod.share_of("tld_pedestrian2") == "other"


def test_recall_is_pooled_over_absent_frames_not_averaged_over_runs(tmp_path):
    rows = [dict(zip(FIELDS, map(str, r))) for r in ROWS]
    table = _load().pooled(rows)
    f = table["fusion-pf"]
    # (0.2 * 100 + 1.0 * 10 + 0.5 * 40) / 150, not the runs' mean (0.2 + 1.0 + 0.5) / 3
    assert math.isclose(f["recall"], 50 / 150)
    assert f["absent"] == 150
    assert math.isclose(f["by_share"]["55"][0], 30 / 110) and f["by_share"]["55"][1] == 110
    assert math.isclose(f["by_share"]["40"][0], 0.5) and "70" not in f["by_share"]  # no absent frames there
    assert f["runs"] == 4 and math.isclose(f["auc"], (0.5 + 0.3 + 0.7 + 0.1) / 4)  # the failed run is left out
    assert (f["reacquired"], f["reappearances"]) == (1, 2)
    assert table["color-pf"]["recall"] == 0.0
    results = tmp_path / "results.csv"
    with results.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(FIELDS)
        w.writerows(ROWS)
    out = subprocess.run([sys.executable, str(SCRIPT), str(results)], capture_output=True, text=True,
                         check=True).stdout
    line = next(ln for ln in out.splitlines() if ln.startswith("fusion-pf"))
    assert line.split()[1] == "0.333" and line.rstrip().endswith("1 / 2")
