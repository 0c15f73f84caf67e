"""Benchmark: simulation-study throughput (cells per second), serial and parallel.

One workload per device (a ψ × ν grid without the slices, ``--trials`` noisy calibrations plus a
noise-free one and the CRLB per cell), run
1. serially with OpenBLAS's default thread count (what a plain loop would do),
2. serially with one BLAS thread (``procam.paper.study`` does this itself),
3. with joblib processes (``--jobs``),
4. optionally on a local Dask cluster through joblib's dask backend (``--dask``).
Each parallel result is checked to equal the serial one.

    python benchmarks/study.py [--grid -40:40:20] [--trials 10] [--jobs 2] [--dask]
"""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import header  # noqa: E402

from procam.paper import study  # noqa: E402


def _same(a, b) -> bool:
    """Rows equal apart from the timing, NaN == NaN."""
    if len(a.rows) != len(b.rows):
        return False
    for ra, rb in zip(a.rows, b.rows):
        for k, va in ra.items():
            vb = rb[k]
            if k == "seconds":
                continue
            if isinstance(va, float) and isinstance(vb, float):
                if not (va == vb or (va != va and vb != vb)):
                    return False
            elif va != vb:
                return False
    return True


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grid", default="-40:40:20", help="psi and nu grid (deg)")
    ap.add_argument("--trials", type=int, default=10)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--dask", action="store_true", help="also run on a local dask.distributed cluster")
    ap.add_argument("--devices", default="camera,projector")
    args = ap.parse_args()
    grid = study.parse_grid(args.grid)
    print(header("procam study throughput"))
    print(f"load average at start: {os.getloadavg()[0]:.2f} (the machine is shared; times are wall clock)")
    print(f"workload per device: {grid.size}x{grid.size} cells, {args.trials} noisy trials + 1 noise-free "
          f"calibration + CRLB per cell, model error 'paper'\n")
    print("| device | run | cells | seconds | cells/s | calibrations/s | same as serial |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for device in args.devices.split(","):
        cfg = study.StudyConfig(device, psi=grid, nu=grid, trials=args.trials, slices=False)
        study._preset(cfg.preset)  # warm the cache outside the timings
        runs = []

        @contextlib.contextmanager
        def default_threads():
            saved = study.single_threaded_blas
            study.single_threaded_blas = contextlib.nullcontext
            try:
                yield
            finally:
                study.single_threaded_blas = saved

        with default_threads():
            runs.append(("serial, default BLAS threads", study.run_study(cfg)))
        ref = study.run_study(cfg)
        runs.append(("serial, 1 BLAS thread", ref))
        try:
            runs.append((f"joblib loky, {args.jobs} processes", study.run_study(cfg, n_jobs=args.jobs)))
        except Exception as e:  # noqa: BLE001 - report and go on
            print(f"| {device} | joblib | failed: {e} | | | | |")
        if args.dask:
            from dask.distributed import Client, LocalCluster

            with LocalCluster(n_workers=args.jobs, threads_per_worker=1, processes=True,
                              dashboard_address=None) as cl, Client(cl):
                runs.append((f"dask LocalCluster, {args.jobs} workers", study.run_study(cfg, backend="dask")))
        n = len(ref.rows)
        for name, res in runs:
            same = "yes" if _same(res, ref) else "NO"
            print(f"| {device} | {name} | {n} | {res.seconds:.2f} | {n / res.seconds:.2f} | "
                  f"{n * (args.trials + 1) / res.seconds:.1f} | {same} |")
    print(f"\nload average at end: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    t0 = time.perf_counter()
    main()
    print(f"total {time.perf_counter() - t0:.1f} s")
