"""pisc against colour and template trackers on scenes whose light changes (book ch. 1 experiment).

    python scripts/pisc_illumination.py

Fresh seeds 100-111 of two synthetic scene kinds, the same seeds for every tracker; mean OTB AUC.
Results: docs/pisc.md.
"""

import numpy as np

import pftrack
from pftrack.eval.metrics import ope_scores
from pftrack.synth import Scene, illumination_scene, varied_scene
from pftrack.trackers.warmup import warm_up

names=["pisc","color-pf","template","fusion-pf"]
for n in names: warm_up(n)
for label, make in (("varied, light drift always (seeds 100-111)", lambda s: varied_scene(s, illumination=1.0)),
                    ("illumination_scene (seeds 100-111)", lambda s: illumination_scene(s))):
    res={n:[] for n in names}
    for seed in range(100,112):
        sc=Scene(make(seed)); fr=sc.frames(); gt=sc.groundtruth(0)
        for n in names:
            t=pftrack.create_tracker(n, seed=seed); t.init(fr[0], tuple(gt[0])); b=[gt[0]]
            for f in fr[1:]: b.append(t.update(f).box)
            res[n].append(ope_scores(np.array(b), gt).auc)
    print(label, " ".join(f"{n} {np.mean(v):.3f}" for n,v in res.items()))
