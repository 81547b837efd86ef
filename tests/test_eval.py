"""Evaluation: metrics, protocols, MOT parity, peers, baselines, runner and report."""

import csv
import re
from pathlib import Path

import cv2
import numpy as np
import pytest

import pftrack
from pftrack.eval.metrics import THRESHOLDS, frame_ious, ope_scores
from pftrack.eval.mot import import_motmetrics, mot_scores
from pftrack.eval.report import write_report
from pftrack.eval.runner import Job, Runner, TrackerConfig, build_jobs, parse_tracker_list, run_job, strip_timings
from pftrack.eval.vot import run_vot
from pftrack.io import read_sequence
from pftrack.io.datasets import read_mot_txt
from pftrack.synth import Scene, simple_scene
from pftrack.trackers.base import TrackState

from .conftest import render_scene, shared_sequence


# ------------------------------------------------------------------ metrics against hand-computed cases

def test_perfect_tracker_auc_is_20_of_21():
    gt = np.array([[10, 10, 20, 30], [12, 11, 20, 30], [14, 12, 21, 30]], float)
    res = ope_scores(gt, gt)
    assert res.auc == pytest.approx(20 / 21)  # IoU 1 is not > 1
    assert res.precision == 1.0 and res.mean_iou == pytest.approx(1.0)


def test_shifted_box_has_known_iou():
    gt = np.array([[0, 0, 10, 10]] * 4, float)
    pred = gt + [2.5, 0, 0, 0]  # overlap 7.5 x 10 = 75, union 125
    assert frame_ious(pred, gt) == pytest.approx([0.6] * 4)
    res = ope_scores(pred, gt)
    assert res.auc == pytest.approx(np.mean(0.6 > THRESHOLDS))
    assert res.precision == 1.0  # 2.5 px centre error


def test_nan_and_zero_size_ground_truth_rows_are_skipped():
    gt = np.array([[0, 0, 10, 10], [np.nan] * 4, [0, 0, 0, 0], [0, 0, 10, 10]], float)
    pred = np.array([[0, 0, 10, 10], [50, 50, 5, 5], [50, 50, 5, 5], [0, 0, 10, 10]], float)
    res = ope_scores(pred, gt)
    assert res.n_frames == 2 and res.auc == pytest.approx(20 / 21)
    # a missing prediction (NaN) counts as a miss, never as NaN
    res = ope_scores(np.array([[np.nan] * 4, [0, 0, 10, 10]]), np.array([[0, 0, 10, 10]] * 2, float))
    assert res.auc == pytest.approx(10 / 21)


def independent_ope(pred, gt):
    """pysot-style scorer written from the published definitions (continuous IoU, IoU > t, 21 thresholds)."""
    ok = (gt[:, 2] > 0) & (gt[:, 3] > 0) & np.isfinite(gt).all(1)
    g, p = gt[ok], pred[ok]
    left = np.maximum(g[:, 0], p[:, 0])
    right = np.minimum(g[:, 0] + g[:, 2], p[:, 0] + p[:, 2])
    top = np.maximum(g[:, 1], p[:, 1])
    bottom = np.minimum(g[:, 1] + g[:, 3], p[:, 1] + p[:, 3])
    inter = np.maximum(0, right - left) * np.maximum(0, bottom - top)
    ov = inter / (g[:, 2] * g[:, 3] + p[:, 2] * p[:, 3] - inter)
    auc = np.mean([np.sum(ov > t) / len(ov) for t in np.arange(0, 1.05, 0.05)])
    c = np.hypot(g[:, 0] + g[:, 2] / 2 - p[:, 0] - p[:, 2] / 2, g[:, 1] + g[:, 3] / 2 - p[:, 1] - p[:, 3] / 2)
    return auc, np.mean(c <= 20)


def test_ope_agrees_with_an_independent_scorer(rng):
    gt = np.column_stack([rng.uniform(0, 300, 200), rng.uniform(0, 200, 200), rng.uniform(5, 80, 200),
                          rng.uniform(5, 80, 200)])
    pred = gt + rng.normal(0, 8, gt.shape)
    pred[:, 2:] = np.abs(pred[:, 2:]) + 1
    auc, prec = independent_ope(pred, gt)
    res = ope_scores(pred, gt)
    assert res.auc == pytest.approx(auc, abs=1e-12) and res.precision == pytest.approx(prec, abs=1e-12)


# ------------------------------------------------------------------ VOT protocol

class ScriptedTracker:
    """Returns scripted boxes; records when it is (re)initialised."""

    def __init__(self, script):
        self.script = script
        self.t = 0
        self.inits = []

    def init(self, frame, box):
        self.inits.append(int(frame))
        self.t = int(frame)
        return TrackState(box=tuple(box), score=1, lost=False)

    def update(self, frame):
        self.t = int(frame)
        return TrackState(box=self.script(self.t), score=1, lost=False)


def test_vot_protocol_counts_failures_and_reinits_exactly():
    n = 40
    gt = np.tile([10.0, 10.0, 10.0, 10.0], (n, 1))
    bad = {5, 20}  # the tracker misses completely on these frames

    def script(t):
        return (200.0, 200.0, 10.0, 10.0) if t in bad else (12.0, 10.0, 10.0, 10.0)  # IoU 0.8 otherwise

    tr = ScriptedTracker(script)
    res = run_vot(tr, range(n), gt)
    assert res.failures == 2 and res.failure_frames == [5, 20]
    assert tr.inits == [0, 10, 25] and res.inits == [0, 10, 25]
    assert np.isnan(res.ious[6:10]).all() and np.isnan(res.ious[21:25]).all()
    # accuracy excludes the 10 frames after each (re)init: only frames 35..39 count (IoU 80/120 each)
    assert np.isfinite(res.ious[26:35]).all()
    assert res.accuracy == pytest.approx(80 / 120)
    res_short = run_vot(ScriptedTracker(script), range(n), gt, burn_in=0)
    assert res_short.accuracy == pytest.approx(80 / 120)  # same IoU everywhere it succeeds


def test_vot_waits_for_valid_ground_truth():
    gt = np.array([[np.nan] * 4, [np.nan] * 4, [5, 5, 10, 10], [5, 5, 10, 10]], float)
    tr = ScriptedTracker(lambda t: (5.0, 5.0, 10.0, 10.0))
    res = run_vot(tr, range(4), gt)
    assert tr.inits == [2] and res.failures == 0


# ------------------------------------------------------------------ MOT metrics

def test_motmetrics_parity_on_tud_campus():
    mm = import_motmetrics()
    d = Path(mm.__file__).parent / "data" / "TUD-Campus"
    s = mot_scores(read_mot_txt(d / "gt.txt"), read_mot_txt(d / "test.txt"))
    assert s.mota == pytest.approx(0.526462, abs=1e-6)
    assert s.motp == pytest.approx(0.277201, abs=1e-6)
    assert s.idf1 == pytest.approx(0.557659, abs=1e-6)
    assert (s.num_switches, s.num_false_positives, s.num_misses) == (7, 13, 150)


def test_mot_perfect_hypothesis():
    gt = np.array([[1, 1, 0, 0, 10, 10, 1], [2, 1, 1, 0, 10, 10, 1], [1, 2, 50, 50, 10, 10, 1]], float)
    s = mot_scores(gt, gt)
    assert s.mota == 1.0 and s.idf1 == 1.0 and s.num_switches == 0


# ------------------------------------------------------------------ peers and seed baselines

def _synthetic_clip(seed=0, n=30):
    scene, frames, _ = render_scene(simple_scene(seed, n_frames=n))
    return frames, scene.groundtruth(0)


def test_opencv_mil_refuses_a_box_it_would_hang_on():
    """OpenCV's MIL never returns on a 4 x 4 box: the adapter refuses it with a BoxError (exit 2 from the CLI)
    instead of hanging, and takes a 5 x 5 one."""
    from pftrack.errors import BoxError

    frame = np.random.default_rng(0).integers(0, 255, (120, 160, 3), dtype=np.uint8)
    with pytest.raises(BoxError, match="too small"):
        pftrack.create_tracker("opencv-mil").init(frame, (50, 50, 4, 4))
    with pytest.raises(BoxError):
        pftrack.create_tracker("opencv-mil").init(frame, (50, 50, 2, 10))
    t = pftrack.create_tracker("opencv-mil")
    t.init(frame, (50, 50, 5, 5))
    assert np.all(np.isfinite(t.update(frame).box))


def test_opencv_tracker_that_refuses_its_box_gives_a_box_error(tmp_path):
    """OpenCV's MIL cannot place its samples around a box that fills the frame: an OpenCV assertion becomes a
    BoxError, and the command prints one line and exits with code 2."""
    from pftrack.cli import main
    from pftrack.errors import BoxError

    frame = np.random.default_rng(0).integers(0, 255, (120, 160, 3), dtype=np.uint8)
    with pytest.raises(BoxError, match="cannot start on box"):
        pftrack.create_tracker("opencv-mil").init(frame, (0, 0, 160, 120))
    for i in range(3):
        cv2.imwrite(str(tmp_path / f"{i:04d}.png"), frame)
    assert main(["track", str(tmp_path), "--tracker", "opencv-mil", "--box", "0,0,160,120", "--out",
                 str(tmp_path / "o.csv")]) == 2


@pytest.mark.parametrize("name", ["opencv-csrt", "opencv-kcf", "opencv-mil", "opencv-mosse", "opencv-medianflow",
                                  "opencv-tld", "camshift", "meanshift", "kalman-meanshift"])
def test_peers_and_baselines_follow_the_protocol(name):
    frames, gt = _synthetic_clip()
    tr = pftrack.create_tracker(name)
    st = tr.init(frames[0], gt[0])
    assert st.box == pytest.approx(tuple(gt[0]))
    states = [tr.update(f) for f in frames[1:]]
    assert all(len(s.box) == 4 and np.all(np.isfinite(s.box)) for s in states)
    if name in ("meanshift", "kalman-meanshift", "opencv-csrt"):
        err = np.hypot(*(np.array([s.box for s in states])[:, :2] + np.array([s.box for s in states])[:, 2:] / 2
                         - gt[1:, :2] - gt[1:, 2:] / 2).T)
        assert err.mean() < 4.0


def test_peer_failure_maps_to_lost_and_keeps_last_box(monkeypatch):
    from pftrack.trackers import opencv as ocv

    class Fake:
        def __init__(self):
            self.n = 0

        def init(self, frame, rect):
            return None

        def update(self, frame):
            self.n += 1
            return (self.n < 3), (self.n, 2.0, 3.0, 4.0)

    monkeypatch.setitem(ocv._FACTORIES, "kcf", Fake)
    tr = pftrack.create_tracker("opencv-kcf")
    frame = np.zeros((50, 50, 3), np.uint8)
    tr.init(frame, (1, 2, 3, 4))
    s1, s2, s3 = (tr.update(frame) for _ in range(3))
    assert not s1.lost and s2.box == (2.0, 2.0, 3.0, 4.0)
    assert s3.lost and s3.box == s2.box


# ------------------------------------------------------------------ runner and report

def write_otb(folder: Path, seed: int, n: int = 15) -> Path:
    scene = Scene(simple_scene(seed, n_frames=n))
    (folder / "img").mkdir(parents=True)
    for t, f in enumerate(scene.frames()):
        cv2.imwrite(str(folder / "img" / f"{t + 1:04d}.png"), f)
    np.savetxt(folder / "groundtruth_rect.txt", scene.groundtruth(0), delimiter=",", fmt="%.3f")
    return folder


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    root = tmp_path_factory.mktemp("ds")
    write_otb(root / "seqA", 1)
    write_otb(root / "seqB", 2)
    return root


def jobs_for(dataset, protocol="ope"):
    from pftrack.io import discover_sequences

    trackers = parse_tracker_list("color-pf[n_particles=30],meanshift")
    return build_jobs(discover_sequences(dataset), trackers, seeds=2, protocol=protocol)


def test_tracker_spec_parsing():
    cfgs = parse_tracker_list("color-pf, color-pf[n_particles=50;sigma=0.2],opencv-csrt")
    assert [c.label for c in cfgs] == ["color-pf", "color-pf[n_particles=50;sigma=0.2]", "opencv-csrt"]
    assert cfgs[1].param_dict == {"n_particles": "50", "sigma": "0.2"}
    with pytest.raises(pftrack.ParameterError):
        parse_tracker_list("color-pf[bogus=1]")
    with pytest.raises(pftrack.ParameterError):
        parse_tracker_list("nope")
    assert any(c.name == "opencv-csrt" for c in parse_tracker_list("opencv"))


def test_runner_same_results_with_1_and_2_workers_and_dask(dataset):
    jobs = jobs_for(dataset)
    assert len(jobs) == 2 * (2 + 1)  # meanshift is deterministic: one seed
    r1 = [strip_timings(r) for r in Runner(workers=1, progress=False).run(jobs)]
    r2 = [strip_timings(r) for r in Runner(workers=2, progress=False).run(jobs)]
    assert r1 == r2
    from dask.distributed import Client, LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        r3 = [strip_timings(r) for r in Runner(scheduler=client, progress=False).run(jobs)]
    assert r1 == r3
    assert all(r["auc"] > 0.5 for r in r1)


def test_runner_resumes_after_interruption(dataset, tmp_path):
    jobs = jobs_for(dataset, protocol="vot")
    calls = []

    class Stop(Exception):
        pass

    def interrupt(rec):
        calls.append(rec["tracker"])
        if len(calls) == 2:
            raise Stop()

    with pytest.raises(Stop):
        Runner(report_dir=tmp_path, workers=1, progress=False, on_result=interrupt).run(jobs)
    cached = sorted((tmp_path / "runs").glob("*.json"))
    assert len(cached) == 2
    runner = Runner(report_dir=tmp_path, workers=1, progress=False)
    recs = runner.run(jobs)
    assert runner.reused == 2 and runner.ran == len(jobs) - 2
    fresh = Runner(workers=1, progress=False).run(jobs)
    assert [strip_timings(r) for r in recs] == [strip_timings(r) for r in fresh]
    # a corrupt cache file is recomputed, not trusted
    cached[0].write_text("{not json")
    runner = Runner(report_dir=tmp_path, workers=1, progress=False)
    runner.run(jobs)
    assert runner.ran == 1


def test_report_html_references_existing_files(dataset, tmp_path):
    jobs = jobs_for(dataset)
    recs = Runner(workers=1, progress=False).run(jobs)
    seqs = {"seqA": str(dataset / "seqA"), "seqB": str(dataset / "seqB")}
    paths = write_report(recs, tmp_path / "rep", sequences=seqs, command="pftrack eval ...")
    html = paths["index"].read_text()
    refs = re.findall(r"(?:src|href)='([^']+)'", html)
    assert "results.csv" in refs and "success.png" in refs and any(r.startswith("frames/") for r in refs)
    for ref in refs:
        assert (tmp_path / "rep" / ref).is_file(), ref
    header = (tmp_path / "rep" / "results.csv").read_text().splitlines()[0]
    for col in ["tracker", "sequence", "seed", "auc", "precision", "mean_iou", "failures", "fps"]:
        assert col in header.split(",")
    assert "| `color-pf[n_particles=30]` |" in (tmp_path / "rep" / "summary.md").read_text()


def test_eval_cli_end_to_end(dataset, tmp_path, capsys):
    from pftrack.cli import main

    rc = main(["eval", str(dataset), "--trackers", "meanshift,camshift", "--report", str(tmp_path / "r"),
               "--workers", "1", "--quiet", "--doc", str(tmp_path / "bench.md")])
    assert rc == 0
    assert "mean AUC" in capsys.readouterr().out
    assert (tmp_path / "r" / "index.html").is_file() and (tmp_path / "bench.md").is_file()
    assert main(["eval", str(tmp_path / "missing"), "--trackers", "meanshift", "--quiet"]) == 2
    assert main(["eval", str(dataset), "--trackers", "meanshift[zzz=1]", "--quiet"]) == 2


def test_sre_perturbations_follow_otb():
    """OTB's SRE: 8 shifts of 10 % of the size (4 centre, 4 corner) and scales 0.8, 0.9, 1.1, 1.2 about the
    centre; clipped to the frame; a box shifted out of it falls back to the ground truth's."""
    from pftrack.eval.runner import SRE_PERTURBATIONS, perturbed_box

    assert len(SRE_PERTURBATIONS) == 12
    box = (100.0, 50.0, 40.0, 20.0)
    got = [perturbed_box(box, k) for k in range(12)]
    centres = {(round(x + w / 2 - 120, 6), round(y + h / 2 - 60, 6)) for x, y, w, h in got[:8]}
    assert centres == {(dx, dy) for dx in (-4.0, 0.0, 4.0) for dy in (-2.0, 0.0, 2.0)} - {(0.0, 0.0)}
    assert all((w, h) == (40.0, 20.0) for _, _, w, h in got[:8])
    for (x, y, w, h), s in zip(got[8:], (0.8, 0.9, 1.1, 1.2)):
        assert (w, h) == pytest.approx((40 * s, 20 * s)) and (x + w / 2, y + h / 2) == pytest.approx((120, 60))
    assert perturbed_box((0.0, 0.0, 40.0, 20.0), 0, (200, 100)) == pytest.approx((0.0, 0.0, 36.0, 20.0))
    assert perturbed_box((0.0, 0.0, 1.0, 1.0), 4, (200, 100)) == (0.0, 0.0, 1.0, 1.0)


def test_sre_protocol_runs_every_tracker_from_each_perturbed_box(dataset, tmp_path, capsys):
    from pftrack.cli import main
    from pftrack.io import discover_sequences

    jobs = build_jobs(discover_sequences(dataset), parse_tracker_list("meanshift,color-pf[n_particles=30]"),
                      seeds=1, protocol="sre")
    assert len(jobs) == 2 * 2 * 12  # deterministic or not, once per perturbation; --seeds is ignored
    job = next(j for j in jobs if j.tracker.name == "meanshift" and j.seed == 9)
    rec = run_job(job)
    gt = read_sequence(job.sequence).groundtruth
    x, y, w, h = gt[0]
    assert rec["init_box"] == pytest.approx([x + 0.05 * w, y + 0.05 * h, 0.9 * w, 0.9 * h])
    assert rec["auc"] > 0.3 and rec["protocol"] == "sre"
    rc = main(["eval", str(dataset / "seqA"), "--trackers", "meanshift", "--protocol", "sre", "--workers", "1",
               "--quiet", "--report", str(tmp_path / "r")])
    out = capsys.readouterr().out
    assert rc == 0 and "SRE (OTB's spatial robustness evaluation)" in out and "| `meanshift` |" in out
    assert (tmp_path / "r" / "success.png").is_file()


@pytest.mark.shared_data
def test_csrt_auc_agrees_with_independent_scorer_on_dev_sequence():
    seq_path = shared_sequence("otb_crossing")
    rec = run_job(Job(TrackerConfig("opencv-csrt", "opencv-csrt"), str(seq_path), "otb_crossing", 0, "ope"))
    gt = read_sequence(seq_path).groundtruth
    pred = np.array(rec["boxes"], float).reshape(-1, 4)
    auc, prec = independent_ope(pred, gt)
    assert rec["auc"] == pytest.approx(auc, abs=5e-4) and rec["precision"] == pytest.approx(prec, abs=5e-4)


def test_bench_cli_writes_table_and_plot(tmp_path):
    """A tiny `pftrack bench`: sweeps, peers in the same run, a markdown table and the scaling plot."""
    from pftrack.cli import main

    out = tmp_path / "b"
    assert main(["bench", "--trackers", "color-pf,opencv-kcf", "--particles", "50,100", "--targets", "25",
                 "--frames", "640x480", "--rounds", "1", "--n-frames", "20", "--out", str(out), "--quiet"]) == 0
    text = (out / "bench.md").read_text()
    assert "## Reference synthetic clip" in text and "`color-pf`" in text and "`opencv-kcf`" in text
    assert "### Update fps against particles N" in text  # swept: 50 and 100
    assert "### Update fps against frame size" not in text  # the reference size only: no one-column table
    assert (out / "scaling.png").stat().st_size > 1000
    assert main(["bench", "--trackers", "no-such-tracker", "--quiet", "--out", str(out)]) == 2


def test_summary_gives_speed_ratios_to_the_opencv_peer_in_the_run():
    from pftrack.eval.report import aggregate, sequence_speed_ratios, speed_peer, strict_speed_ratios, summary_markdown

    records = []
    for s, (fast, peer) in enumerate([(1000.0, 10.0), (1200.0, 40.0), (900.0, 60.0)]):
        for seed in range(3):
            records.append(dict(tracker="fusion-pf", sequence=f"s{s}", seed=seed, protocol="ope", auc=0.5,
                                fps=fast + 100.0 * seed))
        records.append(dict(tracker="opencv-csrt", sequence=f"s{s}", seed=0, protocol="ope", auc=0.4, fps=peer))
    assert speed_peer(["fusion-pf", "opencv-csrt", "opencv-mil"]) == "opencv-csrt"
    assert speed_peer(["fusion-pf", "opencv-mil"]) == "opencv-mil"
    assert speed_peer(["fusion-pf"]) is None and speed_peer(["opencv-kcf", "opencv-mil"]) is None
    # strict: upper median of the 9 fusion-pf rates (1100) over that of the 3 CSRT rates (40)
    assert strict_speed_ratios(records, "opencv-csrt")["fusion-pf"] == pytest.approx(1100.0 / 40.0)
    md = summary_markdown(records)
    header = next(line for line in md.splitlines() if line.startswith("| tracker |"))
    assert header.endswith("| median fps | × CSRT |")
    row = next(line for line in md.splitlines() if line.startswith("| `fusion-pf` |"))
    # the median over sequences of the per-sequence medians: 1100 against 40
    assert row.endswith("| 1100 | 27.5 |")
    assert "`fusion-pf` 27.5×" in md
    # sequence by sequence: 1100 / 10, 1300 / 40, 1000 / 60 (the medians over seeds)
    lo, med, hi = sequence_speed_ratios(aggregate(records), "opencv-csrt")["fusion-pf"]
    assert (lo, med, hi) == pytest.approx((1000.0 / 60.0, 1300.0 / 40.0, 1100.0 / 10.0))
    assert "`fusion-pf` 16.7×, 32.5×, 110.0×" in md


def test_the_html_report_gives_the_speed_ratios_too(tmp_path):
    from pftrack.eval.report import write_report

    records = []
    for s, (fast, peer) in enumerate([(1000.0, 10.0), (1200.0, 40.0), (900.0, 60.0)]):
        records.append(dict(tracker="fusion-pf", sequence=f"s{s}", seed=0, protocol="ope", auc=0.5, fps=fast))
        records.append(dict(tracker="opencv-csrt", sequence=f"s{s}", seed=0, protocol="ope", auc=0.4, fps=peer))
    page = write_report(records, tmp_path / "r")["index"].read_text(encoding="utf-8")
    assert "<th>× CSRT</th>" in page
    assert "<td>1000</td><td>25.0</td>" in page  # median 1000 against 40
    assert "<code>fusion-pf</code> 15.0×, 30.0×, 100.0×" in page  # 900 / 60, 1200 / 40, 1000 / 10


def test_speed_ratios_without_a_peer_rate_are_undefined_not_an_error():
    from pftrack.eval.report import strict_speed_ratios, summary_markdown

    records = [dict(tracker="fusion-pf", sequence="s", seed=0, protocol="ope", auc=0.5, fps=1000.0),
               dict(tracker="opencv-csrt", sequence="s", seed=0, protocol="ope", auc=0.4, fps=0.0)]
    assert np.isnan(strict_speed_ratios(records, "opencv-csrt")["fusion-pf"])
    assert "| `fusion-pf` |" in summary_markdown(records)


def _failing_meanshift(monkeypatch, at: int):
    """`meanshift` raises on its ``at``-th update (counted per tracker)."""
    from pftrack.trackers.meanshift import MeanShift

    real = MeanShift._update

    def _update(self, frame):
        self._calls = getattr(self, "_calls", 0) + 1
        if self._calls == at:
            raise RuntimeError("kernel exploded\nsecond line")
        return real(self, frame)

    monkeypatch.setattr(MeanShift, "_update", _update)


def test_a_tracker_that_raises_fails_its_run_and_the_evaluation_goes_on(dataset, tmp_path, capsys, monkeypatch):
    """One tracker raising on one frame does not stop `pftrack eval`: its runs are recorded as failed (scored
    with no box from the failure on, kept apart from the cache), the other trackers' runs are complete, the
    report names the failures and the command exits with 1."""
    from pftrack.cli import main
    from pftrack.io import discover_sequences

    seq = discover_sequences(dataset / "seqA")[0]
    cfg = parse_tracker_list("meanshift")[0]
    good = run_job(Job(cfg, str(seq.path), seq.name, 0, "ope"))
    _failing_meanshift(monkeypatch, at=10)
    rec = run_job(Job(cfg, str(seq.path), seq.name, 0, "ope"))
    assert rec["error"] == "RuntimeError: kernel exploded second line" and rec["error_frame"] == 11
    assert "kernel exploded" in rec["traceback"] and rec["updates"] == 9
    boxes, gt = np.array(rec["boxes"], float).reshape(-1, 4), seq.groundtruth
    assert np.allclose(boxes[:10], np.array(good["boxes"], float).reshape(-1, 4)[:10])
    assert np.isnan(boxes[10:]).all()
    assert rec["auc"] == pytest.approx(ope_scores(boxes, gt).auc) and rec["auc"] < good["auc"]
    assert len(rec["lost"]) == len(boxes)
    vot = run_job(Job(cfg, str(seq.path), seq.name, 0, "vot"))
    assert vot["error"].startswith("RuntimeError") and vot["failures"] is None and vot["accuracy"] is None

    rdir = tmp_path / "r"
    argv = ["eval", str(dataset), "--trackers", "color-pf[n_particles=30],meanshift", "--seeds", "1",
            "--workers", "1", "--quiet", "--report", str(rdir)]
    assert main(argv) == 1
    cap = capsys.readouterr()
    assert "pftrack: error: 2 of 4 runs failed, first meanshift on seqA (seed 0, frame 11): RuntimeError" in cap.err
    assert "**2 of 4 runs failed**" in cap.out and "| `meanshift` | seqA | 0 | 11 | RuntimeError" in cap.out
    runs = sorted(p.name for p in (rdir / "runs").iterdir())
    assert len(runs) == 2 and all("color-pf" in n for n in runs)
    assert len(list((rdir / "failed").iterdir())) == 2
    with open(rdir / "results.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert sorted(r["error"] != "" for r in rows) == [False, False, True, True]
    assert "Failed runs: 2 of 4" in (rdir / "index.html").read_text()
    # mended: the failed runs are run again, the finished ones reused, and the failures are forgotten
    monkeypatch.undo()
    assert main(argv) == 0
    cap = capsys.readouterr()
    assert "2 runs computed, 2 reused" in cap.err and "failed" not in cap.out
    assert not list((rdir / "failed").iterdir())


def test_a_multi_target_tracker_that_raises_is_scored_on_the_frames_before(tmp_path, monkeypatch):
    from pftrack.eval.runner import Job, TrackerConfig, run_job
    from pftrack.multi.tracker import MultiPF
    from pftrack.synth.traffic import export_traffic, traffic_scene

    path = tmp_path / "t"
    export_traffic(traffic_scene(0, n_vehicles=2), path)
    real = MultiPF.update
    calls = []

    def update(self, frame):
        calls.append(1)
        if len(calls) == 20:
            raise ValueError("bad")
        return real(self, frame)

    monkeypatch.setattr(MultiPF, "update", update)
    rec = run_job(Job(TrackerConfig("multi-pf", "multi-pf"), str(path), "t", 0, "mot"))
    assert rec["error"] == "ValueError: bad" and rec["error_frame"] == 20 and rec["mota"] is not None


@pytest.mark.skipif("fork" not in __import__("multiprocessing").get_all_start_methods(),
                    reason="the test's stand-in trackers reach the runs' processes by fork")
def test_timeout_kills_a_hanging_run_and_notes_a_crashed_one(dataset, tmp_path, capsys, monkeypatch):
    """``--timeout``: every run has a process of its own; a run that hangs is killed at the limit and one whose
    process dies (a native fault) is recorded as failed; the other runs finish, and bad input still stops the
    evaluation with exit code 2."""
    import os
    import signal
    import time as _time

    from pftrack.cli import main
    from pftrack.trackers.meanshift import KalmanMeanShift, MeanShift

    real = MeanShift._update

    def hang(self, frame):
        self._calls = getattr(self, "_calls", 0) + 1
        if self._calls == 5:
            _time.sleep(60)
        return real(self, frame)

    def crash(self, frame):  # a native fault (pytest's own fault handler off, as in a user's process)
        __import__("faulthandler").disable()
        os.kill(os.getpid(), signal.SIGSEGV)

    monkeypatch.setattr(MeanShift, "_update", hang)
    monkeypatch.setattr(KalmanMeanShift, "_update", crash)
    rdir = tmp_path / "r"
    t0 = _time.perf_counter()
    rc = main(["eval", str(dataset / "seqA"), "--trackers", "meanshift,kalman-meanshift,color-pf[n_particles=30]",
               "--workers", "2", "--timeout", "3", "--quiet", "--report", str(rdir)])
    assert rc == 1 and _time.perf_counter() - t0 < 40
    cap = capsys.readouterr()
    out = cap.out
    assert "pftrack: error: 2 of 3 runs failed, first meanshift on seqA (seed 0): timed out after 3 s" in cap.err
    assert "| `meanshift` | seqA | 0 | – | timed out after 3 s |" in out
    assert "| `kalman-meanshift` | seqA | 0 | – | the run's process was killed by signal SIGSEGV |" in out
    with open(rdir / "results.csv", newline="") as fh:
        rows = {r["tracker"]: r for r in csv.DictReader(fh)}
    assert rows["color-pf[n_particles=30]"]["error"] == "" and float(rows["color-pf[n_particles=30]"]["auc"]) > 0.3
    assert [p.name.split("__")[2] for p in (rdir / "runs").iterdir()] == ["color-pf_n_particles=30"]
    # bad input found inside a run stops the evaluation, as without a time limit
    bad = tmp_path / "bad"
    write_otb(bad, 3, n=6)
    (bad / "img" / "0003.png").write_bytes(b"not an image")
    assert main(["eval", str(bad), "--trackers", "color-pf[n_particles=30]", "--timeout", "30", "--quiet"]) == 2
    assert "cannot be decoded" in capsys.readouterr().err
    assert main(["eval", str(bad), "--trackers", "color-pf", "--timeout", "0", "--quiet"]) == 2


def test_worker_processes_start_after_opencv_ran_in_parallel(dataset):
    """A process that has used OpenCV's thread pool can still run evaluations in worker processes (a forked child
    used to wait forever on the pool's threads it does not have).  Run in a fresh interpreter, with a time limit."""
    import subprocess
    import sys

    code = f"""
import cv2, numpy as np
cv2.setNumThreads(2)
big = np.random.default_rng(0).integers(0, 255, (2000, 2000, 3), dtype=np.uint8)
for _ in range(3):
    cv2.GaussianBlur(cv2.resize(big, (1500, 1500)), (31, 31), 5)
from pftrack.eval.runner import Runner, build_jobs, parse_tracker_list
from pftrack.io import discover_sequences
jobs = build_jobs(discover_sequences({str(dataset)!r}), parse_tracker_list("color-pf[n_particles=30]"), seeds=2,
                  protocol="ope")
recs = Runner(workers=2, progress=False).run(jobs)
assert len(recs) == 4 and all(r["auc"] > 0.3 for r in recs)
assert cv2.getNumThreads() == 2
print("done")
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0 and out.stdout.strip() == "done", out.stderr[-2000:]


def test_a_tracker_that_fails_from_the_first_frame_is_a_failed_run(dataset, monkeypatch):
    """Raising in ``init`` (and so in the warm-up too): a failed run scored 0, not an aborted evaluation."""
    from pftrack.io import discover_sequences
    from pftrack.trackers.meanshift import MeanShift

    def refuse(self, frame, box):
        raise ValueError("cannot start")

    monkeypatch.setattr(MeanShift, "_init", refuse)
    monkeypatch.setattr("pftrack.trackers.warmup._WARMED", set())  # warmed again, and failing there
    seq = discover_sequences(dataset / "seqB")[0]
    rec = run_job(Job(parse_tracker_list("meanshift")[0], str(seq.path), seq.name, 0, "ope"))
    assert rec["error"] == "ValueError: cannot start" and rec["error_frame"] == 1
    assert rec["auc"] == 0.0 and rec["updates"] == 0 and rec["fps"] is None


def test_paired_auc_differences_against_the_peer():
    """Per sequence the mean over seeds, then the paired differences: their mean, standard error, wins and losses
    and the signed-rank test; the summary and the HTML report give them against the speed peer."""
    from scipy.stats import wilcoxon

    from pftrack.eval.paired import paired_auc, paired_reference
    from pftrack.eval.report import aggregate, summary_markdown

    gains = [0.10, 0.05, 0.20, -0.02, 0.08, 0.12, 0.03, 0.07]
    records = []
    for s, g in enumerate(gains):
        for seed, jitter in enumerate((-0.01, 0.01)):  # seeds average out to 0.5 + g
            records.append(dict(tracker="fusion-pf", sequence=f"s{s}", seed=seed, protocol="ope", auc=0.5 + g + jitter,
                                fps=1000.0))
        records.append(dict(tracker="opencv-csrt", sequence=f"s{s}", seed=0, protocol="ope", auc=0.5, fps=40.0))
    records.append(dict(tracker="opencv-csrt", sequence="only-csrt", seed=0, protocol="ope", auc=0.9, fps=40.0))
    agg = aggregate(records)
    r = paired_auc(agg, "opencv-csrt", "fusion-pf")
    d = np.array(gains)
    assert r.n == 8 and r.better == 7 and r.worse == 1  # the sequence only one tracker ran is left out
    assert r.mean == pytest.approx(d.mean()) and r.se == pytest.approx(d.std(ddof=1) / np.sqrt(8))
    assert r.p == pytest.approx(wilcoxon(d).pvalue) and r.p < 0.05
    assert paired_reference(["fusion-pf", "opencv-csrt"], "opencv-csrt") == "opencv-csrt"
    assert paired_reference(["color-pf", "fusion-pf"], None) == "color-pf"
    assert paired_reference(["color-pf"], None) is None
    md = summary_markdown(records)
    assert "## Paired AUC differences against `opencv-csrt`" in md
    assert f"| `fusion-pf` | 8 | +{d.mean():.3f} | {d.std(ddof=1) / np.sqrt(8):.3f} | 7 / 1 |" in md
    few = paired_auc(aggregate([x for x in records if x["sequence"] in ("s0", "s1", "s2")]), "opencv-csrt",
                     "fusion-pf")
    assert few.n == 3 and np.isnan(few.p)  # too few sequences for the test


def test_the_html_report_gives_the_paired_differences(tmp_path):
    from pftrack.eval.report import write_report

    records = [dict(tracker=t, sequence=f"s{s}", seed=0, protocol="ope", auc=a + 0.01 * s, fps=100.0)
               for s in range(6) for t, a in (("color-pf", 0.4), ("fusion-pf", 0.5))]
    page = write_report(records, tmp_path / "r")["index"].read_text(encoding="utf-8")
    assert "<h2>Paired AUC differences against color-pf</h2>" in page
    assert "<td>fusion-pf</td><td>6</td><td>+0.100</td><td>0.000</td><td>6 / 0</td>" in page
