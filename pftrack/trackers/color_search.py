"""Initialisation mode of the colour particle filters (Nummiaro et al. §6): search, detect, re-acquire.

While the target is lost, or before it has been seen, samples are spread over
the frame (or over entry regions) and the appearance condition (Eq. 15) picks a
candidate; with the likelihood loss test (:mod:`pftrack.filtering.loss`) the
candidate must also look like the target's score history before tracking
resumes.  A detector callable may propose candidates too.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from ..cues.color import reachable_roi
from ..cues.intensity import gain_maps, shifted_rho
from ..cues.lk import gray_of
from ..errors import ParameterError
from ..filtering.dynamics import HX, HY, X, Y, lost_prediction, reappearance_log_prior
from ..filtering.loss import confidence
from ..filtering.resampling import weighted_choice
from ..frames import as_bgr_uint8
from ..geometry import Box, box_to_ellipse, ellipse_box, ellipse_to_box, exit_edge, in_frame_fraction, validate_box
from .base import TrackState
from .vetoes import SearchCandidates, near_mask, search_rank

_ELL_COLS = np.array([X, Y, HX, HY])


class SearchMixin:
    """Search, automatic initialisation and detector hand-off for :class:`ColorParticleFilter`."""

    def init_auto(self, frame: np.ndarray, histogram: np.ndarray, size: tuple[float, float], *,
                  regions: Sequence[Sequence[float]] | None = None) -> TrackState:
        """Automatic initialisation from a known target histogram (§6).

        Parameters
        ----------
        histogram : the target model ``q`` (any non-negative array with ``cue.n_bins``
            entries; it is normalised).
        size : expected ``(w, h)`` of the target in pixels.
        regions : optional entry regions ``(x, y, w, h)`` where the target is expected
            to appear (doors, image borders); by default samples cover the whole frame.

        The tracker starts in initialisation mode and reports ``lost=True`` until more
        than ``b N`` samples satisfy the appearance condition (Eq. 15).
        """
        frame = as_bgr_uint8(frame, where="init frame")
        hist = np.asarray(histogram, dtype=np.float64).ravel()
        if hist.size != self.cue.n_bins or not np.all(np.isfinite(hist)) or hist.min() < 0 or hist.sum() <= 0:
            raise ParameterError(
                f"histogram must have {self.cue.n_bins} finite non-negative values with a positive sum")
        w, h = (float(v) for v in size)
        if not (w > 0 and h > 0 and math.isfinite(w) and math.isfinite(h)):
            raise ParameterError(f"size must be a positive (w, h), got {size!r}")
        self._shape = frame.shape[:2]
        self.frame_index = 0
        self._reset()
        self._quotient, self._raw_check = None, None  # a given histogram is of the frames as they are
        self._drop_structure_check()  # no reference patch without a box
        self._set_model(hist)
        self.size = (w / 2.0, h / 2.0)
        if regions is not None:
            fh, fw = self._shape
            self.regions = np.array([validate_box(r, fw, fh) for r in regions], dtype=np.float64).reshape(-1, 4)
        self.cue.adapt_to(frame, levels=False)  # the given histogram's bins: over 0-255 (no dark_stretch)
        self.cue.new_frame(frame)
        self._background_stats(frame, None)
        self.loss.reset(1.0, sd=0.2)  # no target history yet: a vague prior on its score
        self.loss.lost = True
        self.mode = "searching"
        return self._search(frame)

    def init_detect(self, frame: np.ndarray) -> TrackState:
        """Initialise from the tracker's detector: the highest-scoring detection becomes the target.

        Without a detection the tracker waits (``lost=True``) and runs the detector on
        the following frames until one appears.
        """
        if self.detector is None:
            raise ParameterError("init_detect needs a detector (create_tracker(..., detector=callable))")
        frame = as_bgr_uint8(frame, where="init frame")
        self._shape = frame.shape[:2]
        self.frame_index = 0
        self._reset()
        self._quotient, self._raw_check = None, None  # the detector sees the frames as they are
        box = self._best_detection(frame)
        if box is not None:
            return self._init(frame, box)
        self.mode = "detecting"
        return self._state(box=(0.0, 0.0, 0.0, 0.0), score=0.0, lost=True)

    def _detections(self, frame: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        out = self.detector(frame)
        boxes, scores = [], []
        for det in out if out is not None else []:
            det = [float(v) for v in det]
            if len(det) < 4:
                continue
            x, y, w, h = det[:4]
            if w > 0 and h > 0 and all(math.isfinite(v) for v in det[:4]):
                boxes.append((x, y, w, h))
                scores.append(det[4] if len(det) > 4 else 1.0)
        return np.array(boxes, dtype=np.float64).reshape(-1, 4), np.array(scores, dtype=np.float64)

    def _best_detection(self, frame: np.ndarray) -> Box | None:
        boxes, scores = self._detections(frame)
        fh, fw = frame.shape[:2]
        for i in np.argsort(-scores, kind="stable"):
            try:
                return validate_box(boxes[i], fw, fh)
            except ValueError:
                continue
        return None

    # ------------------------------------------------------------------ search
    def _n_search(self) -> int:
        p = self.params
        if p.search_particles:
            return p.search_particles
        fh, fw = self._shape
        hx, hy = self.size
        boxes = self._sample_boxes()
        area = fw * fh if boxes is None else float(np.sum(boxes[:, 2] * boxes[:, 3]))
        # about four samples per target-sized cell: the likelihood peak is narrower than the target
        cells = int(math.ceil(area / max(hx * hy, 1.0)))
        return int(min(max(cells, p.n_particles), 10 * p.n_particles))

    def _uniform_positions(self, m: int) -> np.ndarray:
        """``m`` stratified positions over the frame (or the entry regions, or the border after an exit)."""
        rng = self.rng
        boxes = self._sample_boxes()
        if boxes is None:
            fh, fw = self._shape
            boxes = np.array([[0.0, 0.0, fw, fh]])
        if len(boxes) == 1:  # the frame or one strip: all m there (the apportionment below gives m)
            counts = [m]
        else:  # split m among the regions in proportion to their area (largest remainder)
            areas = boxes[:, 2] * boxes[:, 3]
            share = m * areas / areas.sum()
            counts = np.floor(share).astype(int)
            counts[np.argsort(-(share - counts))[: m - counts.sum()]] += 1
        out = []
        for (x, y, w, h), c in zip(boxes, counts):
            if c <= 0:
                continue
            nx = max(1, int(round(math.sqrt(c * w / h))))
            ny = max(1, int(math.ceil(c / nx)))
            cell = rng.permutation(nx * ny)[:c]
            xy = np.empty((c, 2))
            xy[:, 0] = (cell % nx + rng.random(c)) * (w / nx) + x
            xy[:, 1] = (cell // nx + rng.random(c)) * (h / ny) + y
            out.append(xy)
        if len(out) == 1:
            return out[0]
        return np.concatenate(out) if out else np.empty((0, 2))

    def _search_due(self) -> bool:
        """Search on this frame? Every frame for the first ``search_dense`` frames of a search, then every
        ``search_interval``-th."""
        p = self.params
        if p.search_interval <= 1 or self._last_search is None:
            return True
        k = self.frame_index - self._search_since
        return k <= p.search_dense or k % p.search_interval == 0

    def _waiting_state(self) -> TrackState:
        """A frame between two searches: the last search's result again (the target is still lost)."""
        last = self._last_search
        return replace(last, info={**last.info, "mode": "waiting"})

    def _sample_boxes(self) -> np.ndarray | None:
        """Where the search spreads its samples: the entry regions, the border band after an exit, or the whole
        frame (``None``)."""
        return self.regions if self.regions is not None else self._exit_band()

    def _exit_strip(self) -> tuple[int, float] | None:
        """``reenter_border``: after the target left the view, the edge it left through (0 left, 1 right, 2 top,
        3 bottom) and how far from it a candidate's centre may lie: a box within ``b`` target sizes of the edge,
        plus the distance the target could have walked in since the loss at the speed it left with. ``None`` when
        off, with entry regions, or when the target was not seen leaving (its last confident position, moved on
        at the mean displacement of its last confident frames to the frame the loss was declared, has at least
        ``reenter_exit_share`` of its box inside)."""
        b = self.params.reenter_border
        if b <= 0 or self.regions is not None or self._lost_at is None:
            return None
        hx, hy = float(self.size[0]), float(self.size[1])  # Python floats: called several times a search frame
        fh, fw = self._shape
        k = self._search_since - self._lost_at[0]
        vx, vy = self._exit_velocity
        cx = float(self._lost_at[1][0]) + k * float(vx)
        cy = float(self._lost_at[1][1]) + k * float(vy)
        if in_frame_fraction(ellipse_box(cx, cy, hx, hy), fw, fh) >= self.params.reenter_exit_share:
            # reenter_memory: a box seen mostly outside just before the loss (the tracker slid back inside after)
            seen = [e for e in self._edge_seen if e[0] >= self._search_since - self.params.reenter_memory]
            if not seen:
                return None
            cx, cy = float(seen[-1][1]), float(seen[-1][2])
        # the edge it left through: the one its predicted centre is furthest beyond (in target sizes)
        edge = exit_edge(cx, cy, hx, hy, fw, fh)
        speed = self.params.reenter_grow * math.hypot(*self._exit_velocity)
        grow = speed * max(self.frame_index - self._search_since, 0)
        half, extent = (hx, fw) if edge < 2 else (hy, fh)
        depth = half * (1.0 + 2.0 * b) + grow
        if self.params.reenter_reach > 0:  # a strip grown this deep is as far as a returning target is looked for
            depth = min(depth, max(half * (1.0 + 2.0 * b), 2.0 * half * self.params.reenter_reach))
        return edge, min(depth, float(extent))

    def _exit_band(self) -> np.ndarray | None:
        """The strip of :meth:`_exit_strip` as a rectangle ``[[x, y, w, h]]`` of sample centres (``None`` as
        there)."""
        strip = self._exit_strip()
        if strip is None:
            return None
        edge, d = strip
        fh, fw = self._shape
        return np.array([[(0.0, 0.0, d, fh), (fw - d, 0.0, d, fh), (0.0, 0.0, fw, d), (0.0, fh - d, fw, d)][edge]])

    def _position_log_prior(self, states: np.ndarray) -> np.ndarray | None:
        """The log prior of each search sample's position: ``search_prior``'s term (below) and, after an exit
        (``reenter_border``), ``-inf`` farther than the strip's depth from the edge the target left through (a
        centre beyond the edge is in); ``None`` when neither applies."""
        out = self._motion_log_prior(states)
        strip = self._exit_strip()
        if strip is None:
            return out
        edge, d = strip
        fh, fw = self._shape
        x, y = states[:, X], states[:, Y]
        near = (x <= d, x >= fw - d, y <= d, y >= fh - d)[edge]
        gate = np.where(near, 0.0, -np.inf)
        return gate if out is None else out + gate

    def _frame_gray(self, frame: np.ndarray) -> np.ndarray:
        """This frame's grey image, converted once (``_leaving`` needs it, the search keeps it for the next frame,
        and on grey input the equalisation table and the self-quotient image start from it)."""
        cached = self._gray_now
        if cached is None or cached[0] != self.frame_index or cached[2] is not frame:
            cached = self._gray_now = (self.frame_index, gray_of(frame), frame)
        return cached[1]

    def _motion_log_prior(self, states: np.ndarray) -> np.ndarray | None:
        """``search_prior``: log prior odds of each search sample's position, ``log((1 - e) A N(x; m, s^2 I) + e)``
        with ``m`` the constant-velocity prediction from the last confident frame, ``s`` the search's spread
        (growing with the time lost), ``A`` the frame's area and ``e = search_prior`` the chance that the target
        reappears anywhere (uniform); ``None`` when off or nothing was seen moving."""
        eps = self.params.search_prior
        if eps <= 0 or self._lost_at is None:
            return None
        centre, sd = lost_prediction(self._lost_at, self.frame_index, self.size)
        fh, fw = self._shape
        return reappearance_log_prior(states[:, X:Y + 1], centre, sd, fw * fh, eps, cap=self.params.search_prior_cap)

    def _search_proposals(self, frame: np.ndarray) -> np.ndarray | None:
        """Positions ``(m, 2)`` a cue proposes to the search (default: none; fusion-pf's structural cue)."""
        return None

    def _search_rho(self, frame: np.ndarray, ell: np.ndarray):
        """The search samples' colour ``rho``, quantised features and masses (``_rho``).  With ``relit_search`` on
        colour input, once a channel's level is 5 % or more away from the last background refresh while the
        target was seen, the frame's per-channel gain is undone first (von Kries; ``"replace"``), or the better
        of the two scores is kept (``"max"``): a target whose colours drifted with the light while it was hidden
        is still recognised."""
        ref = self._seen_levels
        if self.params.relit_search != "off" and ref is not None and frame.ndim == 3 and self.cue.color_space == "rgb":
            g = self._frame_gain(frame, ref)
            if g is not None and np.any(np.abs(g - 1.0) >= 0.05):  # the light changed (5 % dead zone)
                h, w = self._shape
                roi = reachable_roi(ell, w, h)
                lut = self.cue.mapped_lut(gain_maps(g, np.ones(3)))
                relit = self.cue.prepare(frame, roi, self.cue.step_for(ell), lut=lut)
                rho, tot = self.cue.rho(relit, ell, self._sqrt_q, reuse=False)
                self._relit_at = self.frame_index  # a refined layer must be scored the same way (_refine_layer)
                if self.params.relit_search == "max":
                    raw, _, feats = self._rho(frame, ell)
                    return np.maximum(rho, raw), tot, feats
                return rho, tot, relit
        rho, tot, feats = self._rho(frame, ell)
        k = self.params.grey_relit_shift
        if k > 0 and self.cue.color_space == "gray" and len(ell):  # a target relit on its own (intensity.shifted_rho)
            hist, _ = self.cue.histograms(feats, ell, reuse=False)
            rho = np.where(tot > 0, np.maximum(rho, shifted_rho(hist, self._sqrt_q, *self.cue.gray_bins, k)), rho)
        return rho, tot, feats

    def _search_refine(self) -> float:
        """The refined layer's share: ``grey_search_refine`` on grey input when set, else ``search_refine``."""
        p = self.params
        grey = p.grey_search_refine
        return p.search_refine if grey is None or self.cue.color_space != "gray" else grey

    def _refine_layer(self, frame, states, ell, rho, tot, loglik, prior, feats):
        """``search_refine``: a second layer of samples drawn from the first layer's posterior, moved by a quarter
        of the half-axes and scored the same way (sizes kept: drawn afresh around the searched size instead, the
        tune split lost 0.012 real AUC and re-acquired 0.71 against 0.76, docs/fusion-pf.md); both layers are
        returned together (the region of the colour features then spans both)."""
        p = self.params
        roi = feats.roi
        rank = search_rank(loglik, prior, tot)
        if not np.isfinite(rank).any():
            return states, ell, rho, tot, loglik, prior, roi
        m = int(round(self._search_refine() * len(states)))
        if m < 1:  # a search of one or two samples: no second layer
            return states, ell, rho, tot, loglik, prior, roi
        rho, tot = rho.copy(), tot.copy()  # the cue's result buffers are reused by the next call
        w = np.exp(rank - rank.max())
        idx = weighted_choice(w / w.sum(), m, self.rng)
        extra = states[idx].copy()
        extra[:, X:Y + 1] += self.rng.normal(0.0, 0.25, (m, 2)) * extra[:, HX:HY + 1]
        self._clip_states(extra)
        e_ell = self._ellipses(extra)
        fh, fw = self._shape
        x0, y0, x1, y1 = reachable_roi(e_ell, fw, fh)
        if (self._relit_at != self.frame_index and not (p.grey_relit_shift > 0 and self.cue.color_space == "gray")
                and roi[0] <= x0 and roi[1] <= y0 and x1 <= roi[2] and y1 <= roi[3]):
            # inside the first layer's quantised region (the usual case), and that layer was not scored on the
            # relit frame: scored on the same features
            e_rho, e_tot = self._cue_rho(feats, e_ell)
            e_feats = feats
        else:
            e_rho, e_tot, e_feats = self._search_rho(frame, e_ell)
        e_ll = self._search_log_lik(frame, extra, self._log_lik(e_rho, e_tot), e_feats)
        e_ll = np.where(np.isfinite(e_ll), e_ll, -np.inf)
        e_prior = self._position_log_prior(extra)
        both = None if prior is None else np.concatenate([prior, e_prior])
        r1 = e_feats.roi
        box = (min(roi[0], r1[0]), min(roi[1], r1[1]), max(roi[2], r1[2]), max(roi[3], r1[3]))
        return (np.concatenate([states, extra]), np.concatenate([ell, e_ell]), np.concatenate([rho, e_rho]),
                np.concatenate([tot, e_tot]), np.concatenate([loglik, e_ll]), both, box)

    def _position_step_std(self, hx: float, hy: float) -> float:
        """The dynamic model's one-step std of the centre for a target of half-axes ``(hx, hy)`` (each tracker's
        own: :meth:`_step_std`), the spread of the search samples kept from the last search."""
        est = np.zeros(self.dim)
        est[HX], est[HY] = hx, hy
        return float(self._step_std(est)[X])

    def _search_candidates(self, frame: np.ndarray, exclude: np.ndarray | None = None) -> SearchCandidates:
        """One search layer (or two, ``search_refine``) over the frame and its best candidate.  ``exclude``: an
        ellipse whose neighbourhood (two half-axes each way) is left out of the ranking, and look-alikes are not
        followed (a search beside tracking, :mod:`.probation`)."""
        p = self.params
        n_s = self._n_search()
        hx, hy = self.size
        states = np.zeros((n_s, self.dim))
        n_keep = 0
        if self._search_states is not None and p.search_keep > 0:
            n_keep = int(round(p.search_keep * n_s))
            w = np.exp(self._search_loglik - self._search_loglik.max())
            idx = self.resampler(w / w.sum(), self.rng)[:n_keep]
            if idx.size < n_keep:
                idx = idx[self.rng.integers(0, idx.size, n_keep)]
            states[:n_keep] = self._search_states[idx]
            spread = 2.0 * self._position_step_std(hx, hy)
            states[:n_keep, X:Y + 1] += self.rng.normal(0.0, spread, (n_keep, 2))
            # sizes are drawn afresh around the searched size (a random walk would let them drift)
            states[:n_keep, HX:HY + 1] = np.array([hx, hy]) * np.exp(self.rng.normal(0.0, 0.1, (n_keep, 1)))
        n_new = n_s - n_keep
        n_pred = 0
        if self._lost_at is not None and p.search_predict > 0:
            # a share of the new samples where the target would be had it kept its velocity (behind an
            # occluder, a target usually comes out on the far side), spreading as time passes
            n_pred = int(round(p.search_predict * n_new))
            centre, sd = lost_prediction(self._lost_at, self.frame_index, self.size)
            states[n_keep:n_keep + n_pred, X:Y + 1] = centre + self.rng.normal(0.0, sd, (n_pred, 2))
        states[n_keep + n_pred:, X:Y + 1] = self._uniform_positions(n_new - n_pred)
        scale = np.exp(self.rng.normal(0.0, 0.1, (n_new, 1)))
        states[n_keep:, HX] = hx * scale[:, 0]
        states[n_keep:, HY] = hy * scale[:, 0]
        props = self._search_proposals(frame)
        if props is not None and len(props):
            # candidates proposed by a cue that sees the whole frame take the place of some uniform samples
            m = min(len(props), n_new - n_pred)
            i0 = n_keep + n_pred
            states[i0:i0 + m, X:Y + 1] = props[:m]
            states[i0:i0 + m, HX] = hx
            states[i0:i0 + m, HY] = hy
        self._clip_states(states)
        ell = self._ellipses(states)
        rho, tot, feats = self._search_rho(frame, ell)
        loglik = self._search_log_lik(frame, states, self._log_lik(rho, tot), feats)
        if not np.isfinite(loglik).any():
            loglik = np.zeros_like(loglik)
        prior = self._position_log_prior(states)
        roi = feats.roi
        if self._search_refine() > 0:
            states, ell, rho, tot, loglik, prior, roi = self._refine_layer(frame, states, ell, rho, tot, loglik,
                                                                             prior, feats)
        self._search_states = states
        self._search_loglik = loglik
        rank = search_rank(loglik, prior, tot)
        if exclude is not None:
            ex, ey, ehx, ehy = (float(v) for v in exclude)
            rank = np.where(near_mask(states, (ex, ey), (ehx, ehy)), -np.inf, rank)
        else:
            # look-alikes met earlier in this loss are followed and not chosen (distractor_frames)
            known = self._distractors.follow(states[:, X:Y + 1], rank, self.frame_index, self._lost_at, self.size,
                                             self._search_since)
            if known.any() and not known.all():
                rank = np.where(known, -np.inf, rank)
        def scores(i):  # a candidate's loss-test scores and log prior
            lp_i = 0.0 if prior is None else float(prior[i])
            return self._loss_scores(frame, ell[i:i + 1], rho[i:i + 1], roi)[0], lp_i

        best = int(np.argmax(rank)) if np.any(tot > 0) else 0
        best, (s_best, lp) = self._skip_scene(frame, ell, rank, best, scores)
        near = near_mask(states, states[best, X:Y + 1], self.size)  # the samples belonging to the best candidate
        return SearchCandidates(states, ell, rho, tot, loglik, roi, best, lp, near, s_best, n_keep, rank, scores)

    def _search(self, frame: np.ndarray) -> TrackState:
        """Initialisation mode (§6): spread samples, test the appearance condition, re-acquire."""
        p = self.params
        self._end_probation()  # lost while on probation
        c = self._search_candidates(frame)
        states, ell, rho, tot, loglik = c.states, c.ell, c.rho, c.tot, c.loglik
        best, lp, near, s_best, n_keep = c.best, c.lp, c.near, c.s_best, c.n_keep
        thr = self._threshold()
        conf = None
        vetoes: tuple[str, ...] = ()
        if p.search_method == "appearance" and p.loss_test == "likelihood":
            # the best candidate must look like the target's score history (hysteresis); that test is stricter
            # than the count of passing samples, which then only needs a few supporters; a candidate a veto
            # refuses gives way to the next (search_retries, .vetoes)
            a = self._choose(frame, c, self._appearance_pass(rho, thr, loglik) & (tot > 0))
            best, s_best, lp, near, cluster, found, vetoes = a
            conf = confidence(self.loss.llr)
        else:
            if p.search_method == "appearance":
                cluster = near & self._appearance_pass(rho, thr, loglik) & (tot > 0)
                found = cluster.sum() > p.kickoff_fraction * p.n_particles
            else:
                cluster = near & (tot > 0)
                lw = np.where(cluster, loglik, -np.inf)
                ww = np.exp(lw - lw.max())
                ww /= ww.sum()
                pos = states[:, X:Y + 1]
                mean = (ww[:, None] * pos).sum(axis=0)
                var = float(np.mean((ww[:, None] * (pos - mean) ** 2).sum(axis=0)))
                found = n_keep > 0 and var < p.variance_threshold and rho[best] > thr
            reason = self._vetoed_by(frame, ell[best]) if found else None
            if reason is not None:
                vetoes = (reason,)
                found = False
                self.loss.lost = True
        if not found and self.detector is not None and self.frame_index % p.detector_interval == 0:
            boxes, _ = self._detections(frame)
            if boxes.shape[0]:
                d_ell = box_to_ellipse(boxes)
                d_rho, d_tot, _ = self._rho(frame, d_ell)
                d_rho = np.where(d_tot > 0, d_rho, -1.0)
                k = int(np.argmax(d_rho))
                if d_rho[k] > thr and (p.loss_test != "likelihood" or self.loss.acquire(
                        self._loss_scores(frame, d_ell[k:k + 1], d_rho[k:k + 1], (0, 0, *self._shape[::-1]))[0])):
                    self.size = self._confident_size = (float(d_ell[k, 2]), float(d_ell[k, 3]))
                    state = self._initial_state(d_ell[k])
                    self._start_tracking(np.tile(state, (p.n_particles, 1)))
                    box = tuple(float(v) for v in boxes[k])
                    self.last_box = box
                    return self._state(box=box, score=float(d_rho[k]), lost=False,
                                       info={"mode": "acquired", "threshold": thr})
        if not found and (restart := self._persist_step(frame, ell[best], s_best)) is not None:
            return restart  # a changed target the search keeps finding in one place (.persistence)
        info = {"mode": "searching", "n_pass": int(np.count_nonzero(rho > thr)), "threshold": thr,
                "vetoed": bool(vetoes), "vetoes": list(vetoes)}  # why candidates were refused (.vetoes.Acquisition)
        if found:
            lost_at = self._lost_at
            exited = self._exit_strip() is not None  # the target had left the view through an edge
            self._start_tracking(states[cluster], loglik[cluster])
            self._begin_probation(lost_at, exited=exited)
            est = self.estimate
            box = tuple(float(v) for v in ellipse_to_box(est[_ELL_COLS]))
            self.last_box = box
            self.size = self._confident_size = (float(est[HX]), float(est[HY]))
            # a weak acquisition under probation_lost_llr: followed, reported absent
            score, lost = self._as_reported(float(rho[best]) if conf is None else conf)
            return self._state(box=box, score=score, lost=lost, info={**info, "mode": "acquired"})
        box = self.last_box
        if box is None:
            box = tuple(float(v) for v in ellipse_to_box(ell[best]))
        score = float(max(rho[best], 0.0)) if p.loss_test != "likelihood" else min(
            confidence(self.loss.evaluate(s_best)), 0.5)
        return self._state(box=box, score=score, lost=True, info=info,
                           particles=states, weights=np.exp(loglik - loglik.max()))
