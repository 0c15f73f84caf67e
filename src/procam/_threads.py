"""Threads of the numerical libraries: one thread for OpenCV and BLAS where results must not depend on them.

OpenCV's parallel loops (inside ``calibrateCamera``, ``stereoCalibrate``, ``projectPoints`` ...) split sums
across threads in an order that changes from run to run, so a multi-pose calibration differed in the last
digits between two runs (and a start could win a tie in one run and lose it in the next).  Inside
:func:`deterministic` OpenCV and BLAS run on one thread, so the same inputs give the same bytes; the previous
settings are restored on exit (no global side effect).  The calibrations are small, so one thread costs
nothing measurable.
"""

from __future__ import annotations

import threading
from contextlib import contextmanager

import numpy as np

__all__ = ["deterministic", "single_threaded_blas"]


_LOCK = threading.Lock()
_depth = {"blas": 0, "cv": 0}  # blocks open (in any thread) that hold the setting at one thread
_restore: dict = {}  # how to undo it when the last of them closes


def _enter(kind: str, limit) -> None:
    with _LOCK:
        if _depth[kind] == 0:
            _restore[kind] = limit()
        _depth[kind] += 1


def _leave(kind: str) -> None:
    with _LOCK:
        _depth[kind] -= 1
        if _depth[kind] == 0:
            _restore.pop(kind)()


def _limit_blas():
    """Set BLAS to one thread; return the function that restores the previous setting."""
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:
        threadpool_limits = None
    if threadpool_limits is not None:
        limits = threadpool_limits(limits=1, user_api="blas")
        return limits.restore_original_limits
    old = []
    for get, set_ in _openblas_handles():
        try:
            old.append((set_, int(get())))
            set_(1)
        except Exception:  # pragma: no cover - exotic builds
            pass

    def restore():
        for set_, n in old:
            try:
                set_(n)
            except Exception:  # pragma: no cover
                pass

    return restore


@contextmanager
def single_threaded_blas():
    """Limit BLAS to one thread inside the block (best effort; restores the previous setting).

    Every linear-algebra call of a cell is tiny (matrices of ~120 × 9), so multi-threaded BLAS
    only costs: on a loaded 2-core machine a calibration took 0.12 s with OpenBLAS's default
    threads against 0.02 s with one.  Uses ``threadpoolctl`` when installed, otherwise the
    ``*_set_num_threads`` entry points of the OpenBLAS copies bundled with numpy and scipy.
    Parallel workers need nothing: joblib's loky workers already get ``cpu_count // n_jobs``
    BLAS threads.  The setting is process-wide: blocks open at the same time in several threads
    share it, and the last one to close restores it (no block runs with the setting undone under it).
    """
    _enter("blas", _limit_blas)
    try:
        yield
    finally:
        _leave("blas")


_BLAS_HANDLES = None


def _openblas_handles():
    """``(get_num_threads, set_num_threads)`` ctypes pairs of the loaded OpenBLAS libraries."""
    global _BLAS_HANDLES
    if _BLAS_HANDLES is not None:
        return _BLAS_HANDLES
    import ctypes
    import glob
    import os

    import scipy

    found = []
    dirs = {os.path.join(os.path.dirname(os.path.dirname(m.__file__)), f"{m.__name__}.libs") for m in (np, scipy)}
    for d in sorted(dirs):
        for path in sorted(glob.glob(os.path.join(d, "*openblas*.so*"))):
            try:
                lib = ctypes.CDLL(path, mode=getattr(os, "RTLD_NOLOAD", 0) | ctypes.RTLD_LOCAL)
            except OSError:
                continue
            for suffix in ("scipy_openblas_{}64_", "scipy_openblas_{}_64_", "scipy_openblas_{}", "openblas_{}"):
                g, st = (getattr(lib, suffix.format(x), None) for x in ("get_num_threads", "set_num_threads"))
                if g is not None and st is not None:
                    g.restype = ctypes.c_int
                    st.argtypes = [ctypes.c_int]
                    found.append((g, st))
                    break
    _BLAS_HANDLES = found
    return found



@contextmanager
def deterministic():
    """One OpenCV thread and one BLAS thread inside the block (previous settings restored when the last block
    open in any thread closes)."""
    import cv2

    def limit_cv():
        n = cv2.getNumThreads()
        cv2.setNumThreads(1)
        return lambda: cv2.setNumThreads(n)

    _enter("cv", limit_cv)
    try:
        with single_threaded_blas():
            yield
    finally:
        _leave("cv")
