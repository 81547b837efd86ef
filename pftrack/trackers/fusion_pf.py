"""``fusion-pf``: pftrack's default tracker — colour, background-aware contrast and grey-patch structure, fused.

It is ``color-pf`` (Nummiaro et al.) with the ingredients that make a colour
particle filter hold on real footage, grey video and illumination change, each a
documented parameter with an ablation in ``docs/fusion-pf.md``:

* **Likelihood = product of cues** (independent observations), in the log domain:
  ``log p(y | x) = w_col log p_colour + contrast_gain c + w_str structure_gain r [+ log p_motion]`` where
  ``p_colour`` is Eq. 10 of Nummiaro et al. on the kernel histogram, ``c`` the object/surround
  contrast of the foreground-probability map (:mod:`pftrack.cues.contrast`; it also observes the
  target's extent), ``r`` the NCC of the particle's grey patch with the reference
  (:mod:`pftrack.cues.structure`; book ch. 14's criterion, blind to gain and offset), and
  ``p_motion`` the optional local-motion likelihood of Kristan et al. (Eq. 7).
* **Reliability weights** ``w``: each cue's separation ``d'`` between its target-score history
  and the upper tail of its background scores (the loss test's statistics), ``min(1, d'/reliability_d)``.
* **The lost flag on fused evidence**: :class:`~pftrack.filtering.loss.FusedLoss` adds the
  colour's and the structure's clipped log-likelihood ratios; the search scores its samples with
  every cue.
* **Gated model updates**: the colour model (Eqs. 11–12), the object/surround counts and the
  structural reference adapt only on confident frames (the reference also only while it still
  resembles the first frame's patch).
"""

from __future__ import annotations

import math

import numpy as np

from ..cues.contrast import (
    blend_counts,
    box_counts,
    contrast_scores_ellipses,
    foreground_lut,
    probability_integral,
)
from ..cues.intensity import gain_maps, is_gray, light_levels
from ..cues.grey_patch import grey_patch
from ..cues.mass_size import mass_factor, object_area
from ..cues.motion import LocalMotionCue, local_motion
from ..cues.scale_search import aspect_factor, best_shape_score, size_factor
from ..cues.structure import StructureCue
from ..cues.structure_hog import BestStructure, HogStructure
from ..cues.structure_light import LitStructure
from ..filtering.dynamics import HX, HY, VX, VY
from ..filtering.loss import FusedLoss
from ..geometry import box_to_ellipse, ellipse_box
from .color_hooks import fused_supporters
from .color_pf import _ELL_COLS, ColorPF
from .fusion_params import FusionPFParams


class FusionPF(ColorPF):
    """Colour PF fused with a background-aware contrast cue and, optionally, local motion."""

    name = "fusion-pf"
    Params = FusionPFParams

    def __init__(self, params: FusionPFParams | None = None, *, rng=None, seed=None, detector=None):
        super().__init__(params, rng=rng, seed=seed, detector=detector)
        p = self.params
        self.motion_cue = LocalMotionCue(levels=p.lk_levels, max_features=p.max_features)
        self.structure = self._structure_cue(None)
        if self._fused:
            self.loss = FusedLoss(2, cue_clip=p.loss_cue_clip, cue_floor=p.loss_cue_floor,
                                  acquire_z=p.acquire_z, acquire_margin=p.acquire_margin,
                                  history_miss_z=p.loss_history_z, lost_frames=p.lost_frames,
                                  reacquire_margin=p.reacquire_margin,
                                  history_rate=p.history_rate, sd_floor_target=p.score_sd_floor,
                                  sd_floor_background=p.score_sd_floor, learn_z=p.history_z)
        self._obj = None
        self._sur = None
        self._lut = None
        self._ii: np.ndarray | None = None  # the integral image's buffer, reused between frames
        self._ii_of = None  # (frame index, features) the integral image was computed from
        self._prev_gray = None
        self._gray = None
        self._flow = None
        self.v_ref = None
        self._ref_levels: np.ndarray | None = None
        self._levels: tuple[int, np.ndarray] | None = None
        self._mass_ref: tuple[float, float] | None = None  # mass_size: the first reading's (area, size)

    @property
    def _fused(self) -> bool:
        p = self.params
        return p.structure and p.fused_loss and p.loss_test == "likelihood"

    # ------------------------------------------------------------------ init
    def _structure_cue(self, frame):
        """A fresh structural cue for the input ``frame`` (None: unknown): on grey input with ``grey_structure`` other
        than 'levels', the quotient and grey-level pair of pftrack.cues.structure_light."""
        p = self.params
        if p.structure_features == "hog" or (p.structure_features == "hog-on-grey" and frame is not None
                                             and is_gray(frame)):
            return HogStructure(cells=p.hog_cells)
        if frame is not None and p.grey_structure != "levels" and p.illumination == "none" and is_gray(frame):
            ncc = LitStructure(p.structure_pixels, weighting=p.structure_weighting, sigma=p.illumination_sigma,
                               mode=p.grey_structure, gray_of=self._frame_gray)
        else:
            ncc = StructureCue(p.structure_pixels, weighting=p.structure_weighting)
        if p.structure_features in ("ncc", "hog-on-grey"):
            return ncc
        return BestStructure(ncc, HogStructure(cells=p.hog_cells))

    def _lit_structure(self) -> LitStructure | None:
        """The structural cue's quotient and grey-level pair, when it has one."""
        s = self.structure.primary if isinstance(self.structure, BestStructure) else self.structure
        return s if isinstance(s, LitStructure) else None

    def _grey_shared(self) -> bool:
        lit = self._lit_structure()
        return (self.cue.color_space == "gray" and lit is not None and lit.shares_gray) or super()._grey_shared()

    def _shared_quotient(self):
        """The grey structural cue's self-quotient image (same frames, same ``illumination_sigma``), when it has one;
        otherwise (the gradient cue on grey input) :meth:`ColorPF._shared_quotient`'s own."""
        lit = self._lit_structure()
        return lit._qf if lit is not None else super()._shared_quotient()

    def init_auto(self, frame, histogram, size, *, regions=None):
        """As :meth:`ColorPF.init_auto`; a known histogram gives no reference patch, so the structural cue
        stays off (no evidence) for this target."""
        self.structure = self._structure_cue(None)
        self._mass_ref = None
        return super().init_auto(frame, histogram, size, regions=regions)

    def _init(self, frame, box):
        p = self.params
        if p.structure:  # before the colour init: its background statistics need the structural reference
            self.structure = self._structure_cue(frame)
            self.structure.init(frame, box_to_ellipse(box))
        st = super()._init(frame, box)
        if p.contrast:
            pitch = self.cue.step_for(box_to_ellipse(box).reshape(1, 4))
            feats = self.cue.prepare_frame(frame, pitch)
            self._obj, self._sur = box_counts(feats.bins, feats.x0, feats.y0, box, self.cue.feature_bins, ring=p.ring,
                                              pitch=pitch)
            self._lut = foreground_lut(self._obj, self._sur).astype(np.float64)  # exact: the integral's type
        self.v_ref = None
        self._mass_ref = None
        self._prev_gray = grey_patch(frame) if p.motion else None
        # the background statistics reduced this frame for the structural cue: the next frame must not reuse it
        self.structure.new_frame()
        return st

    # ------------------------------------------------------------------ observation
    def _propagate(self, states):
        x0, y0, x1, y1 = super()._propagate(states)
        if self.params.contrast:  # the rings must be inside the quantised region too
            r = self.params.ring
            top_x, top_y = states[:, HX:HY + 1].max(axis=0).tolist()  # HY follows HX
            mx = 2.0 * r * top_x + 1.0
            my = 2.0 * r * top_y + 1.0
            return x0 - mx, y0 - my, x1 + mx, y1 + my
        return x0, y0, x1, y1

    def _reliability(self) -> tuple[float, float]:
        """Reliability factors of the colour and structural cues (see ``reliability_d``)."""
        p = self.params
        if not self._fused or p.reliability_d <= 0:
            return 1.0, 1.0
        out = []
        for m in self.loss.members:
            d = (m.mu_t - m.mu_b) / max(m.sd_b, 1e-9)
            out.append(min(1.0, max(p.reliability_floor, d / p.reliability_d)))
        return out[0], out[1]

    def _fused_log_lik(self, frame, ell, log_lik, roi, feats):
        """The colour log-likelihood scaled by its reliability, plus the contrast and structural terms."""
        p = self.params
        w_col, w_str = self._reliability()
        if w_col != 1.0:
            log_lik = log_lik * w_col
        if p.contrast and self._lut is not None:
            if self._ii_of is not None and self._ii_of[0] == self.frame_index and self._ii_of[1] is feats:
                ii = self._ii  # the same quantised region again on this frame (the search's refined layer)
            else:
                ii = self._ii = probability_integral(feats.bins, self._lut, out=self._ii)
                self._ii_of = (self.frame_index, feats)
            c = contrast_scores_ellipses(ii, feats.x0, feats.y0, ell, ring=p.ring, pitch=feats.pitch,
                                         shape=p.contrast_shape)
            log_lik = log_lik + p.contrast_gain * c
        if p.structure and p.structure_gain > 0 and self.structure.ready:
            log_lik = log_lik + (w_str * p.structure_gain) * self.structure.scores(frame, roi, ell)
        return log_lik

    def _extra_log_lik(self, frame, states, log_lik, roi, feats):
        p = self.params
        log_lik = self._fused_log_lik(frame, self._ellipses(states), log_lik, roi, feats)
        if p.motion:
            if self._flow is None:  # once a frame: the grey levels where the flow reads them (cues.grey_patch)
                self._gray = self.motion_cue.frame_patch(frame, roi)
                self._flow = self.motion_cue.prepare(self._prev_gray, self._gray, roi)
            if self.v_ref is not None:
                log_lik = log_lik + self.motion_cue.log_likelihood(self._flow, self._ellipses(states), self.v_ref)
        return log_lik

    def _background_stats(self, frame, exclude):
        super()._background_stats(frame, exclude)
        if self.params.relit_colour and self.cue.color_space == "rgb" and frame.ndim == 3 and self.mode == "tracking":
            self._ref_levels = light_levels(frame)  # the light while the target is seen (as the relit search reads it)

    def _relit_rho(self, frame: np.ndarray, ellipse: np.ndarray) -> float:
        """Colour rho of one ellipse with the frame's per-channel gain against ``_ref_levels`` undone."""
        if self._levels is None or self._levels[0] != self.frame_index:
            self._levels = (self.frame_index, light_levels(frame))
        e = np.asarray(ellipse, dtype=np.float64).reshape(1, 4)
        fh, fw = self._shape
        roi = (max(int(e[0, 0] - e[0, 2]) - 1, 0), max(int(e[0, 1] - e[0, 3]) - 1, 0),
               min(int(e[0, 0] + e[0, 2]) + 2, fw), min(int(e[0, 1] + e[0, 3]) + 2, fh))
        feats = self.cue.prepare(frame, roi, self.cue.step_for(e),
                                 lut=self.cue.mapped_lut(gain_maps(self._ref_levels, self._levels[1])))
        r, tot = self.cue.rho(feats, e, self._sqrt_q, reuse=False)
        return float(r[0]) if tot[0] > 0 else 0.0

    def _loss_scores(self, frame, ellipses, rho, roi):
        if not self._fused:
            return rho
        if not self.structure.ready:  # started from a histogram (init_auto): no reference patch, no evidence
            return np.column_stack([rho, np.full(len(rho), np.nan)])
        s = self.structure.scores(frame, roi, ellipses)
        if len(rho) == 1 and self.params.visible_structure:
            # a box partly outside the frame (the search's candidate, or the estimate while tracking): its visible
            # part against the same part of the references
            visible = getattr(self.structure, "visible_score", None)  # not every structural cue has one
            v = visible(frame, ellipses[0]) if visible is not None else None
            if v is not None and v > s[0]:
                s[0] = v
        if self.mode == "searching" and len(rho) == 1 and self.params.acquire_shape_step > 0:
            # a target back with another shape (acquire_shape_step): the best of 9 shapes around the candidate
            s[0] = max(s[0], best_shape_score(self.structure, frame, ellipses[0], self.params.acquire_shape_step))
        s += 1.0
        s *= 0.5
        if (self.mode == "searching" and len(rho) == 1 and self.params.relit_colour and self._ref_levels is not None
                and frame.ndim == 3 and self.cue.color_space == "rgb"):
            col, st = self.loss.members
            # the colour would veto a candidate the structure alone could acquire: is it only the light?
            if ((float(rho[0]) - col.mu_t) / col.sd_t <= -col.learn_z
                    and st.evaluate(float(s[0])) - self.loss.cue_floor > self.loss.reacquire_margin):
                rho = np.maximum(rho, self._relit_rho(frame, ellipses[0]))
        out = np.empty((len(s), 2))
        out[:, 0] = rho
        out[:, 1] = s
        return out

    def _appearance_pass(self, rho, threshold, log_lik):
        if not self._fused:
            return rho > threshold
        return fused_supporters(log_lik)

    def _search_proposals(self, frame):
        k = self.params.search_proposals
        if k <= 0 or not self._fused or not self.structure.ready:
            return None
        return self.structure.proposals(frame, self.size, k)[0]

    def _search_log_lik(self, frame, states, log_lik, feats):
        if not self._fused:
            return log_lik
        return self._fused_log_lik(frame, self._ellipses(states), log_lik, feats.roi, feats)

    def _after_estimate(self, frame, estimate):
        p = self.params
        if p.scale_search > 0 and p.scale_search_rate > 0 and p.structure and self.structure.ready:
            self._search_scale(frame, estimate)
        if not p.motion or self._flow is None:
            return
        v_obs, defined = local_motion(self._flow, estimate[_ELL_COLS].reshape(1, 4))
        if defined[0]:
            self.v_ref = (v_obs[0].copy() if self.v_ref is None
                          else self.motion_cue.adapt(self.v_ref, estimate[[VX, VY]], v_obs[0]))

    def _mass_factor(self, estimate) -> float:
        """``mass_size``: the factor toward the size the object's area on this frame's foreground-probability map
        implies (:mod:`pftrack.cues.mass_size`; 1 without a reading). The first reading is the reference."""
        if self._ii_of is None or self._ii_of[0] != self.frame_index:
            return 1.0  # no map of this frame
        feats = self._ii_of[1]
        ell = estimate[_ELL_COLS]
        frame = (self._shape[1], self._shape[0]) if self.params.mass_frame else None
        read = object_area(self._ii, feats.x0, feats.y0, feats.pitch, ell, gate=self.params.mass_gate, frame=frame)
        if read is None:
            return 1.0
        size = math.sqrt(float(ell[2]) * float(ell[3]))
        if self._mass_ref is None:
            self._mass_ref = (read[0], size)
            return 1.0
        return mass_factor(self._mass_ref, read[0], size, self.params.mass_size)

    def _search_scale(self, frame, estimate):
        """``scale_search``: move the estimate's and the particles' size (in place) toward the size whose grey
        patch best matches the structural references."""
        p = self.params
        self._scale_size(estimate, size_factor(self.structure, frame, estimate[_ELL_COLS], p.scale_search,
                                               p.scale_search_rate,
                                               anchor_only=p.scale_search_reference == "anchor"))
        if p.aspect_search > 0 and p.aspect_search_rate > 0 and self.loss.llr > self.loss.reacquire_margin:
            f = aspect_factor(self.structure, frame, estimate[_ELL_COLS], p.aspect_search, p.aspect_search_rate)
            if f != 1.0:
                estimate[HX] *= f
                estimate[HY] /= f
                self.ps.scale_columns(HX, HX + 1, f)
                self.ps.scale_columns(HY, HY + 1, 1.0 / f)

    def _update_models(self, frame, estimate, feats, rho_e):
        """On the frames the models learn from (the loss test confident): the structural reference, the contrast
        counts, and with ``mass_size`` the size, read before the counts change the map and applied to the estimate
        and the particles after the models took the estimate's box."""
        p = self.params
        k = self._mass_factor(estimate) if p.mass_size > 0 and p.contrast else 1.0
        if p.structure:
            self.structure.update(frame, estimate[_ELL_COLS], p.structure_rate, p.structure_anchor_gate)
        if p.contrast and p.contrast_alpha > 0:
            obj, sur = box_counts(feats.bins, feats.x0, feats.y0, ellipse_box(*estimate[_ELL_COLS].tolist()),
                                  self.cue.feature_bins, ring=p.ring, pitch=feats.pitch)
            # counts are compared as distributions scaled to the reference areas
            blended = blend_counts(self._obj, obj, self._sur, sur, p.contrast_alpha)
            if blended is not None:
                self._obj, self._sur, self._lut = blended
                self._ii_of = None  # an integral image of this frame was taken with the former table
        self._scale_size(estimate, k)

    def _on_frame(self, frame):
        self.structure.new_frame()
        if self.params.motion:
            self._prev_gray = self._gray if self._gray is not None else grey_patch(frame)
            self._gray = None
            self._flow = None
