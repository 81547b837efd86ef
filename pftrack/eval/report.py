"""Evaluation reports: results table, Markdown summary, plots and a static HTML page.

Everything is written inside the report folder the user named:

* ``results.csv`` — one row per run: ``tracker,sequence,seed,protocol,auc,precision,
  mean_iou,failures,accuracy,fps,frames,lost_frames`` and the columns of :data:`CSV_COLUMNS` after them;
* ``summary.md`` — per-tracker means and per-sequence tables (Markdown);
* ``success.png``, ``precision.png`` (OPE) and ``auc_per_sequence.png`` /
  ``failures_per_sequence.png`` (Matplotlib, Agg backend);
* ``frames/*.jpg`` — a few frames per sequence with the ground truth (green) and
  every tracker's box (seed 0);
* ``timelines/*.png`` — per one-pass sequence, each tracker's IoU per frame, its lost flag and the frames where
  the target is absent (:mod:`pftrack.eval.timeline`);
* ``index.html`` — one self-contained static page (no external resources) that
  links and shows all of the above.
"""

from __future__ import annotations

import csv
import html
import math
import re
from collections import defaultdict
from pathlib import Path
from typing import Iterable

import numpy as np

from ..io.sinks import prepare_output
from .jobs import ONE_PASS, TRE_SEGMENTS, failed
from .notes import (_num, _ratio, lost_notes, sequence_speed_ratios, speed_notes,  # noqa: F401
                    speed_peer, strict_speed_ratios)
from .paired import paired_html, paired_markdown, paired_reference
from .timeline import timelines

CSV_COLUMNS = ["tracker", "sequence", "seed", "protocol", "auc", "precision", "mean_iou", "failures", "accuracy",
               "fps", "frames", "lost_frames", "lost_recall", "false_lost", "absent_frames", "reappearances",
               "reacquired", "mota", "motp", "idf1", "id_rate", "num_switches", "num_fragmentations",
               "mostly_tracked", "mostly_lost", "num_false_positives", "num_misses", "e2e_fps", "covered_frames",
               "norm_precision", "start_frame", "error"]
MOT_FIELDS = ["mota", "motp", "idf1", "id_rate", "num_switches", "num_fragmentations", "mostly_tracked", "mostly_lost",
              "num_false_positives", "num_misses", "e2e_fps"]


def _mean(vals) -> float:
    vals = [v for v in vals if v is not None and math.isfinite(v)]
    return float(np.mean(vals)) if vals else float("nan")


def _median(vals) -> float:
    vals = [v for v in vals if v is not None and math.isfinite(v)]
    return float(np.median(vals)) if vals else float("nan")


def _fmt(v, nd=3) -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "–"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    return f"{v:.{nd}f}"


def _reacq(o: dict) -> str:
    n = int(o.get("reappearances") or 0)
    return f"{int(o.get('reacquired') or 0)}/{n}" if n else "–"


def aggregate(records: list[dict]) -> dict:
    """Per (tracker, sequence): means over seeds; per tracker: means over sequences."""
    per: dict[tuple[str, str], list[dict]] = defaultdict(list)
    for r in records:
        per[(r["tracker"], r["sequence"])].append(r)
    trackers = list(dict.fromkeys(r["tracker"] for r in records))
    sequences = list(dict.fromkeys(r["sequence"] for r in records))
    cell = {}
    for (t, s), rs in per.items():
        cell[(t, s)] = {
            "auc": _mean(_num(r.get("auc")) for r in rs),
            "precision": _mean(_num(r.get("precision")) for r in rs),
            "norm_precision": _mean(_num(r.get("norm_precision")) for r in rs),
            "mean_iou": _mean(_num(r.get("mean_iou")) for r in rs),
            "failures": _mean(_num(r.get("failures")) for r in rs),
            "accuracy": _mean(_num(r.get("accuracy")) for r in rs),
            "fps": _median(_num(r.get("fps")) for r in rs),
            "lost_recall": _mean(_num(r.get("lost_recall")) for r in rs),
            "false_lost": _mean(_num(r.get("false_lost")) for r in rs),
            "reappearances": sum(int(r.get("reappearances") or 0) for r in rs),
            "reacquired": sum(int(r.get("reacquired") or 0) for r in rs),
            "seeds": sorted(r["seed"] for r in rs),
            **{k: _mean(_num(r.get(k)) for r in rs) for k in MOT_FIELDS},
        }
    overall = {}
    for t in trackers:
        cells = [cell[(t, s)] for s in sequences if (t, s) in cell]
        overall[t] = {
            "auc": _mean(c["auc"] for c in cells),
            "precision": _mean(c["precision"] for c in cells),
            "norm_precision": _mean(c["norm_precision"] for c in cells),
            "mean_iou": _mean(c["mean_iou"] for c in cells),
            "failures": float(np.nansum([c["failures"] for c in cells])) if any(
                math.isfinite(c["failures"]) for c in cells) else float("nan"),
            "accuracy": _mean(c["accuracy"] for c in cells),
            "fps": _median(c["fps"] for c in cells),
            # the lost flag: means over the sequences where the rate is defined (absent / covered frames exist)
            "lost_recall": _mean(c["lost_recall"] for c in cells),
            "false_lost": _mean(c["false_lost"] for c in cells),
            "reappearances": sum(c["reappearances"] for c in cells),
            "reacquired": sum(c["reacquired"] for c in cells),
            "seeds": sorted({s for c in cells for s in c["seeds"]}),
            **{k: _mean(c[k] for c in cells) for k in MOT_FIELDS},
        }
    return {"trackers": trackers, "sequences": sequences, "cell": cell, "overall": overall}


def write_results_csv(records: list[dict], path: Path) -> None:
    with open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(CSV_COLUMNS)
        for r in records:
            w.writerow(["" if r.get(c) is None else (f"{r[c]:.6g}" if isinstance(r.get(c), float) else r[c])
                        for c in CSV_COLUMNS])


def _mot_markdown(records: list[dict], agg: dict, lines: list[str]) -> str:
    head = ["tracker", "MOTA", "MOTP", "IDF1", "id. rate", "ID switches", "fragmentations", "MT", "ML", "FP", "FN",
            "fps", "fps end to end"]
    keys = ["mota", "motp", "idf1", "id_rate", "num_switches", "num_fragmentations", "mostly_tracked", "mostly_lost",
            "num_false_positives", "num_misses", "fps", "e2e_fps"]
    nd = [3, 3, 3, 3, 1, 1, 1, 1, 0, 0, 0, 0]
    lines += ["Metrics from py-motmetrics (IoU >= 0.5); MOTP is motmetrics' mean (1 - IoU) of matches; id. rate is "
              "book ch. 1's identification rate (matched detections carrying their person's most frequent identity); "
              "counts are means over seeds; fps include detection, end to end also decoding.", "",
              "| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    order = sorted(agg["trackers"], key=lambda t: -np.nan_to_num(agg["overall"][t]["mota"], nan=-9))
    for t in order:
        o = agg["overall"][t]
        lines.append(f"| `{t}` | " + " | ".join(_fmt(o[k], n) for k, n in zip(keys, nd)) + " |")
    lines.append("")
    return "\n".join(lines)


def _one_pass(protocols) -> bool:
    """Are any of these protocols scored by the OTB curves (one pass from a first box: OPE, SRE, TRE)?"""
    return any(p in ONE_PASS for p in protocols)


def failure_lines(records: list[dict]) -> list[str]:
    """Markdown lines naming the failed runs (none when every run finished)."""
    bad = [r for r in records if failed(r)]
    if not bad:
        return []
    lines = [f"**{len(bad)} of {len(records)} runs failed**: the tracker raised. A failed one-pass run is scored "
             "with no box from the failed frame on, a failed MOT run with no track; a failed VOT run has no scores. "
             "The tracebacks are in the report folder's `failed/`.", "",
             "| tracker | sequence | seed | frame | error |", "|---|---|---|---|---|"]
    for r in bad:
        msg = str(r["error"]).replace("|", "\\|")
        lines.append(f"| `{r['tracker']}` | {r['sequence']} | {r['seed']} | {_fmt(r.get('error_frame'))} | {msg} |")
    return lines + [""]


def summary_markdown(records: list[dict], *, command: str | None = None, title: str = "Evaluation") -> str:
    agg = aggregate(records)
    protocols = sorted({r["protocol"] for r in records})
    lines = [f"# {title}", ""]
    if command:
        lines += ["Reproduce with:", "", "```", command, "```", ""]
    lines += failure_lines(records)
    seeds = sorted({r["seed"] for r in records})
    if protocols == ["mot"]:
        seqs = ", ".join(agg["sequences"])
        lines += [f"Protocol: mot. Sequences: {seqs}. Seeds: {', '.join(map(str, seeds))}.", ""]
        return _mot_markdown(records, agg, lines)
    runs = ("Runs: one per perturbed first box (the seed is its index)" if protocols == ["sre"] else
            "Runs: one per start frame (the seed is its index)" if protocols == ["tre"] else
            f"Seeds: {', '.join(map(str, seeds))} (deterministic trackers run once)")
    lines += [f"Protocol: {', '.join(protocols)}. {runs}. fps = update calls per second on one core, decode "
              "excluded; per sequence the median over seeds, overall the median over sequences.", ""]
    if "sre" in protocols:
        lines += ["SRE (OTB's spatial robustness evaluation): every tracker runs once from each of 12 perturbed first "
                  "boxes (shifted by 10 % of the size in 8 directions, scaled by 0.8, 0.9, 1.1, 1.2); the seed is the "
                  "perturbation, and the figures are means over the 12 runs, scored against the ground truth.", ""]
    if "tre" in protocols:
        lines += [f"TRE (OTB's temporal robustness evaluation): every tracker runs once from each of {TRE_SEGMENTS} "
                  "frames spread evenly over the sequence (the first is OPE's), with that frame's ground-truth box, "
                  "to the end; the seed is the start, and the figures are means over the runs, each scored on its "
                  "own frames.", ""]
    if _one_pass(protocols) or "vot" in protocols:
        lines += ["Single-object boxes are scored within the frame (both cut to the image, as the VOT toolkit does).",
                  ""]
    if _one_pass(protocols):
        lines += ["The lost flag as a detector: *lost recall* = fraction of the frames with the target absent or "
                  "fully hidden on which `lost` is raised; *false-lost rate* = fraction of the frames with IoU >= 0.5 "
                  "on which it is raised (means over the sequences where each is defined); *re-acquired* = "
                  "reappearances after which the target is covered with `lost` down within 15 frames.", ""]
    ope = _one_pass(protocols)
    vot = "vot" in protocols
    head = ["tracker"]
    if ope:
        head += ["mean AUC", "precision@20", "norm. precision", "lost recall", "false-lost rate", "re-acquired"]
    if vot:
        head += ["failures (sum)", "accuracy"]
    head += ["median fps"]
    peer = speed_peer(agg["trackers"])
    if peer is not None:
        head += [f"× {peer.removeprefix('opencv-').upper()}"]
    lines += ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    order = (sorted(agg["trackers"], key=lambda t: -np.nan_to_num(agg["overall"][t]["auc"], nan=-1)) if ope
             else agg["trackers"])
    for t in order:
        o = agg["overall"][t]
        row = [f"`{t}`"]
        if ope:
            row += [_fmt(o["auc"]), _fmt(o["precision"]), _fmt(o["norm_precision"]), _fmt(o["lost_recall"]),
                    _fmt(o["false_lost"]), _reacq(o)]
        if vot:
            row += [_fmt(o["failures"], 1), _fmt(o["accuracy"])]
        row += [_fmt(o["fps"], 0)]
        if peer is not None:
            row += [_fmt(_ratio(o["fps"], agg["overall"][peer]["fps"]), 1)]
        lines.append("| " + " | ".join(row) + " |")
    lines.append("")
    if ope and (pooled := lost_notes(records, order)):
        lines += pooled + [""]
    if peer is not None:
        lines += speed_notes(records, agg, peer, order) + [""]
    reference = paired_reference(agg["trackers"], peer) if ope else None
    if reference is not None:
        lines += paired_markdown(agg, reference, order)
    metric = "auc" if ope else "failures"
    label = "AUC" if ope else "failures"
    lines += [f"## {label} per sequence (mean over seeds)", ""]
    seqs = agg["sequences"]
    lines += ["| tracker | " + " | ".join(seqs) + " |", "|" + "---|" * (len(seqs) + 1)]
    for t in order:
        lines.append(f"| `{t}` | " + " | ".join(_fmt(agg["cell"].get((t, s), {}).get(metric), 3 if ope else 1)
                                                for s in seqs) + " |")
    if ope and any(math.isfinite(agg["cell"].get((t, s), {}).get("lost_recall", float("nan")))
                   for t in order for s in seqs):
        lines += ["", "## lost recall / false-lost rate per sequence (mean over seeds)", ""]
        lines += ["| tracker | " + " | ".join(seqs) + " |", "|" + "---|" * (len(seqs) + 1)]
        for t in order:
            cells = []
            for s in seqs:
                c = agg["cell"].get((t, s), {})
                cells.append(f"{_fmt(c.get('lost_recall'), 2)} / {_fmt(c.get('false_lost'), 2)}")
            lines.append(f"| `{t}` | " + " | ".join(cells) + " |")
    lines += ["", "## fps per sequence (median over seeds)", ""]
    lines += ["| tracker | " + " | ".join(seqs) + " |", "|" + "---|" * (len(seqs) + 1)]
    for t in order:
        lines.append(f"| `{t}` | " + " | ".join(_fmt(agg["cell"].get((t, s), {}).get("fps"), 0) for s in seqs) + " |")
    lines.append("")
    return "\n".join(lines)


def _plots(records: list[dict], out: Path) -> list[str]:
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    from .metrics import PRECISION_THRESHOLDS, THRESHOLDS

    made = []
    agg = aggregate(records)
    trackers, seqs = agg["trackers"], agg["sequences"]
    ope = [r for r in records if _one_pass([r["protocol"]]) and r.get("success")]
    if ope:
        for kind, xs, key, xl in (("success", THRESHOLDS, "success", "overlap threshold"),
                                  ("precision", PRECISION_THRESHOLDS, "precision_curve",
                                   "location error threshold (px)")):
            fig, ax = plt.subplots(figsize=(6, 4.5), dpi=100)
            for t in trackers:
                curves = [np.array([_num(v) for v in r[key]]) for r in ope if r["tracker"] == t]
                if not curves:
                    continue
                m = np.nanmean(np.vstack(curves), axis=0)
                score = np.mean(m) if kind == "success" else m[20]
                ax.plot(xs, m, label=f"{t} [{score:.3f}]")
            ax.set_xlabel(xl)
            ax.set_ylabel("success rate" if kind == "success" else "precision")
            ax.set_title(f"{'Success' if kind == 'success' else 'Precision'} plot of OPE")
            ax.set_ylim(0, 1)
            ax.grid(alpha=0.3)
            ax.legend(fontsize=7, loc="upper right" if kind == "success" else "lower right")
            fig.tight_layout()
            fig.savefig(out / f"{kind}.png")
            plt.close(fig)
            made.append(f"{kind}.png")
    if ope:
        metric, fname = "auc", "auc_per_sequence.png"
    elif any(r["protocol"] == "mot" for r in records):
        metric, fname = "mota", "mota_per_sequence.png"
    else:
        metric, fname = "failures", "failures_per_sequence.png"
    fig, ax = plt.subplots(figsize=(max(6, 1.2 * len(seqs) + 2), 4.5), dpi=100)
    width = 0.8 / max(1, len(trackers))
    for k, t in enumerate(trackers):
        vals = [agg["cell"].get((t, s), {}).get(metric, float("nan")) for s in seqs]
        ax.bar(np.arange(len(seqs)) + k * width, np.nan_to_num(vals), width, label=t)
    ax.set_xticks(np.arange(len(seqs)) + 0.4 - width / 2)
    ax.set_xticklabels(seqs, rotation=30, ha="right", fontsize=8)
    ax.set_ylabel({"auc": "OPE AUC", "mota": "MOTA", "failures": "VOT failures"}[metric])
    ax.legend(fontsize=7)
    ax.grid(axis="y", alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / fname)
    plt.close(fig)
    made.append(fname)
    return made


def _frames(records: list[dict], sequences: dict, out: Path, per_sequence: int = 3) -> dict[str, list[str]]:
    import cv2

    from ..io.datasets import Sequence, read_sequence
    from ..io.sources import read_image
    from ..viz.draw import color_for, draw_box

    (out / "frames").mkdir(exist_ok=True)
    trackers = list(dict.fromkeys(r["tracker"] for r in records))
    made: dict[str, list[str]] = {}
    for name, path in sequences.items():
        seq = path if isinstance(path, Sequence) else read_sequence(path)  # one target of a folder: its Sequence
        if seq.groundtruth is None:
            continue
        n = len(seq.frames)
        picks = sorted({int(round(f * (n - 1))) for f in np.linspace(0.25, 0.9, per_sequence)})
        files = []
        for t_idx in picks:
            img = read_image(seq.frames[t_idx])
            if img is None:
                continue
            from ..frames import as_bgr_uint8

            img = as_bgr_uint8(img)
            draw_box(img, seq.groundtruth[t_idx], (0, 255, 0), 2)
            for k, t in enumerate(trackers):
                recs = [r for r in records if r["tracker"] == t and r["sequence"] == name]
                if not recs:
                    continue
                rec = min(recs, key=lambda r: r["seed"])
                b = rec.get("boxes")
                if not b:
                    continue
                box = [_num(v) for v in b[4 * t_idx: 4 * t_idx + 4]]
                draw_box(img, box, color_for(k + 1), 1)
            cv2.putText(img, f"#{t_idx + 1}", (5, 16), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (255, 255, 255), 1)
            safe = re.sub(r"[^A-Za-z0-9_.-]+", "_", name).lstrip(".") or "sequence"
            fn = f"frames/{safe}_{t_idx + 1:05d}.jpg"
            cv2.imwrite(str(out / fn), img)
            files.append(fn)
        made[name] = files
    return made


def write_report(records: list[dict], report_dir: str | Path, *, sequences: dict | None = None,
                 command: str | None = None, title: str = "pftrack evaluation") -> dict[str, Path]:
    """Write the full report into ``report_dir``; returns the paths written.  ``sequences``: name -> the sequence
    (a :class:`~pftrack.io.datasets.Sequence`, or its folder) for the frames with the boxes drawn."""
    out = Path(report_dir)
    out.mkdir(parents=True, exist_ok=True)
    for name in ("results.csv", "summary.md", "index.html"):
        prepare_output(out / name, within=out)
    write_results_csv(records, out / "results.csv")
    md = summary_markdown(records, command=command, title=title)
    (out / "summary.md").write_text(md, encoding="utf-8")
    plots = _plots(records, out)
    frames = _frames(records, sequences or {}, out) if sequences else {}
    lines = timelines(records, sequences, out) if sequences else {}
    _html(records, out, plots, frames, command, title, lines)
    return {"results": out / "results.csv", "summary": out / "summary.md", "index": out / "index.html"}


def _html(records, out: Path, plots: Iterable[str], frames: dict[str, list[str]], command, title,
          lines: dict[str, str] | None = None) -> None:
    from ..viz.draw import color_for

    agg = aggregate(records)
    e = html.escape
    protocols = sorted({r["protocol"] for r in records})
    ope = _one_pass(protocols)
    peer = speed_peer(agg["trackers"]) if "mot" not in protocols else None
    rows = []
    for t in agg["trackers"]:
        o = agg["overall"][t]
        cells = [e(t)]
        if ope:
            cells += [_fmt(o["auc"]), _fmt(o["precision"]), _fmt(o["norm_precision"]), _fmt(o["lost_recall"]),
                      _fmt(o["false_lost"]), _reacq(o)]
        if "vot" in protocols:
            cells += [_fmt(o["failures"], 1), _fmt(o["accuracy"])]
        cells += [_fmt(o["fps"], 0)]
        if peer is not None:
            cells += [_fmt(_ratio(o["fps"], agg["overall"][peer]["fps"]), 1)]
        rows.append("<tr>" + "".join(f"<td>{c}</td>" for c in cells) + "</tr>")
    if "mot" in protocols:
        rows = []
        for t in agg["trackers"]:
            o = agg["overall"][t]
            cells = [e(t)] + [_fmt(o[k], n) for k, n in (("mota", 3), ("motp", 3), ("idf1", 3), ("num_switches", 1),
                                                         ("num_fragmentations", 1), ("fps", 0), ("e2e_fps", 0))]
            rows.append("<tr>" + "".join(f"<td>{c}</td>" for c in cells) + "</tr>")
    head = ["tracker"] + (["mean AUC", "precision@20", "norm. precision", "lost recall", "false-lost rate",
                           "re-acquired"] if ope
                          else []) + \
        (["failures", "accuracy"] if "vot" in protocols else []) + \
        (["MOTA", "MOTP", "IDF1", "ID switches", "fragmentations", "fps", "fps end to end"] if "mot" in protocols
         else ["median fps"]) + ([f"× {peer.removeprefix('opencv-').upper()}"] if peer is not None else [])
    legend = " ".join(
        f'<span style="color:rgb({c[2]},{c[1]},{c[0]})">&#9632; {e(t)}</span>'
        for t, c in ((t, color_for(k + 1)) for k, t in enumerate(agg["trackers"])))
    parts = [
        "<!DOCTYPE html>", "<html><head><meta charset='utf-8'>", f"<title>{e(title)}</title>",
        "<style>body{font-family:sans-serif;margin:2em;max-width:1200px}table{border-collapse:collapse}"
        "td,th{border:1px solid #ccc;padding:4px 8px;text-align:right}td:first-child{text-align:left}"
        "img{max-width:100%;margin:4px}.frames img{max-width:32%}</style></head><body>",
        f"<h1>{e(title)}</h1>",
    ]
    if command:
        parts.append(f"<p>Command: <code>{e(command)}</code></p>")
    parts += [
        f"<p>Protocols: {e(', '.join(protocols))}. Files: <a href='results.csv'>results.csv</a>, "
        "<a href='summary.md'>summary.md</a>.</p>",
        "<table><tr>" + "".join(f"<th>{e(h)}</th>" for h in head) + "</tr>" + "".join(rows) + "</table>",
    ]
    notes = (lost_notes(records, agg["trackers"]) if ope else []) + (
        speed_notes(records, agg, peer, agg["trackers"]) if peer is not None else [])
    parts += ["<p>" + re.sub(r"`([^`]+)`", r"<code>\1</code>", e(line)) + "</p>" for line in notes]
    reference = paired_reference(agg["trackers"], peer) if ope else None
    if reference is not None:
        parts.append(paired_html(agg, reference, agg["trackers"]))
    bad = [r for r in records if failed(r)]
    if bad:
        parts.append(f"<h2>Failed runs: {len(bad)} of {len(records)}</h2><p>The tracker raised; tracebacks in "
                     "<code>failed/</code>.</p><table><tr><th>tracker</th><th>sequence</th><th>seed</th>"
                     "<th>frame</th><th>error</th></tr>" +
                     "".join(f"<tr><td>{e(r['tracker'])}</td><td>{e(r['sequence'])}</td><td>{r['seed']}</td>"
                             f"<td>{_fmt(r.get('error_frame'))}</td><td>{e(str(r['error']))}</td></tr>"
                             for r in bad) + "</table>")
    for p in plots:
        parts.append(f"<div><a href='{e(p)}'><img src='{e(p)}' alt='{e(p)}'></a></div>")
    if frames or lines:
        parts.append(f"<h2>Sequences</h2><p>Frames: ground truth in green; {legend}. Timelines: each tracker's "
                     "overlap per frame, its lost flag (bars) and the frames where the target is absent (shaded).</p>")
        for seq in dict.fromkeys([*(lines or {}), *frames]):
            parts.append(f"<h3>{e(seq)}</h3>")
            if lines and seq in lines:
                parts.append(f"<div><img src='{e(lines[seq])}' alt='{e(lines[seq])}'></div>")
            parts.append("<div class='frames'>" +
                         "".join(f"<img src='{e(f)}' alt='{e(f)}'>" for f in frames.get(seq, [])) + "</div>")
    parts.append("</body></html>")
    (out / "index.html").write_text("\n".join(parts), encoding="utf-8")
