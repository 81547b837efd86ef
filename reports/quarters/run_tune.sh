set -e
T='fusion-pf,fusion-pf[static_quarters=3],color-pf,color-pf[static_quarters=3]'
W=reports/split
pftrack eval reports/views_tune/* reports/views_tune_more/* --trackers "$T" --seeds 3 --workers 2 --quiet --report reports/quarters/views_tune > /dev/null
python scripts/views_summary.py reports/quarters/views_tune/results.csv > reports/quarters/views_tune.txt
pftrack eval $W/tune_real $W/tune_variants $W/tune_pets $W/tune_synth/{vanish,leave,exit,varied,camouflage,teleport} --trackers "$T" --seeds 3 --workers 2 --quiet --report reports/quarters/split_tune > /dev/null
python scripts/split_summary.py reports/quarters/split_tune/results.csv --scenes $W/tune_synth > reports/quarters/split_tune.txt
pftrack eval reports/exits_tune/* --trackers "$T" --seeds 3 --workers 2 --quiet --report reports/quarters/exits_tune > /dev/null
python scripts/views_summary.py reports/quarters/exits_tune/results.csv > reports/quarters/exits_tune.txt
echo DONE
