"""Evaluation: metrics, protocols, MOT parity, peers and baselines, speed ratios and paired differences."""

from pathlib import Path

import cv2
import numpy as np
import pytest

import pftrack
from pftrack.eval.metrics import THRESHOLDS, frame_ious, ope_scores
from pftrack.eval.mot import import_motmetrics, mot_scores
from pftrack.eval.runner import Job, TrackerConfig, run_job
from pftrack.eval.vot import run_vot
from pftrack.io import read_sequence
from pftrack.io.datasets import read_mot_txt
from pftrack.synth import simple_scene
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


def test_normalised_precision_follows_lasot():
    """LaSOT / TrackingNet: centre errors in units of the ground truth's width and height, the share within t for
    t = 0, 0.01, ..., 0.5, averaged; a missing box is never within; frames without ground truth are skipped."""
    gt = np.array([[0, 0, 100, 50], [0, 0, 100, 50], [0, 0, 10, 10], [0, 0, 10, 10], [np.nan] * 4], float)
    pred = np.array([[10.5, 0, 100, 50],  # 0.105 of the width off: within from t = 0.11 (40 thresholds)
                     [0, 20.75, 100, 50],  # 0.415 of the height off: from 0.42 (9)
                     [2.5, 3.2, 10, 10],  # (0.25, 0.32): 0.406, from 0.41 (10)
                     [np.nan] * 4,  # missing: never
                     [0, 0, 5, 5]], float)
    res = ope_scores(pred, gt)
    d = np.array([0.105, 0.415, np.hypot(0.25, 0.32), np.inf])
    assert res.norm_precision == pytest.approx(np.mean([(d <= x).mean() for x in np.linspace(0, 0.5, 51)]))
    assert res.norm_precision == pytest.approx((40 + 9 + 10) / (51 * 4), abs=1e-12)
    assert ope_scores(gt[:4], gt[:4]).norm_precision == 1.0


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


def test_opencv_tld_refuses_a_box_it_would_crawl_on():
    """OpenCV's legacy TLD takes seconds to minutes a frame on boxes of a few pixels (76 s an update on a 1 x 1 box in
    a 640 x 480 frame): the adapter refuses boxes under 5 pixels a side with a BoxError, and takes a 5 x 5 one."""
    from pftrack.errors import BoxError

    frame = np.random.default_rng(0).integers(0, 255, (120, 160, 3), dtype=np.uint8)
    for box in ((50, 50, 1, 1), (50, 50, 4, 30), (50, 50, 30, 2)):
        with pytest.raises(BoxError, match="too small for OpenCV's TLD"):
            pftrack.create_tracker("opencv-tld").init(frame, box)
    t = pftrack.create_tracker("opencv-tld")
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


def test_opencv_tld_refuses_a_box_it_would_crash_on():
    """OpenCV's legacy TLD ends the process with a segmentation fault on a box that spans the frame one way and is
    20 px or less the other: the adapter refuses it with a BoxError, and takes the box a pixel shorter."""
    from pftrack.errors import BoxError

    frame = np.random.default_rng(0).integers(0, 255, (60, 80, 3), dtype=np.uint8)
    for box in [(70, 0, 10, 60), (0, 0, 20, 60), (0, 50, 80, 10)]:
        with pytest.raises(BoxError, match="TLD crashes"):
            pftrack.create_tracker("opencv-tld", seed=0).init(frame, box)
    t = pftrack.create_tracker("opencv-tld", seed=0)
    t.init(frame, (70, 0, 10, 59))
    assert np.all(np.isfinite(t.update(frame).box))
    # on frames under 50 px it crashes or hangs even on boxes inside the frame
    with pytest.raises(BoxError, match="under 50 px"):
        pftrack.create_tracker("opencv-tld", seed=0).init(frame[:30, :40], (5, 5, 30, 20))


def test_an_opencv_tracker_that_fails_on_a_frame_reports_the_target_lost():
    """CSRT on a 2 x 2 box in the frame's corner moves it half out of the frame, then fails an OpenCV assertion (its
    window is empty): the adapter reports the target lost with the last box instead of raising."""
    rng = np.random.default_rng(0)
    frames = [rng.integers(0, 255, (60, 80, 3), dtype=np.uint8) for _ in range(5)]
    t = pftrack.create_tracker("opencv-csrt")
    t.init(frames[0], (78, 58, 2, 2))
    states = [t.update(f) for f in frames[1:]]
    failed = [s for s in states if "error" in s.info]
    assert failed and all(s.lost and s.score == 0.0 and s.box == states[0].box for s in failed)
    assert "resize" in failed[0].info["error"]


@pytest.mark.parametrize("name", ["opencv-mil", "opencv-tld"])
def test_opencv_mil_and_tld_repeat_a_seeded_run_whatever_ran_before(name):
    """MIL and TLD draw from OpenCV's random state and the C library's rand(), which carry over from run to run in a
    process: the adapter seeds both from the tracker's seed, so a seeded run is the same after any other run, and
    pftrack eval runs them once per seed."""
    from pftrack.trackers import opencv as ocv
    from pftrack.trackers.registry import get_spec

    if ocv._libc() is None:
        pytest.skip("the C library is not found by name here: its rand() cannot be seeded")
    rng = np.random.default_rng(3)
    base = rng.integers(60, 200, (120, 160, 3), dtype=np.uint8)
    frames = []
    for t in range(12):
        f = base.copy()
        f[40:80, 30 + 3 * t:60 + 3 * t] = rng.integers(0, 255, (40, 30, 3), dtype=np.uint8) // 4 + 190
        frames.append(f)

    def run(seed):
        tr = pftrack.create_tracker(name, seed=seed)
        tr.init(frames[0], (30, 40, 30, 40))
        return [tr.update(f).box for f in frames[1:]]

    first = run(0)
    run(5)  # another run in between, as in a worker of pftrack eval
    cv2.setRNGSeed(12345)
    assert run(0) == first
    assert get_spec(name).cls.stochastic and not get_spec("opencv-csrt").cls.stochastic


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


# ------------------------------------------------------------------ SRE boxes, bench, speed ratios, paired differences

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


def test_tre_starts_follow_otb():
    """OTB's TRE (splitSeqTRE): 20 starts spread over the frames a tracker may start on, the first frame first and
    the last start leaving 20 frames; absent, invalid and mostly-outside boxes are never a start."""
    from pftrack.eval.runner import TRE_SEGMENTS, tre_starts

    n = 120
    gt = np.tile([10.0, 10.0, 20.0, 20.0], (n, 1))
    starts = tre_starts(gt)
    assert len(starts) == TRE_SEGMENTS == 20 and starts[0] == 0 and starts[-1] == n - 20
    assert np.all(np.diff(starts) > 0) and np.all(np.diff(starts) <= 6)
    gt[[0, 1]] = np.nan  # no box: OPE starts on frame 2 (0-based), and so does TRE
    absent = np.zeros(n, bool)
    absent[50:70] = True
    gt[30:40, 0] = -15.0  # a quarter of the box outside the frame
    starts = tre_starts(gt, absent, (200, 100))
    assert starts[0] == 2 and starts[-1] == n - 20
    assert not set(starts.tolist()) & (set(range(30, 40)) | set(range(50, 70)))
    assert np.all(np.diff(starts) >= 0)
    short = tre_starts(np.tile([10.0, 10.0, 20.0, 20.0], (12, 1)))  # shorter than 20 frames: the first frame
    assert short.tolist() == [0] * 20
    wide = np.tile([-5.0, 10.0, 20.0, 20.0], (40, 1))  # never 90 % inside: any present frame may start
    assert tre_starts(wide, None, (200, 100))[-1] == 20
    with pytest.raises(pftrack.FormatError):
        tre_starts(np.full((30, 4), np.nan))


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



@pytest.mark.parametrize("argv, message", [
    (["--particles", "50,x"], "comma-separated integers"), (["--targets", "0"], "positive integers"),
    (["--frames", "640by480"], "frame sizes are WxH"), (["--frames", "32x32"], "too small (at least 64x64)"),
    (["--rounds", "0"], "--rounds >= 1"), (["--n-frames", "5"], "--n-frames >= 20"),
])
def test_bench_bad_options_are_one_line(argv, message, tmp_path, capsys):
    from pftrack.cli import main

    assert main(["bench", "--trackers", "color-pf", *argv, "--quiet", "--out", str(tmp_path / "b")]) == 2
    err = [line for line in capsys.readouterr().err.splitlines() if line.strip()]
    assert len(err) == 1 and message in err[0]


def test_bench_dev_sequences_get_a_row_per_tracker_and_the_ratio_to_the_peer(tmp_path):
    """`pftrack bench --dev`: update and end-to-end fps on real-sequence folders, and each tracker's median ratio to
    the peer of the run (the last tracker listed when CSRT is not in it)."""
    from pftrack.cli import main

    assert main(["synth", "simple", "--seeds", "3,4", "--length", "25", "--out", str(tmp_path / "dev")]) == 0
    out = tmp_path / "b"
    assert main(["bench", "--trackers", "color-pf,opencv-kcf", "--particles", "50", "--targets", "25", "--frames",
                 "320x240", "--rounds", "1", "--n-frames", "20", "--dev", str(tmp_path / "dev"), "--out", str(out),
                 "--quiet"]) == 0
    text = (out / "bench.md").read_text()
    table = text.split("## Real sequences: update fps (end-to-end fps)")[1].strip().splitlines()
    assert table[0] == "| tracker | simple-003 | simple-004 | median | × opencv-kcf |"
    rows = {line.split("|")[1].strip(): [c.strip() for c in line.split("|")[2:-1]] for line in table[2:4]}
    assert set(rows) == {"`color-pf`", "`opencv-kcf`"}
    ups = {t: [float(c.split(" (")[0]) for c in cells[:2]] for t, cells in rows.items()}
    assert all(float(c.split(" (")[1].rstrip(")")) > 0 for cells in rows.values() for c in cells[:2])  # end to end
    ratio = sorted(a / b for a, b in zip(ups["`color-pf`"], ups["`opencv-kcf`"]))
    assert float(rows["`color-pf`"][3]) == pytest.approx(sum(ratio) / 2, abs=0.06 + 0.02 * sum(ratio))
    assert rows["`opencv-kcf`"][3] == "1.0"


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


def test_per_frame_iou_keeps_the_frames_aligned():
    """The timelines' overlap: one value per frame, NaN where the ground truth has no box, 0 for a missing box."""
    from pftrack.eval.metrics import per_frame_iou
    from pftrack.eval.timeline import _runs

    gt = np.array([[0, 0, 10, 10], [np.nan] * 4, [0, 0, 10, 10], [0, 0, 10, 10]], dtype=float)
    pred = np.array([[0, 0, 10, 10], [0, 0, 10, 10], [5, 0, 10, 10], [np.nan] * 4], dtype=float)
    got = per_frame_iou(pred, gt)
    assert got[0] == 1.0 and np.isnan(got[1]) and got[2] == pytest.approx(50 / 150) and got[3] == 0.0
    assert _runs(np.array([0, 1, 1, 0, 1], bool)) == [(1, 3), (4, 5)] and _runs(np.zeros(3, bool)) == []


def test_the_lost_flag_rates_pooled_over_frames_weigh_each_frame_once(tmp_path):
    """The summary's rates are means over sequences; the pooled ones count every absent and every covered frame
    once, so a run with few covered frames weighs no more than its frames."""
    from pftrack.eval.notes import pooled_lost_rates
    from pftrack.eval.report import aggregate, summary_markdown, write_report

    def rec(seq, recall, absent, false, covered, **kw):
        return dict(tracker="fusion-pf", sequence=seq, seed=0, protocol="ope", auc=0.5, fps=100.0,
                    lost_recall=recall, absent_frames=absent, false_lost=false, covered_frames=covered, **kw)

    records = [rec("short", 0.5, 2, 0.5, 2), rec("long", 1.0, 98, 0.0, 198)]
    agg = aggregate(records)
    assert agg["overall"]["fusion-pf"]["false_lost"] == pytest.approx(0.25)  # the mean over the two sequences
    p = pooled_lost_rates(records)["fusion-pf"]
    assert p["false"] == pytest.approx(1 / 200) and p["covered"] == 200
    assert p["recall"] == pytest.approx(99 / 100) and p["absent"] == 100
    md = summary_markdown(records)
    assert "`fusion-pf` 0.990 of 100 / 0.005 of 200" in md
    write_report(records, tmp_path / "r")
    assert "0.990 of 100 / 0.005 of 200" in (tmp_path / "r" / "index.html").read_text()
    assert "covered_frames" in (tmp_path / "r" / "results.csv").read_text().splitlines()[0]
    # a record that gives a rate without its frame count leaves the pooled rate unknown, not biased
    old = dict(records[0])
    del old["covered_frames"]
    q = pooled_lost_rates([old, records[1]])["fusion-pf"]
    assert np.isnan(q["false"]) and q["recall"] == pytest.approx(0.99)
    # no absent or covered frame at all (a tracker without the flag's frames): no sentence
    assert "Pooled over" not in summary_markdown([dict(tracker="kcf", sequence="s", seed=0, protocol="ope", auc=0.4,
                                                       fps=300.0)])
