"""Camera calibration from tracked robot markers (book ch. 12 §4.3, ch12.md §1.6).

Tsai's method needs non-coplanar points; it is replaced by its OpenCV equivalent with the same five
intrinsic degrees of freedom: a normalised DLT for the initial projection matrix,
``cv2.decomposeProjectionMatrix`` for ``K, R, t``, then ``cv2.calibrateCamera`` with the intrinsic guess,
one radial coefficient and zero skew.  When every marker lies on one plane (one marker height) the
principal point cannot be estimated: it is fixed at the image centre and a planar calibration is run.

OpenCV starts the pose of a non-planar fit from a DLT, which markers at two heights condition poorly; on an unseen
room (``random_scene(307)``, camera 2) it settled in a pose 2.6 m wrong on the ground. A second start from SQPnP's
global pose (:func:`_pnp_start`, :func:`_pnp_refine`) replaces the fit when it reprojects clearly better
(:data:`STAGED_GAIN`) or when the first fit's principal point is implausibly far from the centre
(:data:`CENTRE_SHARE`); where the second's is too, the centre is fixed.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np


class DegenerateError(ValueError):
    """The points do not determine a camera (coplanar for the DLT, or too few)."""


@dataclass
class CameraEstimate:
    K: np.ndarray
    dist: np.ndarray
    rvec: np.ndarray
    tvec: np.ndarray
    rms: float          # reprojection RMS (px)
    n: int
    planar: bool
    centre_fixed: bool = False  # the principal point held at the image centre (planar, or every fit implausible)

    def to_dict(self) -> dict:
        return {"rvec": self.rvec.ravel().tolist(), "tvec": self.tvec.ravel().tolist(),
                "f": float((self.K[0, 0] + self.K[1, 1]) / 2), "cx": float(self.K[0, 2]), "cy": float(self.K[1, 2]),
                "k1": float(self.dist.ravel()[0]), "reprojection_rms_px": self.rms, "points": self.n,
                "planar": self.planar, "centre_fixed": self.centre_fixed}


#: A fit whose principal point lies further than this share of the image's width (height) from the centre along
#: x (y) is taken for a degenerate one: OpenCV's is then replaced by the second start's, and where that one's lies as
#: far, the second start is refitted with the centre fixed. Lenses put it within a few per cent of the centre;
#: markers seen at two heights over part of the image let a fit trade it against the pose instead.
CENTRE_SHARE = 0.2


#: The second start's fit is taken when its reprojection RMS is below this share of the first's.
STAGED_GAIN = 0.9


def plausible_centre(K: np.ndarray, size: tuple[int, int], share: float = CENTRE_SHARE) -> bool:
    """Does the principal point of ``K`` lie within ``share`` of the image size ``(w, h)`` of its centre?"""
    w, h = size
    return abs(float(K[0, 2]) - (w - 1) / 2) <= share * w and abs(float(K[1, 2]) - (h - 1) / 2) <= share * h


def _normaliser(p: np.ndarray) -> np.ndarray:
    d = p.shape[1]
    m = p.mean(0)
    s = np.sqrt(d) / max(np.mean(np.linalg.norm(p - m, axis=1)), 1e-12)
    T = np.eye(d + 1)
    T[:d, :d] *= s
    T[:d, d] = -s * m
    return T


def dlt(X: np.ndarray, uv: np.ndarray, rank_tol: float = 1e-6) -> np.ndarray:
    """The 3x4 projection matrix from >= 6 non-coplanar points (Hartley-normalised DLT, numpy SVD).

    Raises :class:`DegenerateError` when the 2n x 12 design is rank-deficient (coplanar points, L10671)."""
    X = np.asarray(X, np.float64).reshape(-1, 3)
    uv = np.asarray(uv, np.float64).reshape(-1, 2)
    if len(X) < 6:
        raise DegenerateError("the DLT needs at least 6 points")
    T3, T2 = _normaliser(X), _normaliser(uv)
    Xn = (T3 @ np.c_[X, np.ones(len(X))].T).T
    un = (T2 @ np.c_[uv, np.ones(len(uv))].T).T
    A = np.zeros((2 * len(X), 12))
    A[0::2, 0:4] = Xn
    A[0::2, 8:12] = -un[:, :1] * Xn
    A[1::2, 4:8] = Xn
    A[1::2, 8:12] = -un[:, 1:2] * Xn
    _, s, Vt = np.linalg.svd(A, full_matrices=False)
    if s[-2] / s[0] < rank_tol:
        raise DegenerateError("the DLT design is rank-deficient: the points are coplanar (Tsai needs a 3-D "
                              "calibration object, i.e. markers at several heights)")
    P = np.linalg.inv(T2) @ Vt[-1].reshape(3, 4) @ T3
    P = P / np.linalg.norm(P[2, :3])
    if np.mean(np.c_[X, np.ones(len(X))] @ P[2]) < 0:      # the points lie in front of the camera
        P = -P
    return P


def decompose(P: np.ndarray):
    """``K, R, t`` of ``P = K [R | t]`` (RQ decomposition; positive diagonal of K, a proper rotation).

    ``P`` must be scaled so that points in front of the camera have positive depth (as :func:`dlt` does)."""
    from scipy.linalg import rq

    M = P[:, :3]
    if np.linalg.det(M) < 0:
        P = -P
        M = -M
    K, R = rq(M)
    S = np.diag(np.sign(np.diag(K)))
    K, R = K @ S, S @ R
    t = np.linalg.solve(K, P[:, 3])
    return K / K[2, 2], R, t


def _K(f: float, c) -> np.ndarray:
    return np.array([[f, 0, c[0]], [0, f, c[1]], [0, 0, 1.0]])


def _residuals(X: np.ndarray, uv: np.ndarray, f: float, c, k1: float, rvec, tvec) -> np.ndarray:
    p, _ = cv2.projectPoints(X, rvec, tvec, _K(f, c), np.array([k1, 0.0, 0.0, 0.0, 0.0]))
    return (p.reshape(-1, 2) - uv).ravel()


def _pnp_start(X: np.ndarray, uv: np.ndarray, size: tuple[int, int], f0: float):
    """``(f, rvec, tvec)``: the focal length that reprojects best with the centre fixed and no distortion, SQPnP's
    global pose at each of 17 lengths from f0/2 to 2 f0; None where SQPnP finds no pose."""
    c0 = ((size[0] - 1) / 2, (size[1] - 1) / 2)
    best = None
    for f in f0 * 2.0 ** (np.arange(-8, 9) / 8.0):
        ok, rv, tv = cv2.solvePnP(X, uv, _K(f, c0), np.zeros(5), flags=cv2.SOLVEPNP_SQPNP)
        if ok:
            e = float(np.mean(_residuals(X, uv, f, c0, 0.0, rv, tv) ** 2))
            if best is None or e < best[0]:
                best = (e, f, rv.ravel(), tv.ravel())
    return None if best is None else best[1:]


def _pnp_refine(X: np.ndarray, uv: np.ndarray, size: tuple[int, int], start, *, estimate_k1: bool,
                fix_centre: bool = False):
    """``(rms, K, dist, rvec, tvec)``: f, the principal point (unless ``fix_centre``), k1 (if ``estimate_k1``) and
    the pose refined together by least squares on the reprojection, from ``start`` (:func:`_pnp_start`)."""
    from scipy.optimize import least_squares

    c0 = np.array([(size[0] - 1) / 2, (size[1] - 1) / 2])
    f, rv, tv = start
    free_c, free_k = not fix_centre, estimate_k1

    def unpack(q):
        c = q[1:3] if free_c else c0
        k1 = q[1 + 2 * free_c] if free_k else 0.0
        return q[0], c, k1, q[-6:-3], q[-3:]

    q0 = np.r_[f, c0 if free_c else [], [0.0] if free_k else [], rv, tv]
    sol = least_squares(lambda q: _residuals(X, uv, *unpack(q)), q0, method="lm", xtol=1e-12, ftol=1e-12)
    f, c, k1, rvec, tvec = unpack(sol.x)
    rms = float(np.sqrt(np.mean(np.sum(sol.fun.reshape(-1, 2) ** 2, axis=1))))
    return rms, _K(f, c), np.array([k1, 0.0, 0.0, 0.0, 0.0]), np.asarray(rvec, float), np.asarray(tvec, float)


def calibrate(X: np.ndarray, uv: np.ndarray, size: tuple[int, int], *, estimate_k1: bool = True) -> CameraEstimate:
    """Calibrate one camera from world points ``X`` (n, 3) and their pixels ``uv`` (n, 2)."""
    X = np.asarray(X, np.float64).reshape(-1, 3)
    uv = np.asarray(uv, np.float64).reshape(-1, 2)
    if len(X) < 6:
        raise DegenerateError(f"only {len(X)} marker observations (at least 6 needed)")
    flags = cv2.CALIB_ZERO_TANGENT_DIST | cv2.CALIB_FIX_K2 | cv2.CALIB_FIX_K3 | cv2.CALIB_FIX_ASPECT_RATIO
    if not estimate_k1:
        flags |= cv2.CALIB_FIX_K1
    crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-12)
    zs = X[:, 2]
    planar = float(np.ptp(zs)) < 1e-9
    centre_fixed = planar  # one plane cannot give the principal point
    if not planar:
        K0, _, _ = decompose(dlt(X, uv))
        f0 = (K0[0, 0] + K0[1, 1]) / 2
        K0 = np.array([[f0, 0, K0[0, 2]], [0, f0, K0[1, 2]], [0, 0, 1.0]])
        rms, K, dist, rv, tv = cv2.calibrateCamera(
            [X.astype(np.float32)], [uv.astype(np.float32)], size, K0, np.zeros(5), flags=flags |
            cv2.CALIB_USE_INTRINSIC_GUESS, criteria=crit)
        rvec, tvec = rv[0].ravel(), tv[0].ravel()
        # OpenCV starts the pose from a DLT, which markers at two heights condition poorly: it can settle in a wrong
        # pose whose error the distortion absorbs. A second start from a global PnP solution (SQPnP) replaces the
        # fit when it reprojects clearly better, or when the first fit's principal point is implausible.
        start = _pnp_start(X, uv, size, f0)
        second = None if start is None else _pnp_refine(X, uv, size, start, estimate_k1=estimate_k1)
        if second is not None and (second[0] < STAGED_GAIN * rms or not plausible_centre(K, size)):
            rms, K, dist, rvec, tvec = second
            if not plausible_centre(K, size):  # the point traded against the pose: again, with it at the centre
                rms, K, dist, rvec, tvec = _pnp_refine(X, uv, size, start, estimate_k1=estimate_k1, fix_centre=True)
                centre_fixed = True
    else:
        h = zs[0]
        obj = np.c_[X[:, :2], np.zeros(len(X))].astype(np.float32)
        K0 = cv2.initCameraMatrix2D([obj], [uv.astype(np.float32)], size)
        K0[0, 2], K0[1, 2] = (size[0] - 1) / 2, (size[1] - 1) / 2
        rms, K, dist, rv, tv = cv2.calibrateCamera(
            [obj], [uv.astype(np.float32)], size, K0, np.zeros(5),
            flags=flags | cv2.CALIB_USE_INTRINSIC_GUESS | cv2.CALIB_FIX_PRINCIPAL_POINT, criteria=crit)
        R, _ = cv2.Rodrigues(rv[0])
        rvec = rv[0].ravel()
        tvec = tv[0].ravel() - R @ np.array([0, 0, h])     # back to the world frame (plane z = h)
    return CameraEstimate(K, np.asarray(dist, float).ravel(), rvec, tvec, float(rms), len(X), planar,
                          centre_fixed=centre_fixed)


def image_to_ground(uv, K, dist, rvec, tvec, z: float = 0.0) -> np.ndarray:
    """Back-project pixels to the plane ``Z = z`` (ch12.md §1.8): undistort, ray, intersect."""
    uv = np.asarray(uv, np.float64).reshape(-1, 1, 2)
    xn = cv2.undistortPoints(uv, np.asarray(K, float), np.asarray(dist, float)).reshape(-1, 2)
    R, _ = cv2.Rodrigues(np.asarray(rvec, float))
    C = -R.T @ np.asarray(tvec, float).ravel()
    d = (R.T @ np.c_[xn, np.ones(len(xn))].T).T
    s = (z - C[2]) / d[:, 2]
    return C + s[:, None] * d


def nine_points(size: tuple[int, int]) -> np.ndarray:
    """The evaluation pixels: a 3 x 3 grid at 15/50/85 % of the width and height (ch12.md §5.2)."""
    w, h = size
    return np.array([(fx * w, fy * h) for fy in (0.15, 0.5, 0.85) for fx in (0.15, 0.5, 0.85)])
