"""Joint colour histograms for the hand-over (pftrack's extension of book ch. 11): construction, the push through a
per-channel BTF, similarity, track appearances and the command."""

from pathlib import Path

import numpy as np
import pytest

from pftrack.cli import main
from pftrack.multicam.appearance import region_histograms, similarity
from pftrack.multicam.btf import apply_btf_image, identity_btf
from pftrack.multicam.handover import describe_tracks, link_tracks, similarities
from pftrack.multicam.joint import (
    joint_histogram,
    joint_similarity_matrix,
    mean_sparse,
    push_joint,
    transfer_matrices,
)

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "pets09_s2l1_dev"


def _dense(cells, masses, regions, levels):
    out = np.zeros(regions * levels ** 3)
    np.add.at(out, cells, masses)
    return out


def _image(seed=0, shape=(60, 30)):
    return np.random.default_rng(seed).integers(0, 256, (*shape, 3)).astype(np.uint8)


def test_the_joint_histogram_counts_each_pixel_once_in_its_region_and_colour():
    img = _image()
    cells, masses, n = joint_histogram(img, (0, 0, 30, 60), "positional", levels=8)
    assert n == 8 and masses.sum() == pytest.approx(1.0) and np.all(np.diff(cells) > 0)
    # one region: the cell of a pixel is (r // 32, g // 32, b // 32), R, G, B of the BGR frame
    cells, masses, _ = joint_histogram(img, (0, 0, 30, 60), "whole", levels=8)
    rgb = img[..., ::-1].reshape(-1, 3).astype(int) // 32
    expect = np.bincount((rgb[:, 0] * 8 + rgb[:, 1]) * 8 + rgb[:, 2], minlength=512) / rgb.shape[0]
    np.testing.assert_allclose(_dense(cells, masses, 1, 8), expect)
    fg = np.zeros((60, 30), np.uint8)
    assert len(joint_histogram(img, (0, 0, 30, 60), "whole", fg=fg)[0]) == 0  # no foreground pixel: empty


def test_the_push_through_the_identity_sums_the_fine_cells():
    img = _image(1)
    fine = joint_histogram(img, (0, 0, 30, 60), "positional")          # 32 levels a channel
    coarse = joint_histogram(img, (0, 0, 30, 60), "positional", levels=8)
    np.testing.assert_allclose(push_joint(fine[0], fine[1], 8, identity_btf()), _dense(coarse[0], coarse[1], 8, 8),
                               atol=1e-15)


def test_the_push_equals_histogramming_the_mapped_pixels_for_a_btf_constant_on_each_bin():
    """A table constant on each bin of 8 levels sends all of a cell's pixels to one cell: exact. Any table keeps the
    mass."""
    rng = np.random.default_rng(2)
    steps = np.sort(rng.integers(0, 256, (3, 32)), axis=1).astype(np.float64)
    lut = np.repeat(steps, 8, axis=1)                                    # (3, 256), constant on each bin
    img = _image(2)
    cells, masses, n = joint_histogram(img, (0, 0, 30, 60), "ellipse2")
    mapped = apply_btf_image(img, lut)
    want = joint_histogram(mapped, (0, 0, 30, 60), "ellipse2", levels=8)
    np.testing.assert_allclose(push_joint(cells, masses, n, lut), _dense(want[0], want[1], n, 8), atol=1e-15)
    other = np.sort(rng.uniform(0, 255, (3, 256)), axis=1)
    assert push_joint(cells, masses, n, other).sum() == pytest.approx(masses.sum())
    T = transfer_matrices(other)
    np.testing.assert_allclose(T.sum(axis=2), 1.0)


def test_joint_colours_tell_apart_what_the_channels_one_by_one_do_not():
    """Red over blue against blue over red, in one region: the same three channel histograms, not the same
    colours."""
    a = np.zeros((40, 20, 3), np.uint8)
    a[:20, :, 2] = 220                                                   # red (BGR) on top
    a[20:, :, 0] = 220                                                   # blue below
    b = a[::-1].copy()
    c = a.copy()
    c[:20, :, 1] = 220                                                   # yellow on top instead of red
    box = (0, 0, 20, 40)
    assert similarity(region_histograms(a, box, "whole"), region_histograms(b, box, "whole")) == pytest.approx(1.0)
    d = [push_joint(*joint_histogram(x, box, "whole")[:2], 1, identity_btf()) for x in (a, b, c)]
    S = joint_similarity_matrix(np.stack(d), np.stack(d))
    np.testing.assert_allclose(np.diag(S), 1.0)
    assert S[0, 1] == pytest.approx(1.0)           # the same colours, only swapped between halves: one region
    assert S[0, 2] < 0.5


def test_a_track_keeps_its_mean_joint_histogram_and_empty_frames_count():
    img = _image(4, (100, 100))
    fg = np.zeros((100, 100), np.uint8)
    fg[:50] = 255
    rows = np.array([[1, 7, 0, 0, 40, 40], [2, 7, 0, 60, 40, 40], [3, 7, 0, 0, 40, 40]], dtype=float)
    frames = {1: img, 2: img, 3: img}
    masks = {1: fg, 2: fg, 3: fg}
    app = describe_tracks(frames.get, rows, "positional", fg=masks.get, every=1, histogram="joint")[7]
    cells, masses = app.joint
    assert app.regions == 8 and app.samples == 3
    assert masses.sum() == pytest.approx(2 / 3)                          # frame 2's box has no foreground
    one = joint_histogram(img, (0, 0, 40, 40), "positional", fg=fg)
    np.testing.assert_allclose(_dense(cells, masses, 8, 32), _dense(one[0], one[1], 8, 32) * 2 / 3)
    assert mean_sparse([], 4)[0].size == 0
    with pytest.raises(ValueError):
        describe_tracks(frames.get, rows, "positional", histogram="lab")


def test_a_box_beyond_the_frame_counts_as_an_empty_sample():
    """A ground-truth box that lies wholly outside the frame (MOTChallenge boxes may) gives no pixels: the track
    keeps the sample as empty, as before the patch's colour conversion was shared, and nothing fails."""
    img = _image(4, (100, 100))
    rows = np.array([[1, 7, 0, 0, 40, 40], [2, 7, 120, 10, 30, 40]], dtype=float)
    app = describe_tracks({1: img, 2: img}.get, rows, "positional", every=1, histogram="joint")[7]
    assert app.samples == 2
    assert app.joint[1].sum() == pytest.approx(1 / 2)

def test_links_compare_joint_histograms_when_both_cameras_have_them():
    rng = np.random.default_rng(5)
    imgs = [rng.integers(0, 256, (40, 20, 3)).astype(np.uint8) for _ in range(2)]
    ra = np.array([[1, 1, 0, 0, 20, 40], [2, 2, 0, 0, 20, 40]], dtype=float)
    rb = np.array([[5, 8, 0, 0, 20, 40], [6, 9, 0, 0, 20, 40]], dtype=float)
    fa = {1: imgs[0], 2: imgs[1]}
    fb = {5: imgs[1], 6: imgs[0]}
    app_a = describe_tracks(fa.get, ra, "positional", every=1, histogram="joint")
    app_b = describe_tracks(fb.get, rb, "positional", every=1, histogram="joint")
    ka, kb, S = similarities(app_a, app_b, identity_btf())
    assert (ka, kb) == ([1, 2], [8, 9]) and S[0, 1] == pytest.approx(1.0) and S[1, 0] == pytest.approx(1.0)
    assert sorted((a, b) for a, b, _ in link_tracks(app_a, app_b, identity_btf(), tau_new=0.5)) == [(1, 9), (2, 8)]


@pytest.mark.skipif(not DATA.is_dir(), reason="PETS dev frames not present")
def test_handover_cli_with_joint_histograms(tmp_path):
    from pftrack.synth.twocam import export_twocam, twocam_scene

    sc = twocam_scene(DATA, 3, numbers=(201, 260))
    export_twocam(sc, tmp_path / "tc")
    cam_a, cam_b = tmp_path / "tc" / "cam_a", tmp_path / "tc" / "cam_b"
    out = tmp_path / "links.csv"
    args = ["handover", str(cam_a), str(cam_b), "--tracks-a", str(cam_a / "gt" / "gt.txt"), "--tracks-b",
            str(cam_b / "gt" / "gt.txt"), "--out", str(out), "--quiet", "--histogram", "joint"]
    assert main(args) == 0
    assert out.read_text().splitlines()[0] == "track_a,track_b,similarity"
    with pytest.raises(SystemExit) as bad:
        main(args[:-1] + ["rgb"])
    assert bad.value.code == 2


def test_a_grey_camera_keeps_the_channels_histograms():
    """On grey frames the joint cells would cut the grey diagonal into 8 levels: a grey camera's appearances keep
    no joint histogram, so its links compare the channels' histograms (256 levels)."""
    rng = np.random.default_rng(6)
    colour = rng.integers(0, 256, (40, 20, 3)).astype(np.uint8)
    grey = np.repeat(colour[..., :1], 3, axis=2)
    rows = np.array([[1, 1, 0, 0, 20, 40], [2, 1, 0, 0, 20, 40], [3, 1, 0, 0, 20, 40]], dtype=float)
    mostly_grey = {1: grey, 2: grey, 3: colour}
    assert describe_tracks(mostly_grey.get, rows, "positional", every=1)[1].joint is None
    mostly_colour = {1: colour, 2: colour, 3: grey}
    assert describe_tracks(mostly_colour.get, rows, "positional", every=1)[1].joint is not None
    a = describe_tracks({1: grey}.get, rows[:1], "positional", every=1)
    b = describe_tracks({5: colour}.get, np.array([[5, 9, 0, 0, 20, 40]], float), "positional", every=1)
    assert a[1].joint is None and b[9].joint is not None
    _, _, S = similarities(a, b, identity_btf())   # one grey camera: both compared by their channels
    assert S.shape == (1, 1) and 0.0 < S[0, 0] < 1.0


def test_a_grey_camera_stops_counting_joint_cells_once_most_of_its_frames_are_grey(monkeypatch):
    """Once more than half of the frames to read are grey the camera is grey whatever the rest, and its joint
    histograms would be dropped: none is computed from then on (the appearances are the same)."""
    import pftrack.multicam.handover as handover

    rng = np.random.default_rng(7)
    colour = rng.integers(0, 256, (40, 20, 3)).astype(np.uint8)
    grey = np.repeat(colour[..., :1], 3, axis=2)
    rows = np.array([[n, 1, 0, 0, 20, 40] for n in (1, 2, 3)], dtype=float)
    frames = {1: grey, 2: grey, 3: colour}
    before = describe_tracks(frames.get, rows, "positional", every=1)[1]
    calls = []
    real = handover.joint_histogram
    monkeypatch.setattr(handover, "joint_histogram", lambda *a, **k: calls.append(1) or real(*a, **k))
    after = describe_tracks(frames.get, rows, "positional", every=1)[1]
    assert len(calls) == 1  # frame 1 only: after frame 2, two of the three frames are grey
    assert after.joint is None and before.joint is None
    assert np.array_equal(after.hist, before.hist) and np.array_equal(after.raw, before.raw)
