"""Exceptions raised by procam stages.

Every error a user can cause derives from :class:`ProcamError`; its message is one
line that names the file or pose and says what to do.  The CLI prints it and exits
with a non-zero code, without a traceback.
"""


class ProcamError(Exception):
    """Base class of all user-facing procam errors."""


class CaptureError(ProcamError):
    """A capture folder or image file cannot be used (missing, unreadable, wrong count, ...)."""


class BoardNotFoundError(ProcamError):
    """The chessboard was not found in an image."""


class CorrespondenceError(ProcamError):
    """Too few chessboard corners have usable projector coordinates."""


class CalibrationError(ProcamError):
    """A calibration stage failed (degenerate pose, no valid solution, ...)."""


class CalibrationFileError(ProcamError):
    """A calibration file cannot be read or written."""


class OutputError(ProcamError):
    """An output cannot be written where asked (a folder holding files procam did not write, a read-only
    or full disk, a file that would overwrite an input ...)."""
