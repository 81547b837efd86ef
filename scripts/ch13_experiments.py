"""Book ch. 13 experiments (docs/surfaces.md): deformable-surface tracking with and without the photometric warp.

    python scripts/ch13_experiments.py [--part select,t1,t2,real,lcurve,t4,t6,speed] [--json reports/ch13.json]

Synthetic deforming sheets (`pftrack synth deform`): smooth warps up to ~12 px, shading 0.6-1.3, noise 0.01.
* select: lambda chosen on the tune seeds 0-4 (mean vertex RMSE);
* t1: single-frame accuracy at displacements 2-25 px with 1-4 pyramid levels (report seeds 100-104);
* t2: 60-frame sequences, report seeds 100-107: vertex RMSE and frame-coordinate RMSE (Fig. 5 metric) with and
  without the photometric term;
* real: the same on textures cut from frames of the real dev sequences, JPEG quality 85 (what ch13.md §5.3
  proposes while no real deforming-surface clip is bundled);
* lcurve: E_D and E_S over the chapter's lambda values (Fig. 7) on tune seed 0;
* t4: 300 frames, analysis by synthesis against frame-to-frame chaining (report seeds 100-104);
* t6: stabilised kymograms: camera jitter removed, a local vibration kept, over the mesh's stiffness (report seeds
  100-104);
``--seeds`` (e.g. 300-307) replaces the report seeds of t1, t2, t4 and t6 by others: a fresh draw of neither split.
* speed: frames per second at 480x360 with a 7x7 mesh, and at 768x1024 with a 300x300 region and 20 px spacing.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import cv2
import numpy as np

from pftrack.cli.common import parse_seeds
from pftrack.surfaces.render import frame_rmse
from pftrack.surfaces.tracker import DeformableMesh, MeshParams, gray01
from pftrack.synth.deform import deform_scene, render_frames

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"


def run_sequence(sc, **kw):
    tr = DeformableMesh(MeshParams(**kw))
    tr.init(sc.frames[0], sc.box)
    verr, ferr, t_upd, lost = [], [], 0.0, 0
    I0 = gray01(sc.frames[0])
    for n in range(1, len(sc.frames)):
        t0 = time.perf_counter()
        st = tr.update(sc.frames[n])
        t_upd += time.perf_counter() - t0
        lost += st.lost
        Vt, _ = sc.truth(n, tr.V0)
        verr.append(float(np.sqrt(np.mean(np.sum((st.info["mesh"] - Vt) ** 2, 1)))))
        ferr.append(frame_rmse(I0, gray01(sc.frames[n]), tr.V0, st.info["mesh"], tr.grid.triangles(),
                               tr.rho if tr.params.photometric else None, tr.pgrid))
    return {"vertex_rmse": float(np.mean(verr)), "vertex_rmse_max": float(np.max(verr)),
            "frame_rmse": float(np.nanmean(ferr)), "fps": (len(sc.frames) - 1) / t_upd, "lost": int(lost)}


def part_select(out):
    lams = [0.001, 0.002, 0.005, 0.01, 0.02, 0.05]
    res = {}
    scenes = [deform_scene(s) for s in range(5)]
    for lam in lams:
        r = [run_sequence(sc, lam=lam) for sc in scenes]
        res[lam] = float(np.mean([x["vertex_rmse"] for x in r]))
        print(f"select lam={lam}: tune mean vertex RMSE {res[lam]:.3f} px", flush=True)
    out["select"] = res


#: The report seeds of t1, t4 and t6 (t2: ``T2_SEEDS``) unless ``--seeds`` draws fresh ones.
REPORT_SEEDS = tuple(range(100, 105))


def part_t1(out, seeds=None):
    """One frame from the model: a global shift of A px in a random direction plus bumps of amplitude A/5."""
    rows = []
    for A in (2, 5, 10, 25):
        for levels in (1, 2, 3, 4):
            errs = []
            for seed in seeds or REPORT_SEEDS:
                sc = deform_scene(seed, n_frames=2, amplitude=A / 5.0, shading=False)
                ang = np.random.default_rng(seed).uniform(0, 2 * np.pi)
                sc.drift[1] = A * np.array([np.cos(ang), np.sin(ang)])
                frames = render_frames(sc, np.random.default_rng(seed))
                tr = DeformableMesh(MeshParams(levels=levels, max_iter=20))
                tr.init(frames[0], sc.box)
                st = tr.update(frames[1])
                Vt, _ = sc.truth(1, tr.V0)
                errs.append(float(np.mean(np.linalg.norm(st.info["mesh"] - Vt, axis=1))))
            rows.append({"A": A, "levels": levels, "mean_vertex_error": float(np.mean(errs)),
                         "worst": float(np.max(errs))})
            print(f"t1 A={A:2d}px levels={levels}: mean vertex error {np.mean(errs):.3f} px (worst {np.max(errs):.2f})",
                  flush=True)
    out["t1"] = rows


def _compare(scenes, label, out):
    rows = []
    for name, sc in scenes:
        a = run_sequence(sc)
        b = run_sequence(sc, photometric=False)
        rows.append({"scene": name, "photometric": a, "classical": b})
        print(f"{label} {name}: vertex RMSE {a['vertex_rmse']:.3f} vs {b['vertex_rmse']:.3f} px "
              f"(+{100 * (b['vertex_rmse'] / a['vertex_rmse'] - 1):.0f} %), frame RMSE {a['frame_rmse']:.4f} vs "
              f"{b['frame_rmse']:.4f} (-{100 * (1 - a['frame_rmse'] / b['frame_rmse']):.0f} %), fps {a['fps']:.1f}, "
              f"lost {a['lost']}/{b['lost']}", flush=True)
    va = np.mean([r["photometric"]["vertex_rmse"] for r in rows])
    vb = np.mean([r["classical"]["vertex_rmse"] for r in rows])
    fa = np.mean([r["photometric"]["frame_rmse"] for r in rows])
    fb = np.mean([r["classical"]["frame_rmse"] for r in rows])
    med = float(np.median([r["photometric"]["fps"] for r in rows]))
    print(f"{label} mean: vertex RMSE {va:.3f} vs {vb:.3f} px (raised {100 * (vb / va - 1):.0f} % without the "
          f"photometric term); frame RMSE {fa:.4f} vs {fb:.4f} (reduction {100 * (1 - fa / fb):.0f} %); "
          f"median fps {med:.1f}", flush=True)
    out[label] = {"rows": rows, "vertex_rmse": [va, vb], "frame_rmse": [fa, fb], "median_fps": med}


#: The sheets of t2: the report seeds unless ``--seeds`` draws fresh ones (of neither split).
T2_SEEDS = tuple(range(100, 108))


def part_t2(out, seeds=None):
    _compare([(f"seed{s}", deform_scene(s)) for s in (seeds or T2_SEEDS)], "t2", out)


def real_textures() -> list:
    """``(sequence, texture in [0.1, 0.9])`` from the first frame of each report sequence of ../shared/data."""
    textures = []
    for seq in ("otb_motorrolling", "tld_pedestrian2", "davis16_blackswan", "davis16_car-shadow"):
        d = DATA / seq
        imgs = sorted(p for p in d.rglob("*") if p.suffix.lower() in (".jpg", ".png") and "mask" not in str(p).lower()
                      and "annotation" not in str(p).lower())
        if not imgs:
            continue
        g = cv2.imread(str(imgs[0]), cv2.IMREAD_GRAYSCALE).astype(np.float64) / 255.0
        textures.append((seq, 0.1 + 0.8 * g))
    return textures


def part_real(out):
    textures = real_textures()
    if not textures:
        print("real: ../shared/data not found; skipped")
        return
    _compare([(name, deform_scene(100 + i, texture=t, jpeg=85)) for i, (name, t) in enumerate(textures)], "real", out)


def part_lcurve(out):
    sc = deform_scene(0)
    rows = []
    for lam in (0.0001, 0.001, 0.002, 0.005, 0.01, 0.1, 1, 10):
        tr = DeformableMesh(MeshParams(lam=lam))
        tr.init(sc.frames[0], sc.box)
        ed, es, ve = [], [], []
        for n in range(1, len(sc.frames)):
            st = tr.update(sc.frames[n])
            e_d, e_s = tr.solver.energies(tr.d, tr.rho, gray01(sc.frames[n]))
            ed.append(e_d)
            es.append(e_s)
            Vt, _ = sc.truth(n, tr.V0)
            ve.append(np.sqrt(np.mean(np.sum((st.info["mesh"] - Vt) ** 2, 1))))
        rows.append({"lam": lam, "E_D": float(np.mean(ed)), "E_S": float(np.mean(es)),
                     "vertex_rmse": float(np.mean(ve))})
        print(f"lcurve lam={lam:g}: E_D {np.mean(ed):.3e} E_S {np.mean(es):.3e} "
              f"vertex RMSE {np.mean(ve):.3f}", flush=True)
    x = np.log10([r["E_D"] for r in rows])
    y = np.log10(np.maximum([r["E_S"] for r in rows], 1e-30))
    dx, dy = np.gradient(x), np.gradient(y)
    ddx, ddy = np.gradient(dx), np.gradient(dy)
    curv = np.abs(dx * ddy - dy * ddx) / np.maximum((dx * dx + dy * dy) ** 1.5, 1e-12)
    k = int(np.argmax(curv[1:-1]) + 1)
    print(f"lcurve corner (max curvature): lam={rows[k]['lam']:g}", flush=True)
    out["lcurve"] = {"rows": rows, "corner": rows[k]["lam"]}


def part_t4(out, seeds=None):
    """ch13.md T4: 300 frames, analysis by synthesis (reference I_0) against frame-to-frame chaining (reference: the
    previous real frame in model coordinates). Mean vertex error at frames 10 and 300, and over frames 6-15 and
    291-300 (a single frame's error is noisy)."""
    rows = []
    for seed in seeds or REPORT_SEEDS:
        sc = deform_scene(seed, n_frames=301)
        row = {"seed": seed}
        for ref in ("model", "previous"):
            tr = DeformableMesh(MeshParams(reference=ref))
            tr.init(sc.frames[0], sc.box)
            e, lost = [np.nan], 0
            for n in range(1, len(sc.frames)):
                st = tr.update(sc.frames[n])
                lost += st.lost
                e.append(float(np.mean(np.linalg.norm(st.info["mesh"] - sc.truth(n, tr.V0)[0], axis=1))))
            e = np.array(e)
            row[ref] = {"err10": e[10], "err300": e[300], "ratio": e[300] / e[10],
                        "win_early": float(np.mean(e[6:16])), "win_late": float(np.mean(e[291:301])),
                        "win_ratio": float(np.mean(e[291:301]) / np.mean(e[6:16])), "mean": float(np.nanmean(e)),
                        "lost": int(lost)}
            r = row[ref]
            print(f"t4 seed {seed} {ref:8s}: error at 10 {r['err10']:.3f} px, at 300 {r['err300']:.3f} px "
                  f"(x{r['ratio']:.2f}); frames 6-15 {r['win_early']:.3f}, 291-300 {r['win_late']:.3f} "
                  f"(x{r['win_ratio']:.2f}); mean {r['mean']:.3f}; lost {lost}", flush=True)
        rows.append(row)
    for ref in ("model", "previous"):
        ratios = [r[ref]["ratio"] for r in rows]
        print(f"t4 {ref}: ratio 300/10 {min(ratios):.2f}-{max(ratios):.2f} (median {np.median(ratios):.2f}); "
              f"window ratio median {np.median([r[ref]['win_ratio'] for r in rows]):.2f}; mean error "
              f"{np.mean([r[ref]['mean'] for r in rows]):.3f} px", flush=True)
    out["t4"] = rows


def kymo_measure(ks, roi=None, **kw):
    """T6's figures for one scene (``synth.deform.kymo_scores``) with ``deformable-mesh`` of parameters ``kw``
    stabilising the region ``roi`` (default: the scene's)."""
    from pftrack.surfaces.kymograph import stabilising_transform
    from pftrack.synth.deform import kymo_scores

    sc, roi = ks.scene, roi or ks.roi
    tr = DeformableMesh(MeshParams(**kw))
    tr.init(sc.frames[0], ks.box)
    transforms = []
    for n in range(1, len(sc.frames)):
        tr.update(sc.frames[n])
        transforms.append(stabilising_transform(tr.grid, tr.d, roi, tr.params.model))
    return kymo_scores(ks, transforms, roi)


def part_t6(out, seeds=None):
    """ch13.md T6 (kymography-like stiffness): camera jitter of at most 5 px and a 3 px vibration in a 40 x 40 patch
    (`pftrack synth kymo`, report seeds 100-104, 100 frames). The region of the scene (240 x 180 px) with the default
    7 x 7 mesh, and a tight 80 x 80 region around the patch with a dense 16 x 16 mesh, over the stiffness."""
    from pftrack.synth.deform import kymo_scene

    cases = [("scene region, 7x7", None, 7, lam) for lam in (0.005, 0.5)]
    cases += [("tight 80x80, 16x16", "tight", 16, lam) for lam in (0.005, 0.05, 0.5, 5.0)]
    scenes = [kymo_scene(seed) for seed in seeds or REPORT_SEEDS]
    rows = []
    for label, roi, mesh, lam in cases:
        rs = []
        for ks in scenes:
            c = ks.centre
            rs.append(kymo_measure(ks, (c[0] - 40, c[1] - 40, 80, 80) if roi == "tight" else None, rows=mesh,
                                   cols=mesh, lam=lam))
        row = {"case": label, "lam": lam, "residual": float(np.mean([r["residual"] for r in rs])),
               "residual_max": float(np.max([r["residual_max"] for r in rs])),
               "raw": float(np.mean([r["raw"] for r in rs])),
               "survival_min": float(np.min([r["survival"] for r in rs])),
               "survival_mean": float(np.mean([r["survival"] for r in rs]))}
        rows.append(row)
        print(f"t6 {label} lam={lam:g}: residual global motion {row['residual']:.3f} px (worst frame "
              f"{row['residual_max']:.3f}; {row['raw']:.2f} unstabilised), vibration kept {row['survival_mean']:.3f} "
              f"(lowest {row['survival_min']:.3f})", flush=True)
    out["t6"] = rows


def part_speed(out):
    sc = deform_scene(101, n_frames=31)
    r = run_sequence(sc)
    big = deform_scene(102, n_frames=16, size=(1024, 768))
    x, y, w, h = big.box
    box = (x + w / 2 - 150, y + h / 2 - 150, 300, 300)
    big.box = box
    tr = DeformableMesh(MeshParams(cols=16, rows=16))
    tr.init(big.frames[0], box)
    t0 = time.perf_counter()
    for f in big.frames[1:]:
        tr.update(f)
    fps_big = (len(big.frames) - 1) / (time.perf_counter() - t0)
    print(f"speed: 480x360 7x7 {r['fps']:.1f} fps; 768x1024 region 300x300 16x16 mesh {fps_big:.1f} fps "
          f"({1000 / fps_big:.0f} ms/frame)", flush=True)
    out["speed"] = {"fps_480x360_7x7": r["fps"], "fps_768x1024_300px_16x16": fps_big}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--part", default="select,t1,t2,real,lcurve,t4,t6,speed")
    ap.add_argument("--json")
    ap.add_argument("--seeds", help="t1, t2, t4 and t6's scenes instead of the report seeds, e.g. 300-307 (a fresh "
                                    "draw of neither split)")
    a = ap.parse_args()
    out: dict = {}
    seeds = parse_seeds(a.seeds) if a.seeds else None
    parts = {"select": part_select, "t1": lambda o: part_t1(o, seeds), "t2": lambda o: part_t2(o, seeds),
             "real": part_real, "lcurve": part_lcurve, "t4": lambda o: part_t4(o, seeds),
             "t6": lambda o: part_t6(o, seeds), "speed": part_speed}
    for p in a.part.split(","):
        parts[p](out)
    if a.json:
        Path(a.json).parent.mkdir(parents=True, exist_ok=True)
        Path(a.json).write_text(json.dumps(out, indent=1, default=float))


if __name__ == "__main__":
    main()
