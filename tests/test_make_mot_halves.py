"""scripts/make_mot_halves.py: the PETS halves as MOTChallenge folders, and their dark, noisy copies (--dim)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np

SCRIPT = Path(__file__).resolve().parents[1] / "scripts" / "make_mot_halves.py"


def _fake_pets(root: Path) -> Path:
    """A PETS-shaped folder: 400 small flat frames (level 200) and one person box on every frame."""
    pets = root / "data" / "pets09_s2l1_dev"
    (pets / "img1").mkdir(parents=True)
    (pets / "gt").mkdir()
    frame = np.full((12, 16, 3), 200, np.uint8)
    for n in range(1, 401):
        cv2.imwrite(str(pets / "img1" / f"{n:06d}.jpg"), frame)
    rows = [f"{n},1,2,3,4,5,1,1,1" for n in range(1, 401)]
    (pets / "gt" / "gt.txt").write_text("\n".join(rows) + "\n")
    return pets.parent


def test_dim_writes_both_halves_dark_and_noisy_with_the_truth_renumbered(tmp_path):
    data = _fake_pets(tmp_path)
    subprocess.run([sys.executable, str(SCRIPT), "--data", str(data), "--out", str(tmp_path / "o"), "--dim", "0.25",
                    "--noise", "2"], check=True, capture_output=True, text=True)
    for half in ("tune", "report"):
        d = tmp_path / "o" / f"dark_{half}" / f"dark_{half}"
        frames = sorted((d / "img1").glob("*.png"))
        assert len(frames) == 200 and frames[0].name == "000001.png"
        img = cv2.imread(str(frames[7])).astype(float)
        assert abs(img.mean() - 50) < 1.0 and 1.0 < img.std() < 3.0  # 200 x 0.25, noise of 2 levels (PNG: exact)
        gt = np.loadtxt(d / "gt" / "gt.txt", delimiter=",", ndmin=2)
        assert gt[:, 0].min() == 1 and gt[:, 0].max() == 200
    bad = subprocess.run([sys.executable, str(SCRIPT), "--data", str(data), "--out", str(tmp_path / "z"), "--dim",
                          "2"], capture_output=True, text=True)
    assert bad.returncode == 2 and "--dim" in bad.stderr
