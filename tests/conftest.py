"""Shared fixtures: paths to the optional development data and cached synthetic scenes."""

from __future__ import annotations

import functools
import os
from pathlib import Path

import numpy as np
import pytest

from pftrack.synth import Scene

REPO = Path(__file__).resolve().parents[1]
SHARED_DATA = Path(os.environ.get("PFTRACK_SHARED_DATA", REPO.parent / "shared" / "data"))


def shared_sequence(name: str) -> Path:
    """Path of a development sequence, or skip the test when ../shared/data is absent."""
    path = SHARED_DATA / name
    if not path.is_dir():
        pytest.skip(f"development data {name} not available (../shared/data)")
    return path


@functools.lru_cache(maxsize=32)
def _render(spec):
    scene = Scene(spec)
    frames = tuple(scene.frames())
    for f in frames:
        f.setflags(write=False)
    truths = tuple(scene.render(t)[1] for t in range(len(scene)))
    return scene, frames, truths


def render_scene(spec):
    """Rendered frames and per-frame truth of a scene spec (cached across tests)."""
    return _render(spec)


@pytest.fixture
def rng():
    return np.random.default_rng(12345)
