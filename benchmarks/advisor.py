"""Benchmark: the live pose advisor's speed, and its accuracy against the simulator.

1. ``speed``: frames per second and latency of :meth:`procam.advisor.Advisor.update` (board detection on a
   downscaled frame, PnP, the Cramer-Rao bounds, the move search when it has to run) on rendered white
   frames of the ``ideal`` rig at 1280x800 and 1920x1080 (camera intrinsics scaled), with the projector side
   known (the rig's truth), frames timed as from a 15 fps camera.  Two runs per size: the board turning
   through poses the advisor wants changed (the search runs), and the board still at a good pose.  With
   pygame-ce installed also the preview's drawing time (off-screen, window size <= 1280x800).
2. ``angles``: nu_p (and psi_p) of the advisor, from an earlier capture's single-pose calibration (a
   rendered capture at the recommended pose), against the truth, over the paper's grid of board poses in the
   projector frame (psi_p, nu_p in -45..45 deg, ``--step``); poses the rig cannot show whole are skipped.
3. ``session``: scripted sessions on the virtual procam from poses with nu_p ~ 0 (and one with psi_c ~ 0): the
   script turns and tilts the simulated board as each JSON advice says until the advice is good, holds it
   still until ready, then the pose is rendered in full, decoded and calibrated (single-pose): steps, and
   |f - truth| against the std the advisor predicted.
4. ``stds``: the advisor's predicted std of f_c and f_p at poses of that grid (``--mc-step``) against the
   spread of ``--trials`` single-pose calibrations of the same pose from corners with the assumed noise
   (0.1 px camera, 0.2 px projector; ``procam.simulate.correspondences`` + ``single_pose.calibrate_camera`` /
   ``calibrate_projector``), where the bound is below 5 % of f (near a degenerate angle the estimate is not
   Gaussian and the bound says only "large").

    python benchmarks/advisor.py                       # all four parts, 15-degree grids, 100 trials (~30 min)
    python benchmarks/advisor.py --part speed
    python benchmarks/advisor.py --part angles --step 5
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import header  # noqa: E402

from procam import models, patterns, pipeline, simulate, single_pose  # noqa: E402
from procam.acquire.cameras import VirtualLiveCamera  # noqa: E402
from procam.advisor import Advisor, AdvisorOptions, apply_move  # noqa: E402
from procam.board import Board  # noqa: E402
from procam.calibration import Calibration, Device, Distortion  # noqa: E402

BOARD = Board(10, 6, 24.0)


def _scene(size):
    """The ideal rig with a camera of ``size`` (same horizontal field of view, the principal point moved with
    the image centre, the division coefficient scaled with the pixel size)."""
    s = simulate.preset("ideal")
    w, h = size
    k = w / s.cam_size[0]
    K = np.array(s.K_cam, float)
    K[0, 0] *= k
    K[1, 1] *= k
    K[0, 2] = K[0, 2] * k
    K[1, 2] = h / 2 + (K[1, 2] - s.cam_size[1] / 2) * k
    s = s.replace(cam_size=(w, h), K_cam=K, cam_dist_coeffs=(s.cam_dist_coeffs[0] / k ** 2, 0.0))
    return simulate.with_board_pose(s, simulate.RECOMMENDED_POSE)


def _truth_calibration(s) -> Calibration:
    return Calibration(camera=Device(s.K_cam, s.cam_size, Distortion("division", tuple(s.cam_center),
                                                                     *s.cam_dist_coeffs)),
                       projector=Device(s.K_proj, s.proj_size), R=s.R, T=s.T, method="truth")


def _stats(ms) -> str:
    ms = np.asarray(ms)
    return f"{np.median(ms):.1f} | {np.percentile(ms, 90):.1f} | {ms.max():.1f}"


def speed(frames_per_pose: int = 6) -> None:
    print("## speed: Advisor.update per frame (ms), frames timed as from a 15 fps camera (default options)")
    print("| camera | board | frames | detect median ms | update median ms | p90 ms | max ms | advisor fps | "
          "draw median ms | fps with preview |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    try:
        os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
        import pygame  # noqa: F401

        from procam.acquire.preview import PreviewWindow
    except ImportError:
        PreviewWindow = None
    for size in ((1280, 800), (1920, 1080)):
        s = _scene(size)
        runs = {}
        # the board turning 1.5 deg per pose from a pose the advisor wants changed (nu_p = 4 deg), and still
        start = simulate.with_board_pose(s, (12.0, 4.0, 0.0), frame="projector")
        cam = VirtualLiveCamera(start, seed=1)
        moving = []
        for k in range(10):
            R, t = apply_move(start.R_board, start.t_board, turn_deg=-1.5 * k)
            cam.set_board(R, t)
            moving += [cam.grab().image for _ in range(frames_per_pose)]
        runs["turning"] = moving
        cam.set_scene(simulate.with_board_pose(s, (25.0, 25.0, 0.0), frame="projector"))
        runs["still, good"] = [cam.grab().image for _ in range(frames_per_pose * 10)]
        for name, frames in runs.items():
            adv = Advisor(BOARD, size, AdvisorOptions())
            adv.set_calibration(_truth_calibration(s), "the rig's truth")
            win = PreviewWindow(size) if PreviewWindow is not None else None
            upd, det, draw, states = [], [], [], []
            for i, img in enumerate(frames):
                t0 = time.perf_counter()
                a = adv.update(img, i / 15.0)
                upd.append(1000 * (time.perf_counter() - t0))
                det.append(a.timings_ms["detect"])
                states.append(a.state)
                if win is not None:
                    t0 = time.perf_counter()
                    win.render_offscreen(img, a)
                    draw.append(1000 * (time.perf_counter() - t0))
            fps = 1000 * len(upd) / np.sum(upd)
            d = f"{np.median(draw):.1f} | {1000 * len(upd) / (np.sum(upd) + np.sum(draw)):.1f}" if draw else "- | -"
            print(f"| {size[0]}x{size[1]} | {name} ({states.count('adjust')} adjust, "
                  f"{len(states) - states.count('adjust')} good) | {len(frames)} | {np.median(det):.1f} | "
                  f"{_stats(upd)} | {fps:.1f} | {d} |")
    print()


def _earlier_calibration(s):
    stack, _ = simulate.render(s.replace(supersample=1), seed=1)
    view, _ = pipeline.view_from_stack(stack, patterns.pattern_set(*s.proj_size), BOARD, name="pose01")
    return single_pose.calibrate(view)


def _grid_poses(s, step, limit=45.0):
    """(angles, scene) over the grid in the projector frame; poses the rig cannot show whole are skipped."""
    out, skipped = [], 0
    grid = np.arange(-limit, limit + 1e-9, step)
    for psi in grid:
        for nu in grid:
            sc = simulate.with_board_pose(s, (psi, nu, 0.0), frame="projector")
            if simulate.fit_margin(sc) < 0:
                skipped += 1
                continue
            out.append(((psi, nu), sc))
    return out, skipped


def angles(step: float) -> None:
    s = simulate.preset("ideal")
    calib = _earlier_calibration(s)
    print(f"## angles: nu_p, psi_p from an earlier capture's R, T (single-pose at the recommended pose: "
          f"R Euler {np.round(models.euler_deg(calib.R), 2).tolist()} deg, truth "
          f"{np.round(models.euler_deg(s.R), 2).tolist()})")
    poses, skipped = _grid_poses(s, step)
    adv = Advisor(BOARD, s.cam_size, AdvisorOptions(search_interval_s=60.0, search_refresh_s=3600.0))
    adv.set_calibration(calib, "pose01")
    cam = VirtualLiveCamera(s, seed=2)
    dnu, dpsi, lost = [], [], 0
    worst = (0.0, None)
    for (psi, nu), sc in poses:
        cam.set_scene(sc)
        a = adv.update(cam.grab().image, 0.0)
        if a.projector is None:
            lost += 1
            continue
        true = models.board_angles_deg(sc.R_board_proj, sc.t_board_proj)
        dn, dp = a.projector.angles_deg[1] - true[1], a.projector.angles_deg[0] - true[0]
        dnu.append(dn)
        dpsi.append(dp)
        if abs(dn) > abs(worst[0]):
            worst = (dn, (float(psi), float(nu)))
    dnu, dpsi = np.abs(dnu), np.abs(dpsi)
    print(f"grid psi_p, nu_p in -45..45 step {step:g} deg: {len(poses)} poses shown whole ({skipped} skipped: the rig "
          f"cannot show them whole), board found in {len(dnu)} ({lost} not found)")
    print("| | median | p95 | max | within 1 deg |\n|---|---|---|---|---|")
    for name, d in (("|nu_p error| deg", dnu), ("|psi_p error| deg", dpsi)):
        print(f"| {name} | {np.median(d):.3f} | {np.percentile(d, 95):.3f} | {d.max():.3f} | "
              f"{np.mean(d < 1.0):.1%} |")
    print(f"largest nu_p error {worst[0]:+.3f} deg at psi_p, nu_p = {worst[1]}\n")


def session() -> None:
    import json

    s = simulate.preset("ideal")
    calib = _earlier_calibration(s)
    print("## session: follow the JSON advice from a degenerate pose (earlier capture's calibration known)")
    print("| start (psi_p, nu_p) | start advice | steps to good | frames to ready | final psi_c, nu_c, nu_p | "
          "f_c error / predicted std | f_p error / predicted std |")
    print("|---|---|---|---|---|---|---|")
    for start in ((12.0, 0.5), (-10.0, 1.0), (20.0, -0.5), (0.0, 0.0), (25.0, 2.0)):
        sc = simulate.with_board_pose(s, (*start, 0.0), frame="projector")
        cam = VirtualLiveCamera(sc, seed=7)
        adv = Advisor(BOARD, s.cam_size, AdvisorOptions())
        adv.set_calibration(calib, "pose01")
        t, first, steps = 0.0, None, None
        for k in range(8):
            d = json.loads(adv.update(cam.grab().image, t).to_json())
            t += 1 / 15
            first = first or d["message"]
            if d["state"] in ("good", "ready"):
                steps = k
                break
            turn = sum(a["degrees"] for a in d["actions"] if a["kind"] == "turn")
            tilt = sum(a["degrees"] for a in d["actions"] if a["kind"] == "tilt")
            cam.move(turn, tilt)
        if steps is None:
            print(f"| {start} | {first} | not within 8 | - | - | - | - |")
            continue
        for n in range(1, 30):
            a = adv.update(cam.grab().image, t)
            t += 1 / 15
            if a.ready:
                break
        fs = cam.scene
        stack, _ = simulate.render(fs, seed=11)
        c = single_pose.calibrate(pipeline.view_from_stack(stack, patterns.pattern_set(*fs.proj_size), BOARD)[0])
        ec, ep = c.camera.K[0, 0] - fs.K_cam[0, 0], c.projector.K[0, 0] - fs.K_proj[0, 0]
        print(f"| {start} | {first} | {steps} | {n} | {a.camera.angles_deg[0]:.1f}, {a.camera.angles_deg[1]:.1f}, "
              f"{a.projector.angles_deg[1]:.1f} | {ec:+.2f} / {a.camera.std_f:.2f} px "
              f"({abs(ec) / a.camera.std_f:.2f}) | "
              f"{ep:+.2f} / {a.projector.std_f:.2f} px ({abs(ep) / a.projector.std_f:.2f}) |")
    print()


def stds(step: float, trials: int, limit: float) -> None:
    s = simulate.preset("ideal")
    calib = _earlier_calibration(s)
    poses, _ = _grid_poses(s, step, limit)
    adv = Advisor(BOARD, s.cam_size, AdvisorOptions(search_interval_s=60.0, search_refresh_s=3600.0))
    adv.set_calibration(calib, "pose01")
    cam = VirtualLiveCamera(s, seed=3)
    print(f"## stds: predicted std (advisor, one frame) vs Monte Carlo of {trials} single-pose calibrations "
          f"(noise 0.1 px camera, 0.2 px projector), psi_p, nu_p in -{limit:g}..{limit:g} step {step:g} deg, where "
          "the bound < 5 % of f")
    print("| psi_p | nu_p | psi_c | nu_c | f_c: predicted | MC | ratio | f_p: predicted | MC | ratio |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    ratios = {"f_c": [], "f_p": []}
    rule_ok = {"f_c": [], "f_p": []}   # the pose passes the camera rule's minimum angle (the advisor's domain)
    for i, ((psi, nu), sc) in enumerate(poses):
        cam.set_scene(sc)
        a = adv.update(cam.grab().image, 0.0)
        if a.projector is None:
            continue
        use_c = a.camera.rel_std_f < 0.05
        use_p = a.projector.rel_std_f < 0.05
        if not (use_c or use_p):
            continue
        fc, fp = [], []
        for k in range(trials):
            obj, c, p = simulate.correspondences(sc, 0.1, 0.2, seed=10_000 + 1000 * i + k)  # new draws per pose
            if use_c:
                try:
                    fc.append(single_pose.calibrate_camera(obj, c, sc.cam_size).K[0, 0])
                except Exception:  # a failed trial counts as missing
                    pass
            if use_p:
                fp.append(single_pose.calibrate_projector(obj, p, sc.proj_size).K[0, 0])
        cells = []
        for key, use, st, f in (("f_c", use_c, a.camera, fc), ("f_p", use_p, a.projector, fp)):
            if use and len(f) > 10:
                mc = float(np.std(f, ddof=1))
                ratios[key].append(st.std_f / mc)
                rule_ok[key].append(min(abs(a.camera.angles_deg[0]), abs(a.camera.angles_deg[1]))
                                    >= adv.options.rating.weak_angle_deg)
                cells.append(f"{st.std_f:.2f} | {mc:.2f} | {st.std_f / mc:.2f}")
            else:
                cells.append(f"{st.std_f:.3g} | - | -")
        ca = a.camera.angles_deg
        print(f"| {psi:g} | {nu:g} | {ca[0]:.1f} | {ca[1]:.1f} | {cells[0]} | {cells[1]} |")
    for key, r in ratios.items():
        r, ok = np.array(r), np.array(rule_ok[key], bool)
        for label, sel in (("all", np.ones(r.size, bool)), ("camera angles >= the rule's 4 deg", ok)):
            if sel.any():
                q = r[sel]
                print(f"\n{key} ({label}): predicted / Monte Carlo over {q.size} poses: median {np.median(q):.3f}, "
                      f"range {q.min():.3f} .. {q.max():.3f}; within 20 %: {np.mean(np.abs(q - 1) <= 0.2):.0%}")
    print()


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--part", choices=("speed", "angles", "session", "stds", "all"), default="all")
    ap.add_argument("--step", type=float, default=15.0, help="angles: grid step (deg)")
    ap.add_argument("--mc-step", type=float, default=15.0, help="stds: grid step (deg)")
    ap.add_argument("--mc-max", type=float, default=30.0, help="stds: largest |angle| of the grid (deg)")
    ap.add_argument("--trials", type=int, default=100, help="stds: Monte-Carlo trials per pose")
    args = ap.parse_args()
    print(header("procam advise: the live pose advisor's speed and accuracy (virtual procam, ideal rig)"))
    print(f"load average: {os.getloadavg()[0]:.2f}\n")
    if args.part in ("speed", "all"):
        speed()
    if args.part in ("angles", "all"):
        angles(args.step)
    if args.part in ("session", "all"):
        session()
    if args.part in ("stds", "all"):
        stds(args.mc_step, args.trials, args.mc_max)


if __name__ == "__main__":
    main()
