#!/usr/bin/env bash
# Regenerate docs/benchmarks.md: every tracker on the development sequences, then the fusion-pf ablation,
# each in one `pftrack eval` run (so speeds are comparable within a table).  One worker = one core per run.
# Usage: bash scripts/make_benchmarks.sh [DATA_DIR]   (default ../shared/data)
set -euo pipefail
cd "$(dirname "$0")/.."
DATA="${1:-../shared/data}"
PFTRACK="${PFTRACK:-.venv/bin/pftrack}"
OUT=docs/benchmarks.md
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# the trackers compared as ratios are always re-timed in this run (their cached runs are dropped)
rm -f reports/bench-all/runs/*__fusion-pf__* reports/bench-all/runs/*__color-pf__* reports/bench-all/runs/*__opencv-csrt__*
rm -f reports/bench-ablation/runs/*
"$PFTRACK" eval "$DATA" --trackers all --seeds 5 --workers 1 --report reports/bench-all \
  --title "All trackers on the development sequences (OTB one-pass)" --doc "$tmp/all.md" --quiet > /dev/null
"$PFTRACK" eval "$DATA" --seeds 5 --workers 1 --report reports/bench-ablation \
  --trackers "fusion-pf,fusion-pf[structure=false],fusion-pf[fused_loss=false],fusion-pf[reliability_d=0],fusion-pf[structure_anchor_gate=-1],fusion-pf[structure_weighting=kernel],fusion-pf[contrast=false],fusion-pf[motion=true],fusion-pf[search=false],fusion-pf[update_gate=never],fusion-pf[scale_rate_noise=0],color-pf,opencv-csrt" \
  --title "fusion-pf ablation (each row removes or changes one ingredient)" --doc "$tmp/ablation.md" --quiet > /dev/null

{
  echo "# Benchmarks"
  echo
  echo "Produced by \`bash scripts/make_benchmarks.sh\` (both tables below; each table is one \`pftrack eval\` run,"
  echo "so the speeds in a table were measured side by side — except that a rerun reuses the cached runs whose"
  echo "tracker and parameters did not change, so a tracker whose defaults changed is timed in the later run;"
  echo "\`fusion-pf\`, \`color-pf\` and CSRT, the trackers compared as ratios, are always re-timed in the run)."
  echo "Definitions: [evaluation.md](evaluation.md)."
  echo "Speed in detail (synthetic sweeps, end-to-end, ratios): [performance.md](performance.md)."
  echo
  echo "Every tracker on scenes of neither split, cut from photographs (40 scenes, one run seed each, lost rates and"
  echo "re-acquisitions): [robustness-cameras.md](robustness-cameras.md#every-tracker-on-the-photo-scenes)."
  echo
  echo "The ratio to CSRT depends on the sequences: CSRT's cost grows with the target's size and ours hardly does, so"
  echo "the line under each table gives it sequence by sequence too (lowest, median, highest)."
  echo
  sed 's/^# /## /; s/^## AUC/### AUC/; s/^## fps/### fps/' "$tmp/all.md"
  echo
  echo "### The same run by split (GUIDE §8)"
  echo
  echo "Defaults were chosen on the tune sequences only; the report sequences were never used to select them."
  echo '`python scripts/split_table.py reports/bench-all/results.csv`; fps over all nine sequences, ratio to CSRT'"'"'s.'
  echo
  "${PY:-.venv/bin/python}" scripts/split_table.py reports/bench-all/results.csv
  echo
  sed 's/^# /## /; s/^## AUC/### AUC/; s/^## fps/### fps/' "$tmp/ablation.md"
} > "$OUT"
echo "wrote $OUT" >&2
