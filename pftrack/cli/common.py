"""Helpers shared by the command modules: the argument parser, progress bars, closing, reproduction lines."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

DEFAULT_TRACKER = "fusion-pf"


class ArgumentParser(argparse.ArgumentParser):
    def error(self, message: str):  # one line, exit 2
        self.exit(2, f"pftrack: error: {message}\n")


def counted(n: int, word: str, plural: str | None = None) -> str:
    """``"1 frame"``, ``"2 frames"``: a count with its noun in the right number (``plural``: an irregular plural)."""
    return f"{n} {word if n == 1 else (plural or word + 's')}"


def parse_seeds(text: str) -> list[int]:
    """Seeds written as ranges and single values, ``0-9``, ``1,4,7`` or ``100,200-202``, in order; ValueError for
    anything else (a negative seed, a descending range, no seed at all)."""
    seeds: list[int] = []
    for part in str(text).split(","):
        part = part.strip()
        if not part:
            continue
        lo, sep, hi = part.partition("-")
        a = int(lo)
        b = int(hi) if sep else a
        if a < 0 or b < a:
            raise ValueError(f"bad seed range {part!r}")
        seeds.extend(range(a, b + 1))
    if not seeds:
        raise ValueError("no seeds given")
    return seeds


def _non_negative(text: str, what: str) -> int:
    """``text`` as an integer >= 0, else argparse's one-line usage error saying ``what`` it is."""
    try:
        value = int(text)
    except ValueError:
        value = -1
    if value < 0:
        raise argparse.ArgumentTypeError(f"{what} is an integer >= 0, got {text!r}")
    return value


def seed_value(text: str) -> int:
    """An argparse type for a random seed: an integer >= 0 (NumPy's seeds), else a one-line usage error."""
    return _non_negative(text, "a seed")


def target_id(text: str) -> int:
    """An argparse type for ``--target``: an integer >= 0 (a ground-truth track id, or an OTB target's N)."""
    return _non_negative(text, "a target id")


def reconnect_count(text: str) -> int:
    """An argparse type for ``--reconnect``: an integer >= 0."""
    return _non_negative(text, "--reconnect")


def add_reconnect(p) -> None:
    """``--reconnect N`` for the commands that read live streams."""
    p.add_argument("--reconnect", type=reconnect_count, default=0, metavar="N", help=(
        "a live stream URL (rtsp://, ...) whose feed breaks off is opened again, up to N times in a row, waiting "
        "1, 2, 4, then 8 s between tries; its frames are numbered on (default 0: the run ends with the feed)"))


def reconnected_note(source) -> str:
    """`` (the stream was opened again N times)`` for the closing message, or nothing."""
    n = len(getattr(source, "reconnected", ()))
    return f" (the stream was opened again {counted(n, 'time')})" if n else ""


def progress(total: int | None, desc: str, quiet: bool):
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, unit="frame", file=sys.stderr, disable=quiet or None,
                dynamic_ncols=True, leave=False)


def close_all(bar, sinks, source) -> None:
    """Finish the progress bar, then every sink (flushing and finalising videos), then the source."""
    if bar is not None:
        bar.close()
    for sink in sinks:
        sink.close()
    source.close()


def reproduce_command(drop: tuple[str, ...] = ()) -> str | None:
    """The command line that produced a report, without output-destination options (``drop``)."""
    import shlex

    if not sys.argv or Path(sys.argv[0]).name != "pftrack":
        return None
    args, skip = [], False
    for a in sys.argv[1:]:
        if skip:
            skip = False
            continue
        if a in drop:
            skip = True
            continue
        if any(a.startswith(d + "=") for d in drop):
            continue
        args.append(a)
    return "pftrack " + shlex.join(args)


def follow_frames(first_number, first_frame, frames, init, step, emit) -> tuple[int, int]:
    """The loop shared by the per-frame commands: emit ``init(first frame)``, then ``step(frame)`` for every
    other frame, stopping cleanly on SIGTERM.  Returns (frames done, frames whose state was lost)."""
    from ..pipeline import interrupt_on_sigterm

    done = lost = 0
    with interrupt_on_sigterm() as stop:
        emit(first_number, first_frame, init(first_frame))
        done = 1
        for number, frame in frames:
            st = step(frame)
            lost += bool(getattr(st, "lost", False))
            emit(number, frame, st)
            done += 1
            stop.check()
    return done, lost


def first_frame(source, what: str):
    """``(frames iterator, (number, frame))`` of a source's first frame; closes it and raises on no frames."""
    from ..errors import SourceError

    frames = source.numbered()
    try:
        return frames, next(frames)
    except StopIteration:
        source.close()
        raise SourceError(f"{what}: no frames") from None


def first_truth_box(source) -> tuple[tuple[float, float, float, float], str] | None:
    """A sequence folder's ground-truth box when it starts on the first frame, with its text ``X,Y,W,H`` (for the
    commands that take the folder's own object when none is given); None otherwise."""
    box = source.init_box
    if box is None or source.init_number != 1:
        return None
    box = tuple(float(v) for v in box)
    return box, ",".join(f"{v:g}" for v in box)


def image_file(path: str):
    """An image read from a file given on the command line, or a one-line error (missing / not an image)."""
    from ..errors import SourceError
    from ..io.sources import read_image

    p = Path(path)
    if not p.is_file():
        raise SourceError(f"{path}: no such file")
    img = read_image(p)
    if img is None:
        raise SourceError(f"{path}: not an image")
    return img
