"""Book ch. 11: brightness transfer functions, appearance partitions, hand-over linking, the command."""

from pathlib import Path

import numpy as np
import pytest

from pftrack.cli import main
from pftrack.multicam.appearance import (
    region_histograms,
    region_labels,
    similarity,
    similarity_matrix,
)
from pftrack.multicam.btf import (
    apply_btf_hist,
    apply_btf_image,
    btf_from_hists,
    cbtf,
    cum_hist,
    mbtf,
)
from pftrack.multicam.handover import TrackAppearance, link_tracks

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "pets09_s2l1_dev"


def _monotone(rng):
    v = np.arange(256) / 255.0
    return np.stack([np.floor(255 * np.clip(rng.uniform(0.7, 1.2) * v ** rng.uniform(0.5, 2.0), 0, 1))
                     for _ in range(3)])


def test_btf_recovery_is_exact_on_occupied_bins():
    rng = np.random.default_rng(0)
    f = _monotone(rng).astype(int)  # monotone with ties
    pix = rng.integers(0, 256, (3, 5000))
    h1 = np.stack([np.bincount(pix[c], minlength=256) for c in range(3)]).astype(float)
    h2 = np.stack([np.bincount(f[c][pix[c]], minlength=256) for c in range(3)]).astype(float)
    lut = btf_from_hists(h1, h2)
    for c in range(3):
        occ = h1[c] > 0
        np.testing.assert_array_equal(lut[c][occ], f[c][occ])
    # pushing the histogram through the BTF gives the destination histogram
    np.testing.assert_allclose(apply_btf_hist(h1[None], lut)[0], h2)
    np.testing.assert_allclose(cum_hist(h2)[:, -1], 1.0)


def test_cbtf_beats_mbtf_on_sparse_training():
    rng = np.random.default_rng(1)
    f = _monotone(rng)
    src, dst = [], []
    for _ in range(12):  # twelve small patches: each histogram has few pixels
        base = rng.normal(rng.uniform(60, 200), 25, (3, 40)).clip(0, 255).astype(int)
        src.append(np.stack([np.bincount(base[c], minlength=256) for c in range(3)]).astype(float))
        dst.append(np.stack([np.bincount(f[c].astype(int)[base[c]], minlength=256) for c in range(3)]).astype(float))
    occ = np.sum(src, axis=0) > 0
    err_m = np.abs(mbtf(src, dst, [(k, k) for k in range(12)]) - f)[occ].mean()
    err_c = np.abs(cbtf(src, dst) - f)[occ].mean()
    assert err_c < err_m


def test_btf_on_images_matches_the_histogram_push_forward():
    rng = np.random.default_rng(2)
    img = rng.integers(0, 256, (20, 30, 3)).astype(np.uint8)
    lut = _monotone(rng)
    out = apply_btf_image(img, lut)
    box = (0, 0, 30, 20)
    h_img = region_histograms(out, box, "whole", raw=True)
    h_push = apply_btf_hist(region_histograms(img, box, "whole", raw=True), lut)
    np.testing.assert_allclose(h_img, h_push)


@pytest.mark.parametrize("shape", [(80, 30), (61, 23), (40, 40)])
def test_positional_partition_covers_every_pixel_once(shape):
    lab, n = region_labels(*shape, "positional", n_rings=2, n_sectors=4)
    assert n == 8
    assert lab.min() >= 0 and lab.max() == 7
    assert set(np.unique(lab)) == set(range(8))
    for feature in ("ellipse1", "ellipse2"):
        lab_e, n_e = region_labels(*shape, feature)
        assert lab_e.max() == n_e - 1 and (lab_e >= 0).mean() > 0.4


def test_similarity_is_one_for_identical_and_symmetric():
    rng = np.random.default_rng(3)
    img = rng.integers(0, 256, (60, 30, 3)).astype(np.uint8)
    a = region_histograms(img, (0, 0, 30, 60), "positional")
    b = region_histograms(img[::-1], (0, 0, 30, 60), "positional")
    assert similarity(a, a) == pytest.approx(1.0)
    assert similarity(a, b) == pytest.approx(similarity(b, a))
    assert similarity(a, b) < 1.0
    np.testing.assert_allclose(np.sum(a, axis=(0, 2)), 1.0)
    assert similarity_matrix(np.stack([a, b]), np.stack([a])).shape == (2, 1)


def _app(tid, first, last, colour):
    h = np.zeros((1, 3, 256))
    for c in range(3):
        h[0, c, colour[c]] = 1.0
    return TrackAppearance(tid, first, last, h, h[0] * 100)


def test_linking_is_one_to_one_in_time_order_with_new_people():
    lut = np.tile(np.arange(256.0), (3, 1))
    a = {1: _app(1, 1, 10, (200, 10, 10)), 2: _app(2, 5, 20, (10, 200, 10))}
    b = {7: _app(7, 30, 40, (10, 200, 10)), 8: _app(8, 25, 35, (200, 10, 10)), 9: _app(9, 50, 60, (10, 10, 200))}
    links = link_tracks(a, b, lut, tau_new=0.5)
    assert sorted((x, y) for x, y, _ in links) == [(1, 8), (2, 7)]  # 9 matches nobody: a new person
    # a track cannot be linked to one that overlaps it in time
    b2 = {7: _app(7, 15, 40, (10, 200, 10))}
    assert link_tracks({2: a[2]}, b2, lut, tau_new=0.0) == []


def test_new_person_threshold_from_tracks_seen_at_the_same_time_in_both_cameras():
    from pftrack.multicam.handover import cooccur_threshold

    lut = np.tile(np.arange(256.0), (3, 1))
    # one-hot colours: the similarity is the fraction of channels in the same bin
    a = {1: _app(1, 1, 10, (200, 10, 10)), 2: _app(2, 1, 10, (10, 200, 10))}
    b = {5: _app(5, 1, 10, (200, 200, 10)),    # seen with 1 and 2: similarities 2/3 and 2/3
         6: _app(6, 5, 12, (10, 10, 200)),     # seen with 1 and 2: 1/3 and 1/3
         7: _app(7, 30, 40, (200, 10, 10))}    # after both: identical to 1, but not a co-occurring pair
    assert cooccur_threshold(a, b, lut, 0.25) == pytest.approx(1 / 3)
    assert cooccur_threshold(a, b, lut, 0.5) == pytest.approx(0.5)
    assert cooccur_threshold(a, b, lut, 1.0) == pytest.approx(2 / 3)
    assert cooccur_threshold(a, {7: b[7]}, lut) is None
    with pytest.raises(ValueError):
        cooccur_threshold(a, b, lut, 1.5)
    # the pairs are scored through the BTF, as the links are: mapping camera A's green 10 to 200 makes
    # 1 identical to 5 (similarity 1) and unlike 6 (0)
    lut2 = lut.copy()
    lut2[1, 10] = 200
    assert cooccur_threshold(a, b, lut2, 1.0) == pytest.approx(1.0)
    assert cooccur_threshold(a, b, lut2, 0.0) == pytest.approx(0.0)
    # end to end: 7 is linked to 1 (identical) under the threshold, and a probe only as similar as the
    # least alike co-occurring people is a new person
    tau = cooccur_threshold(a, b, lut, 0.25)
    b[8] = _app(8, 50, 60, (10, 10, 200))
    links = link_tracks(a, b, lut, tau_new=tau + 1e-9)
    assert [(x, y) for x, y, _ in links] == [(1, 7)]


def test_new_person_threshold_from_the_training_pairs():
    """The former rule (``--new-threshold pairs``): the threshold with the fewest errors between the training
    pairs (genuine) and training tracks of different people (impostors), ties to the lowest."""
    from pftrack.multicam.handover import new_threshold

    a = {1: _app(1, 1, 10, (200, 10, 10)), 2: _app(2, 1, 10, (10, 200, 10)), 3: _app(3, 1, 10, (10, 10, 200))}
    b = {11: _app(11, 20, 30, (200, 10, 10)), 12: _app(12, 20, 30, (10, 200, 10)),
         13: _app(13, 20, 30, (10, 10, 200))}
    pairs = [(1, 11), (2, 12), (3, 13)]
    # genuine pairs are identical (1); impostors share one channel of three (1/3): every threshold in (1/3, 1]
    # separates them, and the lowest candidate that does is a similarity seen, 1
    assert new_threshold(a, b, pairs, "none") == pytest.approx(1.0)
    # a genuine pair that is less alike (two channels of three) moves it down to that pair's similarity
    b[13] = _app(13, 20, 30, (10, 200, 200))
    assert new_threshold(a, b, pairs, "none") == pytest.approx(2 / 3)
    # one pair gives no impostor: 0.9 of the genuine similarity; no pair, no threshold
    assert new_threshold(a, b, [(1, 11)], "none") == pytest.approx(0.9)
    assert new_threshold(a, b, [], "cbtf") == 0.0


def test_transit_time_breaks_a_tie_between_look_alikes():
    from pftrack.multicam.handover import fit_transit

    lut = np.tile(np.arange(256.0), (3, 1))
    # training: two people crossing the blind zone in about 20 frames
    a = {1: _app(1, 1, 10, (200, 10, 10)), 2: _app(2, 5, 15, (10, 200, 10)),
         3: _app(3, 100, 110, (50, 50, 50))}
    b = {11: _app(11, 30, 40, (200, 10, 10)), 12: _app(12, 36, 50, (10, 200, 10)),
         13: _app(13, 112, 130, (50, 50, 52)), 14: _app(14, 131, 140, (50, 50, 50))}
    tr = fit_transit(a, b, [(1, 11), (2, 12)])
    assert tr is not None and tr[0] == pytest.approx(np.log(20.5), abs=0.1)
    # appearance alone prefers the exact colour match arriving after 21 frames (14) ...
    plain = link_tracks(a, b, lut, exclude_a=[1, 2], exclude_b=[11, 12])
    assert [(x, y) for x, y, _ in plain] == [(3, 14)]
    # ... with the transit model, the near-identical one arriving after 2 frames (13) loses too: 14 stays
    assert [(x, y) for x, y, _ in link_tracks(a, b, lut, exclude_a=[1, 2], exclude_b=[11, 12], transit=tr)] == [(3, 14)]
    # a look-alike arriving at the usual time wins over an identical one arriving far too late
    b[14] = _app(14, 400, 410, (50, 50, 50))
    b[13] = _app(13, 130, 140, (50, 50, 56))
    assert [(x, y) for x, y, _ in link_tracks(a, b, lut, exclude_a=[1, 2], exclude_b=[11, 12])] == [(3, 14)]
    assert [(x, y) for x, y, _ in link_tracks(a, b, lut, exclude_a=[1, 2], exclude_b=[11, 12], transit=tr)] == [(3, 13)]


@pytest.mark.shared_data
@pytest.mark.skipif(not DATA.is_dir(), reason="shared data absent")
def test_handover_cli_on_a_pets_two_camera_scene(tmp_path):
    from pftrack.synth.twocam import export_twocam, twocam_scene

    sc = twocam_scene(DATA, 3, numbers=(201, 400))
    export_twocam(sc, tmp_path / "tc")
    ho = sc.handovers()
    assert ho
    pairs = tmp_path / "pairs.csv"
    pairs.write_text("track_a,track_b\n" + f"{ho[0][0]},{ho[0][1]}\n")
    out = tmp_path / "links.csv"
    cam_a, cam_b = tmp_path / "tc" / "cam_a", tmp_path / "tc" / "cam_b"
    args = ["handover", str(cam_a), str(cam_b), "--tracks-a", str(cam_a / "gt" / "gt.txt"), "--tracks-b",
            str(cam_b / "gt" / "gt.txt"), "--out", str(out), "--quiet"]
    assert main(args + ["--train-pairs", str(pairs)]) == 0
    rows = out.read_text().splitlines()
    assert rows[0] == "track_a,track_b,similarity"
    links = [tuple(int(v) for v in r.split(",")[:2]) for r in rows[1:]]
    assert links
    # each track has at most one predecessor and one successor (ch11.md §1.1)
    span_a = {t: (sc.tracks_a[sc.tracks_a[:, 1] == t, 0].min(), sc.tracks_a[sc.tracks_a[:, 1] == t, 0].max())
              for t in np.unique(sc.tracks_a[:, 1]).astype(int)}
    span_b = {t: (sc.tracks_b[sc.tracks_b[:, 1] == t, 0].min(), sc.tracks_b[sc.tracks_b[:, 1] == t, 0].max())
              for t in np.unique(sc.tracks_b[:, 1]).astype(int)}
    pred, succ = [], []
    for a, b in links:
        first, second = (("a", a), ("b", b)) if span_a[a][1] < span_b[b][0] else (("b", b), ("a", a))
        pred.append(first)
        succ.append(second)
    assert len(set(pred)) == len(pred) and len(set(succ)) == len(succ)
    assert ho[0] not in links  # training pairs are not linked again
    assert main(args[:4] + [str(tmp_path / "none.txt")] + args[5:]) == 2
    bad = tmp_path / "bad.csv"
    bad.write_text("999,1\n")
    assert main(args + ["--train-pairs", str(bad)]) == 2


@pytest.mark.skipif(not DATA.is_dir(), reason="shared data absent")
def test_handover_cli_options_and_its_bad_input(tmp_path, capsys):
    from pftrack.synth.twocam import export_twocam, twocam_scene

    sc = twocam_scene(DATA, 5, numbers=(201, 260))
    export_twocam(sc, tmp_path / "tc")
    cam_a, cam_b = tmp_path / "tc" / "cam_a", tmp_path / "tc" / "cam_b"
    out = tmp_path / "links.csv"
    args = ["handover", str(cam_a), str(cam_b), "--tracks-a", str(cam_a / "gt" / "gt.txt"), "--tracks-b",
            str(cam_b / "gt" / "gt.txt"), "--out", str(out), "--quiet"]
    links = {}
    for tau in ("none", "0.99"):  # no probe judged new, against a bar few pairs pass
        assert main(args + ["--new-threshold", tau]) == 0
        assert out.read_text().splitlines()[0] == "track_a,track_b,similarity"
        links[tau] = [float(r.split(",")[2]) for r in out.read_text().splitlines()[1:]]
        assert f"new below {float(0 if tau == 'none' else tau):.3f}" in capsys.readouterr().err
    assert all(v >= 0.99 for v in links["0.99"]) and len(links["0.99"]) <= len(links["none"])
    bad = tmp_path / "pairs.csv"
    for text, message in [(None, "no such file"), ("track_a,track_b\n1;x\n", ":2: expected track_a,track_b"),
                          ("7\n", ":1: expected track_a,track_b")]:
        if text is not None:
            bad.write_text(text)
        assert main(args + ["--train-pairs", str(bad)]) == 2
        assert message in capsys.readouterr().err
        bad.write_text("")
        bad.unlink()
    for extra, message in [(["--new-threshold", "high"], "--new-threshold must be a number"),
                           (["--transit"], "--transit needs training pairs")]:
        assert main(args + extra) == 2
        assert message in capsys.readouterr().err


def test_btf_subspace_loglik_matches_the_gaussian_and_ranks_in_family_btfs_higher():
    from scipy.stats import multivariate_normal

    from pftrack.multicam.btf import (
        btf_from_hists,
        btf_subspace_loglik,
        fit_btf_subspace,
    )

    rng = np.random.default_rng(0)
    small = rng.normal(0, 3, (12, 1, 8)) + np.linspace(0, 70, 8)
    m = fit_btf_subspace(small, q=2)
    cov = m["W"] @ m["W"].T + m["sigma2"] * np.eye(8)
    x = small[0].ravel() + 1.0
    assert btf_subspace_loglik(m, x) == pytest.approx(multivariate_normal(m["mean"], cov).logpdf(x) / 8, rel=1e-9)
    # BTFs of a gamma family (one camera pair) vs an inverted response
    v = np.arange(256.0)

    def gamma_lut(g):
        return np.stack([255 * (v / 255) ** (g * k) for k in (1.0, 1.1, 0.9)])

    train = np.stack([gamma_lut(g) + rng.normal(0, 1, (3, 256)) for g in rng.uniform(0.6, 0.9, 15)])
    model = fit_btf_subspace(train)
    assert btf_subspace_loglik(model, gamma_lut(0.75)) > btf_subspace_loglik(model, 255 - gamma_lut(0.75))
    h = np.tile(np.bincount(rng.integers(0, 256, 5000), minlength=256), (3, 1)).astype(float)
    assert btf_from_hists(h, h).shape == (3, 256)


def test_colour_responses_are_monotone_and_the_strong_family_is_wider():
    from pftrack.synth.twocam import colour_response

    mild = [colour_response(np.random.default_rng(s)) for s in range(40)]
    strong = [colour_response(np.random.default_rng(s), "strong") for s in range(40)]
    for t in mild + strong:
        assert t.shape == (3, 256) and np.all(np.diff(t, axis=1) >= 0) and t.min() >= 0 and t.max() <= 255
    # the same seed gives the same mild tables as before the strong family existed (rng drawn g, gamma, o)
    rng = np.random.default_rng(7)
    v = np.arange(256) / 255.0
    ref = [255.0 * np.clip(rng.uniform(0.7, 1.25) * v ** rng.uniform(0.55, 1.8) + rng.uniform(-0.1, 0.1), 0, 1)
           for _ in range(3)]
    np.testing.assert_allclose(colour_response(np.random.default_rng(7)), np.maximum.accumulate(np.stack(ref), 1))
    # how far a mid-grey moves: the strong family spreads it more
    spread = lambda ts: np.std([t[:, 128] for t in ts])  # noqa: E731
    assert spread(strong) > 1.3 * spread(mild)


def test_cbtf_weights_people_alike_or_by_pixels():
    """cbtf(weight="people") scales each training histogram to unit mass before pooling; "pixels" pools raw counts.
    Two training people show the same levels, rendered differently by camera 2 (0.5 v and 0.9 v): the big one
    decides the pixel-weighted BTF, while the people-weighted one gives both their share."""
    v = np.arange(256)
    h = np.zeros((3, 256))
    h[:, 100:160] = 1.0
    g1, g2 = np.zeros((3, 256)), np.zeros((3, 256))
    for c in range(3):
        np.add.at(g1[c], np.round(0.5 * v[100:160]).astype(int), 1.0)
        np.add.at(g2[c], np.round(0.9 * v[100:160]).astype(int), 1.0)
    big = 50.0                                        # person 2 seen 50 times larger
    src, dst = [h, big * h], [g1, big * g2]
    by_people = cbtf(src, dst, weight="people")
    by_pixels = cbtf(src, dst, weight="pixels")
    assert np.array_equal(by_people, cbtf([h, h], [g1, g2], weight="pixels"))  # unit mass: size no longer counts
    f1, f2 = 0.5 * v[100:160], 0.9 * v[100:160]
    assert np.abs(by_pixels[0, 100:160] - f2).mean() < 4          # the big person's response
    err_people = np.abs(by_people[0, 100:160] - f1).mean()
    err_pixels = np.abs(by_pixels[0, 100:160] - f1).mean()
    assert err_people < 0.8 * err_pixels, (err_people, err_pixels)
    with pytest.raises(ValueError):
        cbtf(src, dst, weight="area")


def test_synth_twocam_scales_its_strip_to_any_source_and_takes_frames_and_strip(tmp_path):
    """``pftrack synth twocam`` on a MOTChallenge folder that is not PETS: the blind strip sits at the same fractions
    of the width by default (340 and 430 of PETS's 768 pixels), ``--frames`` and ``--strip`` choose the frames and
    the strip, and the cameras keep the source's frame rate."""
    import configparser

    import cv2

    from pftrack.synth.traffic import export_traffic, traffic_scene
    from pftrack.synth.twocam import default_split

    assert default_split(768) == (340, 430) and default_split(320) == (142, 180)
    src = tmp_path / "src"
    export_traffic(traffic_scene(0, n_vehicles=3), src)
    n = len(list((src / "img1").iterdir()))

    def info(folder):
        cp = configparser.ConfigParser()
        cp.read(folder / "seqinfo.ini")
        return cp["Sequence"]

    assert main(["synth", "twocam", "--source", str(src), "--seeds", "0", "--out", str(tmp_path / "d")]) == 0
    a, b = tmp_path / "d" / "twocam-000" / "cam_a", tmp_path / "d" / "twocam-000" / "cam_b"
    assert cv2.imread(str(a / "img1" / "000001.jpg")).shape[1] == 142
    assert cv2.imread(str(b / "img1" / "000001.jpg")).shape[1] == 320 - 180
    assert info(a)["seqLength"] == str(n) and info(a)["frameRate"] == "30"
    assert main(["synth", "twocam", "--source", str(src), "--seeds", "0", "--frames", "2-10", "--strip", "100,50",
                 "--out", str(tmp_path / "e")]) == 0
    a, b = tmp_path / "e" / "twocam-000" / "cam_a", tmp_path / "e" / "twocam-000" / "cam_b"
    assert cv2.imread(str(a / "img1" / "000001.jpg")).shape[1] == 100
    assert cv2.imread(str(b / "img1" / "000001.jpg")).shape[1] == 170
    assert info(b)["seqLength"] == "9" and len(list((b / "img1").iterdir())) == 9
    for bad in (["--strip", "300,50"], ["--strip", "x"], ["--frames", "0-5"], ["--frames", f"1-{n + 1}"]):
        assert main(["synth", "twocam", "--source", str(src), "--seeds", "0", *bad, "--out", str(tmp_path / "f")]) == 2
