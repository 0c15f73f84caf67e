"""Single-pose calibration accuracy against the Cramer-Rao bound, and the paper's simulation.

Part 1 (``ideal`` preset: the method's assumptions hold, division distortion k1 = -1e-7): over a grid
of board poses (psi_c, nu_c) in the camera frame, Monte-Carlo RMS of |Delta f_c| for the paper's
staged estimate (COD -> k -> H -> LM) and for the joint refinement, and RMS |Delta f_p|, next to the
Cramer-Rao bound of that pose (:mod:`procam.crlb`, METHOD §13) and their ratio.

Part 2 (``paper`` simulation, METHOD §12): noise-free |Delta f| of the camera with its principal
point fixed at truth + (5, 5) px and no distortion, and of the projector with u0p = W/2, alpha = 1
against a truth of (1013, 1.002), board centred at 500 mm in each device's frame; next to
METHOD §12's expected table.

Usage::

    python benchmarks/single_pose.py                    # --source points, 40 trials per pose
    python benchmarks/single_pose.py --trials 200 --sigma-cam 0.1 --sigma-proj 0.2
    python benchmarks/single_pose.py --source render    # rendered Gray-code captures (needs procam.pipeline)
    python benchmarks/single_pose.py --outliers 3 --skip-paper   # 3 outlier corners per device (3-10 px)
    python benchmarks/single_pose.py --skip-sim --skip-paper --known --trials 200   # camera intrinsics known
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # oversubscribed BLAS slows least_squares on small problems

import argparse
import datetime
import platform
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from procam import board, crlb, models, simulate, single_pose as sp
from procam.errors import ProcamError

GRID = [(5, 5), (10, 10), (20, 5), (20, 20), (30, 5), (30, 30), (15, 12), (-20, 20), (10, 30)]

# METHOD §12 expected noise-free |Delta f| (D = 500 mm)
CAM_SLICE_ANGLES = [-45, -20, -10, -5, -2, 2, 5, 10, 20, 45]
CAM_PSI_SLICE = [12.1, 20.1, 28.4, 43.7, 89.7, 58.9, 15.6, 1.1, 5.8, 6.7]   # (psi_c = a, nu_c = 10)
CAM_NU_SLICE = [28.8, 21.8, 27.8, 41.6, 82.3, 57.3, 13.7, 1.1, 10.2, 29.1]  # (psi_c = 10, nu_c = a)
PROJ_SLICE_ANGLES = [-45, -30, -20, -10, -5, 5, 10, 20, 30, 45]
PROJ_NU_SLICE = [44, 75, 114, 228, 531, 634, 348, 170, 105, 60]               # (psi_p = 10, nu_p = a)
PROJ_PSI_SLICE = [488, 639, 721, 839, 1054, 1054, 839, 721, 639, 488]         # (psi_p = a, nu_p = 3.5)


def _header(args):
    try:
        commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                                cwd=Path(__file__).resolve().parent).stdout.strip()
    except OSError:
        commit = "?"
    print(f"# single-pose benchmark  {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M UTC}  "
          f"commit {commit}  {platform.machine()} {platform.python_version()}  numpy {np.__version__}")
    print(f"# source={args.source} trials={args.trials} sigma_cam={args.sigma_cam} sigma_proj={args.sigma_proj} "
          f"seed={args.seed} outliers={args.outliers} per device (3-10 px; rejection "
          f"{'off' if args.no_reject else 'on'})")


def _displace(o, c, p, n, seed):
    """Move n camera and n projector corners by 3-10 px in random directions (outlier corners)."""
    rng = np.random.default_rng(seed + 7)
    c, p = np.array(c, float), np.array(p, float)
    for pts in (c, p):
        idx = rng.choice(len(o), n, replace=False)
        ang, r = rng.uniform(0, 2 * np.pi, n), rng.uniform(3.0, 10.0, n)
        pts[idx] += np.column_stack([r * np.cos(ang), r * np.sin(ang)])
    return o, c, p


def _observations(scene, args, seed):
    if args.source == "points":
        o, c, p = simulate.correspondences(scene, args.sigma_cam, args.sigma_proj, seed=seed)
        return _displace(o, c, p, args.outliers, seed) if args.outliers else (o, c, p)
    try:
        from procam.patterns import pattern_set
        from procam.board import Board
        from procam.pipeline import view_from_stack
        render = simulate.render
    except (ImportError, AttributeError) as e:
        sys.exit(f"--source render needs procam.simulate.render and procam.pipeline.view_from_stack, which are "
                 f"not available ({e}); use --source points")
    stack, _ = render(scene, order="opencv", seed=seed)
    ps = pattern_set(*scene.proj_size, order="opencv")
    view, _ = view_from_stack(stack, ps, Board(scene.board_cols, scene.board_rows, scene.square),
                              name=f"render-{seed}")
    return view.obj_pts, view.cam_pts, view.proj_pts


def part1(args):
    ideal = simulate.preset("ideal")
    Kc, Kp = np.asarray(ideal.K_cam), np.asarray(ideal.K_proj)
    k1, k2 = ideal.cam_dist_coeffs
    print("\n## Part 1: ideal preset, Monte Carlo RMS error vs Cramer-Rao bound (px)")
    print("staged = the paper's pipeline (cod='paper', refine='none'); joint = procam's default "
          "(cod='auto', refine='joint'); pp from = trials whose principal point came from cod/joint/image-center")
    print("| psi_c, nu_c | nu_p | CRLB f_c | staged f_c | ratio | joint f_c | ratio | CRLB f_p | f_p | ratio "
          "| staged failed | pp from | s/trial |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    ratios = {"staged": [], "joint": [], "proj": []}
    for psi, nu in args.grid:
        scene = simulate.with_board_pose(ideal, (psi, nu, 0.0))
        obj = simulate.correspondences(scene, 0, 0)[0]
        cb = crlb.camera_bound(Kc, None, k1, k2, scene.R_board, scene.t_board, obj, sigma=args.sigma_cam)
        pb = crlb.projector_bound(Kp, scene.R_board_proj, scene.t_board_proj, obj, sigma=args.sigma_proj)
        nu_p = simulate.matrix_euler(scene.R_board_proj)[1]
        e_st, e_j, e_p, fb = [], [], [], {}
        robust = sp.RobustOptions(reject_outliers=not args.no_reject)
        t0 = time.time()
        for trial in range(args.trials):
            o, c, p = _observations(scene, args, args.seed + 1000 * trial)
            try:   # the paper's pipeline: COD always, staged (COD -> k -> H -> LM)
                e_st.append(sp.calibrate_camera(o, c, ideal.cam_size, sp.CameraOptions(cod="paper", refine="none"),
                                                robust=robust).K[0, 0] - Kc[0, 0])
            except ProcamError:
                e_st.append(np.nan)
            try:   # procam's default: cod="auto", joint refinement
                cam = sp.calibrate_camera(o, c, ideal.cam_size, robust=robust)
                e_j.append(cam.K[0, 0] - Kc[0, 0])
                fb[cam.principal_point_source] = fb.get(cam.principal_point_source, 0) + 1
            except ProcamError:
                e_j.append(np.nan)
            try:
                e_p.append(sp.calibrate_projector(o, p, ideal.proj_size, robust=robust).K[0, 0] - Kp[0, 0])
            except ProcamError:
                pass
        dt = (time.time() - t0) / args.trials
        rms = [float(np.sqrt(np.nanmean(np.square(e)))) if e else float("nan") for e in (e_st, e_j, e_p)]
        fails = int(np.sum(np.isnan(e_st)))
        r = [rms[0] / cb.std["f_c"], rms[1] / cb.std["f_c"], rms[2] / pb.std["f_p"]]
        for key, v in zip(("staged", "joint", "proj"), r):
            ratios[key].append(v)
        print(f"| {psi:g}, {nu:g} | {nu_p:.1f} | {cb.std['f_c']:.2f} | {rms[0]:.2f} | {r[0]:.2f} | {rms[1]:.2f} | "
              f"{r[1]:.2f} | {pb.std['f_p']:.2f} | {rms[2]:.2f} | {r[2]:.2f} | {fails} | "
              f"{fb.get('cod', 0)}/{fb.get('joint', 0)}/{fb.get('image-center', 0)} | {dt:.2f} |")
    med = {k: float(np.nanmedian(v)) for k, v in ratios.items()}
    print(f"\nmedian ratio to the CRLB: staged camera {med['staged']:.2f}, joint camera {med['joint']:.2f}, "
          f"projector {med['proj']:.2f}  (paper pipeline ~1.5 for the camera; goal <= 1.2)")


def _device_pose(angles):
    return models.euler_to_matrix(*np.radians([angles[0], angles[1], 0.0])), np.array([0.0, 0.0, 500.0])


def part2():
    paper = simulate.preset("paper")
    Kc, Kp = np.asarray(paper.K_cam), np.asarray(paper.K_proj)
    obj = board.object_points(paper.board_cols, paper.board_rows, paper.square)
    pp = (Kc[0, 2] + 5.0, Kc[1, 2] + 5.0)
    print("\n## Part 2: paper simulation (METHOD §12), noise-free |Delta f| (px): ours / METHOD's table")

    def cam_row(label, angles_list, expected):
        cells = []
        for a, ex in zip(angles_list, expected):
            R, t = _device_pose(a)
            m = models.project(Kc, R, t, obj)
            f = sp.calibrate_camera(obj, m, paper.cam_size, sp.CameraOptions(principal_point=pp, distortion=None)).K[0, 0]
            cells.append(f"{abs(f - Kc[0, 0]):.1f}/{ex:g}")
        print(f"| {label} | " + " | ".join(cells) + " |")

    def proj_row(label, angles_list, expected):
        cells = []
        for a, ex in zip(angles_list, expected):
            R, t = _device_pose(a)
            m = models.project(Kp, R, t, obj)
            try:
                f = sp.calibrate_projector(obj, m, paper.proj_size).K[0, 0]
                cells.append(f"{abs(f - Kp[0, 0]):.0f}/{ex:g}")
            except ProcamError:
                cells.append(f"fail/{ex:g}")
        print(f"| {label} | " + " | ".join(cells) + " |")

    print("| camera, angle = | " + " | ".join(str(a) for a in CAM_SLICE_ANGLES) + " |")
    print("|---" * (len(CAM_SLICE_ANGLES) + 1) + "|")
    cam_row("psi_c = a, nu_c = 10", [(a, 10) for a in CAM_SLICE_ANGLES], CAM_PSI_SLICE)
    cam_row("psi_c = 10, nu_c = a", [(10, a) for a in CAM_SLICE_ANGLES], CAM_NU_SLICE)
    print("\n| projector, angle = | " + " | ".join(str(a) for a in PROJ_SLICE_ANGLES) + " |")
    print("|---" * (len(PROJ_SLICE_ANGLES) + 1) + "|")
    proj_row("psi_p = 10, nu_p = a", [(10, a) for a in PROJ_SLICE_ANGLES], PROJ_NU_SLICE)
    proj_row("psi_p = a, nu_p = 3.5", [(a, 3.5) for a in PROJ_SLICE_ANGLES], PROJ_PSI_SLICE)


REAL_REFERENCE = {"left": (536.11, 536.11, 342.37, 235.60), "right": (542.36, 541.62, 328.32, 246.95)}


def part3(folder):
    """Camera-only single-pose calibration of each OpenCV sample photo vs its 13-photo reference."""
    import cv2

    folder = Path(folder)
    paths = sorted(folder.glob("*.jpg"))
    if not paths:
        print(f"\n(no photos in {folder}; part 3 skipped)")
        return
    obj = board.object_points(9, 6, 25.0)
    print(f"\n## Part 3: real photos ({folder.name}), one photo each; reference fx = "
          f"{REAL_REFERENCE['left'][0]} (left), {REAL_REFERENCE['right'][0]} (right)")
    print("| image | psi_c, nu_c | s8/s9 | pp from | f_c joint +- std | dev % | f_c staged (refine=none) | dev % "
          "| pp (u0, v0) | rms px | advice |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    devs = {"joint": [], "staged": [], "joint_ok": []}
    for path in paths:
        img = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
        ok, c = cv2.findChessboardCorners(img, (9, 6))
        if not ok:
            print(f"| {path.name} | board not found |")
            continue
        c = cv2.cornerSubPix(img, c, (11, 11), (-1, -1),
                             (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 30, 0.01)).reshape(-1, 2)
        fx = REAL_REFERENCE["left" if path.name.startswith("left") else "right"][0]
        cal = sp.calibrate_camera_only(obj, c, (img.shape[1], img.shape[0]), name=path.name)
        cam = cal.info["camera"]
        f, fs = cal.camera.K[0, 0], cam.staged["f"]
        adv = cal.poses[0]["advice"]["camera"]
        tag = "degenerate" if adv["degenerate"] else "weak" if adv["weak"] else "ok"
        d, ds = 100 * (f - fx) / fx, 100 * (fs - fx) / fx
        devs["joint"].append(abs(d))
        devs["staged"].append(abs(ds))
        if tag == "ok":
            devs["joint_ok"].append(abs(d))
        a = cam.angles_deg
        print(f"| {path.name} | {a[0]:.1f}, {a[1]:.1f} | {cam.cod.score:.1f} | {cam.principal_point_source} | "
              f"{f:.1f} +- {cal.std['f_c']:.1f} | {d:+.1f} | {fs:.1f} | {ds:+.1f} | "
              f"({cal.camera.K[0, 2]:.0f}, {cal.camera.K[1, 2]:.0f}) | {cam.rms_px:.2f} | {tag} |")
    print(f"\nmedian |dev|: joint {np.median(devs['joint']):.1f} %, staged {np.median(devs['staged']):.1f} %, "
          f"joint on poses advised ok {np.median(devs['joint_ok']) if devs['joint_ok'] else float('nan'):.1f} % "
          f"({len(devs['joint_ok'])} of {len(devs['joint'])})")


def part4(args):
    """Known camera intrinsics (``single_pose.calibrate(known_camera=...)``): Monte-Carlo std of f_p and T
    against the Cramer-Rao bound of that case, and against the same poses with the camera estimated."""
    import warnings

    from procam.calibration import Device, Distortion
    from procam.errors import ProcamWarning
    from procam.view import View

    print("\n## Part 4: known camera intrinsics ('ideal' rig; Monte-Carlo std over "
          f"{args.trials} trials, sigma {args.sigma_cam} / {args.sigma_proj} px)\n")
    print("| pose (camera) | | f_p std | T std (x, y, z) | T bias (x, y, z) |")
    print("|---|---|---|---|---|")
    for pose in args.known_grid:
        sc = simulate.with_board_pose(simulate.preset("ideal"), pose)
        dev = Device(np.array(sc.K_cam), sc.cam_size, Distortion("division", tuple(sc.cam_center), *sc.cam_dist_coeffs))
        obj = simulate.board_corners(sc)
        cb = crlb.camera_bound(sc.K_cam, None, sc.cam_dist_coeffs[0], 0.0, sc.R_board, sc.t_board, obj,
                               args.sigma_cam, "known_intrinsics")
        pb = crlb.projector_bound(sc.K_proj, sc.R_board_proj, sc.t_board_proj, obj, args.sigma_proj)
        eb = crlb.extrinsics_bound(cb, pb, sc.R_board, sc.t_board, sc.R_board_proj, sc.t_board_proj)
        rows = {"known": [], "free": []}
        for k in range(args.trials):
            o, c, p = simulate.correspondences(sc, args.sigma_cam, args.sigma_proj, args.seed + 1000 + k)
            v = View(o, c, p, "s", sc.cam_size, sc.proj_size)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", ProcamWarning)
                for key, kw in (("known", {"known_camera": dev}), ("free", {})):
                    try:
                        cal = sp.calibrate(v, **kw)
                    except ProcamError:
                        continue
                    rows[key].append(np.r_[cal.projector.K[0, 0] - sc.K_proj[0, 0], cal.T - sc.T])
        def fmt3(a):
            return ", ".join(f"{x:.2f}" for x in a)
        print(f"| {pose} | bound (camera known) | {pb.std['f_p']:.2f} | {fmt3(eb.T)} | |")
        for key, label in (("known", "camera known"), ("free", "camera from the same pose")):
            e = np.array(rows[key])
            if len(e) < 2:
                print(f"| | {label} | failed | | |")
                continue
            print(f"| | {label} ({len(e)} runs) | {e[:, 0].std():.2f} | {fmt3(e[:, 1:].std(axis=0))} | "
                  f"{fmt3(e[:, 1:].mean(axis=0))} |")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--source", choices=("points", "render"), default="points")
    ap.add_argument("--trials", type=int, default=40)
    ap.add_argument("--sigma-cam", type=float, default=0.1)
    ap.add_argument("--sigma-proj", type=float, default=0.2)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--outliers", type=int, default=0,
                    help="part 1 (points): displace this many camera and projector corners by 3-10 px per trial")
    ap.add_argument("--no-reject", action="store_true", help="part 1: turn the outlier rejection off")
    ap.add_argument("--grid", type=str, default=None, help="poses 'psi,nu;psi,nu;...' in degrees (camera frame)")
    ap.add_argument("--skip-paper", action="store_true", help="skip part 2")
    ap.add_argument("--skip-sim", action="store_true", help="skip part 1")
    ap.add_argument("--known", action="store_true", help="part 4: known camera intrinsics against their bound")
    ap.add_argument("--real", type=str, default=None,
                    help="folder of the OpenCV left/right sample photos (part 3), "
                         "e.g. ../shared/data/opencv-left-right")
    args = ap.parse_args(argv)
    args.grid = [tuple(float(v) for v in c.split(",")) for c in args.grid.split(";")] if args.grid else GRID
    _header(args)
    if not args.skip_sim:
        part1(args)
    if not args.skip_paper:
        part2()
    if args.real:
        part3(args.real)
    if args.known:
        args.known_grid = [simulate.RECOMMENDED_POSE, (20.0, 20.0, 0.0), (10.0, 30.0, 0.0)]
        part4(args)


if __name__ == "__main__":
    main()
