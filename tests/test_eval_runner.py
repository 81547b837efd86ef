"""Evaluation runner and report: workers and Dask, resumption, the HTML report, the CLI, SRE runs, failures and
timeouts."""

import csv
import re
from pathlib import Path

import cv2
import numpy as np
import pytest

import pftrack
from pftrack.eval.metrics import ope_scores
from pftrack.eval.report import write_report
from pftrack.eval.runner import Job, Runner, build_jobs, parse_tracker_list, run_job, strip_timings
from pftrack.io import read_sequence
from pftrack.synth import Scene, simple_scene


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


@pytest.mark.parametrize("text, message", [
    ("color-pf[n_particles=30", "malformed tracker spec"),
    ("color-pf[n_particles]", "expected key=value"),
    ("color-pf,color-pf", "listed twice"),
    (" , ", "no trackers given"),
])
def test_bad_tracker_lists_are_named_in_one_message(text, message):
    with pytest.raises(pftrack.ParameterError, match=message):
        parse_tracker_list(text)


def test_multi_target_specs_for_the_mot_protocol():
    cfgs = parse_tracker_list("multi-pf, multi-pf[n_particles=40;occlusion=false]", protocol="mot")
    assert [c.name for c in cfgs] == ["multi-pf", "multi-pf"]
    assert cfgs[1].param_dict == {"n_particles": "40", "occlusion": "false"}
    for text, message in [("color-pf", "unknown multi-target tracker spec"), ("multi-pf[n_particles]", "key=value"),
                          ("multi-pf[bogus=1]", "bogus"), ("", "no trackers given")]:
        with pytest.raises(pftrack.ParameterError, match=message):
            parse_tracker_list(text, protocol="mot")


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
    assert "timelines/seqA.png" in refs and "timelines/seqB.png" in refs
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


def test_tre_protocol_runs_every_tracker_from_each_start_frame(tmp_path, capsys):
    """TRE: 20 runs per tracker whatever --seeds says, run k starting on its start frame with that frame's box and
    scored on the frames from there (none before it is decoded or boxed)."""
    from pftrack.cli import main
    from pftrack.eval.runner import tre_starts
    from pftrack.io import discover_sequences

    write_otb(tmp_path / "ds" / "seqL", 3, n=60)
    seqs = discover_sequences(tmp_path / "ds")
    jobs = build_jobs(seqs, parse_tracker_list("meanshift,color-pf[n_particles=30]"), seeds=3, protocol="tre")
    assert len(jobs) == 2 * 20
    gt = read_sequence(tmp_path / "ds" / "seqL").groundtruth
    starts = tre_starts(gt)
    assert starts[0] == 0 and starts[-1] == 40
    job = next(j for j in jobs if j.tracker.name == "meanshift" and j.seed == 13)
    rec = run_job(job)
    s = int(starts[13])
    assert rec["start_frame"] == s + 1 and rec["protocol"] == "tre"
    boxes = np.array([np.nan if v is None else v for v in rec["boxes"]], float).reshape(-1, 4)
    assert np.all(np.isnan(boxes[:s])) and boxes[s] == pytest.approx(gt[s]) and np.all(np.isfinite(boxes[s:]))
    assert rec["updates"] == 60 - s - 1
    assert rec["auc"] == pytest.approx(ope_scores(boxes[s:], gt[s:], bounds=(320, 240)).auc)
    rc = main(["eval", str(tmp_path / "ds"), "--trackers", "meanshift", "--protocol", "tre", "--workers", "1",
               "--quiet", "--report", str(tmp_path / "r")])
    out = capsys.readouterr().out
    assert rc == 0 and "TRE (OTB's temporal robustness evaluation)" in out and "| `meanshift` |" in out


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


def test_runs_reused_from_other_code_are_counted_and_fresh_computes_them_again(dataset, tmp_path, capsys):
    """Each cached run records the fingerprint of the code that made it: a report folder reused after the code
    changed says how many of its reused runs came from other code, and --fresh computes every run again."""
    import json

    from pftrack.cli import main
    from pftrack.eval.runner import code_fingerprint

    rdir = tmp_path / "r"
    argv = ["eval", str(dataset), "--trackers", "meanshift", "--workers", "1", "--quiet", "--report", str(rdir)]
    assert main(argv) == 0
    runs = sorted((rdir / "runs").glob("*.json"))
    assert len(runs) == 2 and all(json.loads(f.read_text())["code"] == code_fingerprint() for f in runs)
    capsys.readouterr()
    assert main(argv) == 0
    err = capsys.readouterr().err
    assert "0 runs computed, 2 reused" in err and "warning" not in err
    rec = json.loads(runs[0].read_text())
    rec["code"] = "0123456789ab"  # as if made before a change of the code
    runs[0].write_text(json.dumps(rec))
    assert main(argv) == 0
    err = capsys.readouterr().err
    assert "warning: 1 of the 2 reused runs were made by other pftrack code than this; --fresh" in err
    assert main(argv + ["--fresh"]) == 0
    assert "2 runs computed, 0 reused" in capsys.readouterr().err
    assert json.loads(runs[0].read_text())["code"] == code_fingerprint()
    assert main(argv) == 0
    assert "warning" not in capsys.readouterr().err
