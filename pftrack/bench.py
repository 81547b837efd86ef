"""``pftrack bench``: update and end-to-end speed of every tracker, with the OpenCV peers in the same run.

Speeds on a shared or virtual machine drift by tens of percent from minute to
minute, so every configuration is measured in rounds that interleave all
trackers (round-robin), and the reported figure is the median over rounds.
Ratios between trackers measured in the same round are therefore meaningful
even when absolute numbers move.

* **update fps** — calls to ``tracker.update`` per second (frames are decoded
  beforehand; the initialisation frame is not timed);
* **end-to-end fps** — frames per second including decoding the video file from
  disk (synthetic clips are written as MJPG AVI files first; dev sequences are
  decoded from their JPEG frames).

The synthetic scene is one textured target moving across a textured
background; its size, the frame size and the number of particles are varied
one at a time around the reference configuration 640x480, 50x50, N = 100.
"""

from __future__ import annotations

import math
import statistics
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import cv2
import numpy as np

from .synth import Scene, SceneSpec, Target

REFERENCE = {"frame": (640, 480), "target": 50, "particles": 100}


def _scene(frame=(640, 480), target=50, n_frames=120, seed=0) -> tuple[list[np.ndarray], np.ndarray]:
    w, h = frame
    t = float(target)
    path = ((0, w * 0.25, h * 0.45), (n_frames * 0.5, w * 0.6, h * 0.55), (n_frames - 1, w * 0.75, h * 0.45))
    spec = SceneSpec(width=w, height=h, n_frames=n_frames, seed=seed, targets=(Target(path=path, size=(t, t)),))
    scene = Scene(spec)
    return scene.frames(), scene.groundtruth(0)


def _write_avi(frames: list[np.ndarray], path: Path) -> None:
    h, w = frames[0].shape[:2]
    vw = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 25, (w, h))
    for f in frames:
        vw.write(f)
    vw.release()


def _decode_avi(path: Path):
    cap = cv2.VideoCapture(str(path))
    try:
        while True:
            ok, f = cap.read()
            if not ok:
                return
            yield f
    finally:
        cap.release()


@dataclass
class Measurement:
    tracker: str
    config: dict
    update_fps: list[float] = field(default_factory=list)
    e2e_fps: list[float] = field(default_factory=list)

    @property
    def update(self) -> float:
        return statistics.median(self.update_fps) if self.update_fps else float("nan")

    @property
    def e2e(self) -> float:
        return statistics.median(self.e2e_fps) if self.e2e_fps else float("nan")


def _make(name: str, particles: int | None, seed: int = 0):
    from .trackers.registry import create_tracker, get_spec

    spec = get_spec(name)
    kw = {}
    if particles is not None and "n_particles" in spec.params_cls.field_names():
        kw["n_particles"] = particles
    return create_tracker(name, seed=seed, **kw)


def time_update(name: str, frames: list[np.ndarray], box, particles: int | None = None, warmup: int = 5) -> float:
    """Update fps over pre-decoded frames (the first ``warmup`` updates are not timed)."""
    tr = _make(name, particles)
    tr.init(frames[0], box)
    for f in frames[1:1 + warmup]:
        tr.update(f)
    t0 = time.perf_counter()
    for f in frames[1 + warmup:]:
        tr.update(f)
    dt = time.perf_counter() - t0
    return (len(frames) - 1 - warmup) / dt if dt > 0 else float("nan")


def time_end_to_end(name: str, frame_iter: Callable, box, particles: int | None = None) -> float:
    """Frames per second including decoding (``frame_iter()`` yields frames from disk)."""
    tr = _make(name, particles)
    t0 = time.perf_counter()
    n = 0
    for i, f in enumerate(frame_iter()):
        if i == 0:
            tr.init(f, box)
        else:
            tr.update(f)
        n += 1
    dt = time.perf_counter() - t0
    return n / dt if dt > 0 else float("nan")


def uses_particles(name: str) -> bool:
    from .trackers.registry import get_spec

    return "n_particles" in get_spec(name).params_cls.field_names()


def run_synthetic(trackers: list[str], *, particles=(50, 100, 200, 400, 800), targets=(25, 50, 100),
                  frames=((320, 240), (640, 480), (1280, 720)), rounds: int = 3, n_frames: int = 120,
                  progress: Callable[[str], None] | None = None) -> list[Measurement]:
    """Measure every tracker on the reference synthetic clip and the three one-at-a-time sweeps."""
    configs = [{"frame": REFERENCE["frame"], "target": REFERENCE["target"], "particles": REFERENCE["particles"]}]
    for n in particles:
        configs.append({"frame": REFERENCE["frame"], "target": REFERENCE["target"], "particles": n})
    for t in targets:
        configs.append({"frame": REFERENCE["frame"], "target": t, "particles": REFERENCE["particles"]})
    for fr in frames:
        configs.append({"frame": tuple(fr), "target": REFERENCE["target"], "particles": REFERENCE["particles"]})
    unique = []
    for c in configs:
        if c not in unique:
            unique.append(c)
    out: list[Measurement] = []
    with tempfile.TemporaryDirectory() as tmp:
        for c in unique:
            clip, gt = _scene(c["frame"], c["target"], n_frames)
            avi = Path(tmp) / "clip.avi"
            _write_avi(clip, avi)
            is_ref = c == configs[0]
            names = [n for n in trackers if uses_particles(n) or c["particles"] == REFERENCE["particles"]]
            ms = {n: Measurement(n, dict(c)) for n in names}
            for r in range(rounds):
                for n in names:
                    p = c["particles"] if uses_particles(n) else None
                    ms[n].update_fps.append(time_update(n, clip, gt[0], p))
                    if is_ref:
                        ms[n].e2e_fps.append(time_end_to_end(n, lambda: _decode_avi(avi), gt[0], p))
            out.extend(ms.values())
            if progress:
                progress(f"synthetic {c['frame'][0]}x{c['frame'][1]} target {c['target']} N={c['particles']}")
    return out


def run_sequences(trackers: list[str], sequences, *, rounds: int = 3,
                  progress: Callable[[str], None] | None = None) -> list[Measurement]:
    """Update and end-to-end fps of every tracker on real sequences (interleaved rounds)."""
    from .frames import as_bgr_uint8
    from .io.sources import read_image

    out = []
    for seq in sequences:
        frames = [as_bgr_uint8(read_image(p)) for p in seq.frames]
        start = seq.init_index
        frames = frames[start:]
        box = seq.init_box

        def from_disk(files=seq.frames[start:]):
            for p in files:
                yield as_bgr_uint8(read_image(p))

        ms = {n: Measurement(n, {"sequence": seq.name}) for n in trackers}
        for r in range(rounds):
            for n in trackers:
                ms[n].update_fps.append(time_update(n, frames, box))
                ms[n].e2e_fps.append(time_end_to_end(n, from_disk, box))
        out.extend(ms.values())
        if progress:
            progress(f"sequence {seq.name}")
    return out


def _fmt(v: float, nd: int = 0) -> str:
    return "–" if not (isinstance(v, float) and math.isfinite(v)) else f"{v:.{nd}f}"


def report_markdown(synth: list[Measurement], real: list[Measurement], *, reference_peer: str = "opencv-csrt",
                    command: str | None = None, machine: str | None = None) -> str:
    lines = ["# pftrack bench", ""]
    if command:
        lines += ["Reproduce with:", "", "```", command, "```", ""]
    if machine:
        lines += [machine, ""]
    lines += ["Median over interleaved rounds; one thread per tracker; update fps exclude decoding, end-to-end fps "
              "include it.", ""]
    ref = [m for m in synth if m.config == {"frame": REFERENCE["frame"], "target": REFERENCE["target"],
                                             "particles": REFERENCE["particles"]}]
    if ref:
        peer = next((m for m in ref if m.tracker == reference_peer), None)
        lines += ["## Reference synthetic clip: 640x480, 50x50 target, N = 100", "",
                  f"| tracker | update fps | end-to-end fps | × {reference_peer} (update) |", "|---|---|---|---|"]
        for m in sorted(ref, key=lambda m: -m.update):
            ratio = m.update / peer.update if peer and peer.update > 0 else float("nan")
            lines.append(f"| `{m.tracker}` | {_fmt(m.update)} | {_fmt(m.e2e)} | {_fmt(ratio, 1)} |")
        lines.append("")
        for key, label in (("particles", "particles N (640x480, 50x50)"),
                           ("target", "target side in px (640x480, N=100)"),
                           ("frame", "frame size (50x50, N=100)")):
            rows = {}
            vals = []
            for m in synth:
                c = m.config
                varies = {k: c[k] != REFERENCE[k] for k in REFERENCE}
                if any(v for k, v in varies.items() if k != key):
                    continue
                v = c[key]
                vals.append(v)
                rows.setdefault(m.tracker, {})[v if not isinstance(v, tuple) else f"{v[0]}x{v[1]}"] = m.update
            cols = []
            for v in vals:
                k = v if not isinstance(v, tuple) else f"{v[0]}x{v[1]}"
                if k not in cols:
                    cols.append(k)
            cols.sort(key=lambda k: (int(str(k).split("x")[0]) if isinstance(k, str) else k))
            if len(cols) < 2:  # nothing swept: the reference table above says it all
                continue
            lines += [f"### Update fps against {label}", "",
                      "| tracker | " + " | ".join(str(c) for c in cols) + " |", "|" + "---|" * (len(cols) + 1)]
            for t, r in rows.items():
                if len(r) == 1 and key == "particles":
                    continue
                lines.append(f"| `{t}` | " + " | ".join(_fmt(r.get(c, float('nan'))) for c in cols) + " |")
            lines.append("")
    if real:
        seqs = list(dict.fromkeys(m.config["sequence"] for m in real))
        trackers = list(dict.fromkeys(m.tracker for m in real))
        by = {(m.tracker, m.config["sequence"]): m for m in real}
        lines += ["## Real sequences: update fps (end-to-end fps)", "",
                  "| tracker | " + " | ".join(seqs) + f" | median | × {reference_peer} |",
                  "|" + "---|" * (len(seqs) + 3)]
        for t in trackers:
            ups = [by[(t, s)].update for s in seqs]
            ratios = [by[(t, s)].update / by[(reference_peer, s)].update for s in seqs
                      if (reference_peer, s) in by and by[(reference_peer, s)].update > 0]
            lines.append(f"| `{t}` | " + " | ".join(f"{_fmt(by[(t, s)].update)} ({_fmt(by[(t, s)].e2e)})" for s in seqs)
                         + f" | {_fmt(statistics.median(ups))} | "
                         + f"{_fmt(statistics.median(ratios), 1) if ratios else '–'} |")
        lines.append("")
    return "\n".join(lines)


def scaling_plot(synth: list[Measurement], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(14, 4.2), dpi=100)
    for ax, key, xl in zip(axes, ("particles", "target", "frame"),
                           ("particles N", "target side (px)", "frame pixels (millions)")):
        series: dict[str, list[tuple[float, float]]] = {}
        for m in synth:
            c = m.config
            if any(c[k] != REFERENCE[k] for k in REFERENCE if k != key):
                continue
            x = c[key]
            x = x[0] * x[1] / 1e6 if isinstance(x, tuple) else x
            series.setdefault(m.tracker, []).append((x, m.update))
        for t, pts in series.items():
            if len(pts) < 2:
                continue
            pts.sort()
            ax.plot([p[0] for p in pts], [p[1] for p in pts], marker="o", label=t)
        ax.set_xlabel(xl)
        ax.set_ylabel("update fps")
        ax.set_yscale("log")
        if key == "particles":
            ax.set_xscale("log")
        ax.grid(alpha=0.3, which="both")
    handles = [h for ax in axes for h in ax.get_lines()]
    if handles:
        axes[0].legend(handles=[h for h in axes[0].get_lines()] or handles, fontsize=7)
    fig.suptitle("Update speed on one core (synthetic clip; one parameter varied around 640x480, 50x50, N=100)")
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
