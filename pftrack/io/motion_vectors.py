"""Compressed-domain motion vectors with PyAV (book ch. 8, ch08.md §1.2).

FFmpeg exports per-partition motion vectors of H.264 and MPEG-4 Part 2 streams when the decoder gets
``flags2=+export_mvs`` (side data ``MOTION_VECTORS``: ``source, w, h, src_x, src_y, dst_x, dst_y, flags,
motion_x, motion_y, motion_scale``; ``dst`` is the block centre, ``motion`` points from the current block to
its reference, in ``1/motion_scale`` pixels).  It exports no residuals; :func:`pseudo_residual` is the honest
substitute of ch08.md: ``R_f(x) = Y_f(x) - Y_{f-1}(x + mv(x))`` from the decoded luma.  It costs a full decode
(the chapter's "no pixel decoding" speed argument does not carry over) and differs from the coded residual by
the deblocking filter, the codec's sub-pixel interpolation, multiple references and the sub-8x8 vectors that
FFmpeg does not export; on encodes with full-pel vectors, no deblocking and one reference it is exact.

PyAV is an optional dependency (its wheels bundle FFmpeg; ``pip install 'pftrack[mv]'``); the rest of
pftrack imports without it.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from .._numba import njit, numba_enabled
from ..errors import ParameterError, SourceError
from . import streams
from .prefetch import default_depth, prefetch

BLOCK = 4


def require_av():
    try:
        import av
    except ImportError:
        raise ParameterError("motion-vector features need PyAV: pip install 'pftrack[mv]'") from None
    return av


@dataclass
class MVFrame:
    number: int                    # from 1
    pict_type: str                 # 'I', 'P', 'B', ...
    mvs: np.ndarray | None         # the structured side data (None on intra frames)
    y: np.ndarray                  # decoded luma (h, w) uint8
    bgr: np.ndarray | None = None
    analysis: object = None        # what MVSource.analyse returned for this frame (on the decoding thread)


def _luma(frame) -> np.ndarray:
    plane = frame.planes[0]
    h, w = frame.height, frame.width
    buf = np.frombuffer(plane, np.uint8)
    return buf.reshape(-1, plane.line_size)[:h, :w].copy()


def _luma_bgr(frame) -> tuple[np.ndarray, np.ndarray]:
    """Luma and BGR pixels of an even-sized yuv420p frame: the planes once, converted by OpenCV (BT.601, as
    FFmpeg's default scaler; within a grey level or two of it) in about a quarter of the scaler's time."""
    yuv = frame.to_ndarray()                                 # (3h/2, w): Y, then U and V
    return yuv[:frame.height], cv2.cvtColor(yuv, cv2.COLOR_YUV2BGR_I420)


def _pict_type(pt) -> str:
    name = getattr(pt, "name", None)
    if isinstance(name, str):
        return name[:1] if name else "?"
    return {1: "I", 2: "P", 3: "B"}.get(int(pt), "?") if isinstance(pt, (int, np.integer)) else str(pt)[:1]


def iter_mv_frames(path, *, bgr: bool = False, threads: bool = False) -> Iterator[MVFrame]:
    """Decode ``path`` and yield every frame's motion vectors and luma (and BGR pixels if asked)."""
    av = require_av()
    url = streams.is_url(str(path))
    if not url and not Path(str(path)).is_file():
        raise SourceError(f"{path}: no such file")
    where = streams.redact(str(path)) if url else path
    try:
        container = _open(av, str(path), url)
    except Exception as exc:  # noqa: BLE001 - PyAV raises many FFmpeg error classes
        raise SourceError(f"{where}: cannot open as a video ({str(exc).splitlines()[0][:120]})") from None
    try:
        if not container.streams.video:
            raise SourceError(f"{where}: has no video stream")
        stream = container.streams.video[0]
        stream.codec_context.options = {"flags2": "+export_mvs"}
        if threads:
            stream.thread_type = "AUTO"
        for n, frame in enumerate(_frames_of(container, stream, url, av), start=1):
            sd = frame.side_data.get("MOTION_VECTORS") if hasattr(frame.side_data, "get") else None
            mvs = sd.to_ndarray() if sd is not None else None
            if bgr and frame.format.name == "yuv420p" and frame.width % 2 == 0 and frame.height % 2 == 0:
                y, pix = _luma_bgr(frame)
            else:
                y, pix = _luma(frame), (frame.to_ndarray(format="bgr24") if bgr else None)
            yield MVFrame(n, _pict_type(frame.pict_type), mvs, y, pix)
    finally:
        container.close()


def _open(av, name: str, url: bool):
    """PyAV's container of a video file, or of a stream URL with :func:`pftrack.io.streams.av_open`'s options."""
    return streams.av_open(name) if url else av.open(name)


def _frames_of(container, stream, url: bool, av):
    """The decoded frames of ``stream``; a stream URL's feed that breaks off (a server that closes the connection,
    a camera that stops) ends them, as OpenCV's reader ends, where a file's read error is raised."""
    frames = container.decode(stream)
    while True:
        try:
            frame = next(frames)
        except StopIteration:
            return
        except (OSError, av.error.FFmpegError):
            if not url:
                raise
            try:  # the frames the decoder still holds
                yield from stream.decode(None)
            except (OSError, av.error.FFmpegError):
                pass
            return
        yield frame


class MVSource:
    """A frame source over a compressed video that also keeps each frame's motion vectors in ``current``
    (for the ``mv`` detector); the same interface as :class:`pftrack.io.sources.FrameSource`."""

    kind = "compressed video"

    def __init__(self, path):
        av = require_av()
        self.name = str(path)
        url = streams.is_url(self.name)
        if not url and not Path(self.name).is_file():
            what = "is a folder" if Path(self.name).is_dir() else "no such file"
            raise SourceError(f"{path}: {what} (motion vectors need a compressed video file)")
        where = streams.redact(self.name) if url else path
        try:
            with _open(av, self.name, url) as c:
                if not c.streams.video:
                    raise SourceError(f"{where}: has no video stream")
                st = c.streams.video[0]
                self.fps = float(st.average_rate) if st.average_rate else None
                self._len = st.frames or None
                codec = st.codec_context.name
        except SourceError:
            raise
        except Exception as exc:  # noqa: BLE001
            raise SourceError(f"{where}: cannot open as a video ({str(exc).splitlines()[0][:120]})") from None
        if codec not in ("h264", "mpeg4", "h263", "mpeg2video", "mpeg1video", "hevc"):
            raise SourceError(f"{where}: codec {codec} exports no motion vectors (use H.264 or MPEG-4 Part 2)")
        # a live stream (rtsp://, ...; or a URL without a frame count) is opened again to be decoded: its first
        # frames pass meanwhile
        self.live = url and (streams.is_live(self.name) or self._len is None)
        if self.live:
            self._len = None
        self.current: MVFrame | None = None
        self.prefetch = default_depth()  # frames decoded ahead on a second thread (0, the default on one CPU:
        # decode in the caller's thread)
        # an optional per-frame analysis run where the frames are decoded (with prefetch, on the second thread),
        # its result kept in each frame's ``analysis``: the mv detector's groups are found there
        self.analyse = None
        self.size = None
        self.sequence = None
        self.skipped: list[int] = []

    def __len__(self) -> int:
        if self._len is None:
            raise TypeError("unknown length")
        return self._len

    @property
    def length(self):
        return self._len

    def _analysed(self, frames):
        for f in frames:
            f.analysis = self.analyse(f)
            yield f

    def numbered(self):
        frames = iter_mv_frames(self.name, bgr=True, threads=True)
        if self.analyse is not None:      # on the decoding thread, ahead of the caller, frame by frame in order
            frames = self._analysed(frames)
        for f in prefetch(frames, depth=self.prefetch):
            self.current = f
            if self.size is None:
                self.size = (f.y.shape[1], f.y.shape[0])
            yield f.number, f.bgr

    def __iter__(self):
        for _, frame in self.numbered():
            yield frame

    def close(self) -> None:
        pass


def mv_field(mvs: np.ndarray | None, shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """Paint every exported partition onto the 4x4-block grid of a frame of ``shape`` (h, w).

    Returns ``(fwd, has)``: ``fwd`` (I, J, 2) the forward displacement in pixels of each block
    (``-motion/scale``: the object's motion from the reference to the current frame), ``has`` (I, J) True where
    a past-referencing vector covers the block.  Intra blocks (no vector) stay False."""
    h, w = shape
    I, J = (h + BLOCK - 1) // BLOCK, (w + BLOCK - 1) // BLOCK
    fwd = np.zeros((I, J, 2), np.float32)
    has = np.zeros((I, J), bool)
    if mvs is None or len(mvs) == 0:
        return fwd, has
    if numba_enabled() and _RECORD_FIELDS <= set(mvs.dtype.names):
        _paint_records(mvs, fwd, has)
        return fwd, has
    m = mvs[mvs["source"] < 0] if "source" in mvs.dtype.names else mvs
    scale = np.maximum(m["motion_scale"].astype(np.float32), 1)
    vx = -m["motion_x"].astype(np.float32) / scale
    vy = -m["motion_y"].astype(np.float32) / scale
    x0 = (m["dst_x"].astype(np.int64) - m["w"].astype(np.int64) // 2) // BLOCK
    y0 = (m["dst_y"].astype(np.int64) - m["h"].astype(np.int64) // 2) // BLOCK
    bw = np.maximum(m["w"].astype(np.int64) // BLOCK, 1)
    bh = np.maximum(m["h"].astype(np.int64) // BLOCK, 1)
    for k in np.unique(np.stack([bw, bh], 1), axis=0):     # vectorised per partition size
        sel = (bw == k[0]) & (bh == k[1])
        dy, dx = np.meshgrid(np.arange(k[1]), np.arange(k[0]), indexing="ij")
        yy = (y0[sel, None] + dy.ravel()[None]).ravel()
        xx = (x0[sel, None] + dx.ravel()[None]).ravel()
        ok = (yy >= 0) & (yy < I) & (xx >= 0) & (xx < J)
        rep = int(k[0] * k[1])
        fwd[yy[ok], xx[ok], 0] = np.repeat(vx[sel], rep)[ok]
        fwd[yy[ok], xx[ok], 1] = np.repeat(vy[sel], rep)[ok]
        has[yy[ok], xx[ok]] = True
    return fwd, has


_RECORD_FIELDS = {"source", "w", "h", "dst_x", "dst_y", "motion_x", "motion_y", "motion_scale"}


@njit(cache=True)
def _paint_records(mvs, fwd, has):
    """:func:`mv_field` in one compiled pass over FFmpeg's records: the past-referencing partitions painted
    in the same order (by width, then height in blocks, then as exported), with the same float32 vectors."""
    I, J = has.shape
    n = mvs.shape[0]
    bws = np.empty(n, np.int64)
    bhs = np.empty(n, np.int64)
    mw = mh = 1
    for t in range(n):
        bws[t] = max(np.int64(mvs[t].w) // 4, 1)
        bhs[t] = max(np.int64(mvs[t].h) // 4, 1)
        mw, mh = max(mw, bws[t]), max(mh, bhs[t])
    count = np.zeros((mw + 1, mh + 1), np.int64)
    for t in range(n):
        count[bws[t], bhs[t]] += 1
    for cw in range(1, mw + 1):
        for ch in range(1, mh + 1):
            if count[cw, ch] == 0:
                continue
            for t in range(n):
                r = mvs[t]
                if bws[t] != cw or bhs[t] != ch or r.source >= 0:
                    continue
                sc = np.float32(max(np.int64(r.motion_scale), 1))
                vx = -np.float32(r.motion_x) / sc
                vy = -np.float32(r.motion_y) / sc
                x0 = (np.int64(r.dst_x) - np.int64(r.w) // 2) // 4
                y0 = (np.int64(r.dst_y) - np.int64(r.h) // 2) // 4
                for dy in range(ch):
                    yy = y0 + dy
                    if yy < 0 or yy >= I:
                        continue
                    for dx in range(cw):
                        xx = x0 + dx
                        if 0 <= xx < J:
                            fwd[yy, xx, 0] = vx
                            fwd[yy, xx, 1] = vy
                            has[yy, xx] = True


def pseudo_residual(y_cur: np.ndarray, y_prev: np.ndarray, fwd: np.ndarray) -> np.ndarray:
    """``R_f(x) = Y_f(x) - Y_{f-1}(x - fwd(x))`` (bilinear), per pixel, float32."""
    h, w = y_cur.shape
    disp = np.repeat(np.repeat(fwd, BLOCK, axis=0), BLOCK, axis=1)[:h, :w]
    xs, ys = np.meshgrid(np.arange(w, dtype=np.float32), np.arange(h, dtype=np.float32))
    ref = cv2.remap(y_prev, xs - disp[..., 0], ys - disp[..., 1], cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    return y_cur.astype(np.float32) - ref.astype(np.float32)


def block_energy(R: np.ndarray) -> np.ndarray:
    """``sum R^2`` per 4x4 block (partial blocks at the border padded with zeros)."""
    h, w = R.shape
    I, J = (h + BLOCK - 1) // BLOCK, (w + BLOCK - 1) // BLOCK
    P = np.zeros((I * BLOCK, J * BLOCK), np.float64)
    P[:h, :w] = R.astype(np.float64) ** 2
    return P.reshape(I, BLOCK, J, BLOCK).sum(axis=(1, 3))


def block_energy_at(y_cur: np.ndarray, y_prev: np.ndarray, fwd: np.ndarray, blocks: np.ndarray) -> np.ndarray:
    """:func:`block_energy` of the pseudo-residual, computed only for the blocks in the (I, J) mask ``blocks``
    (the others are 0): only blocks with motion can be foreground, so this is all the detector needs."""
    I, J = blocks.shape
    E = np.zeros((I, J), np.float64)
    bi, bj = np.nonzero(blocks)
    if len(bi) == 0:
        return E
    if numba_enabled() and BLOCK == 4:
        _block_energy(np.ascontiguousarray(y_cur), np.ascontiguousarray(y_prev), fwd, bi, bj, E)
        return E
    h, w = y_cur.shape
    oy, ox = np.meshgrid(np.arange(BLOCK), np.arange(BLOCK), indexing="ij")
    ys = (bi[:, None] * BLOCK + oy.ravel()[None]).clip(0, h - 1)
    xs = (bj[:, None] * BLOCK + ox.ravel()[None]).clip(0, w - 1)
    cur = y_cur[ys, xs].astype(np.float64)
    px = np.clip(xs - fwd[bi, bj, 0][:, None], 0, w - 1)
    py = np.clip(ys - fwd[bi, bj, 1][:, None], 0, h - 1)
    x0 = np.minimum(np.floor(px).astype(np.int64), w - 2)
    y0 = np.minimum(np.floor(py).astype(np.int64), h - 2)
    tx, ty = px - x0, py - y0
    yp = y_prev.astype(np.float64)
    ref = ((1 - ty) * ((1 - tx) * yp[y0, x0] + tx * yp[y0, x0 + 1])
           + ty * ((1 - tx) * yp[y0 + 1, x0] + tx * yp[y0 + 1, x0 + 1]))
    E[bi, bj] = np.sum((cur - ref) ** 2, axis=1)
    return E


@njit(cache=True)
def _block_energy(y_cur, y_prev, fwd, bi, bj, E):
    """The compiled :func:`block_energy_at` for 4x4 blocks: the same float64 operations, and the 16 squares
    summed in NumPy's pairwise order (eight strided partial sums, then a tree), so the energies are equal bit
    for bit."""
    h, w = y_cur.shape
    sq = np.empty(16)
    for t in range(bi.shape[0]):
        i = bi[t]
        j = bj[t]
        fx = np.float64(fwd[i, j, 0])
        fy = np.float64(fwd[i, j, 1])
        for oy in range(4):
            ys = min(max(i * 4 + oy, 0), h - 1)
            py = min(max(ys - fy, 0.0), h - 1.0)
            y0 = min(int(np.floor(py)), h - 2)
            ty = py - y0
            for ox in range(4):
                xs = min(max(j * 4 + ox, 0), w - 1)
                px = min(max(xs - fx, 0.0), w - 1.0)
                x0 = min(int(np.floor(px)), w - 2)
                tx = px - x0
                a = np.float64(y_prev[y0, x0])
                b = np.float64(y_prev[y0, x0 + 1])
                c = np.float64(y_prev[y0 + 1, x0])
                d = np.float64(y_prev[y0 + 1, x0 + 1])
                ref = (1 - ty) * ((1 - tx) * a + tx * b) + ty * ((1 - tx) * c + tx * d)
                diff = np.float64(y_cur[ys, xs]) - ref
                sq[oy * 4 + ox] = diff * diff
        r0 = sq[0] + sq[8]
        r1 = sq[1] + sq[9]
        r2 = sq[2] + sq[10]
        r3 = sq[3] + sq[11]
        r4 = sq[4] + sq[12]
        r5 = sq[5] + sq[13]
        r6 = sq[6] + sq[14]
        r7 = sq[7] + sq[15]
        E[i, j] = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))


def encode_h264(frames, path, *, fps: float = 25.0, crf: int | None = 23, qp: int | None = None,
                x264_params: str = "bframes=0:ref=1:weightp=0:keyint=1000", exact: bool = False) -> Path:
    """Encode BGR frames with libx264 (baseline-like: no B-frames, one reference).  ``exact`` adds the
    settings that make :func:`pseudo_residual` exact (full-pel vectors, no deblocking, no sub-8x8 partitions)."""
    av = require_av()
    if "libx264" not in av.codecs_available:
        raise ParameterError("this PyAV build has no libx264 encoder")
    path = Path(path)
    out = av.open(str(path), "w")
    try:
        it = iter(frames)
        first = next(it)
        s = out.add_stream("libx264", rate=round(fps))
        s.height, s.width = first.shape[:2]
        s.pix_fmt = "yuv420p"
        params = x264_params + (":subme=0:no-deblock=1:partitions=p8x8:me=esa:merange=16" if exact else "")
        opts = {"x264-params": params}
        if qp is not None:
            opts["qp"] = str(qp)
        elif crf is not None:
            opts["crf"] = str(crf)
        s.options = opts
        for img in [first, *it]:
            for pkt in s.encode(av.VideoFrame.from_ndarray(np.ascontiguousarray(img), format="bgr24")):
                out.mux(pkt)
        for pkt in s.encode():
            out.mux(pkt)
    finally:
        out.close()
    return path
