"""MPEG-7 description of compressed-domain objects (book ch. 8 §4, Fig. 9; ch08.md §1.11).

One ``Video`` description per label with a ``MotionTrajectory`` (``MediaTimePoint`` of each key frame and the
x, y ``KeyValue`` of the box centroid), and a ``VideoSegment`` with ``MotionActivity/Intensity`` for each run of
frames whose activity level is "high" (>= 4).  Written with :mod:`xml.etree.ElementTree`: well formed, not
validated against the ISO schema (out of scope).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

NS = "urn:mpeg:mpeg7:schema:2001"
XSI = "http://www.w3.org/2001/XMLSchema-instance"


def _time_point(frame: int, fps: float) -> str:
    """``T00:00:01:5F25`` style media time (frame fractions at ``fps``)."""
    f = max(round(fps), 1)
    s, fr = divmod(int(frame) - 1, f)
    h, rem = divmod(s, 3600)
    m, s = divmod(rem, 60)
    return f"T{h:02d}:{m:02d}:{s:02d}:{fr}F{f}"


def write_mpeg7(trajectories: dict[int, list[tuple[int, float, float]]], activity: list[tuple[int, int]], path,
                *, fps: float = 25.0, high: int = 4) -> Path:
    """``trajectories``: label -> [(frame, cx, cy)]; ``activity``: [(frame, level 1-5)]."""
    ET.register_namespace("", NS)
    ET.register_namespace("xsi", XSI)
    root = ET.Element(f"{{{NS}}}Mpeg7")
    desc = ET.SubElement(root, f"{{{NS}}}Description", {f"{{{XSI}}}type": "ContentEntityType"})
    for label in sorted(trajectories):
        pts = sorted(trajectories[label])
        if not pts:
            continue
        mc = ET.SubElement(desc, f"{{{NS}}}MultimediaContent", {f"{{{XSI}}}type": "VideoType"})
        video = ET.SubElement(mc, f"{{{NS}}}Video", {"id": f"object{label}"})
        traj = ET.SubElement(video, f"{{{NS}}}MotionTrajectory", {"motionCoordRef": "image"})
        keys = ET.SubElement(traj, f"{{{NS}}}CoordKeyPoints")
        for frame, cx, cy in pts:
            tp = ET.SubElement(keys, f"{{{NS}}}MediaTimePoint")
            tp.text = _time_point(frame, fps)
        for axis, k in (("x", 1), ("y", 2)):
            kv = ET.SubElement(keys, f"{{{NS}}}KeyValue", {"dim": axis})
            kv.text = " ".join(f"{p[k]:.1f}" for p in pts)
    runs, start = [], None
    for i, (frame, level) in enumerate(activity):
        if level >= high and start is None:
            start = frame
        if start is not None and (level < high or i == len(activity) - 1):
            end = frame if level >= high else activity[i - 1][0]
            runs.append((start, end, max(lv for fr, lv in activity if start <= fr <= end)))
            start = None
    for start, end, level in runs:
        mc = ET.SubElement(desc, f"{{{NS}}}MultimediaContent", {f"{{{XSI}}}type": "VideoType"})
        seg = ET.SubElement(mc, f"{{{NS}}}VideoSegment")
        mt = ET.SubElement(seg, f"{{{NS}}}MediaTime")
        ET.SubElement(mt, f"{{{NS}}}MediaTimePoint").text = _time_point(start, fps)
        ET.SubElement(mt, f"{{{NS}}}MediaIncrDuration", {"mediaTimeUnit": f"PT1N{max(round(fps), 1)}F"}).text = \
            str(end - start + 1)
        ma = ET.SubElement(seg, f"{{{NS}}}MotionActivity")
        ET.SubElement(ma, f"{{{NS}}}Intensity").text = str(level)
    path = Path(path)
    ET.ElementTree(root).write(path, encoding="utf-8", xml_declaration=True)
    return path
