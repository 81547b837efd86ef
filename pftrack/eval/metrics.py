"""Single-object accuracy metrics (GUIDE §4).

OTB one-pass evaluation (Wu, Lim & Yang):

* per frame, the IoU of the predicted and ground-truth boxes;
* the **success curve**: the fraction of frames with IoU > t for the 21
  thresholds t = 0, 0.05, ..., 1; its mean is the **AUC**;
* the **precision**: the fraction of frames whose centre error is <= 20 px.

Frames whose ground truth is missing (NaN) or has zero size are skipped.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..geometry import center_error, iou

THRESHOLDS = np.linspace(0.0, 1.0, 21)
PRECISION_THRESHOLDS = np.arange(0, 51, dtype=np.float64)


def valid_gt(gt: np.ndarray) -> np.ndarray:
    """Mask of frames whose ground truth is usable (finite, positive size)."""
    gt = np.asarray(gt, dtype=np.float64).reshape(-1, 4)
    return np.all(np.isfinite(gt), axis=1) & (gt[:, 2] > 0) & (gt[:, 3] > 0)


def _clean_pred(pred: np.ndarray) -> np.ndarray:
    p = np.asarray(pred, dtype=np.float64).reshape(-1, 4).copy()
    bad = ~np.all(np.isfinite(p), axis=1)
    p[bad] = 0.0  # a missing prediction overlaps nothing
    return p


def frame_ious(pred: np.ndarray, gt: np.ndarray) -> np.ndarray:
    """IoU per valid frame (frames without usable ground truth removed)."""
    pred, gt = _align(pred, gt)
    ok = valid_gt(gt)
    return iou(_clean_pred(pred[ok]), gt[ok])


def frame_center_errors(pred: np.ndarray, gt: np.ndarray) -> np.ndarray:
    pred, gt = _align(pred, gt)
    ok = valid_gt(gt)
    p = np.asarray(pred, dtype=np.float64)[ok]
    err = center_error(_clean_pred(p), gt[ok])
    err[~np.all(np.isfinite(p), axis=1)] = np.inf
    return err


def _align(pred, gt):
    pred = np.asarray(pred, dtype=np.float64).reshape(-1, 4)
    gt = np.asarray(gt, dtype=np.float64).reshape(-1, 4)
    n = min(len(pred), len(gt))
    if len(pred) < len(gt):  # missing predictions count as failures
        pad = np.full((len(gt) - n, 4), np.nan)
        pred = np.vstack([pred, pad])
        return pred, gt
    return pred[:n], gt[:n]


def success_curve(ious: np.ndarray) -> np.ndarray:
    """Fraction of frames with IoU > t for each of the 21 thresholds."""
    ious = np.asarray(ious, dtype=np.float64)
    if ious.size == 0:
        return np.full(THRESHOLDS.size, np.nan)
    return (ious[None, :] > THRESHOLDS[:, None]).mean(axis=1)


def precision_curve(errors: np.ndarray) -> np.ndarray:
    errors = np.asarray(errors, dtype=np.float64)
    if errors.size == 0:
        return np.full(PRECISION_THRESHOLDS.size, np.nan)
    return (errors[None, :] <= PRECISION_THRESHOLDS[:, None]).mean(axis=1)


@dataclass(frozen=True)
class OPEResult:
    auc: float
    precision: float  # at 20 px
    mean_iou: float
    success: np.ndarray
    precision_curve: np.ndarray
    n_frames: int


def ope_scores(pred: np.ndarray, gt: np.ndarray) -> OPEResult:
    """OTB one-pass scores of a predicted trajectory against the ground truth."""
    ious = frame_ious(pred, gt)
    errs = frame_center_errors(pred, gt)
    succ = success_curve(ious)
    prec = precision_curve(errs)
    return OPEResult(
        auc=float(np.mean(succ)) if ious.size else float("nan"),
        precision=float(prec[20]) if errs.size else float("nan"),
        mean_iou=float(ious.mean()) if ious.size else float("nan"),
        success=succ,
        precision_curve=prec,
        n_frames=int(ious.size),
    )
