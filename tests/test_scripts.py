"""The experiment scripts (``scripts/*.py``) import without running, and those with a command line answer ``--help``:
a renamed function or module of the package breaks them here rather than when a figure is regenerated."""

from __future__ import annotations

import inspect
import sys

import pytest

from .conftest import REPO, load_script

SCRIPTS = sorted(p.stem for p in (REPO / "scripts").glob("*.py"))


def test_the_scripts_are_found():
    assert len(SCRIPTS) >= 20 and "pisc_illumination" in SCRIPTS


@pytest.mark.parametrize("name", SCRIPTS)
def test_a_script_imports_without_running_and_answers_help(name, monkeypatch, capsys):
    source = (REPO / "scripts" / f"{name}.py").read_text()
    assert 'if __name__ == "__main__":' in source, "the script's work must wait for its main guard"
    mod = load_script(name)  # runs the top level only: the package names the script uses must exist
    main = getattr(mod, "main", None)
    if main is None or "argparse" not in source:
        return
    params = inspect.signature(main).parameters
    if any(p.default is inspect.Parameter.empty for p in params.values()):
        return  # a main of positional values (split_summary, split_table): its command line is in the guard
    monkeypatch.setattr(sys, "argv", [f"{name}.py", "--help"])
    with pytest.raises(SystemExit) as ended:
        main(*([["--help"]] if "argv" in params else []))
    assert ended.value.code == 0
    assert "usage" in capsys.readouterr().out.lower()


def test_ch13_seeds_reach_every_part_that_draws_report_scenes(monkeypatch):
    """``ch13_experiments.py --seeds`` replaces the report seeds of t1, t2, t4 and t6 (a fresh draw of neither
    split); without it each part keeps its report seeds."""
    mod = load_script("ch13_experiments")
    seen: dict = {}
    for part in ("t1", "t2", "t4", "t6"):
        monkeypatch.setattr(mod, f"part_{part}", lambda out, seeds=None, part=part: seen.__setitem__(part, seeds))
    monkeypatch.setattr(sys, "argv", ["ch13_experiments.py", "--part", "t6,t1,t4,t2", "--seeds", "300-302"])
    mod.main()
    assert seen == {p: [300, 301, 302] for p in ("t1", "t2", "t4", "t6")}
    monkeypatch.setattr(sys, "argv", ["ch13_experiments.py", "--part", "t6"])
    mod.main()
    assert seen["t6"] is None and list(mod.REPORT_SEEDS) == list(range(100, 105))


def test_ch03_seeds_draw_the_seir_scenes_afresh(monkeypatch, capsys):
    """``ch03_experiments.py --part seir-synth --seeds`` runs other varied scenes than the report seeds 100-131."""
    mod = load_script("ch03_experiments")
    seen = []
    one = {"ess": 0.5, "centre_error_mean_of_medians": 1.0, "centre_error_median_of_medians": 1.0, "auc": 0.5}
    fake = {"runs": 2, "seir": one, "multinomial": one,
            "centre_error_difference": {"mean": 0.0, "se": 0.0, "seir_lower": 0, "seir_higher": 0}}
    monkeypatch.setattr(mod, "seir_synth_experiment", lambda scenes=range(100, 132): seen.append(list(scenes)) or fake)
    for argv, expect in ((["--seeds", "300-302"], [300, 301, 302]), ([], list(range(100, 132)))):
        monkeypatch.setattr(sys, "argv", ["ch03_experiments.py", "--part", "seir-synth", *argv])
        mod.main()
        assert seen[-1] == expect
        assert f"seeds {expect[0]}-{expect[-1]}" in capsys.readouterr().out


def test_ssim_first_draws_the_scenes_afresh(monkeypatch):
    """``ssim_experiments.py --first S`` builds the camouflage scenes S..S+2 and the fast movers from S."""
    mod = load_script("ssim_experiments")
    drawn = {"camouflage": [], "fig6": []}
    monkeypatch.setattr(mod, "warm_up", lambda *a, **k: None)
    monkeypatch.setattr(mod, "camouflage_scene", lambda seed, n_frames=120: drawn["camouflage"].append(seed) or seed)
    monkeypatch.setattr(mod, "Scene", lambda spec: type("S", (), {"frames": lambda self: [],
                                                                  "groundtruth": lambda self, i: None})())
    monkeypatch.setattr(mod, "table5", lambda seqs, seeds: [])
    monkeypatch.setattr(mod, "fig6", lambda seeds, first=100: drawn["fig6"].append(first) or [])
    monkeypatch.setattr(mod, "batch_speed", lambda: [])
    monkeypatch.setattr(sys, "argv", ["ssim_experiments.py", "--first", "300", "--real", ""])
    mod.main()
    assert drawn == {"camouflage": [300, 301, 302], "fig6": [300]}
