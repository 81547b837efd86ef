"""scripts/fresh_draw.py: a draw of neither split refuses the splits' seeds, writes the scenes, evaluates them and
prints the table by kind."""

from __future__ import annotations

import csv

import pytest

from .conftest import load_script


def test_the_splits_seeds_are_named():
    fresh = load_script("fresh_draw")
    assert fresh.split_seeds([0, 7, 19, 20, 99, 100, 107, 108, 999, 1000, 1019, 1020, 8200]) == [0, 7, 19, 100, 107,
                                                                                                 1000, 1019]
    assert len(fresh.KINDS) == 17 and "photo-exit" in fresh.KINDS


@pytest.mark.parametrize("argv", [["--seeds", "100-103"], ["--seeds", "8200,5"], ["--seeds", "9-2"],
                                  ["--seeds", "8200", "--kinds", "simple,unknown"]])
def test_bad_draws_are_refused_before_anything_is_written(argv, tmp_path, capsys):
    fresh = load_script("fresh_draw")
    with pytest.raises(SystemExit) as ended:
        fresh.main([*argv, "--out", str(tmp_path / "draw")])
    assert ended.value.code == 2
    assert ("--kinds" if "--kinds" in argv else "--seeds") in capsys.readouterr().err
    assert not (tmp_path / "draw").exists()


def test_one_kind_is_drawn_evaluated_and_summarised(tmp_path, capsys):
    fresh = load_script("fresh_draw")
    out = tmp_path / "draw"
    assert fresh.main(["--seeds", "9990", "--kinds", "simple", "--trackers", "fusion-pf", "--run-seeds", "1",
                       "--workers", "1", "--out", str(out)]) == 0
    assert (out / "scenes" / "simple" / "simple-9990" / "meta.json").is_file()
    with open(out / "eval" / "results.csv", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    assert [(r["tracker"], r["sequence"]) for r in rows] == [("fusion-pf", "simple-9990")]
    assert 0.0 <= float(rows[0]["auc"]) <= 1.0
    printed = capsys.readouterr().out
    assert "mean AUC by kind" in printed and "simple" in printed.split("mean AUC by kind")[1]
