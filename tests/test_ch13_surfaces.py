"""Book ch. 13: meshes, Laplacians, the IRLS normal equations, the solver, the tracker and the CLI."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from pftrack._numba import set_numba_enabled
from pftrack.cli import main
from pftrack.surfaces.mesh import (
    Grid,
    directional_laplacian,
    interp_weights,
    parse_mesh,
    signed_areas,
    umbrella_laplacian,
    weights_matrix,
)
from pftrack.surfaces.solver import (
    MeshSolver,
    SolverSettings,
    dense_jacobian,
    gradients,
    huber_rho,
    huber_weights,
    pyramid,
)
from pftrack.synth.deform import band_limited_texture, deform_scene


def _texture(seed=0, size=(240, 320)):
    return band_limited_texture(np.random.default_rng(seed), size).astype(np.float32)


def _warp_image(tex: np.ndarray, fwd) -> np.ndarray:
    """``I_n(x + D(x)) = I_0(x)`` rendered by fixed-point inversion of ``y = fwd(x)``."""
    h, w = tex.shape
    ys, xs = np.mgrid[0:h, 0:w].astype(np.float64)
    y = np.stack([xs.ravel(), ys.ravel()], 1)
    x = y.copy()
    for _ in range(60):
        x = y - (fwd(x) - x)
    return cv2.remap(tex, x[:, 0].reshape(h, w).astype(np.float32), x[:, 1].reshape(h, w).astype(np.float32),
                     cv2.INTER_CUBIC, borderMode=cv2.BORDER_REFLECT)


@pytest.mark.parametrize("model,m", [("affine", 3), ("bilinear", 4)])
def test_interpolation_weights_partition_unity_and_reproduce_affine_motion(model, m):
    g = Grid.for_box((20.5, 10.0, 150, 120), 6, 5)
    rng = np.random.default_rng(0)
    pts = np.c_[rng.uniform(20.5, 170.5, 2000), rng.uniform(10, 130, 2000)]
    idx, w = interp_weights(g, pts, model)
    B = weights_matrix(idx, w, g.K)
    assert np.allclose(np.asarray(B.sum(1)).ravel(), 1, atol=1e-12)
    assert np.all(np.diff(B.indptr) == m) and np.all(w >= -1e-12)
    A, t = np.array([[1.05, -0.1], [0.07, 0.93]]), np.array([3.2, -1.7])
    V = g.vertices()
    d = V @ A.T + t - V
    assert np.max(np.abs(B @ d - (pts @ A.T + t - pts))) < 1e-10
    assert np.max(np.abs(B @ V - pts)) < 1e-10          # the mesh itself interpolates positions exactly


def test_laplacians():
    g = Grid.for_box((0, 0, 100, 80), 5, 6)
    V = g.vertices()
    L = directional_laplacian(g.rows, g.cols)
    A = np.array([[0.9, 0.2], [-0.15, 1.1]])
    for P in (V, V @ A.T + 5):
        assert np.max(np.abs(L @ P)) < 1e-12
    assert np.max(np.abs(L @ np.ones(g.K))) < 1e-12
    U = umbrella_laplacian(g, "graph")
    border = np.ones((g.rows, g.cols), bool)
    border[1:-1, 1:-1] = False
    lv = np.abs(U @ V[:, 0]).reshape(g.rows, g.cols)
    assert lv[border].max() > 1 and lv[~border].max() < 1e-9       # L11452-11458: border problem
    for kind in ("uniform", "distance"):
        Us = umbrella_laplacian(g, kind)
        assert np.allclose(Us @ np.ones(g.K), 0, atol=1e-12)
        assert np.allclose(Us.diagonal(), -1)


def test_huber_weights_and_rho():
    r = np.linspace(-3, 3, 61)
    w = huber_weights(r, 1.0)
    assert np.array_equal(w, np.where(np.abs(r) <= 1, 1.0, 1.0 / np.maximum(np.abs(r), 1e-300)))
    rho = huber_rho(r, 1.0)
    assert np.allclose(rho, np.where(np.abs(r) <= 1, r * r / 2, np.abs(r) - 0.5))
    # w = rho'(r)/r (Eq. 28), checked numerically
    eps = 1e-6
    num = (huber_rho(r + eps, 1.0) - huber_rho(r - eps, 1.0)) / (2 * eps)
    nz = np.abs(r) > 1e-3
    assert np.allclose(num[nz] / r[nz], w[nz], atol=1e-6)


def _solver(photometric=True, lam=0.01, rows=5, cols=5, levels=1, size=(240, 320)):
    I0 = cv2.GaussianBlur(_texture(1, size), (0, 0), 2.0)
    g = Grid.for_box((80, 60, 160, 120), rows, cols)
    gp = Grid.for_box((80, 60, 160, 120), 3, 3)
    return I0, g, gp, MeshSolver(I0, g, gp, SolverSettings(photometric=photometric, lam=lam, levels=levels))


def test_zero_parameters_synthesise_the_model_exactly():
    I0, g, gp, S = _solver()
    r, _ = S.residual(S.levels[0], I0, np.zeros((g.K, 2)), np.ones(gp.K))
    assert np.max(np.abs(r)) < 1e-6


def test_jacobian_matches_finite_differences():
    I0, g, gp, S = _solver()
    rng = np.random.default_rng(0)
    In = cv2.GaussianBlur(I0, (0, 0), 6.0)
    In = (In - In.min()) / (np.ptp(In) + 1e-9)
    gx, gy = gradients(In)
    d = rng.uniform(-3, 3, (g.K, 2))
    rho = rng.uniform(0.7, 1.3, gp.K)
    J = dense_jacobian(S, 0, In, gx, gy, d)
    lv = S.levels[0]
    r0, _ = S.residual(lv, In, d, rho)
    ok = np.isfinite(r0)
    eps = 1e-3
    rel = []
    for k in rng.choice(2 * g.K, 8, replace=False):
        dd = d.copy().ravel(order="F")
        dd[k] += eps
        rp, _ = S.residual(lv, In, dd.reshape(d.shape, order="F"), rho)
        dd[k] -= 2 * eps
        rm, _ = S.residual(lv, In, dd.reshape(d.shape, order="F"), rho)
        num = (rp - rm)[ok] / (2 * eps)
        rel.append(np.linalg.norm(num - J[ok, k]) / max(np.linalg.norm(num), 1e-12))
    # The finite difference sees the slope of the bilinear interpolant, f(x0+1) - f(x0); the analytic row
    # uses the interpolated central-difference gradient.  They differ by ~f''/f' x frac, about 4 % on this
    # smooth image; a wrong sign, scale or column would be off by >= 100 %.
    assert np.median(rel) < 0.06
    for k in range(gp.K):                                  # photometric columns are exact (r is linear in rho)
        e = np.zeros(gp.K)
        e[k] = 1.0
        rp, _ = S.residual(lv, In, d, rho + e)
        assert np.allclose((rp - r0)[ok], J[ok, 2 * g.K + k], atol=1e-6)


def test_normal_equations_equal_the_stacked_least_squares_form():
    """Test 5 of ch13.md: the stacked [J; lam Gamma], [r; lam Gamma theta] system and the closed form agree,
    which pins the lambda that Eq. (32) omits; Gauss-Newton (huge Huber threshold) is the plain LS step."""
    I0, g, gp, S = _solver(lam=0.3)
    rng = np.random.default_rng(2)
    In = np.roll(I0, 2, axis=1)
    gx, gy = gradients(In)
    d = rng.uniform(-1, 1, (g.K, 2))
    rho = rng.uniform(0.9, 1.1, gp.K)
    A, b, r, ok, _ = S.normal_equations(S.levels[0], In, gx, gy, d, rho, vH=1e9)
    J = dense_jacobian(S, 0, In, gx, gy, d)[ok]
    N = ok.sum()
    from pftrack.surfaces.mesh import directional_laplacian as DL

    Lg, Lp = DL(g.rows, g.cols).toarray(), DL(gp.rows, gp.cols).toarray()
    Gam = np.zeros((2 * Lg.shape[0] + Lp.shape[0], 2 * g.K + gp.K))
    Gam[:Lg.shape[0], :g.K] = Lg
    Gam[Lg.shape[0]:2 * Lg.shape[0], g.K:2 * g.K] = Lg
    Gam[2 * Lg.shape[0]:, 2 * g.K:] = S.s.lam_p * Lp
    theta = np.r_[d[:, 0], d[:, 1], rho]
    nG = S.n_gamma
    Js = np.vstack([J / np.sqrt(N), S.s.lam / np.sqrt(nG) * Gam])
    bs = np.r_[r[ok] / np.sqrt(N), S.s.lam / np.sqrt(nG) * Gam @ theta]
    step_ls = np.linalg.lstsq(Js, -bs, rcond=None)[0]
    step = -np.linalg.solve(A, b)
    assert np.allclose(step, step_ls, rtol=1e-8, atol=1e-10)


def test_compiled_and_numpy_assembly_agree():
    I0, g, gp, S = _solver()
    In = np.roll(I0, 1, axis=0)
    gx, gy = gradients(In)
    d = np.random.default_rng(3).uniform(-2, 2, (g.K, 2))
    rho = np.full(gp.K, 1.05)
    A1, b1, *_ = S.normal_equations(S.levels[0], In, gx, gy, d, rho)
    prev = set_numba_enabled(False)
    try:
        A2, b2, *_ = S.normal_equations(S.levels[0], In, gx, gy, d, rho)
    finally:
        set_numba_enabled(prev)
    assert np.allclose(A1, A2, rtol=1e-10, atol=1e-14) and np.allclose(b1, b2, rtol=1e-10, atol=1e-14)


def test_solver_recovers_affine_warp_and_smooth_warp():
    tex = _texture(4)
    box = (80, 60, 160, 120)
    g, gp = Grid.for_box(box, 7, 7), Grid.for_box(box, 4, 4)
    V = g.vertices()
    A, t = np.array([[1.04, 0.05], [-0.03, 0.97]]), np.array([6.0, -4.0])
    c = np.array([160.0, 120.0])
    aff = lambda x: (x - c) @ A.T + c + t
    In = _warp_image(tex, aff)
    S = MeshSolver(tex, g, gp, SolverSettings(lam=0.005, levels=3, max_iter=20, tol=1e-4))
    d, rho, info = S.solve(In, np.zeros((g.K, 2)), np.ones(gp.K))
    err = np.linalg.norm(V + d - aff(V), axis=1)
    assert np.sqrt(np.mean(err ** 2)) < 0.03 and err.max() < 0.1    # the corners see the fewest pixels
    assert np.max(np.abs(rho - 1)) < 0.02

    def smooth(x):
        return x + np.c_[4 * np.sin(x[:, 1] / 40.0), 3 * np.cos(x[:, 0] / 50.0)]

    In = _warp_image(tex, smooth)
    d, rho, info = S.solve(In, np.zeros((g.K, 2)), np.ones(gp.K))
    assert np.sqrt(np.mean(np.sum((V + d - smooth(V)) ** 2, 1))) < 0.3
    assert not info["folded"]


def test_deformable_mesh_tracker_follows_a_synthetic_sheet_and_flags_loss():
    import pftrack

    sc = deform_scene(7, n_frames=25)
    tr = pftrack.create_tracker("deformable-mesh")
    st = tr.init(sc.frames[0], sc.box)
    assert st.info["mesh"].shape == (49, 2) and not st.lost
    errs = []
    for n in range(1, 25):
        st = tr.update(sc.frames[n])
        Vt, _ = sc.truth(n, tr.V0)
        errs.append(np.sqrt(np.mean(np.sum((st.info["mesh"] - Vt) ** 2, 1))))
        assert not st.lost
    assert np.mean(errs) < 1.0
    noise = np.random.default_rng(0).integers(0, 255, sc.frames[0].shape, dtype=np.uint8)
    st = tr.update(noise)
    assert st.lost
    st = tr.update(sc.frames[24])                       # back on the surface: recovered from the kept mesh
    assert not st.lost


def test_parse_mesh_and_pyramid():
    assert parse_mesh("7x5") == (5, 7)
    for bad in ("1x7", "7", "axb"):
        with pytest.raises(ValueError):
            parse_mesh(bad)
    assert len(pyramid(np.zeros((64, 64), np.float32), 3)) == 3
    g = Grid.for_box((0, 0, 10, 10), 3, 3)
    assert np.all(signed_areas(g.vertices(), g.triangles()) > 0)


def test_surface_cli(tmp_path, capsys):
    sc = deform_scene(5, n_frames=6)
    d = tmp_path / "frames"
    d.mkdir()
    for i, f in enumerate(sc.frames):
        cv2.imwrite(str(d / f"{i + 1:04d}.png"), f)
    box = ",".join(f"{v:.1f}" for v in sc.box)
    out = tmp_path / "mesh.csv"
    assert main(["surface", str(d), "--box", box, "--mesh", "5x4", "--out", str(out),
                 "--video-out", str(tmp_path / "m.mp4"), "--quiet"]) == 0
    lines = out.read_text().splitlines()
    assert lines[0].startswith("frame,x0,y0,x1,y1") and len(lines[0].split(",")) == 1 + 2 * 20
    assert len(lines) == 1 + 6 and lines[1].startswith("1,")
    first = np.array(lines[1].split(",")[1:], float).reshape(-1, 2)
    x, y, w, h = sc.box
    assert np.allclose(first[0], (x, y), atol=1e-3) and np.allclose(first[-1], (x + w, y + h), atol=1e-3)
    assert (tmp_path / "m.mp4").stat().st_size > 1000
    assert main(["surface", str(d), "--box", "400,300,200,200", "--out", str(out)]) == 2
    assert main(["surface", str(d), "--box", box, "--mesh", "1x1", "--out", str(out)]) == 2
    assert main(["surface", str(tmp_path / "missing"), "--box", box, "--out", str(out)]) == 2
    assert "error" in capsys.readouterr().err


def test_surface_cli_takes_a_sequence_folder_s_first_box(tmp_path, capsys):
    """Without --box, a sequence folder (OTB layout, as ``pftrack synth deform`` writes) gives its first ground-truth
    box: the same meshes as that box given by hand; a plain frame folder without --box is refused (exit 2, no CSV)."""
    sc = deform_scene(4, n_frames=5)
    seq = tmp_path / "deform-4"
    (seq / "img").mkdir(parents=True)
    for i, f in enumerate(sc.frames):
        cv2.imwrite(str(seq / "img" / f"{i + 1:04d}.png"), f)
    (seq / "groundtruth_rect.txt").write_text("\n".join(",".join(f"{v:.2f}" for v in sc.box) for _ in sc.frames))
    auto, hand = tmp_path / "auto.csv", tmp_path / "hand.csv"
    assert main(["surface", str(seq), "--mesh", "4x4", "--out", str(auto)]) == 0
    assert "ground truth" in capsys.readouterr().err
    box = (seq / "groundtruth_rect.txt").read_text().splitlines()[0]
    assert main(["surface", str(seq), "--box", box, "--mesh", "4x4", "--out", str(hand), "--quiet"]) == 0
    assert auto.read_text() == hand.read_text() and len(auto.read_text().splitlines()) == 6
    frames = seq / "img"
    assert main(["surface", str(frames), "--out", str(tmp_path / "none.csv")]) == 2
    assert not (tmp_path / "none.csv").exists()


def test_analysis_by_synthesis_reproduces_a_translated_frame_and_retextures_inside_the_mesh():
    """``frame_rmse`` (the chapter's Fig. 5 metric) is zero when the mesh is moved exactly as the frame (an
    integer shift), and grows when it is not; the shading grid scales the synthesis; ``retexture`` paints the
    deformed mesh's pixels only; a folded mesh has no synthesis."""
    from pftrack.surfaces.render import frame_rmse, frame_to_model, retexture

    I0 = _texture(3) * 255.0  # grey levels
    box = (100.0, 60.0, 96.0, 80.0)
    grid = Grid.for_box(box, 4, 5)
    V0, tris = grid.vertices(), grid.triangles()
    dx, dy = 7, -4
    In = np.roll(I0, (dy, dx), axis=(0, 1))
    assert frame_rmse(I0, In, V0, V0 + (dx, dy), tris) < 1e-3
    assert frame_rmse(I0, In, V0, V0, tris) > 10.0
    pgrid = Grid.for_box(box, 2, 2)
    half = frame_rmse(I0, 0.5 * In, V0, V0 + (dx, dy), tris, rho=np.full(4, 0.5), pgrid=pgrid)
    assert half < 1e-3  # a uniform shading of 0.5 explains a frame at half the light

    frame = np.zeros((240, 320, 3), np.uint8)
    tex = np.full((10, 10, 3), 200, np.uint8)
    out = retexture(frame, tex, box, V0, V0 + (dx, dy), tris)
    painted = np.argwhere(out[..., 0] == 200)
    (y0, x0), (y1, x1) = painted.min(0), painted.max(0)
    assert abs(x0 - (box[0] + dx)) <= 1 and abs(x1 - (box[0] + box[2] + dx)) <= 1
    assert abs(y0 - (box[1] + dy)) <= 1 and abs(y1 - (box[1] + box[3] + dy)) <= 1
    assert len(painted) == pytest.approx((box[2] + 1) * (box[3] + 1), rel=0.05)
    assert frame.max() == 0  # the input frame is left as it was

    folded = V0.copy()
    folded[6] = folded[12] + (30.0, 20.0)  # an inner vertex pushed across its neighbours
    assert frame_to_model(V0, folded, tris, I0.shape) is None
    assert np.isnan(frame_rmse(I0, In, V0, folded, tris))
    assert frame_to_model(V0, np.full_like(V0, 150.0), tris, I0.shape) is None  # collapsed to a point


def test_to_model_registers_a_translated_frame_onto_the_model():
    """``to_model`` (the chaining reference of ch13.md T4): with every vertex moved by the frame's integer shift the
    frame seen in model coordinates is the model image, inside the mesh and beyond it (the border displacement is
    carried on); a zero displacement returns the frame itself."""
    from pftrack.surfaces.render import to_model

    I0 = _texture(4) * 255.0
    grid = Grid.for_box((100.0, 60.0, 96.0, 80.0), 4, 5)
    dx, dy = 6, -5
    In = np.roll(I0, (dy, dx), axis=(0, 1))
    R = to_model(In, grid, np.tile([dx, dy], (grid.K, 1)).astype(float))
    inner = (slice(10, -10), slice(10, -10))         # away from the rolled-in border
    assert np.max(np.abs(R[inner] - I0[inner])) < 1e-3
    assert np.max(np.abs(to_model(In, grid, np.zeros((grid.K, 2))) - In)) < 1e-3


@pytest.mark.experiment
def test_frame_to_frame_chaining_drifts_where_analysis_by_synthesis_does_not():
    """ch13.md T4 in small (the experiment: scripts/ch13_experiments.py --part t4). On a 40-frame sheet (tune seed
    0) registering each frame onto the previous one ends 1.05 px off (mean vertex error, last 5 frames), analysis by
    synthesis 0.40 px; both start alike (0.07 px at frame 1)."""
    import pftrack

    sc = deform_scene(0, n_frames=40)
    last = {}
    for ref in ("model", "previous"):
        tr = pftrack.create_tracker("deformable-mesh", reference=ref)
        tr.init(sc.frames[0], sc.box)
        errs = []
        for n in range(1, 40):
            st = tr.update(sc.frames[n])
            assert not st.lost
            errs.append(np.mean(np.linalg.norm(st.info["mesh"] - sc.truth(n, tr.V0)[0], axis=1)))
        assert errs[0] < 0.15
        last[ref] = float(np.mean(errs[-5:]))
    assert last["model"] < 0.6
    assert last["previous"] > 2 * last["model"]


def test_fold_safe_step_halves_until_no_triangle_flips():
    from pftrack.surfaces.mesh import fold_safe_step, keeps_orientation

    g = Grid.for_box((0, 0, 20, 20), 3, 3)
    V, tris = g.vertices(), g.triangles()
    area0 = signed_areas(V, tris)
    dd = np.zeros_like(V)
    assert fold_safe_step(V, dd, tris, area0) == (1.0, 0)
    dd[4] = (15.0, 0.0)                # the centre vertex 15 px right: past its neighbours at 10 px, folds
    assert not keeps_orientation(V + dd, tris, area0)
    step, halvings = fold_safe_step(V, dd, tris, area0)
    assert (step, halvings) == (0.5, 1) and keeps_orientation(V + step * dd, tris, area0)
    dd[4] = (400.0, 0.0)               # folds at every step tried: four halvings, the last one unchecked
    assert fold_safe_step(V, dd, tris, area0) == (1 / 16, 4)
