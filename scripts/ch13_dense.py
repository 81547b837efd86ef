"""Book ch. 13's dense (per-pixel) model against the mesh models (docs/surfaces.md, "The dense model").

    python scripts/ch13_dense.py [--part select,compare,real,speed] [--frames 30] [--json reports/ch13_dense.json]

Synthetic deforming sheets (`pftrack synth deform`), two kinds:
* smooth: the default scenes, four bumps of 0.18-0.3 of the box's shorter side, up to ~12 px;
* fine: bumps 0.4 times as wide (about 14-24 px, finer than the 7 x 7 mesh's 40 px cells), up to ~6 px.

The error is the mean distance between the estimated and the true displacement on a 31 x 25 grid of points over
the box (the field, not only the vertices), over every frame.

* select: `dense_lam` chosen on the tune seeds 0-4 of both kinds (lowest mean field error), from 1, 3, 10 (20 frames);
* compare: report seeds 100-104 of both kinds, run once with the selected default: dense against the 7 x 7 and
  13 x 13 affine meshes, and dense without its photometric warp (field error, frame RMSE of the chapter's Fig. 5 metric
  with a mesh every 4 px, seconds per frame);
* real: the same comparison on textures cut from the first frames of the four report sequences, JPEG quality 85
  (report seeds 100-103; skipped without ../shared/data);
* speed: seconds per frame of the dense model with each preconditioner at three region sizes (the last is
  T5's 768 x 1024 frame, with the scene's 512 x 430 region).
"""

from __future__ import annotations

import argparse
import json
import resource
import time
from pathlib import Path

import numpy as np

from pftrack.surfaces.mesh import Grid, displacement_at
from pftrack.surfaces.render import frame_rmse
from pftrack.surfaces.tracker import DeformableMesh, MeshParams, gray01
from pftrack.synth.deform import FINE, deform_scene

KINDS = {"smooth": {}, "fine": FINE}


def scene(kind: str, seed: int, frames: int):
    return deform_scene(seed, n_frames=frames, **KINDS[kind])


def run(sc, **kw) -> dict:
    """Field error, frame RMSE and seconds per frame of one tracker configuration on one scene."""
    tr = DeformableMesh(MeshParams(**kw))
    tr.init(sc.frames[0], sc.box)
    P = Grid.for_box(sc.box, 25, 31).vertices()
    I0 = gray01(sc.frames[0])
    ferr, rmse, t_upd, lost = [], [], 0.0, 0
    for n in range(1, len(sc.frames)):
        t0 = time.perf_counter()
        st = tr.update(sc.frames[n])
        t_upd += time.perf_counter() - t0
        lost += st.lost
        grid, V0, V, rho, pgrid, model = tr.surface_mesh()      # the dense model's: a mesh every 4 px
        D = displacement_at(grid, P, V - V0, model)
        ferr.append(float(np.mean(np.linalg.norm(D - sc.displacement(n, P), axis=1))))
        rmse.append(frame_rmse(I0, gray01(sc.frames[n]), V0, V, grid.triangles(),
                               rho if tr.params.photometric else None, pgrid, model))
    return {"field_error": float(np.mean(ferr)), "frame_rmse": float(np.nanmean(rmse)),
            "s_per_frame": t_upd / (len(sc.frames) - 1), "lost": int(lost)}


def part_select(out, frames):
    res = {}
    scenes = [(k, s, scene(k, s, min(frames, 20))) for k in KINDS for s in range(5)]
    for lam in (1.0, 3.0, 10.0):
        rows = {f"{k}{s}": run(sc, model="dense", dense_lam=lam) for k, s, sc in scenes}
        res[lam] = {"mean_field_error": float(np.mean([r["field_error"] for r in rows.values()])), "rows": rows}
        print(f"select dense_lam={lam}: tune mean field error {res[lam]['mean_field_error']:.4f} px "
              "(" + ", ".join(f"{k} {r['field_error']:.3f}" for k, r in rows.items()) + ")", flush=True)
    best = min(res, key=lambda lam: res[lam]["mean_field_error"])
    print(f"select: dense_lam = {best}", flush=True)
    out["select"] = {"best": best, "by_lam": res}


CONFIGS = {"dense": {"model": "dense"}, "mesh 7x7": {}, "mesh 13x13": {"rows": 13, "cols": 13},
           "dense, no photometric": {"model": "dense", "photometric": False}}


def part_compare(out, frames):
    table = {}
    for kind in KINDS:
        for seed in range(100, 105):
            sc = scene(kind, seed, frames)
            for name, kw in CONFIGS.items():
                r = run(sc, **kw)
                table.setdefault(kind, {}).setdefault(name, []).append(r)
                print(f"compare {kind} seed {seed} {name}: field error {r['field_error']:.3f} px, frame RMSE "
                      f"{r['frame_rmse']:.4f}, {r['s_per_frame']:.2f} s/frame, lost {r['lost']}", flush=True)
    summary = {}
    for kind, byname in table.items():
        for name, rows in byname.items():
            m = {k: float(np.mean([r[k] for r in rows])) for k in ("field_error", "frame_rmse", "s_per_frame")}
            summary[f"{kind} / {name}"] = m
            print(f"compare {kind:6s} {name:22s}: field error {m['field_error']:.3f} px, frame RMSE "
                  f"{m['frame_rmse']:.4f}, {m['s_per_frame']:.2f} s/frame", flush=True)
    out["compare"] = {"rows": table, "summary": summary}


def part_real(out, frames):
    """The comparison on textures cut from the report sequences' first frames, JPEG quality 85 (the same scenes as
    ch13_experiments.py's real part, 30 frames)."""
    from ch13_experiments import real_textures          # the sibling script (scripts/ is on the path when run)

    textures = real_textures()
    if not textures:
        print("real: ../shared/data not found; skipped")
        return
    table = {}
    for i, (name, tex) in enumerate(textures):
        sc = deform_scene(100 + i, n_frames=frames, texture=tex, jpeg=85)
        for cname, kw in CONFIGS.items():
            r = run(sc, **kw)
            table.setdefault(name, {})[cname] = r
            print(f"real {name} {cname}: field error {r['field_error']:.3f} px, frame RMSE {r['frame_rmse']:.4f}, "
                  f"{r['s_per_frame']:.2f} s/frame, lost {r['lost']}", flush=True)
    for cname in CONFIGS:
        fe = np.mean([table[n][cname]["field_error"] for n in table])
        fr = np.mean([table[n][cname]["frame_rmse"] for n in table])
        print(f"real mean {cname:22s}: field error {fe:.3f} px, frame RMSE {fr:.4f}", flush=True)
    out["real"] = table


def part_speed(out, frames):
    rows = []
    for size in ((360, 480), (540, 720), (768, 1024)):
        sc = deform_scene(101, n_frames=6, size=size)
        for solver in ("amg", "lu"):          # amg first: the process's peak memory only grows
            tr = DeformableMesh(MeshParams(model="dense", dense_solver=solver))
            tr.init(sc.frames[0], sc.box)
            tr.update(sc.frames[1])                     # the preconditioners are built on the first frame
            t0 = time.perf_counter()
            for n in range(2, 6):
                tr.update(sc.frames[n])
            s = (time.perf_counter() - t0) / 4
            rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
            rows.append({"size": list(size), "pixels": tr.dense.K, "solver": solver, "s_per_frame": s,
                         "max_rss_mb": rss})
            print(f"speed {size[1]}x{size[0]} ({tr.dense.K} pixels) {solver}: {s:.2f} s/frame "
                  f"(peak memory of the process so far {rss:.0f} MB)", flush=True)
    out["speed"] = rows


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--part", default="select,compare,real,speed")
    ap.add_argument("--frames", type=int, default=30)
    ap.add_argument("--json", default="reports/ch13_dense.json")
    a = ap.parse_args()
    out: dict = {}
    path = Path(a.json)
    if path.exists():
        out = json.loads(path.read_text())
    for part in a.part.split(","):
        {"select": part_select, "compare": part_compare, "real": part_real, "speed": part_speed}[part](out, a.frames)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
