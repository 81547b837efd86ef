"""Book ch. 11 experiments (docs/handover.md): hand-over between two disjoint cameras cut from PETS.

    python scripts/ch11_experiments.py [--data ../shared/data] [--repeats 10] [--json reports/ch11.json]
    python scripts/ch11_experiments.py --seeds 300-309 [--response strong]   # a fresh draw of colour responses
    python scripts/ch11_experiments.py --oracle ...   # also the scene's true colour response as the BTF ('true')
    python scripts/ch11_experiments.py --histogram marginal ...   # the chapter's histograms, channel by channel
    python scripts/ch11_experiments.py --tune-seeds 3-9 ...   # more colour seeds on the tune frames (1-200)

Scenes (`pftrack synth twocam`): camera A sees the left part of the PETS frames, camera B the
right part through a seeded nonlinear colour response; the strip between them is blind.
Tune: frames 1-200, colour seeds 0-2; report: frames 201-400, colour seeds 100-104; each with
three positions of the blind strip.  In every scene the people seen in both cameras are split
`repeats` times at random into training people (40 %: their tracks fit the BTF and the
new-person threshold) and test people; we count the test hand-overs linked correctly by the
one-to-one assignment (`links`) and the fraction of all links that are such hand-overs
(`precision`), and rank-1: whether each test probe's most similar earlier
track of the other camera is the right one.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import cv2
import numpy as np

from pftrack.multicam.appearance import FEATURES, similarity_matrix
from pftrack.multicam.btf import (
    btf_from_hists,
    btf_subspace_loglik,
    fit_btf_subspace,
)
from pftrack.multicam.handover import (
    cooccur_threshold,
    describe_tracks,
    fit_btf,
    fit_transit,
    link_tracks,
    new_threshold,
    similarities,
)
from pftrack.synth.twocam import twocam_scene

SPLITS = ((300, 390), (340, 430), (380, 470))
NEW_QUANTILE = 0.25   # the new-person rule's quantile of co-occurring pairs, chosen on the tune scenes


def foreground(frames: dict) -> dict:
    bgs = cv2.createBackgroundSubtractorMOG2(500, 16, True)
    k = np.ones((3, 3), np.uint8)
    return {n: cv2.morphologyEx((bgs.apply(f) == 255).astype(np.uint8), cv2.MORPH_OPEN, k) for n, f in frames.items()}


def _rank1_hit(app_a, app_b, ex_a, ex_b, lut, a, b) -> bool:
    """Whether the test hand-over (a, b)'s probe (the later track) is most similar to its partner among the other
    camera's tracks that ended before it (training tracks excluded)."""
    if app_a[a].last < app_b[b].first:   # b is the probe, A tracks that ended before it
        cands = {k: app_a[k] for k in app_a if k not in ex_a and app_a[k].last < app_b[b].first}
        ka, _, s = similarities(cands, {b: app_b[b]}, lut)
        return ka[int(np.argmax(s[:, 0]))] == a
    cands = {k: app_b[k] for k in app_b if k not in ex_b and app_b[k].last < app_a[a].first}
    _, kb, s = similarities({a: app_a[a]}, cands, lut)
    return kb[int(np.argmax(s[0]))] == b


def _grey(frame: np.ndarray) -> np.ndarray:
    """A BGR frame as a grey camera gives it: three equal channels."""
    return cv2.cvtColor(cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY), cv2.COLOR_GRAY2BGR)


def scene_scores(sc, repeats: int, seed: int, oracle: bool = False, features=FEATURES,
                 histogram: str = "joint", grey: bool = False) -> dict:
    """Links, rank-1 and link counts per appearance and method in one scene; with ``oracle`` also the scene's own
    colour response used as the BTF (method ``true``: what a perfect estimate of the response would give)."""
    lo, hi = sc.numbers
    FA = {n: sc.frame_a(n) for n in range(lo, hi + 1)}
    FB = {n: sc.frame_b(n) for n in range(lo, hi + 1)}
    if grey:  # two grey cameras (camera B's colour response applied first)
        FA, FB = {n: _grey(f) for n, f in FA.items()}, {n: _grey(f) for n, f in FB.items()}
    fa, fb = foreground(FA), foreground(FB)
    ho = sc.handovers()
    persons = sorted({sc.identity[("a", a)] for a, _ in ho})
    out: dict = {}
    if len(persons) < 2:
        return out
    for feat in features:
        app_a = describe_tracks(FA.get, sc.tracks_a, feat, fg=fa.get, histogram=histogram)
        app_b = describe_tracks(FB.get, sc.tracks_b, feat, fg=fb.get, histogram=histogram)
        rng = np.random.default_rng(seed)
        for _ in range(repeats):
            perm = rng.permutation(persons)
            train = set(perm[:max(1, round(0.4 * len(persons)))].tolist())
            pairs = [(a, b) for (ca, a), pa in sc.identity.items() if ca == "a" and pa in train
                     for (cb, b), pb in sc.identity.items() if cb == "b" and pb == pa]
            test = [(a, b) for a, b in ho if sc.identity[("a", a)] not in train]
            if not test:
                continue
            ex_a, ex_b = [a for a, _ in pairs], [b for _, b in pairs]
            if feat == FEATURES[0] and len(pairs) >= 2:
                # the BTF-subspace extension (Javed et al.): rank-1 by the PPCA likelihood of the BTF between
                # the probe and each candidate (whole-foreground raw histograms, so once per scene and split)
                model = fit_btf_subspace(np.stack([btf_from_hists(app_a[a].raw, app_b[b].raw) for a, b in pairs]))
                r1s = 0
                for a, b in test:
                    if app_a[a].last < app_b[b].first:
                        cands = [k for k in app_a if k not in ex_a and app_a[k].last < app_b[b].first]
                        ll = [btf_subspace_loglik(model, btf_from_hists(app_a[k].raw, app_b[b].raw)) for k in cands]
                        r1s += cands[int(np.argmax(ll))] == a
                    else:
                        cands = [k for k in app_b if k not in ex_b and app_b[k].last < app_a[a].first]
                        ll = [btf_subspace_loglik(model, btf_from_hists(app_a[a].raw, app_b[k].raw)) for k in cands]
                        r1s += cands[int(np.argmax(ll))] == b
                acc_s = out.setdefault("BTF subspace (PPCA) rank-1 only", [0, 0, 0, 0])
                acc_s[1] += r1s
                acc_s[2] += len(test)
            for method in ("none", "mbtf", "cbtf", "cbtf-pixels") + (("true",) if oracle else ()):
                lut = sc.response.astype(np.float64) if method == "true" else fit_btf(app_a, app_b, pairs, method)
                tau = cooccur_threshold(app_a, app_b, lut, NEW_QUANTILE)
                if tau is None:
                    tau = new_threshold(app_a, app_b, pairs, method) if method != "true" else 0.0
                links = link_tracks(app_a, app_b, lut, tau_new=tau, exclude_a=ex_a, exclude_b=ex_b)
                ok = sum((a, b) in set(test) for a, b, _ in links)
                tr = fit_transit(app_a, app_b, pairs)
                links_t = link_tracks(app_a, app_b, lut, tau_new=tau, exclude_a=ex_a, exclude_b=ex_b, transit=tr)
                ok_t = sum((a, b) in set(test) for a, b, _ in links_t)
                acc_t = out.setdefault(f"{feat} {method} +transit", [0, 0, 0, 0])
                acc_t[0] += ok_t
                acc_t[2] += len(test)
                acc_t[3] += len(links_t)
                # the former rule: the threshold that best separates the training pairs from their impostors
                acc_p = out.setdefault(f"{feat} {method} pairs-rule", [0, 0, 0, 0]) if method != "true" else None
                if acc_p is not None:
                    links_p = link_tracks(app_a, app_b, lut, tau_new=new_threshold(app_a, app_b, pairs, method),
                                          exclude_a=ex_a, exclude_b=ex_b)
                    acc_p[0] += sum((a, b) in set(test) for a, b, _ in links_p)
                    acc_p[2] += len(test)
                    acc_p[3] += len(links_p)
                # rank-1: each test probe against the earlier tracks of the other camera (not training ones)
                r1 = sum(_rank1_hit(app_a, app_b, ex_a, ex_b, lut, a, b) for a, b in test)
                acc = out.setdefault(f"{feat} {method}", [0, 0, 0, 0])
                acc[0] += ok
                acc[1] += r1
                acc_t[1] += r1                             # rank-1 is appearance only
                if acc_p is not None:
                    acc_p[1] += r1
                acc[2] += len(test)
                acc[3] += len(links)
    return out


def intra_camera(data: Path, numbers, repeats: int, seed: int = 0) -> dict:
    """E11.1: within one camera (the PETS view), each patch of a person against the mean appearance of every
    person seen in the same frames' range; rank-1 per extraction method.  Each person's frames are split at
    random into gallery (half: the mean appearance) and probe frames (the other half), ``repeats`` times."""
    from pftrack.io.datasets import read_sequence
    from pftrack.multicam.appearance import region_histograms

    seq = read_sequence(data / "pets09_s2l1_dev")
    lo, hi = numbers
    gt = seq.mot_gt[(seq.mot_gt[:, 0] >= lo) & (seq.mot_gt[:, 0] <= hi)]
    frames = {n: cv2.imread(str(seq.frames[n - 1])) for n in range(lo, hi + 1)}
    fg = foreground(frames)
    ids = [int(i) for i in np.unique(gt[:, 1]) if np.sum(gt[:, 1] == i) >= 20]
    rng = np.random.default_rng(seed)
    out = {}
    for feat in FEATURES:
        per_person = {}
        for pid in ids:
            rows = gt[gt[:, 1] == pid]
            per_person[pid] = [region_histograms(frames[int(r[0])], r[2:6], feat, fg=fg[int(r[0])]) for r in rows[::2]]
        hits = total = 0
        for _ in range(repeats):
            gal, probes = {}, []
            for pid, hs in per_person.items():
                perm = rng.permutation(len(hs))
                half = len(hs) // 2
                gal[pid] = np.mean([hs[k] for k in perm[:half]], axis=0)
                probes += [(pid, hs[k]) for k in perm[half:]]
            G = np.stack([gal[p] for p in ids])
            for pid, h in probes:
                s = similarity_matrix(h[None], G)[0]
                hits += ids[int(np.argmax(s))] == pid
                total += 1
        out[feat] = hits / max(total, 1)
    return {"people": len(ids), "rank1": out}


def run(data: Path, numbers, seeds, repeats: int, response: str = "mild", oracle: bool = False, features=FEATURES,
        histogram: str = "joint", grey: bool = False) -> dict:
    per_scene: dict = {}
    total: dict = {}
    for sd in seeds:
        for sp in SPLITS:
            sc = twocam_scene(data / "pets09_s2l1_dev", sd, numbers=numbers, split=sp, response=response)
            sc_scores = scene_scores(sc, repeats, sd, oracle, features, histogram, grey)
            for k, (ok, r1, n, nl) in sc_scores.items():
                per_scene.setdefault(k, []).append(ok / n)
                t = total.setdefault(k, [0, 0, 0, 0])
                t[0] += ok
                t[1] += r1
                t[2] += n
                t[3] += nl
            print(numbers, sd, sp, {k: round(v[0] / v[2], 3) for k, v in sc_scores.items()}, flush=True)
    return {k: {"links": ok / n, "precision": ok / nl if nl else None, "rank1": r1 / n, "handovers": n,
                "links_scene_std": float(np.std(per_scene[k]))}
            for k, (ok, r1, n, nl) in total.items()}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", default="../shared/data")
    ap.add_argument("--repeats", type=int, default=10)
    ap.add_argument("--json", default="reports/ch11.json")
    ap.add_argument("--split", choices=["tune", "report", "both"], default="both")
    ap.add_argument("--seeds", default=None, help="colour seeds A-B or A,B,... of a fresh draw on the report frames "
                    "(201-400), instead of the splits' own (run once, after every choice)")
    ap.add_argument("--tune-seeds", default=None, help="colour seeds A-B or A,B,... on the tune frames (1-200), "
                    "instead of the splits' own")
    ap.add_argument("--features", default=",".join(FEATURES), help="appearances, comma-separated (default all)")
    ap.add_argument("--histogram", choices=["marginal", "joint"], default="joint",
                    help="compare joint colours (default since round 128) or the channels' histograms one by one "
                         "(the chapter's)")
    ap.add_argument("--grey", action="store_true", help="both cameras grey (three equal channels)")
    ap.add_argument("--intra", action="store_true", help="only E11.1 (intra-camera rank-1 per extraction method)")
    ap.add_argument("--response", choices=["mild", "strong"], default="mild",
                    help="camera B's colour response (pftrack.synth.twocam.RESPONSES); 'strong' is a stress test")
    ap.add_argument("--oracle", action="store_true",
                    help="also score the scene's own colour response as the BTF (method 'true'), a diagnostic")
    args = ap.parse_args()
    data = Path(args.data)
    if args.intra:
        for name, nums in (("tune frames 1-200", (1, 200)), ("report frames 201-400", (201, 400))):
            r = intra_camera(data, nums, args.repeats)
            print(f"E11.1 {name}: {r['people']} people, rank-1 " +
                  ", ".join(f"{k} {v:.3f}" for k, v in r["rank1"].items()), flush=True)
        return
    res = {}
    feats = [f for f in args.features.split(",") if f]
    if any(f not in FEATURES for f in feats):
        ap.error(f"--features: each of {', '.join(FEATURES)}")
    opts = dict(response=args.response, oracle=args.oracle, features=feats, histogram=args.histogram, grey=args.grey)

    def seed_list(text):
        lo, _, hi = text.partition("-")
        return list(range(int(lo), int(hi) + 1)) if hi else [int(v) for v in text.split(",")]

    if args.seeds:
        res[f"fresh: report frames 201-400, seeds {args.seeds}"] = run(data, (201, 400), seed_list(args.seeds),
                                                                     args.repeats, **opts)
    elif args.tune_seeds:
        res[f"tune frames 1-200, seeds {args.tune_seeds}"] = run(data, (1, 200), seed_list(args.tune_seeds),
                                                                args.repeats, **opts)
    elif args.split in ("tune", "both"):
        res["tune frames 1-200, seeds 0-2"] = run(data, (1, 200), [0, 1, 2], args.repeats, **opts)
    if args.split in ("report", "both") and not args.seeds and not args.tune_seeds:
        res["report frames 201-400, seeds 100-104"] = run(data, (201, 400), [100, 101, 102, 103, 104], args.repeats,
                                                          **opts)
    for name, table in res.items():
        print(name)
        for k, v in sorted(table.items()):
            prec = "   -  " if v["precision"] is None else f"{v['precision']:.3f}"
            print(f"  {k:28s} links {v['links']:.3f}  precision {prec}  rank-1 {v['rank1']:.3f}  "
                  f"(n = {v['handovers']}, "
                  f"scene std {v['links_scene_std']:.3f})")
    Path(args.json).parent.mkdir(parents=True, exist_ok=True)
    Path(args.json).write_text(json.dumps(res, indent=1) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
