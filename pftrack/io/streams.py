"""Network stream URLs as frame sources: which strings are URLs, which are live, and how to print them.

OpenCV's FFmpeg back end reads ``rtsp://``, ``rtmp://``, ``http(s)://``, ``udp://``, ``tcp://``, ``srt://`` and
``file:`` URLs; :func:`pftrack.io.sources.open_source` hands every string that :func:`is_url` accepts to it
unchanged. A stream is *live* when its protocol carries a live feed (:data:`LIVE_SCHEMES`: an IP camera, a
broadcast) or when FFmpeg reports no frame count (an HTTP MJPEG camera, an HLS playlist); a video file served over
HTTP keeps its length and is read like a file.

>>> is_url("rtsp://user:secret@10.0.0.7:554/stream1"), is_url("clip.mp4"), is_url("C:/clips/a.mp4")
(True, False, False)
>>> redact("rtsp://user:secret@10.0.0.7:554/stream1")
'rtsp://user:***@10.0.0.7:554/stream1'
"""

from __future__ import annotations

import re

#: protocols that carry a live feed: read in the caller's thread, no length, not read twice
LIVE_SCHEMES = frozenset({"rtsp", "rtsps", "rtmp", "rtmps", "rtp", "srt", "udp", "tcp", "mms", "mmsh", "rist"})
#: protocols whose URL may name a file (read as a file when FFmpeg reports its frame count)
FILE_SCHEMES = frozenset({"http", "https", "ftp", "file"})

#: the first wait before a broken-off live stream is opened again (``reconnect``); each further try waits twice as
#: long, up to 8 times this
RECONNECT_WAIT_S = 1.0
#: seconds a stream may take to open, and to deliver a frame, before it counts as unreachable or ended
TIMEOUT_S = 15.0

_URL = re.compile(r"^(?P<scheme>[A-Za-z][A-Za-z0-9+.-]*):(?P<rest>.*)$", re.S)


def scheme(spec: str) -> str | None:
    """The URL's protocol in lower case, or None when ``spec`` is not a URL of a known protocol. A Windows path
    (``C:/...``, a one-letter "scheme") is not a URL."""
    m = _URL.match(spec.strip())
    if m is None:
        return None
    name = m.group("scheme").lower()
    if name not in LIVE_SCHEMES | FILE_SCHEMES:
        return None
    if name != "file" and not m.group("rest").startswith("//"):
        return None
    return name


def is_url(spec: str) -> bool:
    """Is ``spec`` a stream URL (``rtsp://...``, ``http://...``, ``file:...``)?"""
    return scheme(spec) is not None


def is_live(spec: str) -> bool:
    """Does ``spec``'s protocol carry a live feed (:data:`LIVE_SCHEMES`)?"""
    return scheme(spec) in LIVE_SCHEMES


def redact(spec: str) -> str:
    """``spec`` with the password of its ``user:password@`` part replaced by ``***`` (for messages and names). The
    user information runs to the authority's last ``@``, as FFmpeg reads it, so a password with an ``@`` of its own
    is hidden whole."""
    spec = spec.strip()
    m = re.match(r"^([A-Za-z][A-Za-z0-9+.-]*://)([^/?#]*)(.*)$", spec, re.S)
    if m is None or "@" not in m.group(2):
        return spec
    userinfo, host = m.group(2).rsplit("@", 1)
    if ":" not in userinfo:
        return spec
    return f"{m.group(1)}{userinfo.split(':', 1)[0]}:***@{host}{m.group(3)}"


def av_open(spec: str):
    """``av.open`` of the stream URL ``spec`` with :data:`TIMEOUT_S`, RTSP over TCP as OpenCV's reader asks for it."""
    import av

    options = {"rtsp_transport": "tcp"} if scheme(spec) in ("rtsp", "rtsps") else {}
    return av.open(spec, timeout=TIMEOUT_S, options=options)


def open_capture(spec: str):
    """``cv2.VideoCapture`` of the stream URL ``spec`` through FFmpeg, with :data:`TIMEOUT_S` to open and to read."""
    import cv2

    ms = int(TIMEOUT_S * 1000)
    timeouts = [cv2.CAP_PROP_OPEN_TIMEOUT_MSEC, ms, cv2.CAP_PROP_READ_TIMEOUT_MSEC, ms]
    return cv2.VideoCapture(spec, cv2.CAP_FFMPEG, timeouts)


def wait_before_reconnect(attempt: int) -> None:
    """Sleep before the ``attempt``-th (from 0) try to open a broken-off stream again."""
    import time

    time.sleep(RECONNECT_WAIT_S * min(2 ** attempt, 8))
