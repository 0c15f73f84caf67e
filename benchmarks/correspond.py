"""Benchmark: corner and projector-corner accuracy against simulator truth, and the choice of defaults.

Renders the paper preset at several board poses and read-noise levels, then measures in one run:
1. camera-corner RMS error (px) for each detector / cornerSubPix half-window;
2. projector-corner RMS error (projector px) for each local-homography window and estimator
   (with the true camera corners as input, so only the homography step is measured),
3. the full default pipeline (detect + correspond).

    python benchmarks/correspond.py [--quick]
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import header  # noqa: E402

from procam.board import Board  # noqa: E402
from procam import board, correspond, decode, patterns, pipeline, simulate  # noqa: E402


def rms(a, b):
    d = np.asarray(a, float) - np.asarray(b, float)
    ok = np.isfinite(d).all(1)
    return float(np.sqrt(np.mean(np.sum(d[ok] ** 2, axis=1)))) if ok.any() else float("nan"), int(ok.sum())


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="two poses, one noise level")
    args = ap.parse_args()
    poses = [(15, 12, 0), (-10, 20, 5), (25, -5, 0), (5, 30, -3)]
    noises = [1.0, 3.0]
    if args.quick:
        poses, noises = poses[:2], noises[:1]
    det_variants = [("classic", 0), ("classic", 3), ("classic", 5), ("classic", 7), ("classic", 11),
                    ("classic", 15), ("sb", 0), ("sb", 11)]
    windows = [20, 30, 40, 60, 80, 100]
    estimators = correspond.ESTIMATORS
    ps = patterns.pattern_set(1920, 1080)
    base = simulate.preset("paper")
    det_err = {v: [] for v in det_variants}
    det_time = {v: [] for v in det_variants}
    hom_err = {(w, e): [] for w in windows for e in estimators}
    hom_time = {(w, e): [] for w in windows for e in estimators}
    full = []
    for pose in poses:
        for noise in noises:
            scene = dataclasses.replace(simulate.with_board_pose(base, pose), read_noise=noise)
            stack, truth = simulate.render(scene, seed=7)
            cam_t = np.array(truth["corners"]["camera_distorted"])
            proj_t = np.array(truth["corners"]["projector"])
            white = stack[ps.white]
            for v in det_variants:
                t = time.perf_counter()
                c = board.detect_corners(white, (10, 6), detector=v[0], refine_window=v[1])
                det_time[v].append(time.perf_counter() - t)
                det_err[v].append(rms(c, cam_t)[0] if c is not None else np.nan)
            maps = decode.decode(stack, ps)
            for w in windows:
                for e in estimators:
                    t = time.perf_counter()
                    p, _ = correspond.projector_corners(cam_t, maps, correspond.CornerOptions(window=w, estimator=e))
                    hom_time[(w, e)].append(time.perf_counter() - t)
                    hom_err[(w, e)].append(rms(p, proj_t))
            t = time.perf_counter()
            view, _ = pipeline.view_from_stack(stack, ps, Board(10, 6, 24.0))
            full.append((pose, noise, rms(view.cam_pts, cam_t)[0], *rms(view.proj_pts, proj_t),
                         time.perf_counter() - t))
    print(header("correspondences: accuracy against simulator truth (paper preset, 46-image 1280x800 renders)"))
    print(f"poses (psi, nu, phi) in the camera frame: {poses}; read noise (8-bit DN): {noises}\n")
    print("## 1. camera corners: detector and cornerSubPix half-window (RMS px over poses x noise)\n")
    print("| detector | half-window | mean RMS px | worst RMS px | ms per image |")
    print("| --- | --- | --- | --- | --- |")
    for v in det_variants:
        e = np.array(det_err[v], float)
        print(f"| {v[0]} | {v[1]} | {np.nanmean(e):.4f} | {np.nanmax(e):.4f} | {1000 * np.mean(det_time[v]):.0f} |")
    print("\n## 2. projector corners: local-homography window and estimator (true camera corners as input)\n")
    print("| window px | estimator | mean RMS proj px | worst RMS proj px | corners kept | ms per pose |")
    print("| --- | --- | --- | --- | --- | --- |")
    for w in windows:
        for e in estimators:
            r = np.array([x[0] for x in hom_err[(w, e)]])
            kept = sum(x[1] for x in hom_err[(w, e)])
            print(f"| {w} | {e} | {np.nanmean(r):.4f} | {np.nanmax(r):.4f} | {kept}/{60 * len(r)} | "
                  f"{1000 * np.mean(hom_time[(w, e)]):.0f} |")
    print("\n## 3. default pipeline (detect + decode + correspond)\n")
    print("| pose | read noise DN | camera RMS px | projector RMS px | corners | seconds |")
    print("| --- | --- | --- | --- | --- | --- |")
    for pose, noise, ce, pe, n, t in full:
        print(f"| {pose} | {noise} | {ce:.4f} | {pe:.4f} | {n}/60 | {t:.2f} |")


if __name__ == "__main__":
    main()
