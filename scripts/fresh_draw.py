"""A fresh draw of every single-target scene kind, of neither split (docs/results.md, "Synthetic scenes drawn afresh").

    python scripts/fresh_draw.py --seeds 8200-8203 --out reports/fresh8200

Writes each kind's scenes with ``pftrack synth KIND --seeds SEEDS`` (the generators' own share of grey scenes) to
``OUT/scenes/KIND``, runs all of them in one ``pftrack eval`` (``fusion-pf``, ``color-pf`` and OpenCV CSRT unless
``--trackers`` says otherwise; 2 run seeds) into ``OUT/eval``, and prints the mean AUC by kind with the boxes' size,
and the lost flag's pooled rates by kind (``scripts/split_summary.py --by-kind``). The run's own summary is
``OUT/eval/summary.md``.

Seeds of the tune and report splits (GUIDE §8) are refused: the synthetic kinds' tune seeds 0-7 and report seeds
100-107, the photo scenes' 1000-1019 and 0-19. A draw of neither split is one that no choice of a default has seen;
which seeds earlier draws took is written in docs/results.md.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from split_summary import main as summary_by_kind  # noqa: E402

from pftrack.cli import main as pftrack  # noqa: E402
from pftrack.cli.common import parse_seeds  # noqa: E402

#: The single-target kinds of ``pftrack synth``, as the draws of docs/results.md take them.
KINDS = ("camouflage", "crossing", "entering", "exit", "face", "full-occlusion", "illumination", "leave", "occlusion",
         "photo-exit", "photo-leave", "photo-vanish", "simple", "teleport", "vanish", "varied", "waving")

#: Seed ranges (inclusive) that the tune and report splits draw their synthetic scenes from.
SPLIT_SEEDS = ((0, 19), (100, 107), (1000, 1019))


def split_seeds(seeds: list[int]) -> list[int]:
    """The seeds of ``seeds`` that belong to the tune or report split."""
    return [s for s in seeds if any(lo <= s <= hi for lo, hi in SPLIT_SEEDS)]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", required=True, help="scene seeds, e.g. 8200-8203 (none of the splits')")
    ap.add_argument("--out", required=True, help="folder for scenes/ and eval/")
    ap.add_argument("--kinds", default=",".join(KINDS), help="comma-separated kinds (default: all 17)")
    ap.add_argument("--trackers", default="fusion-pf,color-pf,opencv-csrt", help="as pftrack eval --trackers")
    ap.add_argument("--run-seeds", type=int, default=2, help="tracker seeds per scene (pftrack eval --seeds)")
    ap.add_argument("--workers", type=int, default=2, help="pftrack eval --workers")
    args = ap.parse_args(argv)
    try:
        seeds = parse_seeds(args.seeds)
    except ValueError as exc:
        ap.error(f"--seeds: {exc}")
    clash = split_seeds(seeds)
    if clash:
        ap.error(f"--seeds: {', '.join(map(str, clash[:5]))}{' ...' if len(clash) > 5 else ''} belong to the tune or "
                 "report split (GUIDE §8); a fresh draw takes other seeds")
    kinds = [k.strip() for k in args.kinds.split(",") if k.strip()]
    unknown = sorted(set(kinds) - set(KINDS))
    if unknown or not kinds:
        ap.error(f"--kinds: {', '.join(unknown) or 'none given'}; the kinds are {', '.join(KINDS)}")
    out = Path(args.out)
    seed_text = ",".join(map(str, seeds))
    for kind in kinds:
        rc = pftrack(["synth", kind, "--seeds", seed_text, "--out", str(out / "scenes" / kind)])
        if rc:
            return rc
    rc = pftrack(["eval", *(str(out / "scenes" / k) for k in kinds), "--trackers", args.trackers,
                  "--seeds", str(args.run_seeds), "--workers", str(args.workers), "--report", str(out / "eval"),
                  "--quiet"])
    if rc:
        return rc
    summary_by_kind(str(out / "eval" / "results.csv"), [str(out / "scenes")], kinds=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
