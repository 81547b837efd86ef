"""Network streams as sources: a video served over HTTP reads as the file, a live feed (no frame count) is read
once in the caller's thread, and an unreachable stream is one line and exit code 2. The streams are served from
this machine (127.0.0.1) by a small HTTP server in the test."""

from __future__ import annotations

import http.server
import re
import socket
import threading
from pathlib import Path

import numpy as np
import pytest

from pftrack.cli import main
from pftrack.errors import SourceError
from pftrack.io import open_source
from pftrack.io import streams

CLIP = Path(__file__).resolve().parents[1] / "pftrack" / "data" / "crossing" / "crossing.mp4"


class _Server:
    """Serves ``files`` (name -> bytes) at ``http://127.0.0.1:PORT/NAME``: with byte ranges and a length (a file
    over HTTP), or, for names ending in ``.ts``, as an endless-looking feed (no length, no ranges: a live stream)."""

    def __init__(self, files: dict[str, bytes | list[bytes]]):
        served = {k: list(v) if isinstance(v, list) else v for k, v in files.items()}

        class Handler(http.server.BaseHTTPRequestHandler):
            protocol_version = "HTTP/1.1"

            def log_message(self, *args):
                pass

            def do_GET(self):
                data = served.get(self.path.lstrip("/"))
                if isinstance(data, list):  # one payload a connection, in turn, then nothing
                    data = data.pop(0) if data else None
                if data is None:
                    self.send_error(404)
                    return
                live = self.path.endswith(".ts")
                m = None if live else re.match(r"bytes=(\d+)-(\d*)", self.headers.get("Range", ""))
                a = int(m.group(1)) if m else 0
                b = int(m.group(2)) if m and m.group(2) else len(data) - 1
                self.send_response(206 if m else 200)
                self.send_header("Connection", "close")
                if not live:
                    self.send_header("Accept-Ranges", "bytes")
                    self.send_header("Content-Length", str(b - a + 1))
                    if m:
                        self.send_header("Content-Range", f"bytes {a}-{b}/{len(data)}")
                self.end_headers()
                try:
                    for k in range(a, b + 1, 4096):
                        self.wfile.write(data[k:min(k + 4096, b + 1)])
                except OSError:  # the reader seeks elsewhere or stops
                    pass

        self.server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        self.server.daemon_threads = True
        threading.Thread(target=self.server.serve_forever, kwargs={"poll_interval": 0.05}, daemon=True).start()

    def url(self, name: str, auth: str = "") -> str:
        return f"http://{auth}127.0.0.1:{self.server.server_address[1]}/{name}"

    def close(self) -> None:
        self.server.shutdown()
        self.server.server_close()


@pytest.fixture(scope="module")
def live_clip(tmp_path_factory):
    """A 40-frame H.264 MPEG-TS clip of a box moving right (file path), encoded once."""
    from pftrack.io.motion_vectors import encode_h264

    frames = []
    for i in range(40):
        f = np.full((96, 128, 3), 90, np.uint8)
        f[30:60, 10 + 2 * i:40 + 2 * i] = (40, 180, 220)
        frames.append(f)
    return encode_h264(frames, tmp_path_factory.mktemp("live") / "clip.ts", fps=25)


@pytest.fixture(scope="module")
def two_feeds(tmp_path_factory):
    """Two 20-frame MPEG-TS clips of the same size (each starting with a key frame): a feed and its second
    connection."""
    from pftrack.io.motion_vectors import encode_h264

    folder = tmp_path_factory.mktemp("feeds")
    out = []
    for part in range(2):
        frames = []
        for i in range(20):
            f = np.full((96, 128, 3), 60 + 40 * part, np.uint8)
            f[30:60, 10 + 3 * i:40 + 3 * i] = (40, 180, 220)
            frames.append(f)
        out.append(encode_h264(frames, folder / f"part{part}.ts", fps=25).read_bytes())
    return out


@pytest.fixture
def server(live_clip):
    s = _Server({"crossing.mp4": CLIP.read_bytes(), "clip.ts": live_clip.read_bytes()})
    yield s
    s.close()


def _closed_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_stream_urls_are_told_from_paths():
    assert [streams.scheme(s) for s in ("rtsp://cam/1", "HTTP://x/a.mp4", "file:/videos/a.mp4", "srt://h:9000",
                                        "udp://@:1234")] == ["rtsp", "http", "file", "srt", "udp"]
    # paths, Windows drives and unknown or malformed schemes are not URLs
    for spec in ("clip.mp4", "C:/clips/a.mp4", "c:\\clips\\a.mp4", "rtsp:cam", "foo://x", "0", "data/http://x"):
        assert not streams.is_url(spec), spec
    assert streams.is_live("rtsp://cam/1") and streams.is_live("udp://@:1234")
    assert not streams.is_live("https://x/a.mp4") and not streams.is_live("file:/a.mp4")
    assert streams.redact("rtsp://admin:s3cr@t@10.0.0.7/s") == "rtsp://admin:***@10.0.0.7/s"  # FFmpeg: the last @
    assert streams.redact("rtsp://u:p@[::1]:554/a?x=1&y=u:v@w") == "rtsp://u:***@[::1]:554/a?x=1&y=u:v@w"
    assert streams.redact("rtsp://admin@10.0.0.7/s") == "rtsp://admin@10.0.0.7/s"
    assert streams.redact("rtsp://10.0.0.7/user:pw@x") == "rtsp://10.0.0.7/user:pw@x"  # not the userinfo part


def test_a_video_served_over_http_reads_as_the_file(server):
    url = server.url("crossing.mp4", auth="user:secret@")
    src = open_source(url)
    assert not src.live and src.length == 120 and src.fps == pytest.approx(25.0)
    assert "secret" not in src.name and src.name.startswith("http://user:***@")
    got = [f for _, f in src.numbered()]
    want = [f for _, f in open_source(CLIP).numbered()]
    assert len(got) == len(want) == 120
    assert all(np.array_equal(a, b) for a, b in zip(got, want))
    with pytest.raises(SourceError, match="a stream has neither"):
        open_source(url, target=1)


def test_track_reads_a_video_over_http_as_the_file(server, tmp_path, capsys):
    box = ",".join((CLIP.parent / "groundtruth_rect.txt").read_text().split()[:4])
    rows = []
    for spec, name in ((str(CLIP), "file.csv"), (server.url("crossing.mp4"), "url.csv")):
        assert main(["track", spec, "--box", box, "--tracker", "color-pf", "--seed", "3", "--quiet",
                     "--out", str(tmp_path / name)]) == 0
        rows.append((tmp_path / name).read_text())
    assert rows[0] == rows[1] and len(rows[0].splitlines()) == 121


def test_a_live_feed_is_read_once_in_the_callers_thread(server, live_clip):
    src = open_source(server.url("clip.ts"))
    assert src.live and src.length is None and src.prefetch == 0
    with pytest.raises(TypeError, match="live source"):
        len(src)
    got = [f for _, f in src.numbered()]
    want = [f for _, f in open_source(live_clip).numbered()]
    assert len(got) == len(want) == 40 and all(np.array_equal(a, b) for a, b in zip(got, want))
    assert not open_source(live_clip).live  # the same clip as a file has its length


def test_motion_vectors_of_a_live_feed_are_the_files(server, live_clip):
    pytest.importorskip("av")
    from pftrack.io.motion_vectors import MVSource, iter_mv_frames

    src = MVSource(server.url("clip.ts"))
    assert src.live and src.length is None
    file_frames = list(iter_mv_frames(live_clip))
    url_frames = list(iter_mv_frames(server.url("clip.ts")))  # the feed ends by the server closing it
    assert len(url_frames) == len(file_frames) == 40
    moving = 0
    for a, b in zip(url_frames, file_frames):
        assert a.pict_type == b.pict_type and np.array_equal(a.y, b.y)
        assert (a.mvs is None) == (b.mvs is None)
        if a.mvs is not None:
            assert np.array_equal(a.mvs, b.mvs)
            moving += int(len(a.mvs) > 0)
    assert moving >= 30


def test_tripwire_calibrates_on_a_live_feed_once_and_counts_as_from_the_file(server, live_clip, tmp_path, capsys):
    """``--radius auto`` reads the first 10 s: a file is read again from the start, a live feed's frames are kept
    and counted; both give the same rows."""
    out = {}
    for spec, name in ((str(live_clip), "file.csv"), (server.url("clip.ts"), "url.csv")):
        assert main(["tripwire", spec, "--line", "64,5;64,90", "--out", str(tmp_path / name), "--quiet"]) == 0
        out[name] = (tmp_path / name).read_text()
    assert out["file.csv"] == out["url.csv"]
    assert out["file.csv"].splitlines()[0].startswith("frame,direction")
    # the box moves right across a wire drawn downwards: s(P) falls, a negative crossing
    assert len(out["file.csv"].splitlines()) == 2 and out["file.csv"].splitlines()[1].split(",")[1] == "negative"


@pytest.mark.parametrize("argv", [
    ["track", "rtsp://admin:pw123@127.0.0.1:{port}/stream1", "--box", "1,2,3,4"],
    ["mot", "http://127.0.0.1:{port}/feed.mjpg"],
    ["activity", "rtsp://127.0.0.1:{port}/stream1"],
])
def test_an_unreachable_stream_is_one_line_and_exit_2(argv, tmp_path, capsys, monkeypatch):
    if argv[0] == "activity":
        pytest.importorskip("av")
    monkeypatch.chdir(tmp_path)
    port = _closed_port()
    assert main([a.format(port=port) for a in argv]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("pftrack: error: ") and "cannot open" in err[0]
    assert "pw123" not in err[0]
    assert not list(tmp_path.iterdir())  # no output file was started


def test_a_broken_off_feed_is_opened_again_with_reconnect(two_feeds, monkeypatch):
    monkeypatch.setattr(streams, "RECONNECT_WAIT_S", 0.0)
    srv = _Server({"feed.ts": two_feeds})
    try:
        src = open_source(srv.url("feed.ts"), reconnect=2)
        numbers = [n for n, _ in src.numbered()]
        # the second connection's frames are numbered on; the third connection finds nothing and, after two tries,
        # the source ends
        assert numbers == list(range(1, 41)) and src.reconnected == [21]
    finally:
        srv.close()
    srv = _Server({"feed.ts": two_feeds})
    try:
        src = open_source(srv.url("feed.ts"))  # without reconnect the feed's end is the source's
        assert [n for n, _ in src.numbered()] == list(range(1, 21)) and src.reconnected == []
    finally:
        srv.close()


def test_the_commands_reconnect_and_say_so(two_feeds, tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(streams, "RECONNECT_WAIT_S", 0.0)
    srv = _Server({"feed.ts": two_feeds})
    try:
        out = tmp_path / "t.csv"
        assert main(["track", srv.url("feed.ts"), "--box", "10,30,30,30", "--tracker", "color-pf", "--reconnect", "1",
                     "--quiet", "--out", str(out)]) == 0
        assert len(out.read_text().splitlines()) == 41
        assert "(the stream was opened again 1 time)" in capsys.readouterr().err
    finally:
        srv.close()
    # the motion-vector paths read with PyAV and do not reconnect: said before any work, exit 2
    assert main(["mot", "rtsp://127.0.0.1:1/s", "--detector", "mv", "--reconnect", "1", "--out",
                 str(tmp_path / "m.txt")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--reconnect" in err[0] and not (tmp_path / "m.txt").exists()
    with pytest.raises(SystemExit) as e:
        main(["track", "x.mp4", "--reconnect", "-1"])
    assert e.value.code == 2 and "--reconnect is an integer >= 0" in capsys.readouterr().err
