"""Metric verification figures on the simulator (the numbers in docs/exports.md).

Board corners of the ``paper`` rig at 5 poses (simulate.correspondences, corner noise sigma px
camera / 2 sigma projector), triangulated with

* the true calibration;
* the true one with f_p 2 % too long;
* f_p 2 % too long with R, T refitted (cv2.stereoCalibrate, intrinsics fixed);
* a multi-pose calibration of the 5 poses, verified in-sample and leave-one-pose-out;

then, per noise seed, the leave-one-out / in-sample ratio of the rigid RMS; and the point cloud of
a rendered pose (640x400 camera): the board's plane fit and the wall's distance to the truth.

Usage::

    python benchmarks/verify.py [--sigma 0.1] [--seeds 6]
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import sys
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from _common import header  # noqa: E402
from sim_small import small_capture, truth_calibration  # noqa: E402

from procam import simulate  # noqa: E402
from procam.board import board_region  # noqa: E402
from procam.calibration import Device  # noqa: E402
from procam.reconstruct import fit_plane, reconstruct  # noqa: E402
from procam.verify import leave_one_out, verify  # noqa: E402
from procam.view import View  # noqa: E402

POSES = [(15, 12, 0), (-10, 20, 5), (20, -15, -5), (5, 25, 10), (-20, -10, 0)]


def views_of(scenes, sigma, seed):
    out = []
    for k, s in enumerate(scenes):
        obj, cam, proj = simulate.correspondences(s, sigma_cam=sigma, sigma_proj=2 * sigma, seed=100 * seed + k)
        out.append(View(obj, cam, proj, f"p{k}", s.cam_size, s.proj_size))
    return out


def row(label, o):
    return (f"| {label} | {o.scale_error_pct:+.3f} % | {o.spacing_rms:.3f} | {o.planarity_rms:.3f} | "
            f"{o.rigid_rms:.3f} | {o.reproj_rms:.3f} px |")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sigma", type=float, default=0.1)
    ap.add_argument("--seeds", type=int, default=6)
    a = ap.parse_args()
    print(header("metric verification on the simulator"))
    sc = simulate.preset("paper")
    scenes = [simulate.with_board_pose(sc, p) for p in POSES]
    truth = truth_calibration(sc)
    views = views_of(scenes, a.sigma, 0)
    Kp = np.array(truth.projector.K, float)
    Kp[:2, :2] *= 1.02
    fp = truth.replace(projector=Device(Kp, truth.projector.image_size))
    objs = [v.obj_pts.astype(np.float32) for v in views]
    cams = [truth.camera.undistort(v.cam_pts).astype(np.float32) for v in views]
    projs = [v.proj_pts.astype(np.float32) for v in views]
    rms, *_, R, T, _, _ = cv2.stereoCalibrate(objs, cams, projs, np.array(truth.camera.K), None, Kp, None,
                                              truth.camera.image_size, flags=cv2.CALIB_FIX_INTRINSIC)
    refit = fp.replace(R=R, T=T.ravel())
    cv = leave_one_out(views)
    print(f"5 poses, corner noise {a.sigma} px camera / {2 * a.sigma} px projector, board 10x6 at 24 mm; "
          "lengths in mm\n")
    print("| calibration | scale error | spacing RMS | planarity RMS | rigid RMS | reproj RMS |")
    print("|---|---|---|---|---|---|")
    print(row("the true one", verify(truth, views).overall))
    print(row("true, but f_p 2 % too long", verify(fp, views).overall))
    print(row(f"f_p 2 % too long, R, T refitted (stereo RMS {rms:.2f} px)", verify(refit, views).overall))
    print(row("multi-pose, in-sample", cv.in_sample.overall))
    print(row("multi-pose, leave-one-pose-out", cv.held_out.overall))
    print("\nleave-one-out vs in-sample, rigid RMS, per noise seed:")
    print("| seed | LOO / in-sample | poses worse out of sample | LOO / true calibration |")
    print("|---|---|---|---|")
    for seed in range(a.seeds):
        vs = views_of(scenes, a.sigma, seed)
        c = leave_one_out(vs)
        worse = np.mean([h.rigid_rms >= i.rigid_rms for i, h in zip(c.in_sample.poses, c.held_out.poses)])
        tr = verify(truth, vs).overall
        print(f"| {seed} | {c.held_out.overall.rigid_rms / c.in_sample.overall.rigid_rms:.3f} | {worse:.0%} | "
              f"{c.held_out.overall.rigid_rms / tr.rigid_rms:.3f} |")

    scene, stack, tr, maps = small_capture()
    cloud = reconstruct(truth_calibration(scene), maps, stack[maps.pattern_set.white])
    corners = np.array(tr["corners"]["camera_distorted"], float)
    on = cloud.image_mask(board_region(corners, scene.cam_size))
    plane = fit_plane(cloud.points[on])
    n_b = scene.R_board[:, 2]
    ang = np.degrees(np.arccos(min(1.0, abs(float(plane.normal @ n_b)))))
    off = ~cloud.image_mask(board_region(corners, scene.cam_size, shrink=-0.6))
    nw, pw = scene.wall_normal, scene.t_board + scene.wall_offset * np.array([0, 0, 1.0])
    dw = (cloud.points[off] - pw) @ nw
    print(f"\nrendered pose (640x400 camera, true calibration): {len(cloud)} points, {np.mean(cloud.both):.1%} from "
          f"column and row")
    print(f"board: {int(on.sum())} points, plane RMS {plane.rms:.3f} mm at {plane.offset:.0f} mm, "
          f"{np.mean(plane.inliers):.1%} inliers, normal {ang:.3f} deg and "
          f"{abs(plane.distance(scene.t_board[None])[0]):.3f} mm from the true plane")
    print(f"wall: {int(off.sum())} points, distance to the true wall median {np.median(dw):+.3f} mm, "
          f"median |d| {np.median(np.abs(dw)):.3f} mm")


if __name__ == "__main__":
    main()
