import numpy as np
import pytest

from pftrack.errors import BoxError
from pftrack.geometry import (box_to_ellipse, center_error, clip_box, ellipse_mask, ellipse_to_box, iou, iou_matrix,
                              parse_box, polygon_to_box, validate_box)


def test_box_ellipse_roundtrip():
    b = np.array([10.0, 20.0, 30.0, 40.0])
    e = box_to_ellipse(b)
    assert e.tolist() == [25.0, 40.0, 15.0, 20.0]
    assert ellipse_to_box(e).tolist() == b.tolist()


def test_iou_known_values():
    a = (0, 0, 10, 10)
    assert iou(a, a) == pytest.approx(1.0)
    # shifted by half its width: intersection 50, union 150
    assert iou(a, (5, 0, 10, 10)) == pytest.approx(50 / 150)
    assert iou(a, (20, 20, 5, 5)) == 0.0
    # degenerate and non-finite boxes give 0, never NaN
    assert iou(a, (0, 0, 0, 0)) == 0.0
    assert iou(a, (np.nan, 0, 1, 1)) == 0.0


def test_iou_matrix_shape_and_symmetry():
    a = np.array([[0, 0, 10, 10], [5, 5, 10, 10]], float)
    m = iou_matrix(a, a)
    assert m.shape == (2, 2)
    assert np.allclose(m, m.T)
    assert np.allclose(np.diag(m), 1.0)


def test_polygon_to_box():
    poly = [334.02, 128.36, 438.19, 188.78, 396.39, 260.83, 292.23, 200.41]
    b = polygon_to_box(poly)
    assert b == pytest.approx([292.23, 128.36, 438.19 - 292.23, 260.83 - 128.36])
    assert polygon_to_box([1, 2, 3, 4]).tolist() == [1, 2, 3, 4]
    with pytest.raises(BoxError):
        polygon_to_box([1, 2, 3, 4, 5])


def test_clip_and_center_error():
    assert clip_box((-5, -5, 20, 20), 10, 10).tolist() == [0, 0, 10, 10]
    assert clip_box((20, 20, 5, 5), 10, 10)[2:].tolist() == [0, 0]
    assert center_error((0, 0, 10, 10), (3, 4, 10, 10)) == pytest.approx(5.0)


def test_parse_and_validate_box():
    assert parse_box("1,2,3,4") == (1.0, 2.0, 3.0, 4.0)
    assert parse_box("1 2\t3 4") == (1.0, 2.0, 3.0, 4.0)
    for bad in ["1,2,3", "a,b,c,d", ""]:
        with pytest.raises(BoxError):
            parse_box(bad)
    assert validate_box((1, 2, 3, 4), 100, 100) == (1.0, 2.0, 3.0, 4.0)
    for bad in [(0, 0, 0, 5), (0, 0, -1, 5), (200, 0, 5, 5), (-10, -10, 5, 5), (np.nan, 0, 5, 5), (0, 0, 5)]:
        with pytest.raises(BoxError):
            validate_box(bad, 100, 100)


def test_ellipse_mask_area():
    m = ellipse_mask((200, 200), (100, 100, 40, 20))
    assert abs(m.sum() - np.pi * 40 * 20) / (np.pi * 40 * 20) < 0.01


def test_background_grid_covers_the_frame_and_leaves_out_the_target():
    from pftrack.geometry import background_grid

    ell = background_grid(320, 240, 10.0, 20.0, 100)
    assert 80 <= len(ell) <= 120 and np.all(ell[:, 2] == 10.0) and np.all(ell[:, 3] == 20.0)
    assert ell[:, 0].min() > 0 and ell[:, 0].max() < 320 and ell[:, 1].min() > 0 and ell[:, 1].max() < 240
    target = np.array([160.0, 120.0, 15.0, 25.0])
    kept = background_grid(320, 240, 10.0, 20.0, 100, exclude=target)
    assert 0 < len(kept) < len(ell)
    assert np.all((np.abs(kept[:, 0] - 160.0) >= 25.0) | (np.abs(kept[:, 1] - 120.0) >= 45.0))
    assert len(background_grid(320, 240, 400.0, 400.0, 100)) == 1  # no denser than one half-axis per cell


def test_exit_edge_is_numpy_argmin_of_the_four_distances():
    from pftrack.geometry import exit_edge

    g = np.random.default_rng(0)
    for _ in range(3000):
        cx, cy = (float(v) for v in g.integers(-20, 340, 2))
        hx, hy = (float(v) for v in g.integers(1, 40, 2))
        if g.random() < 0.05:
            cx = float("nan")
        want = int(np.argmin([cx / hx, (320 - cx) / hx, cy / hy, (240 - cy) / hy]))
        assert exit_edge(cx, cy, hx, hy, 320, 240) == want
    assert exit_edge(-5.0, 100.0, 10.0, 10.0, 320, 240) == 0
    assert exit_edge(330.0, 100.0, 10.0, 10.0, 320, 240) == 1
    assert exit_edge(160.0, 3.0, 10.0, 10.0, 320, 240) == 2
    assert exit_edge(160.0, 239.0, 10.0, 10.0, 320, 240) == 3


def test_background_grid_compiled_equals_the_numpy_path():
    from pftrack._numba import numba_enabled, set_numba_enabled
    from pftrack.geometry import background_grid

    if not numba_enabled():
        pytest.skip("Numba is off")
    g = np.random.default_rng(5)
    for t in range(300):
        w, h = int(g.integers(10, 1000)), int(g.integers(10, 800))
        hx, hy, cap = float(g.uniform(0.5, 200)), float(g.uniform(0.5, 200)), int(g.integers(1, 300))
        ex = None if t % 3 == 0 else np.array([g.uniform(-50, w + 50), g.uniform(-50, h + 50), g.uniform(1, 150),
                                               g.uniform(1, 150)])
        if ex is not None and t % 7 == 1:
            ex[0] = np.nan  # a NaN centre: its test is false, so only the cells clear of it by the other axis stay
        fast = background_grid(w, h, hx, hy, cap, ex)
        set_numba_enabled(False)
        try:
            ref = background_grid(w, h, hx, hy, cap, ex)
        finally:
            set_numba_enabled(True)
        assert fast.shape == ref.shape and np.array_equal(fast, ref)
