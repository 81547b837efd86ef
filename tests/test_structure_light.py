"""The structural cue on grey input under light that varies across the target (pftrack.cues.structure_light)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

import pftrack
from pftrack.cues.structure import StructureCue
from pftrack.cues.structure_light import LitStructure
from pftrack.eval.metrics import frame_ious

from .conftest import face_proxy_run


def _scene(seed: int = 0, size=(240, 320)):
    """A textured grey image (float levels 40-200, smooth texture); _bgr makes a frame of it."""
    rng = np.random.default_rng(seed)
    g = cv2.GaussianBlur(rng.uniform(0, 255, size).astype(np.float32), (0, 0), 3)
    g = 40 + 160 * (g - g.min()) / (g.max() - g.min())
    return g


def _bgr(g):
    return cv2.cvtColor(np.clip(g, 0, 255).astype(np.uint8), cv2.COLOR_GRAY2BGR)


TARGET = np.array([160.0, 120.0, 40.0, 40.0])  # an 80 x 80 box


def _lit(g, strength):
    """A lamp from the left: the gain runs from 1 + strength to 1 - strength across the frame (smooth)."""
    x = np.linspace(1.0, -1.0, g.shape[1])[None, :]
    return g * (1.0 + strength * np.sin(0.5 * np.pi * x))


def test_a_gradient_of_light_across_the_target_keeps_the_quotient_cue_and_the_better_of_both():
    g = _scene()
    first, relit = _bgr(g), _bgr(_lit(g, 0.6))
    raw = StructureCue(256, weighting="uniform")
    raw.init(first, TARGET)
    lit = LitStructure(256, weighting="uniform", sigma=0.1, mode="both")
    lit.init(first, TARGET)
    e = TARGET.reshape(1, 4)
    r_raw = float(raw.scores(relit, None, e)[0])
    r_q = float(lit.quotient.scores(lit._qf(relit), None, e)[0])
    r_both = float(lit.scores(relit, None, e)[0])
    assert r_q > 0.9 > r_raw + 0.05, (r_q, r_raw)  # measured: quotient 0.99, grey levels 0.70
    assert r_both == pytest.approx(max(r_q, float(lit.levels.scores(relit, None, e)[0])))
    # a box beside the target stays well below (measured: -0.02)
    aside = (TARGET + [60.0, 0, 0, 0]).reshape(1, 4)
    assert float(lit.scores(relit, None, aside)[0]) < r_both - 0.3


def test_the_quotient_image_is_computed_once_per_frame():
    g = _bgr(_scene(1))
    lit = LitStructure(256, mode="quotient")
    assert lit.levels is None
    lit.init(g, TARGET)
    calls = []
    inner = lit._q
    lit._q = lambda f, **kw: calls.append(1) or inner(f, **kw)
    f2 = g.copy()
    lit.new_frame()
    lit.scores(f2, None, TARGET.reshape(1, 4))
    lit.scores(f2, None, (TARGET + [5.0, 0, 0, 0]).reshape(1, 4))
    lit.update(f2, TARGET, 0.1)
    assert len(calls) == 1
    lit.new_frame()
    lit.scores(f2, None, TARGET.reshape(1, 4))
    assert len(calls) == 2
    with pytest.raises(ValueError):
        LitStructure(mode="levels")


@pytest.mark.parametrize(("gray", "mode", "kind"), [
    (True, "both", LitStructure), (True, "levels", StructureCue), (False, "both", StructureCue)])
def test_fusion_pf_picks_the_grey_structure_from_the_input(gray, mode, kind):
    g = _scene(2)
    frame = _bgr(g) if gray else cv2.merge([g.astype(np.uint8), (255 - g).astype(np.uint8), g.astype(np.uint8)])
    box = (120.0, 80.0, 80.0, 80.0)
    t = pftrack.create_tracker("fusion-pf", seed=0, grey_structure=mode, structure_features="ncc")
    t.init(frame, box)
    assert type(t.structure) is kind
    st = t.update(frame)
    assert frame_ious(np.array([st.box]), np.array([box]))[0] > 0.7 and not st.lost
    # illumination='quotient' already transforms every grey frame: the structural cue is left alone
    t = pftrack.create_tracker("fusion-pf", seed=0, illumination="quotient", structure_features="ncc")
    t.init(frame, box)
    assert type(t.structure) is StructureCue


@pytest.mark.parametrize("seed", [0, 5])
def test_default_fusion_pf_holds_a_grey_face_under_a_lamp_and_a_shadow(seed):
    """The grey face proxy's two hardest tune seeds for the grey levels alone (docs/robustness.md). Measured on 150
    frames: mean IoU 0.735 and 0.828; with grey_structure='levels' 0.535 and 0.690."""
    iou, _ = face_proxy_run("fusion-pf", seed)
    assert iou >= 0.7, iou


@pytest.mark.parametrize("gray", [True, False])
def test_the_first_update_scores_structure_on_its_own_frame(gray):
    """init's background statistics reduce the whole first frame for the structural cue; the first update must
    not score its particles on that region (it did before this was fixed, for grey and colour input alike)."""
    g0 = _scene(3)
    g1 = np.roll(g0, 30, axis=1)  # the whole scene moved 30 px to the right
    to = _bgr if gray else (lambda a: cv2.merge([a.astype(np.uint8), (255 - a).astype(np.uint8), a.astype(np.uint8)]))
    f0, f1 = to(g0), to(g1)
    box = (120.0, 80.0, 80.0, 80.0)
    t = pftrack.create_tracker("fusion-pf", seed=0)
    t.init(f0, box)
    moved = np.array([[190.0, 120.0, 40.0, 40.0]])  # the target's place on the second frame
    s = float(t.structure.scores(f1, None, moved)[0])
    assert s > 0.8, s  # measured 0.99 (grey) and 0.85 (colour); 0.14 and 0.12 on the first frame's region
