set -e
T='fusion-pf,fusion-pf[static_quarters=4]'
W=reports/split
pftrack eval reports/views_report/* --trackers "$T,opencv-csrt" --seeds 3 --workers 2 --quiet --report reports/quarters/views_report > /dev/null
python scripts/views_summary.py reports/quarters/views_report/results.csv > reports/quarters/views_report.txt
pftrack eval $W/report_real $W/report_variants $W/report_pets $W/report_synth/* --trackers "$T" --seeds 3 --workers 2 --quiet --report reports/quarters/split_report > /dev/null
python scripts/split_summary.py reports/quarters/split_report/results.csv --scenes $W/report_synth > reports/quarters/split_report.txt
pftrack eval reports/exits_report/* --trackers "$T" --seeds 3 --workers 2 --quiet --report reports/quarters/exits_report > /dev/null
python scripts/views_summary.py reports/quarters/exits_report/results.csv > reports/quarters/exits_report.txt
echo DONE
