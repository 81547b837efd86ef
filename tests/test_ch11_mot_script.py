"""scripts/ch11_mot.py: each track of `pftrack mot` is given the person whose ground-truth box it overlaps most."""

from __future__ import annotations

import numpy as np

from .conftest import load_script


def test_tracks_take_the_person_they_overlap_on_most_frames():
    cm = load_script("ch11_mot")
    gt = np.array([[f, g, 10 + 40 * (g - 1), 10, 20, 40, 1, -1, -1, -1] for f in range(1, 11) for g in (1, 2)], float)
    identity = {("a", 1): 7, ("a", 2): 9}
    rows = []
    for f in range(1, 11):
        rows.append([f, 5, 11, 11, 20, 40])                        # on ground-truth track 1 (person 7)
        rows.append([f, 6, 10 + 40 if f <= 6 else 10, 10, 20, 40])  # on person 9 for 6 frames, then on person 7
        if f <= 2:
            rows.append([f, 8, 50, 10, 20, 40])                    # person 9 on 2 frames only: too few
        rows.append([f, 3, 300, 300, 20, 40])                      # nobody
    got = cm.persons_of(np.array(rows, float), gt, identity, "a")
    assert got == {5: 7, 6: 9}
