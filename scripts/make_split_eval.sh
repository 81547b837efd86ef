#!/usr/bin/env bash
# The tune / report split of GUIDE §8, as two `pftrack eval` runs (each table one run, OpenCV CSRT in it).
#
#   tune:   otb_crossing, otb_couple, vot_bag, otb_dragonbaby, davis16_dog, their grey and grey+light variants,
#           the people of PETS 2009 S2.L1 frames 1-200 (one sequence each, scripts/make_mot_sot.py),
#           synthetic vanish/leave/exit/varied/camouflage/teleport scenes, seeds 0-7   (defaults were chosen here);
#           and, in a run of their own, the PETS walkers of frames 1-200 seen through four narrower windows
#           (scripts/make_pets_views.py: real exits among look-alikes; in another run, windows of 40 % and 70 %),
#           and the five real targets seen through the same windows (exits of one target)
#   report: otb_motorrolling, tld_pedestrian2, davis16_blackswan, davis16_car-shadow, their grey and grey+light
#           variants, the people of PETS frames 201-400, freshly seeded synthetic scenes, seeds 100-107
#           (never tuned on); and the PETS windows of frames 201-400, and the four real targets' windows
#   both:   in a run of their own, each split's real sequences turning grey mid-sequence (make_variants.py --switch);
#           in another, the same copies of each split's synthetic vanish and leave scenes;
#           in a run of their own, the scenes cut from photographs (photo-vanish, photo-leave, photo-exit; a family
#           that shares no drawing with the synthetic scenes above): seeds 1000-1019 for tune, 0-19 for report
#           (docs/rules/photo_scenes_rule.txt);
#           in a run of their own, each split's real sequences from 20 starts each (--protocol tre)
#
# Usage: bash scripts/make_split_eval.sh [DATA_DIR] [WORK_DIR]   (defaults ../shared/data, reports/split)
# Writes WORK_DIR/{tune,report}/ (results.csv, summary.md, index.html) and prints both summaries.
set -euo pipefail
cd "$(dirname "$0")/.."
DATA="${1:-../shared/data}"
WORK="${2:-reports/split}"
PFTRACK="${PFTRACK:-.venv/bin/pftrack}"
PY="${PY:-.venv/bin/python}"
TRACKERS="${TRACKERS:-color-pf,fusion-pf,local-motion-pf,opencv-csrt}"
SEEDS="${SEEDS:-3}"
mkdir -p "$WORK"/{tune_real,report_real}
for s in otb_crossing otb_couple vot_bag otb_dragonbaby davis16_dog; do
  ln -sfn "$(realpath "$DATA/$s")" "$WORK/tune_real/$s"; done
for s in otb_motorrolling tld_pedestrian2 davis16_blackswan davis16_car-shadow; do
  ln -sfn "$(realpath "$DATA/$s")" "$WORK/report_real/$s"; done
[ -d "$WORK/tune_variants" ] || "$PY" scripts/make_variants.py "$WORK"/tune_real/* --out "$WORK/tune_variants"
[ -d "$WORK/report_variants" ] || "$PY" scripts/make_variants.py "$WORK"/report_real/* --out "$WORK/report_variants"
[ -d "$WORK/tune_pets" ] || "$PY" scripts/make_mot_sot.py "$DATA/pets09_s2l1_dev" --frames 1-200 --out "$WORK/tune_pets"
[ -d "$WORK/report_pets" ] || "$PY" scripts/make_mot_sot.py "$DATA/pets09_s2l1_dev" --frames 201-400 \
  --out "$WORK/report_pets"
[ -d "$WORK/tune_views" ] || "$PY" scripts/make_pets_views.py "$DATA/pets09_s2l1_dev" --frames 1-200 \
  --out "$WORK/tune_views"
[ -d "$WORK/report_views" ] || "$PY" scripts/make_pets_views.py "$DATA/pets09_s2l1_dev" --frames 201-400 \
  --out "$WORK/report_views"
# the same walkers through windows of 40 % and 70 % of the frame (docs/rules/enter_extent_surround_rule.txt)
for share in 40 70; do
  [ -d "$WORK/tune_views$share" ] || "$PY" scripts/make_pets_views.py "$DATA/pets09_s2l1_dev" --frames 1-200 \
    --share "0.$share" --out "$WORK/tune_views$share"
  [ -d "$WORK/report_views$share" ] || "$PY" scripts/make_pets_views.py "$DATA/pets09_s2l1_dev" --frames 201-400 \
    --share "0.$share" --out "$WORK/report_views$share"
done
for split in tune report; do
  if [ ! -d "$WORK/${split}_exits" ]; then
    for s in "$WORK/${split}_real"/*; do "$PY" scripts/make_pets_views.py "$s" --out "$WORK/${split}_exits"; done
  fi
done
for kind in vanish leave exit varied camouflage teleport; do
  [ -d "$WORK/tune_synth/$kind" ] || "$PFTRACK" synth "$kind" --seeds 0-7 --out "$WORK/tune_synth/$kind"
  [ -d "$WORK/report_synth/$kind" ] || "$PFTRACK" synth "$kind" --seeds 100-107 --out "$WORK/report_synth/$kind"
done
for kind in photo-vanish photo-leave photo-exit; do
  [ -d "$WORK/tune_photo/$kind" ] || "$PFTRACK" synth "$kind" --seeds 1000-1019 --out "$WORK/tune_photo/$kind"
  [ -d "$WORK/report_photo/$kind" ] || "$PFTRACK" synth "$kind" --seeds 0-19 --out "$WORK/report_photo/$kind"
done
for split in tune report; do
  "$PFTRACK" eval "$WORK/${split}_real" "$WORK/${split}_variants" "$WORK/${split}_pets" \
    "$WORK/${split}_synth"/{vanish,leave,exit,varied,camouflage,teleport} \
    --trackers "$TRACKERS" --seeds "$SEEDS" --workers 2 --quiet --report "$WORK/$split" \
    --title "pftrack: $split split" > "$WORK/$split.md"
  "$PY" scripts/split_summary.py "$WORK/$split/results.csv" --scenes "$WORK/${split}_synth"
  # real exits: PETS walkers through narrower windows (docs/robustness.md), a run of their own
  "$PFTRACK" eval "$WORK/${split}_views" --trackers "$TRACKERS" --seeds "$SEEDS" --workers 2 --quiet \
    --report "$WORK/${split}_views_eval" --title "pftrack: $split split, PETS views" > "$WORK/${split}_views.md"
  "$PFTRACK" eval "$WORK/${split}_views40" "$WORK/${split}_views70" --trackers "$TRACKERS" --seeds "$SEEDS" \
    --workers 2 --quiet --report "$WORK/${split}_views_more_eval" \
    --title "pftrack: $split split, PETS views of 40 % and 70 %" > "$WORK/${split}_views_more.md"
  # the real sequences from 20 starts each (OTB's temporal robustness evaluation; docs/evaluation.md)
  "$PFTRACK" eval "$WORK/${split}_real" --protocol tre --trackers "$TRACKERS" --workers 2 --quiet \
    --report "$WORK/${split}_tre_eval" --title "pftrack: $split split, TRE of the real sequences" > "$WORK/${split}_tre.md"
  # exits of one target: the real sequences of the split through the same windows
  "$PFTRACK" eval "$WORK/${split}_exits" --trackers "$TRACKERS" --seeds "$SEEDS" --workers 2 --quiet \
    --report "$WORK/${split}_exits_eval" --title "pftrack: $split split, windows of the real sequences" \
    > "$WORK/${split}_exits.md"
  # scenes cut from photographs: another drawing style than the synthetic scenes the defaults were chosen on
  "$PFTRACK" eval "$WORK/${split}_photo"/{photo-vanish,photo-leave,photo-exit} --trackers "$TRACKERS" \
    --seeds "$SEEDS" --workers 2 --quiet --report "$WORK/${split}_photo_eval" \
    --title "pftrack: $split split, photo scenes" > "$WORK/${split}_photo.md"
  # the real sequences turning grey mid-sequence (make_variants.py --switch; docs/rules/input_switch_rule.txt)
  [ -d "$WORK/${split}_switch" ] || "$PY" scripts/make_variants.py "$WORK/${split}_real"/* --switch \
    --out "$WORK/${split}_switch" > /dev/null
  "$PFTRACK" eval "$WORK/${split}_switch" --trackers "$TRACKERS" --seeds "$SEEDS" --workers 2 --quiet \
    --report "$WORK/${split}_switch_eval" --title "pftrack: $split split, turning grey" > "$WORK/${split}_switch.md"
  # the split's synthetic vanish and leave scenes turning grey: switches made during a search
  # (docs/rules/input_switch_return_rule.txt)
  if [ ! -d "$WORK/${split}_synth_switch" ]; then
    for kind in vanish leave; do
      "$PY" scripts/make_variants.py "$WORK/${split}_synth/$kind/$kind"-* --switch \
        --out "$WORK/${split}_synth_switch" > /dev/null
    done
  fi
  "$PFTRACK" eval "$WORK/${split}_synth_switch" --trackers "$TRACKERS" --seeds "$SEEDS" --workers 2 --quiet \
    --report "$WORK/${split}_synth_switch_eval" --title "pftrack: $split split, synthetic scenes turning grey" \
    > "$WORK/${split}_synth_switch.md"
done
