"""Exceptions raised at pftrack's boundaries.

Every error a user can cause by giving bad input derives from :class:`PftrackError`
and carries a one-line message that names the file, frame or parameter at fault.
The command line prints that line and exits with code 2; the Python API lets the
exception propagate so callers can catch the specific class.

The input errors also derive from :class:`ValueError` so that generic callers that
already catch ``ValueError`` keep working.
"""

from __future__ import annotations


class PftrackError(Exception):
    """Base class of every error pftrack raises on purpose."""


class InputError(PftrackError, ValueError):
    """Bad input given by the user (file, frame, box, parameter, format)."""


class SourceError(InputError):
    """A frame source cannot be opened or is not what it claims to be."""


class FrameError(SourceError):
    """A frame inside a source is unreadable, of the wrong type or of another size."""

    def __init__(self, message: str, *, index: int | None = None):
        super().__init__(message)
        self.index = index


class BoxError(InputError):
    """A box is unparsable, non-finite, of zero/negative size or outside the image."""


class ParameterError(InputError):
    """An unknown tracker/parameter name, or a parameter value of the wrong type or out of range."""


class FormatError(InputError):
    """A data file (ground truth, sequence description, results) is malformed."""


class OutputError(PftrackError, OSError):
    """An output path cannot be written."""


class Interrupted(PftrackError):
    """Work stopped by SIGINT or SIGTERM after everything computed so far was written."""
