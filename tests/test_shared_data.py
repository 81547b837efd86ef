"""Regression checks on the real development sequences (skipped when ../shared/data is absent)."""

import numpy as np
import pytest

import pftrack
from pftrack.eval.metrics import ope_scores
from pftrack.io import open_source

from .conftest import shared_sequence


@pytest.mark.shared_data
def test_color_pf_tracks_otb_crossing():
    src = open_source(shared_sequence("otb_crossing"))
    tr = pftrack.create_tracker("color-pf", seed=0)
    boxes = []
    for i, frame in enumerate(src):
        st = tr.init(frame, src.init_box) if i == 0 else tr.update(frame)
        assert np.all(np.isfinite(st.box))
        boxes.append(st.box)
    res = ope_scores(np.array(boxes), src.groundtruth)
    assert res.n_frames == 120
    assert res.auc > 0.45 and res.precision > 0.8


@pytest.mark.shared_data
def test_readers_on_every_dev_sequence():
    for name, kind in [("otb_couple", "otb"), ("otb_crossing", "otb"), ("vot_bag", "vot"),
                       ("pets09_s2l1_dev", "mot")]:
        src = open_source(shared_sequence(name))
        assert src.sequence.kind == kind
        assert len(src) > 100
        first = next(iter(src))
        assert first.dtype == np.uint8 and first.ndim == 3
    src = open_source(shared_sequence("vot_bag"))
    assert src.groundtruth.shape == (196, 4) and src.sequence.polygons.shape == (196, 8)
