"""Benchmark: how often the verdict is right, and what the evidence costs (issue 24).

On the simulator's fast correspondence path, over ``--seeds`` noise draws (and, for the sound sets, random
sound pose sets):

* **sound sets** (5 poses tilted 15-30 deg about different axes; the ``paper`` and ``hard`` rigs and the small
  256x160 camera of the issue's user): the share rated good (a false alarm is any other word);
* **square-on sets** (the user's case: 4 boards square to the camera, with and without a fifth tilted one;
  refined and ``--no-refine``): the share NOT rated good or weak (a miss is a trusted result);
* **labellings**: the largest relative difference of K, R, T between the four labellings of a 9x7 board
  (single-pose with outliers, multi-pose);
* **cost**: ``multi_pose.calibrate`` with and without the leave-one-pose-out refits, and
  ``verify_calibration`` reusing them vs refitting (medians of ``--repeat`` runs, alternated in one run).

    OPENBLAS_NUM_THREADS=1 python benchmarks/verdicts.py [--seeds 10] [--repeat 5]
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import header  # noqa: E402

from procam import multi_pose, simulate, single_pose  # noqa: E402
from procam.errors import ProcamError, ProcamWarning  # noqa: E402
from procam.verify import verify_calibration  # noqa: E402
from procam.view import View  # noqa: E402

SMALL = simulate.preset("paper").scaled(0.2).replace(board_cols=9, board_rows=7, square=12.0)
SQUARE_ON = [(0, 0, 0), (0, 0, 3), (1, 0, -4), (0, 1, 2)]


def views_of(base, angles, seed, distance=650.0):
    out = []
    for k, a in enumerate(angles):
        sc = simulate.with_board_pose(base, a, distance=distance)
        obj, cam, proj = simulate.correspondences(sc, 0.1, 0.2, 1000 * seed + k)
        out.append(View(obj, cam, proj, f"p{k}", sc.cam_size, sc.proj_size))
    return out


def sound_angles(rng):
    """5 poses, each tilted 15-30 deg, about axes spread around the circle."""
    out = []
    for k in range(5):
        tilt = rng.uniform(15, 30)
        ax = np.radians(k * 72 + rng.uniform(-15, 15))
        out.append((float(tilt * np.cos(ax)), float(tilt * np.sin(ax)), float(rng.uniform(-10, 10))))
    return out


def word(views, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ProcamWarning)
        try:
            return multi_pose.calibrate(views, **kw).verdict
        except ProcamError:
            return "error (refused)"


def relabel(view, cols, rows, how):
    idx = np.arange(cols * rows).reshape(rows, cols)
    perm, c, r = {"swapped": (idx.T, rows, cols), "far-corner": (idx[::-1, ::-1], cols, rows),
                  "swapped-other-corner": (idx.T[::-1, :], rows, cols)}[how]
    p = perm.ravel()
    s = float(np.min(np.abs(np.diff(np.unique(view.obj_pts[:, 0])))))
    ii, jj = np.meshgrid(np.arange(c), np.arange(r))
    o = np.column_stack([ii.ravel() * s, jj.ravel() * s, np.zeros(c * r)])
    o[:, :2] -= o[:, :2].mean(axis=0)
    return View(o, view.cam_pts[p], view.proj_pts[p], view.name, view.cam_size, view.proj_size)


def numbers(c):
    return np.concatenate([c.camera.K.ravel(), c.projector.K.ravel(), np.ravel(c.R), np.ravel(c.T)])


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--repeat", type=int, default=5)
    a = ap.parse_args()
    print(header("verdicts: right words and the cost of the evidence"))
    rng = np.random.default_rng(0)
    print("\n| pose sets | runs | good | weak | degenerate | failed | refused |")
    print("|---|---|---|---|---|---|---|")
    cases = [("sound, paper rig", lambda s: views_of(simulate.preset("paper"), sound_angles(rng), s), {}),
             ("sound, hard rig", lambda s: views_of(simulate.preset("hard"), sound_angles(rng), s, None), {}),
             ("sound, 256x160 camera", lambda s: views_of(SMALL, sound_angles(rng), s, 600.0), {}),
             ("4 square-on + 1 tilted", lambda s: views_of(SMALL, SQUARE_ON + [(20, -25, 0)], s, 600.0), {}),
             ("4 square-on", lambda s: views_of(SMALL, SQUARE_ON, s, 600.0), {}),
             ("4 square-on, --no-refine", lambda s: views_of(SMALL, SQUARE_ON, s, 600.0), {"refine": False})]
    for label, make, kw in cases:
        words = [word(make(s), **kw) for s in range(a.seeds)]
        counts = [sum(w == x for w in words) for x in ("good", "weak", "degenerate", "failed", "error (refused)")]
        print(f"| {label} | {len(words)} | " + " | ".join(str(c) for c in counts) + " |")

    print("\n| labellings of a 9x7 board | largest relative difference of K, R, T | verdicts |")
    print("|---|---|---|")
    base = simulate.preset("paper").replace(board_cols=9, board_rows=7)
    worst_s, worst_m, same_s, same_m = 0.0, 0.0, True, True
    for s in range(a.seeds):
        sc = simulate.with_board_pose(base, (15, -25, 5))
        obj, cam, proj = simulate.correspondences(sc, 0.3, 0.5, s)
        cam[[4, 22, 40, 51]] += np.random.default_rng(s).normal(0, 2.0, (4, 2))
        v = View(obj, cam, proj, "pose", sc.cam_size, sc.proj_size)
        mv = views_of(base, [(20, -15, 0), (-15, 20, 5), (10, 25, -5), (-25, -10, 0)], s)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ProcamWarning)
            ref, mref = single_pose.calibrate(v), multi_pose.calibrate(mv)
            for how in ("swapped", "far-corner", "swapped-other-corner"):
                o = single_pose.calibrate(relabel(v, 9, 7, how))
                m = multi_pose.calibrate([relabel(x, 9, 7, how) for x in mv])
                worst_s = max(worst_s, float(np.max(np.abs(numbers(o) - numbers(ref)) / np.maximum(abs(numbers(ref)), 1e-3))))
                worst_m = max(worst_m, float(np.max(np.abs(numbers(m) - numbers(mref)) / np.maximum(abs(numbers(mref)), 1e-3))))
                same_s &= o.verdict == ref.verdict
                same_m &= m.verdict == mref.verdict
    print(f"| single-pose, 4 outliers, {a.seeds} seeds | {worst_s:.2g} | {'same' if same_s else 'DIFFER'} |")
    print(f"| multi-pose, 4 poses, {a.seeds} seeds | {worst_m:.2g} | {'same' if same_m else 'DIFFER'} |")

    import inspect

    if "leave_one_out" not in inspect.signature(multi_pose.calibrate).parameters:
        print("\n(this procam has no leave-one-out refits in multi_pose.calibrate: no cost table)")
        return
    views = views_of(simulate.preset("paper"), [(20, -15, 0), (-15, 20, 5), (10, 25, -5), (-25, -10, 0),
                                                (5, -20, 3), (-10, 10, 0), (25, 5, -3)], 0)
    t = {"calibrate, no leave-one-out": [], "calibrate with leave-one-out": [], "verify, refits reused": [],
         "verify, refits made": []}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ProcamWarning)
        for _ in range(a.repeat):
            t0 = time.perf_counter()
            bare = multi_pose.calibrate(views, leave_one_out=False)
            t["calibrate, no leave-one-out"].append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            full = multi_pose.calibrate(views)
            t["calibrate with leave-one-out"].append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            verify_calibration(full)
            t["verify, refits reused"].append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            verify_calibration(bare)
            t["verify, refits made"].append(time.perf_counter() - t0)
    med = {k: statistics.median(v) for k, v in t.items()}
    print(f"\n| 7 poses (1280x800 camera, 60 corners each), median of {a.repeat} | seconds |")
    print("|---|---|")
    for k, v in med.items():
        print(f"| {k} | {v:.3f} |")
    print(f"\ncalibrate with / without the leave-one-out refits: {med['calibrate with leave-one-out'] / med['calibrate, no leave-one-out']:.2f}x; "
          f"calibrate + verify as procam calibrate runs them, now / before: "
          f"{(med['calibrate with leave-one-out'] + med['verify, refits reused']) / (med['calibrate, no leave-one-out'] + med['verify, refits made']):.2f}x")


if __name__ == "__main__":
    main()
