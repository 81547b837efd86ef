"""Plot of MPEG-7 motion activity over time (book ch. 8, Figs. 6-8 style)."""

from __future__ import annotations

import numpy as np

from ..multi.motion_activity import THRESHOLDS


def plot_activity(series, path, title: str = "motion activity") -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    f = np.array([s[0] for s in series])
    sig = np.array([s[1] for s in series])
    lev = np.array([s[2] for s in series])
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(9, 5), sharex=True)
    a1.plot(f, sig, lw=1)
    for t in THRESHOLDS:
        a1.axhline(t, color="0.7", lw=0.8, ls="--")
    a1.set_ylabel("sigma (px)")
    a1.set_title(title)
    a2.step(f, lev, where="mid")
    a2.set_ylim(0.5, 5.5)
    a2.set_yticks([1, 2, 3, 4, 5])
    a2.set_ylabel("level")
    a2.set_xlabel("frame")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
