"""How the paper's sweeps run: one BLAS thread per calibration, and a joblib / Dask executor.

* :func:`single_threaded_blas` - limit BLAS to one thread inside a block (``threadpoolctl`` when
  installed, otherwise the OpenBLAS copies bundled with numpy and scipy through ctypes).
* :func:`run_chunks` - run independent chunks of work on joblib workers (local processes, or a Dask
  cluster through joblib's ``dask`` backend) and gather the results in input order.

joblib is an optional dependency (``procam[parallel]``); nothing here imports it until
:func:`run_chunks` is called.
"""

from __future__ import annotations

import contextlib
import math
from typing import Callable, Sequence

from .._threads import _openblas_handles, single_threaded_blas  # noqa: F401  (re-exported)
from ..errors import ProcamError

__all__ = ["single_threaded_blas", "run_chunks"]


def _chunks(items: list, size: int) -> list[list]:
    return [items[i:i + size] for i in range(0, len(items), size)]


def _task(work: Callable[[list], list], chunk):
    """Module-level joblib task (picklable): ``(indices, results)`` of a chunk of ``(index, item)``."""
    return [i for i, _ in chunk], work([c for _, c in chunk])


def run_chunks(work: Callable[[list], list], items: Sequence, *, n_jobs: int = -1, backend: str | None = None,
               chunk_size: int | None = None,
               progress: Callable[[int, int], None] | None = None) -> tuple[list, dict]:
    """``work`` over chunks of ``items`` on joblib workers; results in the order of ``items``.

    Parameters
    ----------
    work : picklable callable (a module-level function or a ``functools.partial`` of one) that
        takes a list of items and returns one result per item, in order.
    items : the work items.
    n_jobs : joblib worker count (``-1`` / ``0`` / ``None`` = all cores).
    backend : joblib backend: ``None`` (``"loky"`` processes) or ``"dask"`` — the latter needs a
        ``dask.distributed.Client`` connected in this process; the work then runs on that cluster.
    chunk_size : items per task (default: about 4 tasks per worker, at most 16 items).
    progress : called as ``progress(items_done, items_total)`` after each finished chunk (in the
        order chunks finish).

    Returns
    -------
    results : list, one per item, in the order of ``items`` whatever the order the workers finished in.
    run : how it ran: ``n_jobs`` (workers), ``backend``, ``chunk_size``.

    Raises
    ------
    ProcamError
        joblib is not installed.
    """
    try:
        import joblib
    except ImportError:
        raise ProcamError("parallel runs need joblib: pip install 'procam[parallel]' "
                          "(or run serially with --jobs 1)") from None
    todo = list(items)
    total = len(todo)
    workers = joblib.cpu_count() if n_jobs in (-1, 0, None) else max(1, int(n_jobs))
    if chunk_size is None:
        chunk_size = int(min(16, max(1, math.ceil(total / (4 * workers)))))
    chunks = _chunks(list(enumerate(todo)), chunk_size)

    results: dict[int, object] = {}
    done = 0
    ctx = joblib.parallel_config(backend=backend) if backend is not None else contextlib.nullcontext()
    jobs = n_jobs if backend is None or n_jobs != 1 else -1
    with ctx:
        try:  # joblib >= 1.4: results as they finish (live progress)
            par = joblib.Parallel(n_jobs=jobs, return_as="generator_unordered")
        except (TypeError, ValueError):
            par = joblib.Parallel(n_jobs=jobs)
        for idx, out in par(joblib.delayed(_task)(work, chunk) for chunk in chunks):
            for i, r in zip(idx, out):
                results[i] = r
            done += len(idx)
            if progress is not None:
                progress(done, total)
    return ([results[i] for i in range(total)],
            {"n_jobs": workers, "backend": backend or "loky", "chunk_size": chunk_size})
