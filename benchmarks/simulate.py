"""Benchmark: render one 46-image 1280x800 pose with procam.simulate (goals: <= 10 s, <= 2 GB on 2 cores).

Renders the ``paper`` preset (``--preset``: any of procam.simulate.PRESETS, e.g. ``hard``: lenses beyond OpenCV's
model and a room corner with a box and a ball) at the recommended pose (supersampling 3x3 by default) and reports,
per run: wall and CPU seconds for the geometry pass (once per scene) and for the 46 images, and
the whole ``render`` call; optionally ``write_capture`` to a temporary folder.  Peak memory is the
process's maximum resident set size (it includes the interpreter and libraries, ~150 MB), and the
peak of numpy allocations during one render (tracemalloc).  The machine may be shared: the CPU
seconds are the fairer figure when the load average is high (it is printed).

    python benchmarks/simulate.py [--repeat 3] [--supersample 3] [--write]
"""

from __future__ import annotations

import argparse
import os
import resource
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import header  # noqa: E402

from procam import simulate as sim  # noqa: E402


def _timed(fn):
    w, c = time.perf_counter(), time.process_time()
    out = fn()
    return out, time.perf_counter() - w, time.process_time() - c


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--supersample", type=int, default=None, help="rays per pixel per axis (default: the preset's)")
    ap.add_argument("--preset", default="paper", choices=sim.PRESETS)
    ap.add_argument("--write", action="store_true", help="also time write_capture (PNG encoding)")
    args = ap.parse_args()
    scene = sim.preset(args.preset)
    if args.supersample:
        scene = scene.replace(supersample=args.supersample)

    rows = []
    for r in range(args.repeat):
        marks = []

        def progress(done, total):
            if done == 1:  # called once the geometry pass is done
                marks.append((time.perf_counter(), time.process_time()))

        w0, c0 = time.perf_counter(), time.process_time()
        stack, truth = sim.render(scene, seed=r, progress=progress)
        w1, c1 = time.perf_counter(), time.process_time()
        gw, gc = marks[0][0] - w0, marks[0][1] - c0
        ww = wc = float("nan")
        if args.write:
            with tempfile.TemporaryDirectory() as tmp:
                _, ww, wc = _timed(lambda: sim.write_capture(tmp, stack, truth))
        rows.append((gw, gc, w1 - w0, c1 - c0, ww, wc))
    tracemalloc.start()
    sim.render(scene, seed=0)
    _, np_peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    med = np.median(np.array(rows), axis=0)

    print(header(f"simulate: render one pose, {stack.shape[0]} images {stack.shape[2]}x{stack.shape[1]}"))
    print(f"preset {args.preset}, supersample {scene.supersample}x{scene.supersample}, "
          f"{stack.shape[2] * scene.supersample}x{stack.shape[1] * scene.supersample} rays; median of "
          f"{args.repeat} runs; load average {os.getloadavg()[0]:.1f} (1 min)\n")
    print("| step | wall s | CPU s |")
    print("| --- | --- | --- |")
    print(f"| geometry (once per scene) | {med[0]:.2f} | {med[1]:.2f} |")
    print(f"| 46 images (render minus geometry) | {med[2] - med[0]:.2f} | {med[3] - med[1]:.2f} |")
    print(f"| render total (goal <= 10 s) | {med[2]:.2f} | {med[3]:.2f} |")
    if args.write:
        print(f"| write_capture (46 PNG + JSON) | {med[4]:.2f} | {med[5]:.2f} |")
    print(f"\npeak memory: max RSS {peak:.0f} MB (goal <= 2048 MB); numpy peak during render "
          f"{np_peak / 2**20:.0f} MB")


if __name__ == "__main__":
    main()
