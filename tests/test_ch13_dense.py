"""Book ch. 13's dense (per-pixel) model: the sparse normal equations, the Jacobian, the preconditioned solves, the
accuracy against the mesh on deformations finer than its cells, the tracker and the CLI."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
import scipy.sparse.linalg as spla

import pftrack
from pftrack.cli import main
from pftrack.errors import ParameterError
from pftrack.surfaces import dense as dense_mod
from pftrack.surfaces.dense import (
    ChannelPreconditioner,
    DenseSettings,
    DenseSolver,
    choose_method,
    dense_jacobian,
    level_grid,
    solve_spd,
)
from pftrack.surfaces.mesh import Grid, directional_laplacian, displacement_at
from pftrack.surfaces.solver import gradients
from pftrack.synth.deform import FINE, band_limited_texture, deform_scene


def _texture(seed=0, size=(120, 160)):
    return band_limited_texture(np.random.default_rng(seed), size).astype(np.float32)


def test_level_grid_holds_the_pixels_of_each_level_inside_the_box():
    g0 = level_grid((10.5, 20.0, 40.0, 30.0), 0, (120, 160))
    assert (g0.x0, g0.y0, g0.sx, g0.cols, g0.rows) == (11.0, 20.0, 1.0, 40, 31)
    g2 = level_grid((10.5, 20.0, 40.0, 30.0), 2, (30, 40))
    assert (g2.x0, g2.y0, g2.sx, g2.cols, g2.rows) == (12.0, 20.0, 4.0, 10, 8)
    with pytest.raises(ValueError):
        level_grid((0, 0, 6, 6), 2, (30, 40))


def test_normal_equations_equal_the_stacked_least_squares_form():
    """Test 5 of ch13.md for the dense model: the sparse closed form equals the stacked [J; lam Gamma],
    [r; lam Gamma theta] system with the unknowns interleaved per pixel (dx, dy, rho)."""
    tex = _texture(1)
    S = DenseSolver(tex, (40, 30, 14, 11), DenseSettings(lam=0.7, lam_p=4.0, levels=1))
    lv = S.levels[0]
    rng = np.random.default_rng(2)
    In = np.roll(tex, 2, axis=1)
    gx, gy = gradients(In)
    D = rng.uniform(-1, 1, (S.K, 2))
    rho = rng.uniform(0.9, 1.1, S.K)
    A, b, r, ok, _ = S.normal_equations(lv, In, gx, gy, D, rho, vH=1e9)
    J = dense_jacobian(S, 0, In, gx, gy, D)[ok]
    L = directional_laplacian(lv.grid.rows, lv.grid.cols).toarray()
    Gam = np.zeros((3 * L.shape[0], 3 * S.K))
    for a, c in enumerate((1.0, 1.0, S.s.lam_p)):
        Gam[a * L.shape[0]:(a + 1) * L.shape[0], a::3] = c * L
    theta = np.c_[D, rho].ravel()
    N, nG = ok.sum(), Gam.shape[0]
    Js = np.vstack([J / np.sqrt(N), S.s.lam / np.sqrt(nG) * Gam])
    bs = np.r_[r[ok] / np.sqrt(N), S.s.lam / np.sqrt(nG) * Gam @ theta]
    assert np.allclose(A.toarray(), Js.T @ Js, rtol=1e-10, atol=1e-14)
    assert np.allclose(b, Js.T @ bs, rtol=1e-10, atol=1e-14)
    step_ls = np.linalg.lstsq(Js, -bs, rcond=None)[0]
    assert np.allclose(-np.linalg.solve(A.toarray(), b), step_ls, rtol=1e-7, atol=1e-9)


def test_jacobian_matches_finite_differences():
    tex = _texture(0)
    S = DenseSolver(tex, (50, 40, 20, 16), DenseSettings(levels=1))
    lv = S.levels[0]
    In = cv2.GaussianBlur(tex, (0, 0), 6.0)
    In = (In - In.min()) / (np.ptp(In) + 1e-9)
    gx, gy = gradients(In)
    rng = np.random.default_rng(0)
    D = rng.uniform(-3, 3, (S.K, 2))
    rho = rng.uniform(0.7, 1.3, S.K)
    J = dense_jacobian(S, 0, In, gx, gy, D)
    r0, _ = S.residual(lv, In, D, rho)
    eps, rel = 1e-3, []
    for i in rng.choice(S.K, 12, replace=False):
        for a in (0, 1):
            Dp, Dm = D.copy(), D.copy()
            Dp[i, a] += eps
            Dm[i, a] -= eps
            num = (S.residual(lv, In, Dp, rho)[0][i] - S.residual(lv, In, Dm, rho)[0][i]) / (2 * eps)
            rel.append(abs(num - J[i, 3 * i + a]) / max(abs(num), 1e-9))
        rp = rho.copy()
        rp[i] += 1.0
        assert np.isclose(S.residual(lv, In, D, rp)[0][i] - r0[i], J[i, 3 * i + 2], atol=1e-6)   # exact in rho
        assert np.count_nonzero(J[i]) <= 3                 # no coupling between pixels in the data term
    # as for the mesh: the bilinear interpolant's slope against the interpolated central-difference gradient
    assert np.median(rel) < 0.06


@pytest.mark.parametrize("method", ["lu", "amg"])
def test_preconditioned_solves_agree_with_the_direct_solve(method):
    if method == "amg":
        pytest.importorskip("pyamg")
    tex = _texture(3)
    S = DenseSolver(tex, (30, 20, 70, 60), DenseSettings(lam=1.0, levels=1))
    lv = S.levels[0]
    In = np.roll(tex, (1, 2), axis=(0, 1))
    gx, gy = gradients(In)
    A, b, *_ = S.normal_equations(lv, In, gx, gy, np.zeros((S.K, 2)), np.ones(S.K))
    x_direct = spla.spsolve(A.tocsc(), -b)
    M = ChannelPreconditioner(A, 3, lv.V, method).operator()
    x, converged = solve_spd(A, -b, M, rtol=1e-10)
    assert converged
    assert np.linalg.norm(x - x_direct) < 1e-6 * np.linalg.norm(x_direct)


def test_auto_chooses_lu_factors_up_to_the_threshold_and_multigrid_above(monkeypatch):
    assert choose_method("direct", 10) == "direct" and choose_method("amg", 10) == "amg"
    assert choose_method("auto", dense_mod.LU_PIXELS) == "lu"
    monkeypatch.setattr(dense_mod, "amg_available", lambda: True)
    assert choose_method("auto", dense_mod.LU_PIXELS + 1) == "amg"
    monkeypatch.setattr(dense_mod, "amg_available", lambda: False)
    assert choose_method("auto", dense_mod.LU_PIXELS + 1) == "lu"
    with pytest.raises(ParameterError, match=r"pftrack\[dense\]"):     # one line for the CLI, exit 2
        DenseSolver(_texture(), (10, 10, 40, 40), DenseSettings(solver="amg", levels=1))
    with pytest.raises(ParameterError):
        DenseSolver(_texture(), (10, 10, 40, 40), DenseSettings(solver="cholesky", levels=1))


def _field_error(tr, sc, n) -> float:
    P = Grid.for_box(sc.box, 13, 16).vertices()
    grid, V0, V, *_ , model = tr.surface_mesh()
    return float(np.mean(np.linalg.norm(displacement_at(grid, P, V - V0, model) - sc.displacement(n, P), axis=1)))


@pytest.mark.experiment
@pytest.mark.parametrize("seed", [7, 8])
def test_dense_model_follows_deformations_finer_than_the_mesh(seed):
    """Bumps 14-24 px wide, finer than the 7 x 7 mesh's 27 px cells, frame 12 registered onto the model directly.
    The default smoothness (chosen on sequences, where frames move little) and a softer one resolve finer."""
    sc = deform_scene(seed, n_frames=13, size=(240, 320), **FINE)
    errs = {}
    for name, kw in (("dense", {"model": "dense"}), ("soft", {"model": "dense", "dense_lam": 1.0}), ("mesh", {})):
        tr = pftrack.create_tracker("deformable-mesh", **kw)
        tr.init(sc.frames[0], sc.box)
        assert not tr.update(sc.frames[12]).lost
        errs[name] = _field_error(tr, sc, 12)
    assert errs["dense"] < 0.25 and errs["dense"] < 0.85 * errs["mesh"]     # measured 0.17, 0.18 px; 0.74x, 0.67x
    assert errs["soft"] < 0.15 and errs["soft"] < 0.6 * errs["mesh"]        # measured 0.10, 0.11 px; 0.44x, 0.40x


def test_dense_tracker_reports_a_mesh_flags_noise_and_chains():
    sc = deform_scene(5, n_frames=5, size=(160, 220))
    tr = pftrack.create_tracker("deformable-mesh", model="dense", rows=5, cols=6)
    st = tr.init(sc.frames[0], sc.box)
    assert st.info["mesh"].shape == (30, 2) and not st.lost
    for n in (1, 3):
        st = tr.update(sc.frames[n])
    assert not st.lost and st.info["shading"].shape == (16,)
    Vt, _ = sc.truth(3, tr.V0)
    assert np.mean(np.linalg.norm(st.info["mesh"] - Vt, axis=1)) < 0.2
    grid, V0, V, rho, pgrid, model = tr.surface_mesh(4.0)
    assert model == "affine" and V.shape == V0.shape == (grid.K, 2) and rho.shape == (pgrid.K,)
    noise = np.random.default_rng(0).integers(0, 255, sc.frames[0].shape, dtype=np.uint8)
    assert tr.update(noise).lost
    assert not tr.update(sc.frames[4]).lost
    ch = pftrack.create_tracker("deformable-mesh", model="dense", reference="previous", velocity=True)
    ch.init(sc.frames[0], sc.box)
    for n in range(1, 4):
        st = ch.update(sc.frames[n])
    assert not st.lost and _field_error(ch, sc, 3) < 0.3


def test_surface_cli_dense(tmp_path):
    sc = deform_scene(5, n_frames=3, size=(160, 220))
    d = tmp_path / "frames"
    d.mkdir()
    for i, f in enumerate(sc.frames):
        cv2.imwrite(str(d / f"{i + 1:04d}.png"), cv2.cvtColor(f, cv2.COLOR_BGR2GRAY))      # grey input
    box = ",".join(f"{v:.1f}" for v in sc.box)
    out = tmp_path / "mesh.csv"
    tex = tmp_path / "tex.png"
    cv2.imwrite(str(tex), np.full((32, 32, 3), 200, np.uint8))
    assert main(["surface", str(d), "--box", box, "--model", "dense", "--mesh", "4x3", "--lambda", "2",
                 "--out", str(out), "--video-out", str(tmp_path / "m.mp4"), "--texture", str(tex), "--quiet"]) == 0
    lines = out.read_text().splitlines()
    assert len(lines) == 1 + 3 and len(lines[0].split(",")) == 1 + 2 * 12
    last = np.array(lines[-1].split(",")[1:], float).reshape(-1, 2)
    g = Grid.for_box(sc.box, 3, 4)
    Vt, _ = sc.truth(2, g.vertices())
    assert np.mean(np.linalg.norm(last - Vt, axis=1)) < 0.3


def test_energies_vanish_where_they_should():
    """E_S is zero on any affine field (directional Laplacian) and E_D is zero when the frame is the model."""
    tex = _texture(2)
    S = DenseSolver(tex, (30, 20, 60, 50), DenseSettings(levels=1))
    V = S.grid.vertices()
    D_aff = V @ np.array([[0.02, -0.01], [0.03, 0.01]]).T + [1.5, -0.5]
    e_d, e_s = S.energies(np.zeros((S.K, 2)), np.ones(S.K), tex)
    assert e_d < 1e-12 and e_s == 0.0
    _, e_s = S.energies(D_aff, np.ones(S.K), tex)
    assert e_s < 1e-20
    _, e_s = S.energies(np.random.default_rng(0).normal(0, 0.5, (S.K, 2)), np.ones(S.K), tex)
    assert e_s > 1e-3


def test_synth_deform_fine(tmp_path):
    assert main(["synth", "deform", "--fine", "--seeds", "3", "--out", str(tmp_path)]) == 0
    scene = tmp_path / "deform-fine-003"
    assert (scene / "mesh_gt.csv").is_file() and len(list((scene / "img").iterdir())) == 60
    assert main(["synth", "kymo", "--fine", "--seeds", "3", "--out", str(tmp_path)]) == 2
