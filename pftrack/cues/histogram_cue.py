"""The histogram observation model of the colour trackers, with features chosen from the input.

:class:`ColorCue` quantises the region the particles can reach once per frame and
scores a batch of ellipses by their kernel histograms (Nummiaro et al., Eqs. 3-6;
kernels in :mod:`pftrack.cues.color`).  What a pixel's bin describes depends on
the input (the cue chooses its features, GUIDE §8):

* ``"rgb"`` (8x8x8) or ``"hsv"`` (8x8x4) colour bins;
* ``"gray"``: equalised intensity x gradient orientation (:mod:`pftrack.cues.intensity`)
  for frames that carry no colour;
* ``"auto"`` (the trackers' default): ``"gray"`` when the first frame is grey, else
  the colour space given as ``fallback`` — decided by :meth:`ColorCue.adapt_to`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from .._numba import njit, numba_enabled
from ..errors import ParameterError
from ..frames import bgr_view
from .color import DEFAULT_BINS, KERNELS, ColorSpace, KernelName, ellipse_histograms, ellipse_rho, reachable_roi
from .intensity import (channel_equalization_maps, channel_levels, equalization_lut, gain_maps, is_gray,
                        quantize_gray)
from .quantize import (level_gain, level_range, make_lut, quantize, quantize_cells, quantize_region, shift_form,
                       stretched_lut)
from .still_gain import cast_undo, reference_lattice, still_gain

FEATURE_SPACES = ("auto", "rgb", "hsv", "gray")
#: Gains within this of 1 leave the raw colours ("adaptive" and "still"): no jitter from the gain's estimate.
GAIN_DEAD_ZONE = 0.05
#: Default grey features: intensity bins, orientation bins (plus one "flat" bin).
DEFAULT_GRAY_BINS = (16, 8)


def check_gray_bins(bins: tuple[int, ...]) -> None:
    """A tracker parameter ``gray_bins`` must be (intensity bins, orientation bins <= 64)."""
    if len(bins) != 2 or bins[1] > 64:
        raise ParameterError(f"parameter 'gray_bins' must be (intensity, orientation <= 64), got {bins}")


_HALF_XY = np.array([0.5, 0.5, 0.0, 0.0])


@dataclass
class ColorFeatures:
    """A frame region quantised to colour bins (the output of :meth:`ColorCue.prepare`).

    With ``pitch > 1`` only every ``pitch``-th pixel of every ``pitch``-th row was
    quantised (a lattice anchored to the image grid): ``bins[k, l]`` is image pixel
    ``(x0 + l * pitch, y0 + k * pitch)``.
    """

    bins: np.ndarray  # (h, w) uint16, C-contiguous
    x0: int
    y0: int
    pitch: int = 1

    @property
    def roi(self) -> tuple[int, int, int, int]:
        """The image region ``(x0, y0, x1, y1)`` the quantised lattice covers."""
        h, w = self.bins.shape
        return self.x0, self.y0, self.x0 + w * self.pitch, self.y0 + h * self.pitch

    def to_lattice(self, ellipses: np.ndarray) -> tuple[np.ndarray, int, int]:
        """Ellipses in the coordinates of ``bins`` (and the origin to pass to the kernels).

        A lattice sample ``k`` has its centre at image ``x0 + k p + 0.5``; in lattice
        units ``(c - x0 - 0.5) / p + 0.5`` puts it at ``k + 0.5``, and both the
        ellipse test and the kernel weights are invariant to the common scaling.
        """
        if self.pitch == 1:
            return ellipses, self.x0, self.y0
        p = float(self.pitch)
        if numba_enabled():
            e = np.asarray(ellipses, dtype=np.float64)
            return _to_lattice(e, float(self.x0), float(self.y0), p, np.empty(e.shape)), 0, 0
        # the same operations, on the whole (N, 4) array at once (adding or subtracting 0 leaves a number as it is)
        e = ellipses - np.array([self.x0, self.y0, 0.0, 0.0])
        e -= _HALF_XY
        e /= p
        e += _HALF_XY
        return e, 0, 0


@njit
def _to_lattice(e, x0, y0, p, out):
    """:meth:`ColorFeatures.to_lattice`'s operations, element by element (the same numbers)."""
    for i in range(e.shape[0]):
        out[i, 0] = (e[i, 0] - x0 - 0.5) / p + 0.5
        out[i, 1] = (e[i, 1] - y0 - 0.5) / p + 0.5
        out[i, 2] = (e[i, 2] - 0.0 - 0.0) / p + 0.0
        out[i, 3] = (e[i, 3] - 0.0 - 0.0) / p + 0.0
    return out


class ColorCue:
    """Histogram observation model (colour, or intensity x orientation on grey input).

    Parameters
    ----------
    color_space : ``"rgb"`` (8x8x8 bins), ``"hsv"`` (8x8x4 bins), ``"gray"`` (intensity x
        gradient orientation) or ``"auto"`` (grey features on grey input, else ``fallback``;
        see :meth:`adapt_to`).
    bins : colour bins per channel; ``None`` for the default of the colour space.
    kernel : see :func:`~pftrack.cues.color.ellipse_histograms`.
    max_pixels : when an ellipse has more pixels than this, sample it on a regular
        lattice of pitch ``ceil(sqrt(area / max_pixels))`` (0: always every pixel).
    gray_bins : ``(n_intensity, n_orientation)`` of the grey features.
    gradient_threshold : Sobel magnitude (on the equalised image, levels 0-255) below
        which a pixel falls in the "flat" orientation bin.
    fallback : the colour space ``"auto"`` uses on colour input.
    normalize : RGB features under changing light: ``"none"``; ``"gain"`` divides each channel
        by its gain relative to the initialisation frame (per-channel medians, von Kries);
        ``"adaptive"`` is ``"gain"`` with a reference that follows the frames the tracker is
        confident on (:meth:`confirm`) and freezes otherwise, so a lighting change that
        happens while the target is hidden is undone when it reappears;
        ``"equalize"`` equalises each channel's histogram over the frame; ``"still"`` divides each channel by the
        frame's gain against the initialisation frame measured on the same pixels while the view is still
        (:func:`~pftrack.cues.still_gain.still_gain`; held while it moves), with the 5 % dead zone of ``"adaptive"``.
    parts : 1, or 2 for two-part histograms (:func:`~pftrack.cues.color.ellipse_histograms`): the features of the
        rows above and below each ellipse's centre in separate halves of ``n_bins`` (``feature_bins`` each).
    dark_stretch : RGB features of a dark camera: when the initialisation frame's bright end
        (:func:`~pftrack.cues.quantize.level_gain`) needs a gain of at least this to reach level 255, the bins are
        spread over the levels the camera uses (:func:`~pftrack.cues.quantize.stretched_lut`, ``level_gain`` holds
        the gain; at most 8); 0: never (the bins of Nummiaro et al., over 0-255).
    dark_percentile : the percentile of the frame's levels (every channel) that ``dark_stretch`` brings to 255; the
        brighter rest (lamps, headlights) falls into the top bins.
    haze_stretch : RGB features of a hazy camera (fog, a misted lens): when the initialisation frame is not dark
        enough for ``dark_stretch`` but its levels between the ``100 - dark_percentile`` and ``dark_percentile``
        percentiles span at most 255 / ``haze_stretch``, the bins are spread over that span
        (:func:`~pftrack.cues.quantize.level_range`; ``level_offset`` holds its bottom); 0: never.
    cast_jump : RGB features under a white balance that jumps: a frame whose chromatic jump against the previous
        frame (the largest minus the smallest of the channels' median log-ratios,
        :func:`~pftrack.cues.still_gain.frame_jump`) is at least this, every channel's MAD at most
        ``JUMP_MAX_MAD``, multiplies a per-channel gain by the jump's, and the bins undo that gain (with ``"still"``,
        times the gain held from the last still view, which a new still view's gain replaces); with ``normalize``
        ``"none"`` or ``"still"`` only. 0: never.
    light_jump : the same for lamps switched on or off: a frame whose channels' mean median log-ratio is at least
        this in size (every channel at once) takes that jump into the same gain. 0: never.
    """

    def __init__(self, color_space: str = "rgb", bins: tuple[int, int, int] | None = None,
                 kernel: KernelName = "nummiaro", max_pixels: int = 0, *,
                 gray_bins: tuple[int, int] = DEFAULT_GRAY_BINS, gradient_threshold: float = 40.0,
                 fallback: ColorSpace = "rgb", normalize: str = "none", parts: int = 1, dark_stretch: float = 0.0,
                 dark_percentile: float = 99.5, haze_stretch: float = 0.0, cast_jump: float = 0.0,
                 light_jump: float = 0.0):
        if parts not in (1, 2):
            raise ValueError(f"parts must be 1 or 2, got {parts!r}")
        self.parts = int(parts)
        if normalize not in ("none", "gain", "adaptive", "equalize", "still"):
            raise ValueError(f"unknown colour normalisation {normalize!r}")
        self.normalize = normalize
        if not dark_stretch >= 0:
            raise ValueError(f"dark_stretch must be >= 0, got {dark_stretch!r}")
        self.dark_stretch = float(dark_stretch)
        if not 50 <= dark_percentile <= 100:
            raise ValueError(f"dark_percentile must be in [50, 100], got {dark_percentile!r}")
        self.dark_percentile = float(dark_percentile)
        if not haze_stretch >= 0:
            raise ValueError(f"haze_stretch must be >= 0, got {haze_stretch!r}")
        self.haze_stretch = float(haze_stretch)
        if not (cast_jump >= 0 and light_jump >= 0):
            raise ValueError(f"cast_jump and light_jump must be >= 0, got {cast_jump!r}, {light_jump!r}")
        if (cast_jump > 0 or light_jump > 0) and normalize not in ("none", "still"):
            raise ValueError(f"cast_jump and light_jump work with normalize 'none' or 'still', not {normalize!r}")
        self.cast_jump, self.light_jump = float(cast_jump), float(light_jump)
        # cast_jump, light_jump: the jumps read since the start (or the last still view), their product in _cast_gain
        self._jumps = cast_undo(self.cast_jump, self.light_jump)
        self.level_gain = 1.0
        self.level_offset = 0.0
        self._ref_levels: np.ndarray | None = None
        self._still_ref: np.ndarray | None = None  # "still": the initialisation frame's lattice
        self._still_gain = np.ones(3)  # "still": the last gain measured on a still view
        if color_space not in FEATURE_SPACES:
            raise ValueError(f"unknown colour space {color_space!r}")
        if fallback not in DEFAULT_BINS:
            raise ValueError(f"unknown fallback colour space {fallback!r}")
        if kernel not in KERNELS:
            raise ValueError(f"unknown kernel {kernel!r}")
        gb = tuple(int(b) for b in gray_bins)
        if len(gb) != 2 or not (1 <= gb[0] <= 256 and 1 <= gb[1] <= 64):
            raise ValueError(f"gray_bins must be (intensity 1-256, orientation 1-64), got {gray_bins!r}")
        self.requested = color_space
        self.fallback = fallback
        self.user_bins = bins
        self.gray_bins = gb
        self.gradient_threshold = float(gradient_threshold)
        self.kernel = kernel
        self.max_pixels = int(max_pixels)
        self._eq_lut = np.arange(256, dtype=np.uint8)
        self._set_space(fallback if color_space == "auto" else color_space)

    def adapt_to(self, frame: np.ndarray, *, levels: bool = True) -> str:
        """Choose the features from the input (``"auto"``): grey features on a grey frame.

        Called by the trackers on their initialisation frame; returns the space in use. With ``levels=False`` the
        RGB bins stay over 0-255 whatever ``dark_stretch`` (a histogram given by the caller is of the frames as
        they are).
        """
        if self.requested == "auto":
            self._set_space("gray" if is_gray(frame) else self.fallback)
        if self.color_space == "rgb" and (self.dark_stretch > 0 or self.haze_stretch > 0 or self.level_gain != 1.0):
            self._fit_levels(frame if levels else None)
        if self.color_space == "rgb" and self.normalize in ("gain", "adaptive") and frame.ndim == 3:
            self._ref_levels = channel_levels(frame)
        ok = self.color_space == "rgb" and frame.ndim == 3 and frame.dtype == np.uint8
        if self.normalize == "still":
            self._still_ref = reference_lattice(frame) if ok else None
            self._still_gain = np.ones(3)
            self.lut = self._base_lut
        if self._jumps is not None:
            self._jumps.reset(frame if ok else None)
            if self.normalize == "none" and self.color_space == "rgb":
                self.lut = self._base_lut
        return self.color_space

    def new_frame(self, frame: np.ndarray, *, gray: np.ndarray | None = None) -> None:
        """Per-frame preparation (cheap, from a subsampled frame): the equalisation table of the grey
        features, or the lighting normalisation of the RGB bins (``gray``: the frame's grey image, if at hand)."""
        if self.color_space == "gray":
            self._eq_lut = equalization_lut(frame, gray=gray)
        elif self.color_space == "rgb" and frame.ndim == 3 and (self.normalize != "none" or self._jumps is not None):
            jumped = self._jumps is not None and frame.dtype == np.uint8 and self._jumps.read(frame)
            if self.normalize == "none":
                if jumped:
                    self._gain_lut(self._cast_gain)
                return
            if self.normalize == "still":
                # the lattice the jump reader copied from this frame (hot, contiguous): the same levels
                lattice = self._jumps.reader.lattice if self._jumps is not None and frame.dtype == np.uint8 else None
                g = None if self._still_ref is None else (still_gain(self._still_ref, frame) if lattice is None
                                                          else still_gain(self._still_ref, lattice, stride=1))
                if g is not None:  # a still view: its gain against the first frame holds every jump before it
                    if not np.array_equal(g, self._still_gain) or not np.all(self._cast_gain == 1.0):
                        self._still_gain = g
                        if self._jumps is not None and not np.all(self._jumps.gain == 1.0):
                            self._jumps.reset(frame)  # the still gain holds every jump before this frame
                        self._gain_lut(g)  # else the table in use stays
                elif jumped:
                    self._gain_lut(self._still_gain * self._cast_gain)
                return
            if self.normalize in ("gain", "adaptive"):
                self._levels = channel_levels(frame)
                if self._ref_levels is None:
                    self._ref_levels = self._levels.copy()
                gains = self._ref_levels / self._levels
                if self.normalize == "adaptive" and np.all(np.abs(gains - 1.0) < GAIN_DEAD_ZONE):
                    self.lut = self._base_lut  # within the dead zone: raw colours (no jitter from the medians)
                    return
                self.lut = self.mapped_lut(gain_maps(self._ref_levels, self._levels))
            else:
                self.lut = self.mapped_lut(channel_equalization_maps(frame))

    def _gain_lut(self, g: np.ndarray) -> None:
        """The RGB table that undoes a per-channel gain ``g`` of the frame (none within the dead zone)."""
        self.lut = (self._base_lut if np.all(np.abs(g - 1.0) < GAIN_DEAD_ZONE)
                    else self.mapped_lut(gain_maps(np.ones(3), g)))

    @property
    def _cast_gain(self) -> np.ndarray:
        """``cast_jump``: the product of the jumps read since the start or the last still view (1 without)."""
        return np.ones(3) if self._jumps is None else self._jumps.gain

    def _fit_levels(self, frame: np.ndarray | None) -> None:
        """``dark_stretch`` and ``haze_stretch``: the RGB bins over the levels ``frame`` uses when it is dark or hazy
        enough, else (or with no frame) over 0-255."""
        lut = make_lut("rgb", self.bins)
        colour = frame is not None and frame.ndim == 3
        g = level_gain(frame, percentile=self.dark_percentile) if colour and self.dark_stretch > 0 else 1.0
        self.level_gain = g if g >= self.dark_stretch else 1.0
        self.level_offset = 0.0
        if self.level_gain == 1.0 and colour and self.haze_stretch > 0:
            g, lo = level_range(frame, percentile=self.dark_percentile)
            if g >= self.haze_stretch:
                self.level_gain, self.level_offset = g, lo
        if self.level_gain != 1.0:
            lut = stretched_lut(lut, self.level_gain, self.level_offset)
        self.lut = self._base_lut = lut
        self._shifts = shift_form(lut)

    def mapped_lut(self, maps: np.ndarray) -> np.ndarray:
        """The RGB quantisation table after per-channel value maps ``(3, 256)`` (bin = base_lut[c][map_c[v]]),
        for example :func:`~pftrack.cues.intensity.gain_maps` to undo a lighting change."""
        return np.ascontiguousarray(np.take_along_axis(self._base_lut, np.asarray(maps).astype(np.intp), axis=1))

    def confirm(self, rate: float) -> None:
        """The tracker is confident on this frame: move the ``"adaptive"`` reference towards its levels."""
        if self.normalize == "adaptive" and self._ref_levels is not None and getattr(self, "_levels", None) is not None:
            self._ref_levels += rate * (self._levels - self._ref_levels)

    def _set_space(self, space: str) -> None:
        self.color_space = space
        if space == "gray":
            ni, no = self.gray_bins
            self.bins = (ni, no + 1, 1)
            self.lut = None
        else:
            self.bins = tuple(int(b) for b in (self.user_bins or DEFAULT_BINS[space]))
            if len(self.bins) != 3 or min(self.bins) < 1 or max(self.bins) > 256:
                raise ValueError(f"bins must be 3 integers in [1, 256], got {self.user_bins!r}")
            self.lut = make_lut(space, self.bins)
        self._base_lut = self.lut
        self._shifts = shift_form(self.lut) if space == "rgb" else None
        self.feature_bins = int(np.prod(self.bins))  # the bins a pixel's features take
        self.n_bins = self.feature_bins * self.parts  # a histogram's bins (parts of feature_bins each)
        self._qbuf = np.empty(0, dtype=np.uint16)
        self._cbuf = np.empty((0, 0), dtype=np.uint16)  # prepare_cells' lattice of the whole frame
        self._hbuf = np.empty((0, self.n_bins))
        self._tbuf = np.empty(0)
        self._rbuf = np.empty(0)
        self._rtot = np.empty(0)
        self._scratch = np.zeros((2, self.n_bins))

    # -- features -----------------------------------------------------------------
    def prepare(self, frame: np.ndarray, roi: tuple[int, int, int, int], pitch: int = 1, *,
                lut: np.ndarray | None = None) -> ColorFeatures:
        """Quantise the region ``roi = (x0, y0, x1, y1)`` of a BGR frame once.

        With ``pitch > 1`` only the lattice ``x % pitch == y % pitch == 0`` is quantised
        (see :meth:`step_for`), which divides the work by ``pitch**2``.  With ``lut`` (RGB features only,
        e.g. :meth:`mapped_lut`) the region is quantised with that table into a new array, leaving the
        frame's features (the shared buffer) untouched.
        """
        x0, y0, x1, y1 = roi
        pitch = max(int(pitch), 1)
        x0 -= x0 % pitch
        y0 -= y0 % pitch
        if lut is not None:
            if self.color_space != "rgb":
                raise ValueError("a quantisation table applies to RGB features only")
            region = frame[y0:y1:pitch, x0:x1:pitch]
            bins = np.empty(region.shape[:2], dtype=np.uint16)
            if region.size:
                quantize(np.ascontiguousarray(region), lut, bins)
            return ColorFeatures(bins, x0, y0, pitch)
        if self.color_space == "gray":
            h, w = len(range(y0, min(y1, frame.shape[0]), pitch)), len(range(x0, min(x1, frame.shape[1]), pitch))
            if self._qbuf.size < h * w:
                self._qbuf = np.empty(h * w, dtype=np.uint16)
            out = self._qbuf[: h * w].reshape(h, w)
            if h and w:
                ni, no = self.gray_bins
                quantize_gray(frame, (x0, y0, x1, y1), pitch, self._eq_lut, n_intensity=ni, n_orientation=no,
                              gradient_threshold=self.gradient_threshold, out=out)
            return ColorFeatures(out, x0, y0, pitch)
        region = frame[y0:y1:pitch, x0:x1:pitch]
        if self.color_space == "hsv" and region.size:
            region = cv2.cvtColor(bgr_view(region), cv2.COLOR_BGR2HSV)
        h, w = region.shape[:2]
        if self._qbuf.size < h * w:
            self._qbuf = np.empty(h * w, dtype=np.uint16)
        out = self._qbuf[: h * w].reshape(h, w)  # contiguous: rows of the region are adjacent in memory
        if h and w:
            if pitch == 1 and self.color_space == "rgb" and self.lut is self._base_lut:
                quantize_region(frame, x0, y0, x1, y1, self.lut, out, self._shifts)
            else:
                quantize(region, self.lut, out)
        return ColorFeatures(out, x0, y0, pitch)

    def prepare_cells(self, frame: np.ndarray, pitch: int, ellipses: np.ndarray) -> ColorFeatures | None:
        """The whole frame's features (:meth:`prepare` of ``(0, 0, W, H)`` at ``pitch``) with only the lattice pixels
        that ``ellipses`` can read quantised: each ellipse's bounding box and two lattice pixels around it. The
        ellipses' coefficients (:meth:`rho`) are then those of the whole frame's features, at a cost that does not
        grow with the frame: the background statistics' ellipses of a small target cover a few per cent of a large
        frame. None where that saves nothing or does not apply (grey or HSV features, a frame other than 8-bit BGR,
        ellipses that cover half of the lattice or more): call :meth:`prepare` then."""
        if (self.color_space != "rgb" or frame.ndim != 3 or frame.shape[2] != 3 or frame.dtype != np.uint8
                or self.lut is None):
            return None
        p = max(int(pitch), 1)
        h, w = frame.shape[:2]
        rows, cols = -(-h // p), -(-w // p)
        e = np.asarray(ellipses, dtype=np.float64).reshape(-1, 4)
        if rows == 0 or cols == 0 or e.shape[0] == 0:
            return None
        cells = np.empty((e.shape[0], 4), np.int64)  # in lattice pixels; pixel k's centre lies at image k p + 0.5
        cells[:, 0] = np.floor((e[:, 1] - e[:, 3] - 0.5) / p) - 2
        cells[:, 1] = np.ceil((e[:, 1] + e[:, 3] - 0.5) / p) + 3
        cells[:, 2] = np.floor((e[:, 0] - e[:, 2] - 0.5) / p) - 2
        cells[:, 3] = np.ceil((e[:, 0] + e[:, 2] - 0.5) / p) + 3
        np.clip(cells[:, :2], 0, rows, out=cells[:, :2])
        np.clip(cells[:, 2:], 0, cols, out=cells[:, 2:])
        area = np.maximum(cells[:, 1] - cells[:, 0], 0) * np.maximum(cells[:, 3] - cells[:, 2], 0)
        if 2 * int(area.sum()) >= rows * cols:  # as much as the whole lattice (and the kernel would scan it all)
            return None
        if self._cbuf.shape != (rows, cols):
            self._cbuf = np.zeros((rows, cols), dtype=np.uint16)  # outside the cells: never read
        quantize_cells(frame, p, cells, self.lut, self._cbuf)
        return ColorFeatures(self._cbuf, 0, 0, p)

    def prepare_frame(self, frame: np.ndarray, pitch: int = 1) -> ColorFeatures:
        return self.prepare(frame, (0, 0, frame.shape[1], frame.shape[0]), pitch)

    # -- histograms ---------------------------------------------------------------
    def step_for(self, ellipses: np.ndarray) -> int:
        """Lattice pitch for a batch of ellipses: one for all, from their mean area and ``max_pixels``."""
        if self.max_pixels <= 0:
            return 1
        e = np.asarray(ellipses).reshape(-1, 4)
        a = e[:, 2] * e[:, 3]
        area = math.pi * float(a.sum() / a.size)  # np.mean's numbers without its dispatch
        return max(1, int(math.ceil(math.sqrt(area / self.max_pixels))))

    def histograms(self, features: ColorFeatures, ellipses: np.ndarray, *, reuse: bool = True
                   ) -> tuple[np.ndarray, np.ndarray]:
        """Histograms of a batch of ellipses; with ``reuse`` the returned arrays are
        internal buffers valid until the next call."""
        e = np.asarray(ellipses, dtype=np.float64).reshape(-1, 4)
        n = e.shape[0]
        if reuse:
            if self._hbuf.shape[0] < n:
                self._hbuf = np.empty((n, self.n_bins))
                self._tbuf = np.empty(n)
            out, tot = self._hbuf[:n], self._tbuf[:n]
        else:
            out, tot = np.empty((n, self.n_bins)), np.empty(n)
        e, ox, oy = features.to_lattice(e)
        return ellipse_histograms(features.bins, ox, oy, e, self.n_bins, kernel=self.kernel, out=out, totals=tot,
                                  parts=self.parts)

    def rho(self, features: ColorFeatures, ellipses: np.ndarray, sqrt_q: np.ndarray, *, reuse: bool = True
            ) -> tuple[np.ndarray, np.ndarray]:
        """Bhattacharyya coefficients with a model (given as ``sqrt(q)``) and kernel masses of a batch."""
        e = np.asarray(ellipses, dtype=np.float64).reshape(-1, 4)
        n = e.shape[0]
        if reuse:
            if self._rbuf.shape[0] < n:
                self._rbuf = np.empty(n)
                self._rtot = np.empty(n)
            out, tot = self._rbuf[:n], self._rtot[:n]
        else:
            out, tot = np.empty(n), np.empty(n)
        e, ox, oy = features.to_lattice(e)
        return ellipse_rho(features.bins, ox, oy, e, sqrt_q, kernel=self.kernel, out=out, totals=tot,
                           _scratch=self._scratch, parts=self.parts)

    def histogram(self, frame: np.ndarray, ellipse) -> np.ndarray:
        """Histogram of one ellipse in a frame (a new array)."""
        e = np.asarray(ellipse, dtype=np.float64).reshape(1, 4)
        roi = reachable_roi(e, frame.shape[1], frame.shape[0])
        feats = self.prepare(frame, roi, self.step_for(e))
        hist, _ = self.histograms(feats, e, reuse=False)
        return hist[0]
