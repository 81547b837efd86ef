#!/usr/bin/env bash
# The loss monitor's experiments (docs/evaluation.md, "The monitor on by default ..." and "... monitor_cues=fused"):
# the tune split with and without the monitor for the trackers whose own flag is weak, the fused monitor's two
# variants and both grey histograms on seven probes, and the report split of the probes (own flag, colour monitor,
# fused monitor), 3 seeds.
# Needs the split's inputs: bash scripts/make_split_eval.sh (or its first half) writes them to WORK_DIR.
#
# Usage: bash scripts/monitor_experiments.sh [WORK_DIR] [OUT_DIR]   (defaults reports/split, reports)
set -euo pipefail
cd "$(dirname "$0")/.."
W="${1:-reports/split}"
OUT="${2:-reports}"
PFTRACK="${PFTRACK:-.venv/bin/pftrack}"
with() {  # with SUFFIX TRACKER... -> "t1SUFFIX,t2SUFFIX,..."
  local suffix="$1"; shift; local out=""
  for t in "$@"; do out="$out,$t$suffix"; done; echo "${out#,}"
}
run() {  # run SPLIT NAME TRACKERS
  "$PFTRACK" eval "$W/$1_real" "$W/$1_variants" "$W/$1_pets" \
    "$W/$1_synth"/{vanish,leave,exit,varied,camouflage,teleport} --trackers "$3" --seeds 3 --workers 2 --quiet \
    --report "$OUT/$2" --title "loss monitor: $2" > "$OUT/$2.md"
}
WEAK=(flow-pf ssim-pf dssim hybrid-ssim-pf template pisc cotrain-pf switching fs-meanshift anisotropic-meanshift)
PROBES=(opencv-csrt template dssim ssim-pf pisc fs-meanshift flow-pf)
run tune mondef_tune "$(with "" "${WEAK[@]}"),$(with "[monitor=true]" "${WEAK[@]}")"
FUSED="[monitor=true;monitor_cues=fused"
LIT="[monitor=true;monitor_grey_histogram=both"
run tune monfused_tune "opencv-csrt,opencv-csrt[monitor=true],$(with "$FUSED;monitor_structure=ncc]" "${PROBES[@]}")"
run tune monhog_tune "$(with "$FUSED;monitor_structure=hog-on-grey]" "${PROBES[@]}")"
run tune monlit_tune "$(with "$LIT]" "${PROBES[@]}"),$(with "$LIT;monitor_cues=fused]" "${PROBES[@]}")"
run report monitor_cues_report \
  "$(with "" "${PROBES[@]}"),$(with "[monitor=true]" "${PROBES[@]}"),$(with "$FUSED]" "${PROBES[@]}")"
for r in mondef_tune monfused_tune monhog_tune monlit_tune monitor_cues_report; do
  grep '^| `' "$OUT/$r.md" | head -30
done
