"""The HTML report of a 5-pose multi-pose calibration: build time, size, and load time in headless Chromium.

The ``paper`` rig, board 10x6 at 24 mm, 5 poses (simulate.correspondences, corner noise 0.1 px camera /
0.2 px projector), multi-pose calibration with leave-one-pose-out.  The load time is the browser's own
navigation timing (``loadEventEnd``), the median of ``--repeats`` fresh loads.

Usage::

    python benchmarks/report.py [--repeats 5] [--out report.html] [--screenshot report.png]
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("MPLBACKEND", "Agg")

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from _common import header  # noqa: E402
from browser import Browser, find_chromium  # noqa: E402

from procam import multi_pose, simulate  # noqa: E402
from procam.report import build_report, write_report  # noqa: E402
from procam.verify import verify_calibration  # noqa: E402
from procam.view import View  # noqa: E402

POSES = [(15, 12, 0), (-10, 20, 5), (20, -15, -5), (5, 25, 10), (-20, -10, 0)]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--out", type=Path, default=None)
    ap.add_argument("--screenshot", type=Path, default=None)
    a = ap.parse_args()
    print(header("HTML report of a 5-pose multi-pose calibration"))
    sc = simulate.preset("paper")
    views = []
    for k, p in enumerate(POSES):
        s = simulate.with_board_pose(sc, p)
        obj, cam, proj = simulate.correspondences(s, 0.1, 0.2, seed=k)
        views.append(View(obj, cam, proj, f"pose{k + 1}", s.cam_size, s.proj_size))
    calib = multi_pose.calibrate(views)
    t0 = time.perf_counter()
    check = verify_calibration(calib)
    t1 = time.perf_counter()
    page = build_report(calib, check=check, name="benchmark")
    t2 = time.perf_counter()
    out = a.out or Path(tempfile.mkdtemp(prefix="procam-")) / "report.html"
    write_report(page, out)
    print(f"verification incl. leave-one-out: {t1 - t0:.2f} s; page built in {t2 - t1:.2f} s; "
          f"{len(page.encode('utf-8')) / 1e6:.3f} MB: {out}")
    exe = find_chromium()
    if exe is None:
        print("no Chromium: load time not measured")
        return
    loads = []
    for _ in range(a.repeats):
        with Browser(exe) as b:
            b.open(out.as_uri())
            loads.append(b.evaluate("performance.getEntriesByType('navigation')[0].loadEventEnd"))
            if a.screenshot is not None and len(loads) == 1:
                b.screenshot(a.screenshot)
            b.drain()
            problems = b.console_problems()
    print(f"load (navigation timing, {a.repeats} fresh browsers): median {np.median(loads):.0f} ms, "
          f"max {max(loads):.0f} ms; console problems: {problems or 'none'}")


if __name__ == "__main__":
    main()
