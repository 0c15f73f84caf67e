"""Exceptions and warnings of procam.

Every error a user can cause derives from :class:`ProcamError`; its message is one
line that names the file or pose and says what to do.  The CLI prints it and exits
with a non-zero code, without a traceback.

A result that is there but must not be trusted as is comes with a :class:`ProcamWarning` (through
:func:`warnings.warn`), and the result carries the same words (``Calibration.verdict``,
``Calibration.warnings``). The CLI prints them, and does not write a degenerate or failed calibration
unless told to (``--force``; exit code 3).
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


class DegeneratePoseError(CalibrationError):
    """The pose does not determine the calibration (``strict=True``, or no solution at all at such a pose)."""


class CalibrationFileError(ProcamError):
    """A calibration file cannot be read or written."""


class OutputError(ProcamError):
    """An output cannot be written where asked (a folder holding files procam did not write, a read-only
    or full disk, a file that would overwrite an input ...)."""


class ProcamWarning(UserWarning):
    """Base class of procam's warnings: the result exists, read why it may not be what you think."""


class WeakPoseWarning(ProcamWarning):
    """A single-pose calibration from a weak pose: usable, but less precise than a better pose would give."""


class DegeneratePoseWarning(ProcamWarning):
    """The pose does not determine some of the parameters: their values may be anything."""


class FailedEstimateWarning(ProcamWarning):
    """An estimate is impossible (e.g. a focal length no real lens has): the calibration failed."""


class ModelErrorWarning(ProcamWarning):
    """The data disagree with the model beyond the noise (a model assumption does not hold)."""
