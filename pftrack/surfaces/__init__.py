"""Deformable-surface tracking (book ch. 13): mesh warps, a multiplicative photometric warp, robust
Gauss-Newton with Laplacian smoothness, coarse to fine; rendering for analysis by synthesis.

- :mod:`.mesh` — regular meshes, barycentric/bilinear weights, Laplacians (Eqs. 8-11, 22-24);
- :mod:`.solver` — Huber IRLS normal equations (Eqs. 25-38), coarse-to-fine solve, fold check;
- :mod:`.dense` — the dense (per-pixel) model (Eq. 7): sparse normal equations solved by conjugate gradients
  preconditioned by multigrid (PyAMG) or sparse LU factors;
- :mod:`.render` — frame-coordinate synthesis, RMSE, re-texturing, mesh drawing, a frame seen in model
  coordinates (the reference of frame-to-frame chaining);
- :mod:`.kymograph` — stabilised kymograms: the rigid motion of a region from the mesh, scan lines.

The tracker on top is ``deformable-mesh`` (:mod:`.tracker`, registered by :mod:`pftrack.trackers.registry`).
"""

from .mesh import (
           Grid,
           directional_laplacian,
           displacement_at,
           interp_weights,
           parse_mesh,
           umbrella_laplacian,
           weights_matrix,
)
from .dense import DenseSettings, DenseSolver
from .solver import MeshSolver, SolverSettings, huber_rho, huber_weights

__all__ = ["DenseSettings", "DenseSolver", "Grid", "MeshSolver", "SolverSettings", "directional_laplacian",
           "displacement_at", "huber_rho",
           "huber_weights",
           "interp_weights", "parse_mesh", "umbrella_laplacian", "weights_matrix"]
