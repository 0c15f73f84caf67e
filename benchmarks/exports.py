"""Exports for projection mapping against the simulator's truth: the engines' projections, the rectification of
any rig orientation, the datasheet numbers of a lens-shifted projector, the projector's view (accuracy and time).

    python benchmarks/exports.py [--seeds 4]

Engines: the board's corners projected through each engine's camera vs the calibration's pinhole part (largest gap
over both devices, both worlds); Blender through Blender itself when its module is installed (``.[blender]``).
Rectification: a multi-pose calibration of five noisy poses (corner fast path, 0.1 / 0.2 px), the true corners'
rectified rows (largest disagreement) and the share of the board inside both rectified images.  Datasheet: the
``lensshift`` projector from such calibrations, the largest |error| / ± over the numbers, per seed.  Projector's
view: the small 640x400 render (tests/sim_small.py), corner error of the view against the true projector corners
and the time of ``projector_view``.
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from _common import header  # noqa: E402

POSES = [(15, 12, 0), (-10, 20, 5), (20, -15, -5), (5, 25, 10), (-20, -10, 0)]
RIGS = ("paper", "vertical", "ceiling", "lensshift")


def calibrated(preset, seed):
    from procam import multi_pose, simulate
    from procam.view import View

    sc = simulate.preset(preset)
    views = []
    for k, p in enumerate(POSES):
        s = simulate.with_board_pose(sc, p)
        obj, cam, proj = simulate.correspondences(s, 0.1, 0.2, seed=100 * seed + k)
        views.append(View(obj, cam, proj, f"p{k}", s.cam_size, s.proj_size))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return sc, multi_pose.calibrate(views)


def engines_table():
    from procam import models, simulate
    from procam.export import blender, opengl, unity

    try:
        import bpy  # noqa: F401
        have_bpy = True
    except ImportError:
        have_bpy = False
    print("| rig | Blender (view-plane equations) | Blender (bpy) | Unity (projectionMatrix, transform) | OpenGL |")
    print("|---|---|---|---|---|")
    for rig in RIGS:
        sc = simulate.preset(rig)
        calib = simulate.truth_calibration(sc, approximate=True)
        c = simulate.corner_truth(sc)
        Xc = c["board"] @ np.asarray(sc.R_board).T + sc.t_board
        h = np.column_stack([Xc, np.ones(len(Xc))])
        ref = {"camera": models.project(calib.camera.K, np.eye(3), np.zeros(3), Xc),
               "projector": models.project(calib.projector.K, calib.R, calib.T, Xc)}
        gaps = {"bl": 0.0, "bpy": float("nan"), "un": 0.0, "gl": 0.0}
        for world in ("camera", "projector"):
            bdoc = blender.blender_document(calib, world=world)
            Xb = (np.array(bdoc["world_from_camera"]) @ h.T).T[:, :3]
            gdoc = opengl.opengl_document(calib, 10.0, 1e5, world=world)
            Xw = Xc if world == "camera" else Xc @ np.asarray(calib.R).T + np.asarray(calib.T)
            hw = np.column_stack([Xw, np.ones(len(Xw))])
            udoc = unity.unity_document(calib, world=world)
            L = np.array(udoc["camera"]["transform"]["localToWorldMatrix"])
            Xu = (L @ np.column_stack([1e-3 * Xc * [1, -1, 1], np.ones(len(Xc))]).T).T
            for name, dev in (("camera", calib.camera), ("projector", calib.projector)):
                W, H = dev.image_size
                d = bdoc["devices"][name]
                local = (np.linalg.inv(np.array(d["matrix_world"])) @ np.column_stack([Xb, np.ones(len(Xb))]).T).T
                fac = d["data"]["lens"] / d["data"]["sensor_width"] * W
                ycor = d["render"]["pixel_aspect_y"] / d["render"]["pixel_aspect_x"]
                x = local[:, 0] / -local[:, 2] * fac + 0.5 * W - d["data"]["shift_x"] * W - 0.5
                y = (0.5 * ycor * H + d["data"]["shift_y"] * W - local[:, 1] / -local[:, 2] * fac) / ycor - 0.5
                gaps["bl"] = max(gaps["bl"], np.abs(np.column_stack([x, y]) - ref[name]).max())
                P, V = np.array(gdoc[name]["projection"]), np.array(gdoc[name]["view"])
                pix, _ = opengl.clip_to_pixels((P @ V @ hw.T).T, dev.image_size)
                gaps["gl"] = max(gaps["gl"], np.abs(pix - ref[name]).max())
                u = udoc[name]
                clip = (np.array(u["projectionMatrix"]) @ np.diag([1.0, 1, -1, 1])
                        @ np.linalg.inv(np.array(u["transform"]["localToWorldMatrix"])) @ Xu.T).T
                pix, _ = opengl.clip_to_pixels(clip, dev.image_size)
                gaps["un"] = max(gaps["un"], np.abs(pix - ref[name]).max())
            if have_bpy:
                gaps["bpy"] = max(0.0 if np.isnan(gaps["bpy"]) else gaps["bpy"], bpy_gap(calib, bdoc, Xc, Xb, ref))
        print(f"| {rig} | {gaps['bl']:.1e} px | " + ("not installed" if not have_bpy else f"{gaps['bpy']:.1e} px")
              + f" | {gaps['un']:.1e} px | {gaps['gl']:.1e} px |")


def bpy_gap(calib, doc, Xc, Xb, ref):
    import bpy
    import mathutils
    from bpy_extras.object_utils import world_to_camera_view

    from procam.export import blender_cameras

    objs = blender_cameras.create_cameras(doc)
    gap = 0.0
    for name in ("camera", "projector"):
        blender_cameras.use_device(doc, name)
        W, H = getattr(calib, name).image_size
        uv = np.array([tuple(world_to_camera_view(bpy.context.scene, objs[name], mathutils.Vector(p)))[:2]
                       for p in Xb])
        pix = np.column_stack([uv[:, 0] * W - 0.5, (1 - uv[:, 1]) * H - 0.5])
        gap = max(gap, np.abs(pix - ref[name]).max())
    return gap


def rectify_table(seeds):
    from procam import simulate
    from procam.export.rectify import stereo_rectify

    def rectified(dev, pts, R, P):
        und = dev.undistort(pts)
        ray = np.column_stack([und, np.ones(len(und))]) @ np.linalg.inv(dev.K).T @ R.T
        hh = ray @ P[:, :3].T
        return hh[:, :2] / hh[:, 2:3]

    def inside(p, size):
        return (p[:, 0] >= -0.5) & (p[:, 0] <= size[0] - 0.5) & (p[:, 1] >= -0.5) & (p[:, 1] <= size[1] - 0.5)

    print("\n| rig | rows disagree (max over seeds) | board inside both (min) | rows run at (camera, projector) |")
    print("|---|---|---|---|")
    for rig in RIGS:
        worst, frac, turn = 0.0, 1.0, None
        c = simulate.corner_truth(simulate.preset(rig))
        for seed in range(seeds):
            _, calib = calibrated(rig, seed)
            r = stereo_rectify(calib)
            rc = rectified(calib.camera, c["camera_distorted"], r["R1"], r["P1"])
            rp = rectified(calib.projector, c["projector"], r["R2"], r["P2"])
            worst = max(worst, np.abs(rc[:, 1] - rp[:, 1]).max())
            frac = min(frac, float((inside(rc, r["size1"]) & inside(rp, r["size2"])).mean()))
            turn = r["rows_along_deg"]
        print(f"| {rig} | {worst:.3f} px | {frac:.0%} | {turn['camera']:+.0f}°, {turn['projector']:+.0f}° |")


def datasheet_table(seeds):
    from procam import datasheet, simulate

    sc = simulate.preset("lensshift")
    truth = datasheet.datasheet_view(sc.K_proj, sc.proj_size)
    keys = ("throw_ratio", "shift_h_pct", "shift_v_pct", "fov_h_deg", "fov_v_deg")
    print("\nlensshift projector truth: " + ", ".join(f"{k} {getattr(truth, k):.4f}" for k in keys))
    print("| seed | " + " | ".join(f"{k} (err / ±)" for k in keys) + " |")
    print("|---" * (len(keys) + 1) + "|")
    for seed in range(seeds):
        _, calib = calibrated("lensshift", seed)
        got = datasheet.calibration_datasheet(calib)
        print(f"| {seed} | " + " | ".join(f"{getattr(got, k) - getattr(truth, k):+.4f} / {got.std[k]:.4f}"
                                          for k in keys) + " |")


def projector_view_table():
    from procam.board.corners import detect_corners
    from procam.export.projector_view import projector_view
    from sim_small import small_capture

    sc, stack, truth, maps = small_capture()
    white = stack[maps.pattern_set.white]
    t0 = time.perf_counter()
    pv = projector_view(maps.col, maps.row, maps.valid_col & maps.valid_row, white, sc.proj_size)
    dt = time.perf_counter() - t0
    found = detect_corners(pv.image, (10, 6))
    err = np.hypot(*(found - np.array(truth["corners"]["projector"])).T)
    print(f"\nprojector's view (640x400 camera -> 1920x1080 projector): {dt:.2f} s, mask {pv.coverage:.0%} of the "
          f"projector, closing {pv.close_px} px; corners in the view vs truth: RMS "
          f"{np.sqrt(np.mean(err ** 2)):.3f} px, max {err.max():.3f} px")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=4)
    args = ap.parse_args()
    print(header("exports for projection mapping (benchmarks/exports.py)"))
    engines_table()
    rectify_table(args.seeds)
    datasheet_table(args.seeds)
    projector_view_table()


if __name__ == "__main__":
    main()
