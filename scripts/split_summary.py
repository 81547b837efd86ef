"""Group a pftrack eval results.csv by kind of sequence: real, grey, grey+light, synthetic varied/vanish/leave.

    python scripts/split_summary.py reports/split/report/results.csv

Columns: mean OTB AUC per group; lost recall and false-lost rate (means over the runs where each is defined);
the fraction of reappearances re-acquired within 15 frames; the median update fps on the real sequences.
"""
import csv, sys, collections, math
rows=list(csv.DictReader(open(sys.argv[1], encoding="utf-8")))
def grp(seq):
    for g in ("vanish","leave","varied"):
        if seq.startswith(g+"-"): return g
    if seq.endswith("-gray-light"): return "graylight"
    if seq.endswith("-gray"): return "gray"
    return "real"
agg=collections.defaultdict(lambda: collections.defaultdict(list))
for r in rows:
    g=grp(r["sequence"]); t=r["tracker"]
    for k in ("auc","lost_recall","false_lost","fps"):
        v=r.get(k)
        if v not in ("",None): agg[(t,g)][k].append(float(v))
    agg[(t,g)]["reapp"].append(float(r.get("reappearances") or 0)); agg[(t,g)]["reacq"].append(float(r.get("reacquired") or 0))
ts=sorted({t for t,_ in agg}); gs=["real","gray","graylight","varied","vanish","leave"]
print(f"{'tracker':40s} "+" ".join(f"{g:>10s}" for g in gs)+"   recall  falseL  reacq   fps")
for t in ts:
    cells=[]
    for g in gs:
        a=agg.get((t,g),{}).get("auc",[])
        cells.append(f"{sum(a)/len(a):10.3f}" if a else " "*10)
    rec=[v for g in gs for v in agg.get((t,g),{}).get("lost_recall",[])]
    fl=[v for g in gs for v in agg.get((t,g),{}).get("false_lost",[])]
    ra=sum(v for g in gs for v in agg.get((t,g),{}).get("reacq",[])); rp=sum(v for g in gs for v in agg.get((t,g),{}).get("reapp",[]))
    fps=sorted(v for g in ("real",) for v in agg.get((t,g),{}).get("fps",[]))
    print(f"{t:40s} "+" ".join(cells)+f"   {sum(rec)/max(len(rec),1):.3f}   {sum(fl)/max(len(fl),1):.3f}  {ra/max(rp,1):.2f}  {fps[len(fps)//2] if fps else 0:.0f}")
