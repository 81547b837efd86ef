"""Trackers added by other installed packages (the ``pftrack.trackers`` entry-point group)."""

from __future__ import annotations

import sys
import textwrap

import numpy as np
import pytest

import pftrack
from pftrack.trackers import registry

from .test_eval_runner import write_otb

PLUGIN = '''
from dataclasses import dataclass

from pftrack.params import Params, param
from pftrack.trackers.base import Tracker, TrackState


@dataclass(frozen=True, kw_only=True)
class StillParams(Params):
    shift: float = param(0.0, doc="pixels added to x")


class Still(Tracker):
    """Reports the first box (shifted) on every frame."""

    name = "still"
    Params = StillParams
    stochastic = False

    def _init(self, frame, box):
        self.box = (box[0] + self.params.shift, *box[1:])
        return TrackState(box=self.box, score=1.0, lost=False)

    def _update(self, frame):
        return TrackState(box=self.box, score=1.0, lost=False)


REGISTRY_ENTRIES = [("still", Still, "the first box on every frame", {})]
'''


@pytest.fixture
def installed_plugin(tmp_path, monkeypatch):
    """A package ``stillplug`` installed on ``sys.path`` with five entry points: one good, one whose module is
    missing, one whose name is taken by a built-in tracker, one that lists a name twice, one with an unknown option."""
    (tmp_path / "stillplug.py").write_text(PLUGIN)
    (tmp_path / "clash.py").write_text("from stillplug import Still\n"
                                       "REGISTRY_ENTRIES = [('color-pf', Still, 'x', {})]\n")
    (tmp_path / "twice.py").write_text("from stillplug import Still\n"
                                       "REGISTRY_ENTRIES = [('again', Still, 'x', {}), ('again', Still, 'y', {})]\n")
    (tmp_path / "oddopt.py").write_text("from stillplug import Still\n"
                                        "REGISTRY_ENTRIES = [('odd', Still, 'x', {'colour': 'blue'})]\n")
    info = tmp_path / "stillplug-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: stillplug\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(textwrap.dedent("""\
        [pftrack.trackers]
        still = stillplug
        gone = no_such_module_here
        clash = clash
        twice = twice
        oddopt = oddopt
        """))
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setattr(registry, "_REGISTRY", {})
    monkeypatch.setattr(registry, "_loaded", False)
    yield
    for m in ("stillplug", "clash", "twice", "oddopt"):
        sys.modules.pop(m, None)


def test_an_installed_plugin_adds_its_tracker_and_a_broken_one_is_skipped(installed_plugin, tmp_path, capsys):
    with pytest.warns(UserWarning) as rec:
        names = registry.tracker_names()
    msgs = " ".join(str(w.message) for w in rec)
    assert "'gone'" in msgs and "ModuleNotFoundError" in msgs
    assert "'clash'" in msgs and "already registered" in msgs
    assert "'twice'" in msgs and "listed twice" in msgs and "again" not in names
    assert "'oddopt'" in msgs and "unknown options" in msgs and "odd" not in names
    assert "still" in names and "color-pf" in names and registry.get_spec("color-pf").family == "pftrack"
    assert registry.get_spec("still").family == "plugin"
    t = pftrack.create_tracker("still", shift=2)
    frame = np.zeros((40, 60, 3), np.uint8)
    assert t.init(frame, (5, 6, 10, 12)).box == (7, 6, 10, 12) and t.update(frame).box == (7, 6, 10, 12)
    with pytest.raises(pftrack.ParameterError):
        pftrack.create_tracker("still", bogus=1)

    # the command line sees it too
    from pftrack.cli import main

    assert main(["list", "still"]) == 0
    assert "shift" in capsys.readouterr().out
    assert main(["list"]) == 0
    assert "(plugin: stillplug)" in capsys.readouterr().out
    write_otb(tmp_path / "seq", 1)
    assert main(["eval", str(tmp_path / "seq"), "--trackers", "still,still[shift=3]", "--workers", "1", "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "| `still` |" in out and "| `still[shift=3]` |" in out
