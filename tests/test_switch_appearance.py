"""scripts/switch_appearance.py: a break in the tracked box's two-ellipse appearance at a switch (a diagnosis)."""

from __future__ import annotations

import numpy as np
import pytest

from .conftest import load_script


@pytest.fixture(scope="module")
def mod():
    return load_script("switch_appearance")


def _two_coats(top, legs, h=80, w=30):
    """A frame holding one walker: a torso of colour ``top`` over legs of colour ``legs`` on grey ground."""
    frame = np.full((120, 100, 3), 128, np.uint8)
    frame[20:20 + h // 2, 30:30 + w] = top
    frame[20 + h // 2:20 + h, 30:30 + w] = legs
    return frame


def test_the_descriptor_tells_a_swapped_layout_apart(mod):
    """The same two colours, torso and legs swapped: the whole box's colours agree, the two ellipses do not."""
    box = (30.0, 20.0, 30.0, 80.0)
    a = mod.descriptor(_two_coats((200, 30, 30), (30, 30, 200)), box)
    b = mod.descriptor(_two_coats((30, 30, 200), (200, 30, 30)), box)
    assert a.shape == (1024,) and a.sum() == pytest.approx(1.0)
    assert mod.similarity(a, a) == pytest.approx(1.0)
    assert mod.similarity(a, b) < 0.3  # the ellipses reach a little past the coats' border
    whole = [mod.push_joint(*mod.joint_histogram(f, box, "whole"), mod.identity_btf())
             for f in (_two_coats((200, 30, 30), (30, 30, 200)), _two_coats((30, 30, 200), (200, 30, 30)))]
    assert mod.similarity(*whole) == pytest.approx(1.0)


def test_lag_and_break_mark_the_frame_the_appearance_changes(mod):
    rng = np.random.default_rng(0)
    base, other = rng.dirichlet(np.ones(1024)), rng.dirichlet(np.ones(1024))
    desc = np.array([base * (1 + 0.05 * rng.standard_normal(1024)) for _ in range(60)]).clip(0)
    desc /= desc.sum(axis=1, keepdims=True)
    desc[40:] = other  # the box moved onto another object at frame 40
    lag = mod.lag_similarities(desc, base)
    assert lag[:40].min() > 0.95 and lag[40] < 0.6
    brk = mod.breaks(lag)
    assert np.isinf(brk[:mod.MIN_BASE + mod.LAG_NEAR]).all()  # too few lags to compare with
    assert int(np.argmin(brk)) == 40 and brk[40] < -8
    assert (brk[mod.MIN_BASE + mod.LAG_NEAR:40] > -4).all()


def test_switches_are_the_first_frames_on_another_walker_soon_after_the_target(mod):
    tiou = np.array([0.8, 0.7, 0.4, 0.1, 0.0, np.nan, 0.6, 0.2, 0.1])
    walker = np.array([-1, -1, -1, 7, 7, 7, -1, 3, 3])
    assert mod.switches(tiou, walker) == [3, 7]
    assert mod.switches(tiou, np.full(9, -1)) == []
    late = np.r_[0.8, np.full(11, 0.1), 0.1]
    assert mod.switches(late, np.r_[np.full(12, -1), 5]) == []  # 12 frames after the last overlap


def test_the_doubt_flag_rises_at_a_break_and_falls_when_the_box_looks_as_before(mod):
    rng = np.random.default_rng(1)
    base, other = rng.dirichlet(np.ones(1024)), rng.dirichlet(np.ones(1024))
    desc = np.array([base * (1 + 0.05 * rng.standard_normal(1024)) for _ in range(100)]).clip(0)
    desc /= desc.sum(axis=1, keepdims=True)
    desc[40:50] = other  # something passed in front for ten frames
    lag = mod.lag_similarities(desc, base)
    brk = mod.breaks(lag)
    lost = np.zeros(100, bool)
    flag = mod.doubt_flag(desc, lag, brk, lost, -7.0, 30, 3.0)
    assert not flag[:40].any() and flag[40:50].all() and not flag[50:].any()  # back as before: down at once
    desc[50:] = other  # ... and stayed: the flag holds for at most T frames
    lag, brk = mod.lag_similarities(desc, base), None
    brk = mod.breaks(lag)
    flag = mod.doubt_flag(desc, lag, brk, lost, -7.0, 30, 3.0)
    assert flag[40:70].all() and not flag[70:].any()
    assert not mod.doubt_flag(desc, lag, brk, lost, -1e9, 30, 3.0).any()  # no break that deep: the tracker's flag


def test_the_command_traces_saves_and_reads_again(mod, tmp_path):
    """End to end on an OTB-style folder that is not a PETS view (no walkers: no switches), then from the saved
    traces: the same tables."""
    import subprocess
    import sys
    from pathlib import Path

    import cv2

    from pftrack.synth import Scene
    from pftrack.synth.scenes import SceneSpec, Target

    target = Target(path=((0, 60.0, 100.0), (40, 200.0, 100.0)), size=(26.0, 52.0))
    scene = Scene(SceneSpec(n_frames=40, seed=0, targets=(target,), background="flat", kind="simple"))
    seq = tmp_path / "seqs" / "walk"
    (seq / "img").mkdir(parents=True)
    for k, f in enumerate(scene.frames()):
        cv2.imwrite(str(seq / "img" / f"{k + 1:04d}.png"), f)
    np.savetxt(seq / "groundtruth_rect.txt", np.asarray(scene.groundtruth()), fmt="%.2f", delimiter=",")
    script, out = str(Path(mod.__file__)), tmp_path / "trace.npz"
    first = subprocess.run([sys.executable, script, str(tmp_path / "seqs"), "--tracker", "color-pf", "--seeds", "0",
                            "--pets", str(tmp_path / "none"), "--out", str(out)], capture_output=True, text=True,
                           check=True)
    assert "== seqs: 1 runs, 0 switches, " in first.stdout and "doubt z -7, T 30, c 3" in first.stdout
    again = subprocess.run([sys.executable, script, str(tmp_path / "seqs"), "--load", str(out)], capture_output=True,
                           text=True, check=True)
    tables = [ln for ln in first.stdout.splitlines() if ln.startswith(("==", "   "))]
    assert tables == [ln for ln in again.stdout.splitlines() if ln.startswith(("==", "   "))]
