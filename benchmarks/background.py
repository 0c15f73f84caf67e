"""The background behind the board: the check and the refinement of the single-pose projector model.

Rendered Gray-code captures (1280x800 camera, 1920x1080 projector, the simulator's wall 300 mm behind
the board) of two rigs at several board poses:

* ``paper``: u0p = 1013, alpha_p = 1.002 -- the single-pose assumptions (u0p = W/2 = 960, alpha_p = 1)
  are wrong by 53 px;
* ``ideal``: u0p = 960, alpha_p = 1 -- they hold.

Every pose goes through the pipeline (decode, corners, background points), the paper's single-pose
method (no background), then :mod:`procam.single_pose.background`. Tables:

1. the check at every pose: the true u0p error of the assumption, the check's verdict, the size of the
   disagreement (median / 90th percentile distance of the background to its epipolar lines under the
   paper's calibration, projector px), the likelihood ratio against its threshold, and where the
   background puts u0p (error against the truth +- 1 sigma);
2. f_p, u0p and f_c errors against the truth without the background (the paper's method) and with it
   (``free``, the default: always lifted when the background is informative; ``auto``: kept when the
   check finds them consistent, lifted otherwise), with the reported 1 sigma;
3. the metric check (:mod:`procam.verify`) on held-out poses: each pose's single-pose calibration
   triangulates every OTHER pose's corners; scale error, rigid RMS, reprojection RMS pooled over all
   ordered pairs -- for the paper's method, + the background, + dense board points (an experiment kept
   in this script: the decoded board pixels replace the 60 projector corners in the joint fit), and the
   multi-pose leave-one-pose-out calibration of the same poses it is compared with.

Renders are cached (``--cache``, default a folder in the system's temp directory).

Usage::

    python benchmarks/background.py [--poses 8] [--cache DIR] [--no-dense]
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import header  # noqa: E402

from procam.single_pose import background as bg  # noqa: E402
from procam import patterns, pipeline, simulate, single_pose, verify  # noqa: E402
from procam.single_pose.background_fit import PaperFits  # noqa: E402
from procam.board import Board, board_region  # noqa: E402
from procam.errors import ProcamError  # noqa: E402

#: Board (psi, nu, phi) in the camera frame; the rig turns the projector by ~14 deg about y, so nu_p ~ nu_c + 14.
POSES = [(15, 12, 0), (-10, 20, 5), (20, -15, -5), (5, 25, 10), (-20, -10, 0), (10, 30, 0), (-15, 5, -5),
         (25, 20, 5)]
OFF = bg.BackgroundOptions(mode="off")


def capture(preset, k, pose, cache: Path, refine: str = "fit"):
    """(scene, view) of one rendered pose (the render cached as .npz); ``refine``: the camera corners'
    refinement (:data:`procam.board.corners.REFINERS`; ``subpix`` is the paper's cornerSubPix)."""
    scene = simulate.with_board_pose(simulate.preset(preset), pose)
    fn = cache / f"{preset}_{'_'.join(str(a) for a in pose)}_seed{100 + k}.npz"
    if fn.exists():
        stack = np.load(fn)["stack"]
    else:
        stack, _ = simulate.render(scene, seed=100 + k)
        np.savez_compressed(fn, stack=stack)
    ps = patterns.pattern_set(*scene.proj_size, "opencv")
    board = Board(scene.board_cols, scene.board_rows, scene.square)
    options = pipeline.PoseOptions(refine=refine, refine_window=11 if refine == "subpix" else None)
    view, _ = pipeline.view_from_stack(stack, ps, board, name=f"{preset}{k}", options=options)
    return scene, view


# ------------------------------------------------------------------------------------------------
# the dense-board experiment: decoded board pixels instead of the projector's corners in the joint fit
# ------------------------------------------------------------------------------------------------

def board_pixels(view, maps_like, shrink=0.5, max_points=3000):
    """Decoded pixels inside the corners' hull eroded by ``shrink`` squares, subsampled."""
    import cv2

    col, row, valid = maps_like
    H, W = col.shape
    c = view.cam_pts[np.isfinite(view.cam_pts).all(1)]
    d = np.linalg.norm(c[:, None] - c[None], axis=2)
    np.fill_diagonal(d, np.inf)
    r = int(np.ceil(shrink * np.percentile(d.min(1), 10)))
    m = board_region(c, (W, H)).astype(np.uint8)
    m = cv2.erode(m, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * r + 1, 2 * r + 1)))
    ok = valid & (m > 0)
    step = max(1, int(np.ceil(np.sqrt(ok.sum() / max_points))))
    g = np.zeros_like(ok)
    g[step // 2::step, step // 2::step] = True
    ok &= g
    yy, xx = np.nonzero(ok)
    return np.column_stack([xx, yy]).astype(float), np.column_stack([col[ok], row[ok]]).astype(float)


def dense_variant(base, check, view, dense_pts):
    """The freed model (the default mode's), refitted with dense board pixels (noise = the background's)."""
    cs, ps = base.info["camera"], base.info["projector"]
    name = check.selected if check.selected != "assumed" else "u0p"
    free = tuple(name.split("+"))
    bgc, bgp = view.background.cam_pts, view.background.proj_pts
    j = PaperFits(base, cs, ps, bgc, bgp, free, check.noise_px, 0.003, board=(*dense_pts, check.noise_px))
    sel = check.fits[name]
    p = j.solve(j.start(sel.params))
    j.keep = np.abs(j.distances(p)) <= 4 * check.noise_px
    p = j.solve(p)
    return j.fit_result(p, name).calibration


# ------------------------------------------------------------------------------------------------
# tables
# ------------------------------------------------------------------------------------------------

def err(value, truth, std=None):
    if value is None or not np.isfinite(value):
        return "failed"
    s = f"{value - truth:+.1f}"
    return s + (f" ± {std:.1f}" if std is not None and np.isfinite(std) and std > 0 else "")


def pooled(metrics):
    """Pooled held-out figures from a list of PoseMetric."""
    if not metrics:
        return None
    w = np.array([m.n_pairs for m in metrics], float)
    nc = np.array([m.n_corners for m in metrics], float)
    se = np.array([m.scale_error_pct for m in metrics])
    rig = np.array([m.rigid_rms for m in metrics])
    rep = np.array([m.reproj_rms for m in metrics])
    return {"n": len(metrics), "scale_abs": float(np.sum(w * np.abs(se)) / w.sum()),
            "scale_rms": float(np.sqrt(np.sum(w * se ** 2) / w.sum())),
            "rigid": float(np.sqrt(np.sum(nc * rig ** 2) / nc.sum())), "rigid_med": float(np.median(rig)),
            "reproj": float(np.sqrt(np.sum(nc * rep ** 2) / nc.sum()))}


def failed_estimate(cal) -> bool:
    return cal is None or cal.verdict == "failed"


def cross(cals, views):
    """Every calibration of ``cals`` (pose index -> Calibration or None) verified on every other pose; a calibration
    whose verdict says not to use it (failed: an impossible focal length; degenerate: an undetermined one) counts its
    pairs as failed (a degenerate pose's f_p near 0 made the pooled scale errors 1e15 %)."""
    out, failed = [], 0
    for i, cal in cals.items():
        for j, v in enumerate(views):
            if j == i:
                continue
            if failed_estimate(cal) or cal.verdict == "degenerate":
                failed += 1
                continue
            try:
                out.append(verify.verify_pose(cal, v))
            except ProcamError:
                failed += 1
    return pooled(out), failed


def metric_row(label, p, failed=0):
    if p is None:
        return f"| {label} | – | – | – | – | – | all failed |"
    return (f"| {label} | {p['n']} | {p['scale_abs']:.3f} | {p['scale_rms']:.3f} | {p['rigid']:.3f} | "
            f"{p['rigid_med']:.3f} | {p['reproj']:.3f} |" + (f" {failed} pairs failed" if failed else ""))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--poses", type=int, default=len(POSES))
    ap.add_argument("--cache", type=Path, default=Path(tempfile.gettempdir()) / "procam-bench-background")
    ap.add_argument("--no-dense", action="store_true", help="skip the dense-board experiment")
    a = ap.parse_args()
    a.cache.mkdir(parents=True, exist_ok=True)
    import warnings

    from procam.errors import ProcamWarning

    warnings.simplefilter("ignore", ProcamWarning)  # the tables say what the warnings would
    poses = POSES[:a.poses]
    print(header("the background behind the board: check and refinement of the single-pose projector"))
    print(f"renders: 1280x800 camera, 1920x1080 projector, board 10x6 at 24 mm, wall 300 mm behind it; poses "
          f"(psi, nu, phi) camera frame {poses}; renders cached in {a.cache}\n")
    rows = {}
    t_check = []
    for preset in ("paper", "ideal"):
        for k, pose in enumerate(poses):
            scene, view = capture(preset, k, pose, a.cache)
            _, view_subpix = capture(preset, k, pose, a.cache, refine="subpix")
            r = {"scene": scene, "view": view, "pose": pose}
            try:
                r["paper"] = single_pose.calibrate(view_subpix, background=OFF)
                base = single_pose.calibrate(view, background=OFF)
            except ProcamError as e:
                r.update(base=None, error=str(e))
                rows[preset, k] = r
                continue
            t0 = time.perf_counter()
            check = bg.epipolar_check(base, view.background.cam_pts, view.background.proj_pts)
            t_check.append(time.perf_counter() - t0)
            free = bg.apply(base, view.background.cam_pts, view.background.proj_pts)
            auto = bg.apply(base, view.background.cam_pts, view.background.proj_pts, bg.BackgroundOptions(mode="auto"))
            r.update(base=base, check=check, auto=auto, free=free)
            rows[preset, k] = r

    # 1. the check
    print("## 1. The check at every pose\n")
    print("| rig | pose | nu_p (deg) | true u0p - assumed | verdict | size: median / p90 (px) | likelihood ratio "
          "(threshold) | background's u0p - truth | points used |")
    print("|---|---|---|---|---|---|---|---|---|")
    for (preset, k), r in rows.items():
        sc = r["scene"]
        du = sc.K_proj[0, 2] - sc.proj_size[0] / 2
        if r["base"] is None:
            print(f"| {preset} | {r['pose']} | – | {du:+.0f} | calibration failed | – | – | – | – |")
            continue
        c = r["check"]
        nu = r["base"].poses[0]["projector_angles_deg"][1]
        est = (err(c.estimate["u0p"], sc.K_proj[0, 2], c.estimate_std["u0p"]) if c.estimate else "–")
        verdict = c.status if c.status != "no check" else f"no check ({c.reason.split(';')[0].split('(')[0].strip()})"
        print(f"| {preset} | {r['pose']} | {nu:+.1f} | {du:+.0f} | {verdict} | {c.size_px:.1f} / {c.p90_px:.1f} | "
              f"{c.statistic:.1f} ({c.threshold:.1f}) | {est} | {c.n_used} of {c.n_points} |")
    print(f"\ncheck time per pose: median {np.median(t_check):.1f} s, max {np.max(t_check):.1f} s "
          "(three to four joint fits of ~3000 background points)\n")

    # 2. errors with and without the background
    for preset in ("paper", "ideal"):
        print(f"## 2. Errors against the truth, {preset} rig (value - truth ± reported 1 sigma, px)\n")
        print("| pose | f_p: paper's method | f_p: + background (free) | f_p: + background (auto) | u0p: paper's | "
              "u0p: free | u0p: auto | f_c: paper's | f_c: free | f_c: auto | auto's model |")
        print("|---|---|---|---|---|---|---|---|---|---|---|")
        agg = {m: [] for m in ("base", "free", "auto")}
        for (p, k), r in rows.items():
            if p != preset:
                continue
            sc = r["scene"]
            fp, u0, fc = sc.K_proj[0, 0], sc.K_proj[0, 2], sc.K_cam[0, 0]
            if r["base"] is None:
                print(f"| {r['pose']} | failed | | | | | | | | | |")
                continue
            if failed_estimate(r["base"]):
                print(f"| {r['pose']} | failed: f_p = {r['base'].projector.K[0, 0]:.0f} (no background check without "
                      "a start) | | | | | | | | | |")
                continue
            cells = []
            for m in ("base", "free", "auto"):
                c = r[m]
                cells.append((err(c.projector.K[0, 0], fp, c.std.get("f_p")), err(c.projector.K[0, 2], u0, c.std.get("u0p")),
                              err(c.camera.K[0, 0], fc, c.std.get("f_c"))))
                if not failed_estimate(r["base"]):
                    agg[m].append((c.projector.K[0, 0] - fp, c.projector.K[0, 2] - u0, c.camera.K[0, 0] - fc,
                                   (c.projector.K[0, 0] - fp) / max(c.std.get("f_p", np.nan), 1e-9)))
            print(f"| {r['pose']} | " + " | ".join(x[0] for x in cells) + " | " + " | ".join(x[1] for x in cells)
                  + " | " + " | ".join(x[2] for x in cells) + f" | {r['auto'].info.get('background_model')} |")
        print()
        print("| method | RMS f_p error | RMS u0p error | RMS f_c error | RMS (f_p error / its sigma) | poses |")
        print("|---|---|---|---|---|---|")
        for m, label in (("base", "paper's method"), ("free", "+ background (free, the default)"),
                         ("auto", "+ background (auto)")):
            e = np.array(agg[m])
            if len(e):
                print(f"| {label} | {np.sqrt(np.mean(e[:, 0] ** 2)):.1f} | {np.sqrt(np.mean(e[:, 1] ** 2)):.1f} | "
                      f"{np.sqrt(np.mean(e[:, 2] ** 2)):.1f} | {np.sqrt(np.mean(e[:, 3] ** 2)):.1f} | {len(e)} |")
        print("\n(poses whose projector estimate failed -- an impossible f_p -- are left out of the RMS)\n")

    # 3. the metric check on held-out poses
    for preset in ("paper", "ideal"):
        keys = [k for (p, k) in rows if p == preset]
        views = [rows[preset, k]["view"] for k in keys]
        print(f"## 3. Metric check on held-out poses, {preset} rig\n")
        print("Each pose's calibration triangulates the corners of every other pose (procam.verify); pooled over "
              "the ordered pairs. Lengths in mm; scale error = |mean adjacent-corner distance - 24 mm| / 24 mm.\n")
        print("| calibration | verified pairs | mean abs scale error (%) | RMS scale error (%) | rigid RMS (mm) | "
              "median rigid RMS (mm) | reprojection RMS (px) |")
        print("|---|---|---|---|---|---|---|")
        methods = [("paper's method (single pose, cornerSubPix corners)", "paper"),
                   ("+ better camera corners (saddle fit, the default)", "base"),
                   ("+ background (free, the default)", "free"), ("+ background (auto)", "auto")]
        for label, m in methods:
            cals = {i: rows[preset, k].get(m) for i, k in enumerate(keys)}
            p, failed = cross(cals, views)
            print(metric_row(label, p, failed))
        if not a.no_dense:
            from procam import decode

            cals = {}
            for i, k in enumerate(keys):
                r = rows[preset, k]
                if r.get("base") is None or r["check"].status == "no check":
                    cals[i] = r.get("free")
                    continue
                sc = r["scene"]
                fn = a.cache / f"{preset}_{'_'.join(str(x) for x in r['pose'])}_seed{100 + k}.npz"
                maps = decode.decode(np.load(fn)["stack"], patterns.pattern_set(*sc.proj_size, "opencv"))
                dense = board_pixels(r["view"], (maps.col, maps.row, maps.valid))
                cals[i] = dense_variant(r["base"], r["check"], r["view"], dense)
            p, failed = cross(cals, views)
            print(metric_row("+ background (free) + dense board points (experiment)", p, failed))
        try:
            loo = verify.leave_one_out(views)
            p = pooled(list(loo.held_out.poses)) if loo.held_out is not None else None
            print(metric_row(f"multi-pose, leave-one-pose-out ({len(views) - 1} poses each)", p, len(loo.failures)))
        except ProcamError as e:
            print(f"| multi-pose, leave-one-pose-out | failed: {e} |")
        print()


if __name__ == "__main__":
    main()
