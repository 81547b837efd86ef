"""Every switch of the trackers runs: each boolean option flipped and each choice of an option with a fixed set of
values, on a short scene whose target hides and comes back (so the loss test, the search and the re-acquisition run
too). The defaults run on its colour and its grey copy; each switched option on one of the two, alternately, and on
the grey copy when the option's name says it acts on grey input (so the sweep costs a run per option, not two).
The slowest trackers (covariance, switching, graph cuts, the mesh) are left out. An option that crashed only when
switched on (local-motion-pf's ``search``) went unnoticed until such a sweep."""

from __future__ import annotations

import dataclasses
import typing

import pytest

import pftrack
from pftrack.errors import ParameterError
from pftrack.synth import Scene, vanish_scene
from pftrack.trackers.registry import get_spec


def _variants(name: str) -> list[dict]:
    params_cls = get_spec(name).params_cls
    hints = typing.get_type_hints(params_cls)
    out: list[dict] = [{}]  # the defaults first
    for f in dataclasses.fields(params_cls):
        tp = hints[f.name]
        if tp is bool:
            out.append({f.name: not f.default})
        elif typing.get_origin(tp) is typing.Literal:
            out += [{f.name: c} for c in typing.get_args(tp) if c != f.default]
    return out


def _acts_on_grey(variant: dict) -> bool:
    return any(k in name for name in variant for k in ("grey", "gray"))


@pytest.fixture(scope="module")
def scenes():
    return {gray: [(f, tr.boxes[0]) for f, tr in Scene(vanish_scene(1, n_frames=40, gray=gray))]
            for gray in (0.0, 1.0)}


@pytest.mark.parametrize("name", ["color-pf", "fusion-pf", "local-motion-pf", "flow-pf", "cotrain-pf", "ssim-pf",
                                  "hybrid-ssim-pf", "template", "fs-meanshift", "anisotropic-meanshift",
                                  "sift-ransac", "lk-rls", "lk-rls-fuzzy", "meanshift", "kalman-meanshift"])
def test_every_switch_of_a_tracker_runs(name, scenes):
    variants = _variants(name)
    assert len(variants) >= 2
    ran = 0
    for i, v in enumerate(variants):
        on = (0.0, 1.0) if not v else (1.0,) if _acts_on_grey(v) else ((0.0, 1.0)[i % 2],)
        for gray in on:
            pairs = scenes[gray]
            try:
                t = pftrack.create_tracker(name, seed=0, **v)
            except ParameterError:  # a choice this tracker refuses, with a one-line reason (exit code 2 in the CLI)
                assert v, "the defaults must be accepted"
                continue
            ran += 1
            t.init(pairs[0][0], pairs[0][1])
            for f, _ in pairs[1:]:
                st = t.update(f)
            assert st.box[2] > 0 and st.box[3] > 0, (v, gray)
    assert ran >= 4
