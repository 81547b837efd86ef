"""``deformable-mesh``: a textured surface tracked as a 2-D mesh with a photometric warp (book ch. 13).

Book *Object Tracking*, ch. 13 (``shared/book/ch13.md``): the box of the first frame becomes the model
image ``I_0`` with a regular mesh over it.  Every frame, the vertex displacements ``d`` and the shading
ratios ``rho`` (on a coarser mesh) that map ``I_0`` onto the frame are found by Huber-robust Gauss-Newton
with Laplacian smoothness, coarse to fine (:mod:`.solver`).  Because the warp always
starts from ``I_0`` it is the chapter's analysis by synthesis: errors do not accumulate from frame to
frame.  The box reported is the bounding box of the deformed mesh; ``info["mesh"]`` holds the vertices
(row-major) and ``info["shading"]`` the photometric ratios.

``model="dense"`` is the chapter's dense (per-pixel) model (Eq. 7): a displacement and a shading ratio for every
pixel of the box, solved by conjugate gradients preconditioned by multigrid or sparse LU factors (:mod:`.dense`); the
reported mesh is that field sampled at the
``rows x cols`` vertices, and :meth:`DeformableMesh.surface_mesh` gives a finer one for rendering.

``reference="previous"`` registers each frame onto the previous one instead (frame-to-frame chaining, the variant
the chapter argues against; ch13.md T4).

``lost`` is raised while the robust residual RMS stays above ``lost_rms`` (occlusion, the surface left
the frame) or a mesh triangle folds; the last good mesh is kept meanwhile.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import cv2
import numpy as np

from ..geometry import Box
from ..params import Params, param
from ..trackers.base import Tracker, TrackState
from .dense import DenseSettings, DenseSolver
from .mesh import Grid, displacement_at
from .render import to_model
from .solver import MeshSolver, SolverSettings


@dataclass(frozen=True, kw_only=True)
class MeshParams(Params):
    """Parameters of ``deformable-mesh`` (ch. 13; ch13.md §2).  ``lam`` was chosen by the L-curve on the tune
    seeds of the synthetic sheets (docs/surfaces.md); the chapter's 0.5 belongs to another normalisation."""

    cols: int = param(7, ge=2, le=64, doc="Mesh vertices across the box (the box's corners are vertices).")
    rows: int = param(7, ge=2, le=64, doc="Mesh vertices down the box.")
    photo_cols: int = param(4, ge=2, le=64, doc="Vertices across of the coarser photometric mesh (Eq. 4).")
    photo_rows: int = param(4, ge=2, le=64, doc="Vertices down of the photometric mesh.")
    model: Literal["affine", "bilinear", "dense"] = param("affine", doc=(
        "Warp per cell: affine triangles (Eqs. 8-10) or bilinear quads (Eq. 11); 'dense': one displacement and one "
        "shading ratio per pixel (Eq. 7), solved by preconditioned conjugate gradients (dense_solver), with rows x "
        "cols only the reported mesh."))
    photometric: bool = param(True, doc=(
        "Estimate the multiplicative photometric warp (Eq. 2); off = classical optical flow."))
    lam: float = param(0.005, ge=0, le=1e4, doc=(
        "Smoothness weight lambda of Eq. (25), with E_D the mean Huber residual on [0, 1] intensities and E_S the mean "
        "squared directional-Laplacian row (displacements in pixels)."))
    lam_p: float = param(10.0, ge=0, le=1e6, doc="Relative smoothness of the shading ratios, lambda_p of Eq. (38).")
    levels: int = param(4, ge=1, le=8, doc="Pyramid levels (the chapter: 4); fewer when the box is small.")
    max_iter: int = param(10, ge=1, le=100, doc="IRLS iterations per level at most.")
    tol: float = param(0.01, gt=0, le=10, doc=(
        "Stop a level when no vertex moves more than this (pixels of that level); the dense model stops on the "
        "RMS move of its pixels."))
    huber_k: float = param(1.345, gt=0, le=100, doc="Huber threshold v_H = k * 1.4826 MAD(r) (Eq. 29-30).")
    lost_rms: float = param(0.12, gt=0, le=1, doc=(
        "Residual RMS (intensities in [0, 1]) above which the frame is judged not to show the surface."))
    dense_lam: float = param(3.0, ge=0, le=1e4, doc=(
        "The smoothness weight lambda of the dense model (Eq. 25, normalised as lam, with Laplacian rows "
        "between neighbouring pixels of each pyramid level)."))
    dense_solver: Literal["auto", "amg", "lu", "direct"] = param("auto", doc=(
        "The dense model's linear solver: conjugate gradients preconditioned by smoothed-aggregation multigrid "
        "('amg', needs PyAMG: the [dense] extra) or by sparse LU factors ('lu'); 'direct': sparse LU of every step "
        "(exact, slow); 'auto': lu up to 250 000 pixels per pyramid level (measured 2.2x faster than amg up to "
        "221 000), amg above when PyAMG is installed (lu's memory grows faster than the region's)."))
    velocity: bool = param(False, doc=(
        "Start each frame from a constant-velocity prediction of d instead of the last d."))
    reference: Literal["model", "previous"] = param("model", doc=(
        "'model': every frame is registered onto the first frame's model image I_0, the chapter's analysis by "
        "synthesis (§5.5), so errors do not accumulate. 'previous': frame-to-frame chaining, the variant the chapter "
        "argues against (ch13.md T4): each frame is registered onto the previous real frame seen in model "
        "coordinates, and the shading ratios are relative to that frame."))
    max_pixels: int = param(60000, ge=0, le=100_000_000, doc=(
        "Speed bound: on a pyramid level whose region has more pixels, a regular subset of about this many is used "
        "(0: every pixel). The 480x360 sheets of docs/surfaces.md (about 48 000 pixels) stay under it."))


def gray01(frame: np.ndarray) -> np.ndarray:
    g = cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY) if frame.ndim == 3 else frame
    return g.astype(np.float32) / 255.0


class DeformableMesh(Tracker):
    name = "deformable-mesh"
    Params = MeshParams
    stochastic = False

    def _settings(self, box) -> SolverSettings:
        p = self.params
        levels = max(1, min(p.levels, int(np.floor(np.log2(max(min(box[2], box[3]), 16) / 16))) + 1))
        return SolverSettings(lam=p.lam, lam_p=p.lam_p, levels=levels, max_iter=p.max_iter, tol=p.tol,
                              huber_k=p.huber_k, photometric=p.photometric, model=p.model, max_pixels=p.max_pixels)

    def _init(self, frame: np.ndarray, box: Box) -> TrackState:
        p = self.params
        self.I0 = gray01(frame)
        self.box0 = tuple(map(float, box))
        self.grid = Grid.for_box(box, p.rows, p.cols)
        self.pgrid = Grid.for_box(box, p.photo_rows, p.photo_cols)
        self.V0 = self.grid.vertices()
        self.d = np.zeros_like(self.V0)
        self.d_prev = self.d.copy()
        self.rho = np.ones(self.pgrid.K)
        self.dense = self.solver = None
        if p.model == "dense":
            s = self._settings(box)
            self.dense = DenseSolver(self.I0, box, DenseSettings(
                lam=p.dense_lam, lam_p=p.lam_p, levels=s.levels, max_iter=p.max_iter, tol=p.tol, huber_k=p.huber_k,
                photometric=p.photometric, solver=p.dense_solver))
            self.D = np.zeros((self.dense.K, 2))      # the per-pixel field (full-resolution pixels of the box)
            self.D_prev = self.D.copy()
            self.R = np.ones(self.dense.K)
            self.P0 = self.pgrid.vertices()          # where the shading field is reported, every frame
        else:
            self.solver = MeshSolver(self.I0, self.grid, self.pgrid, self._settings(box))
        self.last = {"rms": 0.0, "iterations": 0, "folded": False, "valid_fraction": 1.0}
        return self._state(False)

    def _update(self, frame: np.ndarray) -> TrackState:
        p = self.params
        g = gray01(frame)
        if self.dense is not None:
            return self._update_dense(g)
        start = self.d + (self.d - self.d_prev) if p.velocity else self.d
        d, rho, info = self.solver.solve(g, start, self.rho)
        lost = self._judged_lost(info, d)
        if not lost:
            self.d_prev, self.d, self.rho = self.d, d, rho
            if p.reference == "previous":       # chaining: the next frame is registered onto this one
                self.solver = MeshSolver(to_model(g, self.grid, d, p.model), self.grid, self.pgrid,
                                         self.solver.s)
                self.rho = np.ones(self.pgrid.K)
        self.last = info
        return self._state(lost)

    def _update_dense(self, g: np.ndarray) -> TrackState:
        p = self.params
        start = self.D + (self.D - self.D_prev) if p.velocity else self.D
        D, R, info = self.dense.solve(g, start, self.R)
        lost = self._judged_lost(info, D)
        if not lost:
            self.D_prev, self.D, self.R = self.D, D, R
            if p.reference == "previous":
                self.dense.rebase(to_model(g, self.dense.grid, D, "bilinear"))
                self.R = np.ones(self.dense.K)
            self.d = displacement_at(self.dense.grid, self.V0, self.D, "bilinear")
            self.rho = self._field_at(self.P0, self.R)
        self.last = info
        return self._state(lost)

    def _judged_lost(self, info: dict, displacements: np.ndarray) -> bool:
        """The frame does not show the surface: the registration folded, its residual RMS exceeds ``lost_rms``, less
        than 30 % of the model fell inside the frame, or the solve diverged."""
        return bool(info["folded"] or info["rms"] > self.params.lost_rms or info["valid_fraction"] < 0.3
                    or not np.all(np.isfinite(displacements)))

    def _field_at(self, pts: np.ndarray, values: np.ndarray) -> np.ndarray:
        return displacement_at(self.dense.grid, pts, np.c_[values, values], "bilinear")[:, 0]

    @property
    def mesh_model(self) -> str:
        """How the reported mesh interpolates between its vertices ('affine' for the dense model's sampled mesh)."""
        return "affine" if self.params.model == "dense" else self.params.model

    def surface_mesh(self, step: float = 4.0):
        """``(grid, V0, V, rho, pgrid, model)`` for rendering the current surface: the tracker's own meshes, or for the
        dense model a mesh every ``step`` pixels sampled from its field (shading on the same vertices)."""
        if self.dense is None:
            return self.grid, self.V0, self.mesh(), self.rho, self.pgrid, self.params.model
        b = self.box0
        grid = Grid.for_box(b, max(int(round(b[3] / step)) + 1, 2), max(int(round(b[2] / step)) + 1, 2))
        V0 = grid.vertices()
        V = V0 + displacement_at(self.dense.grid, V0, self.D, "bilinear")
        return grid, V0, V, self._field_at(V0, self.R), grid, "affine"

    def mesh(self) -> np.ndarray:
        """Current vertex positions (K, 2), row-major."""
        return self.V0 + self.d

    def _state(self, lost: bool) -> TrackState:
        V = self.mesh()
        lo, hi = V.min(0), V.max(0)
        box = (float(lo[0]), float(lo[1]), float(max(hi[0] - lo[0], 1.0)), float(max(hi[1] - lo[1], 1.0)))
        score = float(np.clip(1.0 - self.last["rms"] / self.params.lost_rms, 0.0, 1.0))
        return TrackState(box=box, score=score, lost=lost, info={
            "mesh": V.copy(), "shading": self.rho.copy(), "rms": float(self.last["rms"]),
            "iterations": int(self.last["iterations"]), "folded": bool(self.last["folded"])})


#: Registry entry, read by :mod:`pftrack.trackers.registry` (applications register their trackers this way,
#: so the tracker layer never imports the application layer).
REGISTRY_ENTRIES = [
    ("deformable-mesh", DeformableMesh,
     ("A textured, deforming surface as a 2-D mesh with a multiplicative shading warp, robust Gauss-Newton with "
      "Laplacian smoothness, coarse to fine, always from the first frame (book ch. 13)"), {}),
]
