"""Frames through a video encoder and back: what a recorder or a camera hands over instead of clean frames.

Benchmarks ship sequences as JPEG frames; users feed H.264 files. :func:`h264_round_trip` encodes frames with
libx264 in memory and decodes them again, so an experiment can measure a tracker on the artefacts of a real
encoder (blocking, smeared chroma, frames of uneven quality) with the dataset's ground truth unchanged.  It needs
PyAV (the ``mv`` extra, whose wheels bundle FFmpeg with libx264).
"""

from __future__ import annotations

import io

import numpy as np

from ..errors import ParameterError
from .motion_vectors import require_av

__all__ = ["h264_round_trip"]


def h264_round_trip(frames, crf: int, *, fps: float = 25.0, preset: str = "medium") -> list[np.ndarray]:
    """``frames`` (BGR or grey uint8 images of one size) encoded as H.264 (libx264, yuv420p, constant rate factor
    ``crf``: 0 best, 51 worst, 23 libx264's default) and decoded again, as BGR uint8 images of the same size.

    yuv420p needs an even width and height: an odd last row or column is padded by replication for the encoder and
    cropped off again.  The encoder is deterministic for the same frames and settings.
    """
    if not 0 <= int(crf) <= 51:
        raise ParameterError(f"crf must be in 0..51, got {crf}")
    frames = list(frames)
    if not frames:
        return []
    av = require_av()
    h, w = frames[0].shape[:2]
    ph, pw = h + (h & 1), w + (w & 1)
    buf = io.BytesIO()
    with av.open(buf, "w", format="mp4") as container:
        stream = container.add_stream("libx264", rate=max(1, int(round(fps))))
        stream.width, stream.height, stream.pix_fmt = pw, ph, "yuv420p"
        stream.options = {"crf": str(int(crf)), "preset": preset}
        for f in frames:
            f = np.asarray(f)
            if f.shape[:2] != (h, w):
                raise ParameterError(f"frames change size: {f.shape[1]}x{f.shape[0]} after {w}x{h}")
            if f.ndim == 2:
                f = np.repeat(f[:, :, None], 3, axis=2)
            if (ph, pw) != (h, w):
                f = np.pad(f, ((0, ph - h), (0, pw - w), (0, 0)), mode="edge")
            for packet in stream.encode(av.VideoFrame.from_ndarray(np.ascontiguousarray(f), format="bgr24")):
                container.mux(packet)
        for packet in stream.encode():
            container.mux(packet)
    buf.seek(0)
    with av.open(buf) as container:
        out = [fr.to_ndarray(format="bgr24")[:h, :w] for fr in container.decode(video=0)]
    return [np.ascontiguousarray(f) for f in out]
