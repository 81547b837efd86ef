"""Single-object accuracy metrics (GUIDE §4).

OTB one-pass evaluation (Wu, Lim & Yang):

* per frame, the IoU of the predicted and ground-truth boxes;
* the **success curve**: the fraction of frames with IoU > t for the 21
  thresholds t = 0, 0.05, ..., 1; its mean is the **AUC**;
* the **precision**: the fraction of frames whose centre error is <= 20 px;
* the **normalised precision** of LaSOT and TrackingNet (Fan et al., CVPR 2019; Müller et al., ECCV 2018): the
  centre error measured in units of the ground-truth box's width and height, the fraction of frames within t for
  the 51 thresholds t = 0, 0.01, ..., 0.5, and the mean of that curve (its AUC), so that a large target is not
  judged by the pixels of a small one.

Frames whose ground truth is missing (NaN) or has zero size are skipped.

With ``bounds`` (the frame's ``(width, height)``), both boxes are first cut to the frame, as the VOT toolkit
computes its overlaps: datasets disagree on a target at the image's edge (OTB-style annotations box the
visible part, MOTChallenge boxes the whole body beyond the edge), and a box's part outside the image cannot
be checked against it.  A ground-truth box wholly outside the frame then counts as missing.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..geometry import box_center, center_error, clip_box, iou

THRESHOLDS = np.linspace(0.0, 1.0, 21)
PRECISION_THRESHOLDS = np.arange(0, 51, dtype=np.float64)
NORM_PRECISION_THRESHOLDS = np.linspace(0.0, 0.5, 51)


def valid_gt(gt: np.ndarray) -> np.ndarray:
    """Mask of frames whose ground truth is usable (finite, positive size)."""
    gt = np.asarray(gt, dtype=np.float64).reshape(-1, 4)
    return np.all(np.isfinite(gt), axis=1) & (gt[:, 2] > 0) & (gt[:, 3] > 0)


def within_frame(boxes: np.ndarray, bounds: tuple[float, float] | None) -> np.ndarray:
    """``boxes`` ``(n, 4)`` cut to the frame ``bounds = (width, height)`` (NaN rows stay NaN, a box wholly
    outside gets zero size); unchanged (as float64) when ``bounds`` is None."""
    b = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
    if bounds is None:
        return b
    return clip_box(b, float(bounds[0]), float(bounds[1])).reshape(-1, 4)


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


def per_frame_iou(pred: np.ndarray, gt: np.ndarray) -> np.ndarray:
    """IoU of each frame's box with the ground truth, aligned with the frames (unlike :func:`frame_ious`): NaN
    where the ground truth has no usable box, 0 where the prediction is missing."""
    pred = np.asarray(pred, dtype=np.float64).reshape(-1, 4)
    gt = np.asarray(gt, dtype=np.float64).reshape(-1, 4)[: len(pred)]
    out = np.full(len(gt), np.nan)
    ok = valid_gt(gt)
    out[ok] = iou(_clean_pred(pred[: len(gt)][ok]), gt[ok])
    return out


def frame_center_errors(pred: np.ndarray, gt: np.ndarray, *, normalised: bool = False) -> np.ndarray:
    """Per valid frame, the distance of the box centres in pixels, or with ``normalised`` in units of the ground
    truth's width and height, ``||((cx_p - cx_g) / w_g, (cy_p - cy_g) / h_g)||`` (LaSOT's and TrackingNet's
    normalised distance); infinite for a missing prediction."""
    pred, gt = _align(pred, gt)
    ok = valid_gt(gt)
    p, g = np.asarray(pred, dtype=np.float64)[ok], gt[ok]
    if normalised:
        d = (box_center(_clean_pred(p)) - box_center(g)) / g[:, 2:]
        err = np.hypot(d[:, 0], d[:, 1])
    else:
        err = center_error(_clean_pred(p), g)
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
    norm_precision: float = float("nan")  # the mean of the normalised precision curve (LaSOT, TrackingNet)


def ope_scores(pred: np.ndarray, gt: np.ndarray, *, bounds: tuple[float, float] | None = None) -> OPEResult:
    """OTB one-pass scores of a predicted trajectory against the ground truth (both cut to ``bounds``, the
    frame's ``(width, height)``, when given)."""
    pred, gt = within_frame(pred, bounds), within_frame(gt, bounds)
    ious = frame_ious(pred, gt)
    errs = frame_center_errors(pred, gt)
    nerrs = frame_center_errors(pred, gt, normalised=True)
    succ = success_curve(ious)
    prec = precision_curve(errs)
    return OPEResult(
        auc=float(np.mean(succ)) if ious.size else float("nan"),
        precision=float(prec[20]) if errs.size else float("nan"),
        mean_iou=float(ious.mean()) if ious.size else float("nan"),
        success=succ,
        precision_curve=prec,
        n_frames=int(ious.size),
        norm_precision=(float((nerrs[None, :] <= NORM_PRECISION_THRESHOLDS[:, None]).mean())
                        if nerrs.size else float("nan")),
    )


# ------------------------------------------------------------------------------ the lost flag as a detector

#: IoU at or above which the estimate "covers" the visible target (GUIDE §8).
COVER_IOU = 0.5
#: A reappearing target counts as re-acquired when the tracker covers it, not lost, within this many frames.
REACQUIRE_WITHIN = 15


@dataclass(frozen=True)
class LostResult:
    """The ``lost`` flag scored as a detector of target absence (GUIDE §8).

    * ``recall``: fraction of the frames where the target is absent or fully hidden on
      which ``lost`` is raised (NaN when the sequence has no such frame);
    * ``false_rate``: fraction of the frames where the estimate covers the visible target
      (IoU >= 0.5) on which ``lost`` is raised (NaN when there is no such frame);
    * ``reacquired`` / ``reappearances``: reappearance events (an absent run followed by
      a visible frame) after which the tracker covers the target with ``lost`` down
      within :data:`REACQUIRE_WITHIN` frames.
    """

    recall: float
    false_rate: float
    absent_frames: int
    covered_frames: int
    reappearances: int
    reacquired: int


def lost_detection(lost: np.ndarray, pred: np.ndarray, gt: np.ndarray, absent: np.ndarray, *,
                   within: int = REACQUIRE_WITHIN, bounds: tuple[float, float] | None = None) -> LostResult:
    """Score a per-frame ``lost`` flag against the frames where the target is absent.

    ``lost``, ``pred`` (boxes), ``gt`` (boxes, NaN allowed) and ``absent`` (bool) are
    aligned per frame.  Frames that are neither absent nor covered (the estimate is
    off the visible target) count in neither rate: there the flag may go either way.
    With ``bounds`` both boxes are cut to the frame before their IoU (:func:`ope_scores`).
    """
    lost = np.asarray(lost, dtype=bool).ravel()
    absent = np.asarray(absent, dtype=bool).ravel()
    n = min(lost.size, absent.size, len(pred), len(gt))
    lost, absent = lost[:n], absent[:n]
    pred = _clean_pred(within_frame(np.asarray(pred, dtype=np.float64).reshape(-1, 4)[:n], bounds))
    gt = within_frame(np.asarray(gt, dtype=np.float64).reshape(-1, 4)[:n], bounds)
    ok = valid_gt(gt) & ~absent
    ious = np.zeros(n)
    if ok.any():
        ious[ok] = iou(pred[ok], gt[ok])
    covered = ok & (ious >= COVER_IOU)
    recall = float(lost[absent].mean()) if absent.any() else float("nan")
    false_rate = float(lost[covered].mean()) if covered.any() else float("nan")
    events = reacq = 0
    for t in range(1, n):
        if absent[t - 1] and ok[t]:
            events += 1
            win = slice(t, min(n, t + within))
            if np.any(covered[win] & ~lost[win]):
                reacq += 1
    return LostResult(recall=recall, false_rate=false_rate, absent_frames=int(absent.sum()),
                      covered_frames=int(covered.sum()), reappearances=events, reacquired=reacq)


def corner_distance(pred: np.ndarray, gt: np.ndarray) -> np.ndarray:
    """Book ch. 5 Eq. 25, d1: the mean distance of the four corners of axis-aligned boxes, per frame
    (NaN where the ground truth is missing)."""
    pred, gt = _align(pred, gt)
    ok = valid_gt(gt)
    out = np.full(len(gt), np.nan)
    p, g = _clean_pred(pred[ok]), gt[ok]
    d = 0.0
    for cx, cy in ((0, 0), (1, 0), (0, 1), (1, 1)):
        d = d + np.hypot(p[:, 0] + cx * p[:, 2] - g[:, 0] - cx * g[:, 2],
                         p[:, 1] + cy * p[:, 3] - g[:, 1] - cy * g[:, 3])
    out[ok] = d / 4.0
    return out


def param_mae(pred: np.ndarray, gt: np.ndarray) -> np.ndarray:
    """Book ch. 5 Eq. 26 (printed "MSE" but a mean absolute error): ``(4,)`` mean |error| of the centre
    x, y, width and height over the frames with ground truth (the angle is omitted: the ground truth is
    axis-aligned)."""
    pred, gt = _align(pred, gt)
    ok = valid_gt(gt)
    p, g = _clean_pred(pred[ok]), gt[ok]
    pc = np.column_stack([p[:, 0] + p[:, 2] / 2, p[:, 1] + p[:, 3] / 2, p[:, 2], p[:, 3]])
    gc = np.column_stack([g[:, 0] + g[:, 2] / 2, g[:, 1] + g[:, 3] / 2, g[:, 2], g[:, 3]])
    return np.abs(pc - gc).mean(axis=0) if len(g) else np.full(4, np.nan)


def tracking_percentage(pred: np.ndarray, gt: np.ndarray, threshold: float = 0.5) -> float:
    """Book ch. 6 Table 1's undefined "tracking percentage", defined: the fraction of frames with
    ground truth whose IoU is at least ``threshold`` (OTB success at 0.5)."""
    ious = frame_ious(pred, gt)
    ious = ious[np.isfinite(ious)]
    return float(np.mean(ious >= threshold)) if ious.size else float("nan")
