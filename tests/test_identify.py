"""Book ch. 1 identification: features, the reconstructed similarity, and multi-pf identify=true."""

from __future__ import annotations

import numpy as np

from pftrack.multi import create_multi_tracker
from pftrack.multi.identify import IdentityMemory, person_features, similarity
from pftrack.synth import SceneSpec, Target

from .conftest import cached_scene


def _person_frame(colours, boxes, size=(240, 320)):
    img = np.full(size + (3,), 110, np.uint8)
    for (up, low), (x, y, w, h) in zip(colours, boxes):
        img[int(y):int(y + h / 2), int(x):int(x + w)] = up
        img[int(y + h / 2):int(y + h), int(x):int(x + w)] = low
    return img


def test_features_and_similarity():
    f = _person_frame([((200, 40, 40), (40, 40, 200))], [(50, 60, 30, 80)])
    a = person_features(f, (50, 60, 30, 80))
    assert np.allclose(a.mu_u, (200, 40, 40)) and np.allclose(a.mu_l, (40, 40, 200))
    assert np.allclose(a.sd_u, 0) and np.allclose(a.box, (50, 60, 80, 140))
    assert similarity(a, a, 320, 240) == 1.0
    g = _person_frame([((40, 200, 40), (40, 40, 200))], [(50, 60, 30, 80)])
    b = person_features(g, (50, 60, 30, 80))
    assert similarity(a, b, 320, 240) < similarity(a, a, 320, 240)
    mem = IdentityMemory(threshold=0.8, memory=10)
    mem.remember(7, a, 0)
    assert mem.recall(b, 5, 320, 240) is None  # a different upper body
    assert mem.recall(a, 5, 320, 240) == 7 and mem.recall(a, 6, 320, 240) is None  # given back once
    mem.remember(7, a, 0)
    assert mem.recall(a, 20, 320, 240) is None  # forgotten after `memory` frames


def _exit_and_return_scene():
    """Person 0 walks out on the right and comes back; person 1 (other colours) stays in view."""
    n = 140
    a = Target(path=((0, 80, 120), (45, 360, 120), (85, 360, 125), (130, 220, 125)), size=(30, 70),
               colors=((40, 40, 200), (200, 160, 40)), texture=6.0, shape="rect")
    b = Target(path=((0, 60, 150), (139, 120, 150)), size=(30, 70), colors=((60, 200, 60), (160, 60, 160)),
               texture=6.0, shape="rect")
    return SceneSpec(n_frames=n, seed=3, targets=(a, b), background="flat")


def _run(identify: bool):
    scene = cached_scene(_exit_and_return_scene())
    state = {"t": 0}

    def detector(frame):  # a perfect detector of the visible people
        _, truth = scene.render(state["t"])
        return [tuple(b) for b, ok in zip(truth.boxes, truth.present) if ok and np.all(np.isfinite(b))
                and b[0] > 0 and b[0] + b[2] < 320]

    tr = create_multi_tracker("multi-pf", seed=0, detector_fn=detector, identify=identify, birth_frames=2)
    ids_a = []
    for t in range(scene.spec.n_frames):
        state["t"] = t
        frame, truth = scene.render(t)
        outs = tr.update(frame)
        if truth.present[0]:
            gx = truth.boxes[0][0] + truth.boxes[0][2] / 2
            near = [o.track_id for o in outs if abs(o.box[0] + o.box[2] / 2 - gx) < 15
                    and abs(o.box[1] + o.box[3] / 2 - (truth.boxes[0][1] + truth.boxes[0][3] / 2)) < 15]
            ids_a.append((t, near[0] if near else None))
    before = {i for t, i in ids_a if t < 40 and i is not None}
    after = {i for t, i in ids_a if t > 100 and i is not None}
    return before, after


def test_a_returning_person_gets_their_identity_back():
    before, after = _run(identify=True)
    assert len(before) == 1 and after == before
    before0, after0 = _run(identify=False)
    assert len(before0) == 1 and after0 and after0 != before0  # without identification: a new identity


def test_identification_rate_counts_detections_with_their_persons_identity():
    from pftrack.eval.mot import accumulate, identification_rate

    gt, hyp = [], []
    for f in range(1, 11):
        gt += [[f, 1, 10, 10, 20, 40], [f, 2, 100, 10, 20, 40]]
        hyp += [[f, 7, 10, 10, 20, 40], [f, 8 if f <= 6 else 9, 100, 10, 20, 40]]  # person 2 changes id at f=7
    rate = identification_rate(accumulate(np.array(gt, float), np.array(hyp, float)))
    assert rate == (10 + 6) / 20
