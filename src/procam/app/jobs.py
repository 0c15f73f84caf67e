"""Long work off the request thread: one job at a time (a capture, a calibration, a world check), run in a thread
that reports its progress and stops at the next step when it is cancelled.

A job's function gets its :class:`Job` and calls :meth:`Job.step` as it goes; :meth:`Job.step` raises
:class:`Cancelled` once the user asked to stop, so the work unwinds through the library's own clean-up (a capture
removes its partial folder).  A :class:`~procam.errors.ProcamError` (or an OS error) ends the job ``failed`` with
its one line; anything else ends it ``failed`` as an internal error that says so.
"""

from __future__ import annotations

import contextlib
import itertools
import math
import threading
import time
import traceback
import warnings
from collections.abc import Callable

from ..errors import ProcamError, ProcamWarning


@contextlib.contextmanager
def results_carry_warnings():
    """Silence procam's warnings while the app works: every result carries its verdict and reasons, which the page
    shows (as the command line does in :func:`procam.cli._app.user_errors`)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ProcamWarning)
        yield


def finite(obj):
    """``obj`` (JSON-like: dicts, lists, numbers) with every NaN or infinity as None (JSON has neither)."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: finite(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [finite(v) for v in obj]
    return obj


class Cancelled(ProcamError):
    """The user cancelled the job."""


class Busy(ProcamError):
    """Another job is running."""


def error_line(e: BaseException) -> str:
    """One line for an error a job (or a request) ends with: a ProcamError's own words, an OS error's path and
    reason, else an internal error that asks for a report."""
    if isinstance(e, ProcamError):
        return str(e)
    if isinstance(e, OSError):
        return f"{e.filename}: {e.strerror or e}" if e.filename else str(e.strerror or e)
    last = (str(e).strip().splitlines() or [""])[-1][:300]
    return f"internal error ({type(e).__name__}: {last}); please report it"


class Job:
    """One piece of long work: ``kind`` (``"capture"``, ``"calibrate"``, ...), ``state`` (``"running"``,
    ``"done"``, ``"failed"``, ``"cancelled"``), progress ``done`` of ``total`` steps with a ``message``, and at the
    end its ``result`` (a JSON-ready dict) or ``error`` (one line)."""

    def __init__(self, job_id: int, kind: str):
        self.id, self.kind = job_id, kind
        self.state, self.done, self.total, self.message = "running", 0, 0, "starting"
        self.result: dict | None = None
        self.error = ""
        self.started = time.monotonic()
        self.seconds = 0.0
        self._cancel = threading.Event()
        self.thread: threading.Thread | None = None

    def step(self, done: int | None = None, total: int | None = None, message: str | None = None) -> None:
        """Report progress; raises :class:`Cancelled` when the job was cancelled."""
        if done is not None:
            self.done = int(done)
        if total is not None:
            self.total = int(total)
        if message is not None:
            self.message = message
        if self._cancel.is_set():
            raise Cancelled(f"{self.kind} cancelled")

    def cancel(self) -> None:
        self._cancel.set()

    def to_dict(self) -> dict:
        """JSON-ready (a number that is not finite in the result becomes null)."""
        return {"id": self.id, "kind": self.kind, "state": self.state, "done": self.done, "total": self.total,
                "message": self.message, "result": finite(self.result), "error": self.error,
                "seconds": round(self.seconds if self.state != "running" else time.monotonic() - self.started, 2)}


class Jobs:
    """The app's job runner: at most one job runs at a time (the devices are one)."""

    def __init__(self):
        self._lock = threading.Lock()
        self._ids = itertools.count(1)
        self.jobs: dict[int, Job] = {}

    def running(self) -> Job | None:
        return next((j for j in self.jobs.values() if j.state == "running"), None)

    def start(self, kind: str, work: Callable[[Job], dict]) -> Job:
        """Run ``work(job)`` in a thread; its return value is the job's result.  Raises :class:`Busy` while
        another job runs."""
        with self._lock:
            other = self.running()
            if other is not None:
                raise Busy(f"the {other.kind} is still running; wait for it or cancel it")
            job = Job(next(self._ids), kind)
            self.jobs[job.id] = job
        job.thread = threading.Thread(target=self._run, args=(job, work), name=f"procam-app-{kind}", daemon=True)
        job.thread.start()
        return job

    @staticmethod
    def _run(job: Job, work) -> None:
        try:
            with results_carry_warnings():
                job.result = work(job)
            job.state = "done"
        except Cancelled as e:
            job.state, job.error = "cancelled", str(e)
        except Exception as e:  # noqa: BLE001 - every error ends the job with its one line
            job.state, job.error = "failed", error_line(e)
            if not isinstance(e, (ProcamError, OSError)):
                job.message = traceback.format_exception_only(type(e), e)[-1].strip()
        finally:
            job.seconds = time.monotonic() - job.started

    def get(self, job_id: int) -> Job:
        if job_id not in self.jobs:
            raise ProcamError(f"no job {job_id}")
        return self.jobs[job_id]

    def wait(self, timeout: float | None = None) -> None:
        """Wait for the running job (if any) to end."""
        job = self.running()
        if job is not None and job.thread is not None:
            job.thread.join(timeout)
