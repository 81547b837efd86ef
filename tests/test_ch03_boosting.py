"""Book ch. 3 §3.1–3.2: LTP codes and online real AdaBoost (ch03.md §5.1, tests 1, 2 and 4)."""

import numpy as np
import pytest

from pftrack.cues.boosting import (GREY_LTP, LTP_PAIRS, OnlineRealBoost, grey_texture, ltp_codes, ltp_features,
                                   pixel_features, riu2_table)

# neighbour u = 0..7 clockwise from the right: (0,1) (1,1) (1,0) (1,-1) (0,-1) (-1,-1) (-1,0) (-1,1)
_POS = [(1, 2), (2, 2), (2, 1), (2, 0), (1, 0), (0, 0), (0, 1), (0, 2)]


def _patch(centre, neigh):
    p = np.zeros((3, 3), np.uint8)
    p[1, 1] = centre
    for (r, c), v in zip(_POS, neigh):
        p[r, c] = v
    return p


def test_ltp_codes_on_hand_computed_patches():
    riu2 = riu2_table()
    p = _patch(100, [110, 100, 90, 104, 96, 120, 80, 100])
    up, lo = ltp_codes(p, p, 5)
    assert (int(up[1, 1]), int(lo[1, 1])) == (33, 68)
    assert 10 * riu2[33] + riu2[68] == 99
    p = _patch(100, [110, 110, 110, 100, 100, 90, 90, 100])
    up, lo = ltp_codes(p, p, 5)
    assert (int(up[1, 1]), int(lo[1, 1])) == (7, 96)
    assert 10 * riu2[7] + riu2[96] == 32
    # cross-channel: the centre from one channel, the neighbours from another
    centre = np.full((3, 3), 100, np.uint8)
    up, lo = ltp_codes(centre, p, 5)
    assert (int(up[1, 1]), int(lo[1, 1])) == (7, 96)
    up2, lo2 = ltp_codes(p, centre, 5)  # swapped: neighbours all equal the centre value 100 of channel 1
    assert int(up2[1, 1]) == 0 and int(lo2[1, 1]) == 0
    flat = np.full((8, 8), 77, np.uint8)
    u, low = ltp_codes(flat, flat, 5)
    assert not u.any() and not low.any()


def test_pixel_features_shapes_and_ranges():
    img = np.random.default_rng(0).integers(0, 256, (20, 30, 3)).astype(np.uint8)
    col, tex = pixel_features(img)
    assert col.shape == (20, 30, 4) and tex.shape == (20, 30, 9)
    assert col.min() >= 0 and col.max() < 32 and tex.min() >= 0 and tex.max() < 100


def test_weak_learner_value():
    b = OnlineRealBoost(1, 4, n_selectors=1, eps=1.0)
    b.w[0, 0, 2] = (30.0, 10.0)
    b.alpha[0], b.sel[0] = 1.0, 0
    assert b.confidence(np.array([[2]]))[0] == pytest.approx(0.5 * np.log(31 / 11), abs=1e-12)


def test_online_boosting_learns_a_planted_rule():
    rng = np.random.default_rng(1)

    def sample(n):
        pos = rng.random(n) < 0.5
        r = np.where(pos, rng.integers(200, 256, n), rng.integers(0, 101, n))
        g, bl = rng.integers(0, 256, n), rng.integers(0, 256, n)
        x = np.stack([r, g, bl, (r + g + bl) // 3], axis=1) * 32 // 256
        return x, np.where(pos, 1.0, -1.0)

    boost = OnlineRealBoost(4, 32, n_selectors=10)
    x, y = sample(500)
    boost.update(x, y)
    xt, yt = sample(2000)
    acc = np.mean(np.sign(boost.confidence(xt)) == yt)
    assert acc >= 0.99
    assert np.sum(boost.sel == 0) >= 8  # at least 8 of the 10 selectors vote with R
    with pytest.raises(ValueError):
        boost.update(np.array([[40, 0, 0, 0]]), [1.0])


def test_fusion_rule_and_best_blob():
    from pftrack.cues.cotrain import best_blob, fuse

    c = np.array([2.0, 2.0, -2.0])
    t = np.array([3.0, -1.0, -1.0])
    np.testing.assert_array_equal(fuse(c, t), [3.0, -2.0, -2.0])  # both negative stays negative (|.| restored)
    m = np.full((20, 30), -1.0)
    m[2:5, 2:5] = 1.0       # small blob, mass 9
    m[8:18, 10:20] = 0.5    # large blob, mass 50
    b = best_blob(m)
    assert b.mass == pytest.approx(50.0) and b.mask[12, 15] and not b.mask[3, 3]
    np.testing.assert_allclose(b.centre, [14.5, 12.5])
    assert best_blob(np.full((5, 5), -1.0)) is None


def test_cotrainer_separates_a_coloured_textured_target():
    from pftrack.cues.cotrain import CoTrainer

    rng = np.random.default_rng(4)
    img = np.clip(rng.normal(110, 10, (60, 80, 3)), 0, 255).astype(np.uint8)
    img[20:40, 30:50] = np.clip(rng.normal((40, 60, 200), 40, (20, 20, 3)), 0, 255).astype(np.uint8)
    co = CoTrainer(n_selectors=10, rng=rng)
    feats = co.features(img)
    pos = np.zeros((60, 80), bool)
    pos[22:38, 32:48] = True
    neg = np.ones((60, 80), bool)
    neg[16:44, 26:54] = False
    for _ in range(2):
        co.learn(feats, pos, neg, max_each=300)
    cc, _ct, fu = co.maps(feats, opening=1)
    assert (cc[pos] > 0).mean() > 0.8 and (cc[neg] > 0).mean() < 0.2
    assert (fu[pos] > 0).mean() > (fu[neg] > 0).mean() + 0.3


def test_cotrainer_cross_labels_teach_each_view_separately():
    from pftrack.cues.cotrain import CoTrainer

    rng = np.random.default_rng(5)
    img = np.clip(rng.normal(110, 10, (40, 40, 3)), 0, 255).astype(np.uint8)
    co = CoTrainer(n_selectors=5, rng=rng)
    feats = co.features(img)
    pos_c = np.zeros((40, 40), bool)
    pos_c[5:15, 5:15] = True
    pos_t = np.zeros((40, 40), bool)
    pos_t[25:35, 25:35] = True
    neg = np.zeros((40, 40), bool)
    neg[:, 18:22] = True
    n = co.learn(feats, pos_c, neg, pos_texture=pos_t, max_each=50)
    assert n == 4 * 50  # each classifier saw its own 50 positives and 50 negatives
    assert co.colour.alpha.any() and co.texture.alpha.any()


def test_compiled_ltp_features_equal_the_pairwise_codes():
    """The one-pass kernel gives ltp_codes' numbers for the nine channel pairs and the grey radii/thresholds,
    borders included."""
    rng = np.random.default_rng(3)
    img = rng.integers(0, 256, (23, 31, 3)).astype(np.uint8)
    riu2 = riu2_table()

    def blocks(up, lo):
        return 10 * riu2[up] + riu2[lo]

    ref = np.stack([blocks(*ltp_codes(img[..., c], img[..., n], 5.0)) for c, n in LTP_PAIRS], axis=-1)
    assert np.array_equal(ltp_features(img, LTP_PAIRS, t=5.0), ref)
    g = img[..., 1]
    ref = np.stack([blocks(*ltp_codes(g, g, m * 5.0, radius=r)) for r, m in GREY_LTP], axis=-1)
    assert np.array_equal(grey_texture(g, t=5.0), ref)
