"""Benchmark: camera and projector corners against simulator truth and on real photographs; the defaults.

Renders the paper and ideal presets at ordinary and steep board poses (|psi| or |nu| >= 28 deg), with
camera blur 0.5-1.5 px, stronger lens distortion, 8- and 16-bit output, more read noise, three camera
sizes and several seeds, then measures in one run:

1. camera-corner RMS error (px) of every detector / refinement option, and its time;
2. projector-corner RMS error (projector px): ``procam.correspond.projector_corners`` on the decoded
   maps, fed with each option's camera corners;
3. OpenCV's real left/right photographs (``../shared/data/opencv-left-right``, 13 + 13 images, 9x6
   corners): boards found, ``cv2.calibrateCamera`` RMS and focal length per option;
4. detection + refinement time at 1280x800, 1280x1024 and 1920x1080, per detection scale;
5. a wrong ``--board`` (squares counted instead of inner corners): time to fail and the message;
6. projector corners: local-homography window and estimator (true camera corners as input);
7. the default pipeline (detect + decode + correspond) per render.

    python benchmarks/correspond.py [--quick] [--cache DIR] [--data DIR]

``--quick`` renders 4 scenes instead of 16 and skips the slow old wrong-board timing; ``--cache DIR``
keeps the renders (npz) between runs.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import sys
import time
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import header  # noqa: E402

from procam import board, correspond, decode, patterns, pipeline, simulate  # noqa: E402
from procam.board import corners  # noqa: E402
from procam.board import Board  # noqa: E402

BOARD = (10, 6)
CLASSIC = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE
SB_FLAGS = {"SB": cv2.CALIB_CB_NORMALIZE_IMAGE,
            "SB+acc": cv2.CALIB_CB_NORMALIZE_IMAGE | cv2.CALIB_CB_ACCURACY,
            "SB+exh+acc": cv2.CALIB_CB_NORMALIZE_IMAGE | cv2.CALIB_CB_EXHAUSTIVE | cv2.CALIB_CB_ACCURACY}


# --------------------------------------------------------------------------------------------
# scenes
# --------------------------------------------------------------------------------------------

def _K(f, a, u0, v0):
    return np.array([[f, 0, u0], [0, a * f, v0], [0, 0, 1.0]])


#: name -> (preset, (psi, nu, phi) camera frame, Scene changes, seed, tags)
SCENES = {
    "paper 15,12,0": ("paper", (15, 12, 0), {}, 1, ""),
    "paper 0,28,0": ("paper", (0, 28, 0), {}, 2, "steep"),
    "paper 0,28,0 blur1.5": ("paper", (0, 28, 0), {"cam_blur": 1.5}, 3, "steep blur"),
    "paper 0,28,0 k1=-2e-7": ("paper", (0, 28, 0), {"cam_dist_coeffs": (-2e-7, 0.0)}, 4, "steep dist"),
    "paper 0,35,0": ("paper", (0, 35, 0), {}, 5, "steep"),
    "paper 30,0,0": ("paper", (30, 0, 0), {}, 6, "steep"),
    "paper -20,-30,10": ("paper", (-20, -30, 10), {}, 7, "steep"),
    "paper 0,40,0": ("paper", (0, 40, 0), {}, 8, "steep"),
    "paper 0,28,0 blur1": ("paper", (0, 28, 0), {"cam_blur": 1.0}, 9, "steep blur"),
    "paper 15,12,0 blur1.5": ("paper", (15, 12, 0), {"cam_blur": 1.5}, 10, "blur"),
    "paper 0,28,0 16-bit": ("paper", (0, 28, 0), {"bits": 16}, 11, "steep"),
    "paper 0,28,0 noise3": ("paper", (0, 28, 0), {"read_noise": 3.0}, 12, "steep"),
    "ideal 15,12,0": ("ideal", (15, 12, 0), {}, 13, "dist"),
    "ideal 0,35,0 blur1": ("ideal", (0, 35, 0), {"cam_blur": 1.0}, 14, "steep blur dist"),
    "paper 0,28,0 1280x1024": ("paper", (0, 28, 0), {"cam_size": (1280, 1024)}, 15, "steep"),
    "paper 0,28,0 1920x1080": ("paper", (0, 28, 0),
                               {"cam_size": (1920, 1080), "K_cam": _K(2300.0, 1.004, 965.0, 545.0)}, 16, "steep"),
}
QUICK = ["paper 15,12,0", "paper 0,28,0", "paper 0,28,0 blur1.5", "paper 0,28,0 k1=-2e-7"]


def scene_of(name):
    preset, pose, changes, seed, _ = SCENES[name]
    sc = simulate.preset(preset)
    if changes:
        sc = dataclasses.replace(sc, **changes)
    return simulate.with_board_pose(sc, pose), seed


def render(name, cache):
    path = Path(cache) / (name.replace(" ", "_").replace(",", "_") + ".npz") if cache else None
    if path is not None and path.exists():
        z = np.load(path)
        return z["stack"], json.loads(str(z["truth"]))
    sc, seed = scene_of(name)
    stack, truth = simulate.render(sc, seed=seed)
    if path is not None:
        path.parent.mkdir(parents=True, exist_ok=True)
        np.savez_compressed(path, stack=stack, truth=json.dumps(truth))
    return stack, truth


# --------------------------------------------------------------------------------------------
# options: detectors and refinements
# --------------------------------------------------------------------------------------------

def detect_old(img, size):
    """procam < this branch: classic on the stretched full-size image."""
    g8 = corners.to_gray8(img)
    ok, c = cv2.findChessboardCorners(g8, size, flags=CLASSIC)
    return corners.canonical_order(c.reshape(-1, 2).astype(float), *size) if ok else None


def detect_sb(flags):
    def f(img, size):
        ok, c = cv2.findChessboardCornersSB(corners.to_gray8(img), size, flags=flags)
        return corners.canonical_order(c.reshape(-1, 2).astype(float), *size) if ok else None
    return f


def detect_small(width):
    return lambda img, size: corners.find_grid(img, size, detector="classic", max_width=width)


DETECTORS = {"classic full": detect_old, "classic 1024": detect_small(1024), "classic 640": detect_small(640),
             **{k: detect_sb(v) for k, v in SB_FLAGS.items()},
             "default": lambda img, size: corners.detect_corners(img, size)}


def refine_old(frames, c, size):
    """procam < this branch: cornerSubPix 11 (clamped) on the stretched 8-bit image."""
    return corners.refine_corners(corners.to_gray8(frames["white"]), c, size, method="subpix", window=11)


def refine_subpix(win, frame="white"):
    """cornerSubPix on the grey image, half-window clamped by corners.subpix_window."""
    return lambda frames, c, size: corners.refine_corners(frames[frame], c, size, method="subpix", window=win)


def refine_fit(win, frame="white"):
    def f(frames, c, size):
        return corners.refine_corners(frames[frame], c, size, method="fit", window=win,
                                    start_error=frames.get("start_error", 1.0))
    return f


def saddle(image, corners, sigma=1.0, half=3, iterations=20):
    """Quadratic-saddle refinement (measured option, not used by procam): fit
    z = a x^2 + b xy + c y^2 + d x + e y + f to the Gaussian-smoothed image resampled around the
    estimate, move to the saddle point, repeat."""
    f = cv2.GaussianBlur(corners.gray_float(image), (0, 0), sigma)
    u = np.arange(-half, half + 1, dtype=float)
    U, V = (a.ravel() for a in np.meshgrid(u, u))
    w = np.exp(-(U ** 2 + V ** 2) / (2 * (half / 1.5) ** 2))
    A = np.column_stack([U * U, U * V, V * V, U, V, np.ones_like(U)])
    P = np.linalg.solve(A.T @ (A * w[:, None]), (A * w[:, None]).T)
    p0 = np.asarray(corners, float).reshape(-1, 2)
    p = p0.copy()
    for _ in range(iterations):
        z = cv2.remap(f, (p[:, :1] + U).astype(np.float32), (p[:, 1:] + V).astype(np.float32), cv2.INTER_LINEAR,
                      borderMode=cv2.BORDER_REPLICATE).astype(float)
        a, b, c, d, e, _ = (z @ P.T).T
        det = 4 * a * c - b * b
        with np.errstate(all="ignore"):
            step = np.column_stack([(b * e - 2 * c * d) / det, (b * d - 2 * a * e) / det])
        step[~((det < 0) & np.isfinite(step).all(1))] = 0
        p += np.clip(step, -1, 1)
        if np.abs(step).max() < 1e-4:
            break
    far = np.linalg.norm(p - p0, axis=1) > half
    p[far] = p0[far]
    return p


def refine_saddle(frames, c, size):
    w = frames["white"]
    return saddle(w, corners.refine_corners(w, c, size, method="subpix", window=5))


#: label -> (detector, refinement or None, group)
OPTIONS = {
    "procam default: detect_corners() (auto chain, 640 px, fit 15)": ("default", None, "default"),
    "old default: classic full + cornerSubPix 11": ("classic full", refine_old, "old"),
    "classic 640, no refinement": ("classic 640", None, "classic"),
    **{f"classic 640 + cornerSubPix {w}": ("classic 640", refine_subpix(w), "classic") for w in (3, 5, 7, 11, 15)},
    "SB (normalize)": ("SB", None, "sb"),
    "SB + accuracy": ("SB+acc", None, "sb"),
    "SB + exhaustive + accuracy": ("SB+exh+acc", None, "sb"),
    "SB + accuracy, then fit 11": ("SB+acc", refine_fit(11), "sb"),
    "classic 640 + saddle (sigma 1, h 3)": ("classic 640", refine_saddle, "saddle"),
    **{f"classic 640 + fit {w}": ("classic 640", refine_fit(w), "fit") for w in (6, 8, 11, 15, 20)},
    "classic 640 + fit 11 on white - black": ("classic 640", refine_fit(11, "w-b"), "frames"),
    "classic 640 + fit 11 on (white + full - black)/2": ("classic 640", refine_fit(11, "avg"), "frames"),
    "classic 640 + fit 11 on black": ("classic 640", refine_fit(11, "black"), "frames"),
    "classic 640 + cornerSubPix 11 on white - black": ("classic 640", refine_subpix(11, "w-b"), "frames"),
    "classic 1024 + fit 11": ("classic 1024", refine_fit(11), "scale"),
    "classic full + fit 11": ("classic full", refine_fit(11), "scale"),
}
DEFAULT = "procam default: detect_corners() (auto chain, 640 px, fit 15)"
KEY = ["old default: classic full + cornerSubPix 11", "classic 640 + cornerSubPix 5", "SB + accuracy",
       "SB + accuracy, then fit 11", "classic 640 + saddle (sigma 1, h 3)", "classic 640 + fit 11",
       "classic 640 + fit 15", DEFAULT]


def frames_of(stack, ps):
    white, black = stack[ps.white], stack[ps.black]
    full = 255.0 if white.dtype == np.uint8 else 65535.0
    wf, bf = white.astype(np.float32), black.astype(np.float32)
    return {"white": white, "black": black, "w-b": np.clip(wf - bf, 0, None), "avg": 0.5 * (wf + full - bf)}


def rms(a, b):
    if a is None:
        return float("nan"), 0
    d = np.asarray(a, float) - np.asarray(b, float)
    ok = np.isfinite(d).all(1)
    return (float(np.sqrt(np.mean(np.sum(d[ok] ** 2, axis=1)))) if ok.any() else float("nan")), int(ok.sum())


def timed(f, *a, repeat=1):
    ts, out = [], None
    for _ in range(repeat):
        t = time.perf_counter()
        out = f(*a)
        ts.append(time.perf_counter() - t)
    return out, float(np.median(ts))


def group_needs_frames(label):
    return OPTIONS[label][2] == "frames"


def run_options(frames, size):
    """{option: (corners or None, seconds)} for one image set (dict of frames)."""
    det = {}
    for name in {v[0] for v in OPTIONS.values()}:
        det[name] = timed(DETECTORS[name], frames["white"], size)
    out = {}
    for label, (dname, ref, _) in OPTIONS.items():
        c, t = det[dname]
        if ref is not None and group_needs_frames(label) and "black" not in frames:
            continue  # a photograph has no black frame
        if c is not None and ref is not None:
            fr = dict(frames)
            w = frames["white"].shape[1]
            fr["start_error"] = w / 640 if dname == "classic 640" and w > 640 else (
                w / 1024 if dname == "classic 1024" and w > 1024 else 1.0)
            c, tr = timed(ref, fr, c, size)
            t += tr
        out[label] = (c, t)
    return out


# --------------------------------------------------------------------------------------------
# sections
# --------------------------------------------------------------------------------------------

def section_renders(names, cache, ps):
    res = {}  # name -> {option: (cam rms, proj rms, n proj, seconds)}
    extra = {}
    for name in names:
        stack, truth = render(name, cache)
        cam_t = np.array(truth["corners"]["camera_distorted"])
        proj_t = np.array(truth["corners"]["projector"])
        frames = frames_of(stack, ps)
        maps = decode.decode(stack, ps)
        opts = run_options(frames, BOARD)
        row = {}
        for label, (c, t) in opts.items():
            ce = rms(c, cam_t)[0]
            if c is not None:
                p, _ = correspond.projector_corners(c, maps)
                pe, pn = rms(p, proj_t)
            else:
                pe, pn = float("nan"), 0
            row[label] = (ce, pe, pn, t)
        p, _ = correspond.projector_corners(cam_t, maps)
        row["(true camera corners)"] = (0.0, *rms(p, proj_t), 0.0)
        res[name] = row
        extra[name] = (stack, truth, maps)
        print(f"  rendered and measured {name}", file=sys.stderr, flush=True)
    return res, extra


def print_options(res, names):
    tags = {n: SCENES[n][4] for n in names}
    steep = [n for n in names if "steep" in tags[n]]
    blur = [n for n in names if "blur" in tags[n]]
    print("## 1-2. camera and projector corners per option (RMS against truth; projector corners by "
          "local homographies from each option's camera corners)\n")
    print(f"renders: {len(names)} ({len(steep)} steep: |psi| or |nu| >= 28 deg; {len(blur)} with camera blur >= 1 px). "
          "Columns: camera RMS px (mean over renders / mean over steep / mean over blurred / worst), projector RMS "
          "px (mean / worst), boards found, detection + refinement ms (median over renders; see section 4 per "
          "image size).\n")
    print("| option | cam mean | cam steep | cam blur | cam worst | proj mean | proj worst | found | ms |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    labels = list(OPTIONS) + ["(true camera corners)"]
    for label in labels:
        v = np.array([res[n][label] for n in names], float)
        ce, pe, t = v[:, 0], v[:, 1], v[:, 3]
        st = np.array([res[n][label][0] for n in steep], float) if steep else np.array([np.nan])
        bl = np.array([res[n][label][0] for n in blur], float) if blur else np.array([np.nan])
        found = int(np.isfinite(ce).sum())
        mark = " **(default)**" if label == DEFAULT else ""
        print(f"| {label}{mark} | {np.nanmean(ce):.4f} | {np.nanmean(st):.4f} | {np.nanmean(bl):.4f} | "
              f"{np.nanmax(ce):.4f} | {np.nanmean(pe):.4f} | {np.nanmax(pe):.4f} | {found}/{len(names)} | "
              f"{1000 * np.nanmedian(t):.0f} |")
    print("\ncamera RMS px per render, key options:\n")
    print("| render | " + " | ".join(KEY) + " |")
    print("| --- " * (len(KEY) + 1) + "|")
    for n in names:
        print(f"| {n} | " + " | ".join(f"{res[n][k][0]:.4f}" for k in KEY) + " |")
    print("\nprojector RMS px per render, key options (last column: true camera corners):\n")
    print("| render | " + " | ".join(KEY) + " | truth |")
    print("| --- " * (len(KEY) + 2) + "|")
    for n in names:
        print(f"| {n} | " + " | ".join(f"{res[n][k][1]:.4f}" for k in KEY)
              + f" | {res[n]['(true camera corners)'][1]:.4f} |")


def section_real(data):
    print("\n## 3. real photographs: OpenCV's left/right samples (640x480 JPEG, 9x6 corners, 25 mm)\n")
    if data is None or not data.is_dir():
        print(f"skipped: {data} not found\n")
        return
    from procam.io import images as _images

    obj = board.object_points(9, 6, 25.0).astype(np.float32)
    print("cv2.calibrateCamera on the images each option finds the board in (left: CALIB_FIX_ASPECT_RATIO as "
          "the published reference fx = 536.1 (cornerSubPix 11x11, no clamp); right: no flags, reference "
          "fx 542.4); fx +- its standard deviation from calibrateCameraExtended (right only: with a fixed "
          "aspect ratio OpenCV reports none).\n")
    print("| option | left found | left RMS px | left fx | right found | right RMS px | right fx +- sd |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    sets = {}
    for side in ("left", "right"):
        files = sorted(data.glob(f"{side}*.jpg"))
        imgs = [_images.read_image(f) for f in files]
        per = {label: [] for label in OPTIONS}
        per["cornerSubPix 11, no clamp (published reference)"] = []
        for img in imgs:
            opts = run_options({"white": img}, (9, 6))
            for label in OPTIONS:
                if label in opts:
                    per[label].append(opts[label][0])
            c0 = detect_old(img, (9, 6))
            crit = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_MAX_ITER, 30, 0.001)
            per["cornerSubPix 11, no clamp (published reference)"].append(
                None if c0 is None else cv2.cornerSubPix(corners.to_gray8(img), c0.astype(np.float32).reshape(-1, 1, 2),
                                                         (11, 11), (-1, -1), crit).reshape(-1, 2).astype(float))
        sets[side] = (per, imgs[0].shape[1::-1])
    for label in sets["left"][0]:
        if not sets["left"][0][label]:
            continue  # needs a black frame
        cells = []
        for side, flags in (("left", cv2.CALIB_FIX_ASPECT_RATIO), ("right", 0)):
            per, size = sets[side]
            pts = [c for c in per[label] if c is not None]
            if len(pts) < 3:
                cells += [f"{len(pts)}/13", "-", "-"]
                continue
            r = cv2.calibrateCameraExtended([obj] * len(pts), [c.astype(np.float32).reshape(-1, 1, 2) for c in pts],
                                            size, None, None, flags=flags)
            sd = f" +- {r[5][0, 0]:.2f}" if side == "right" else ""
            cells += [f"{len(pts)}/13", f"{r[0]:.3f}", f"{r[1][0, 0]:.2f}{sd}"]
        mark = " **(default)**" if label == DEFAULT else ""
        print(f"| {label}{mark} | " + " | ".join(cells) + " |")


def section_speed(cache, ps):
    print("\n## 4. time per pose: detection + refinement of the white frame (median of 5, ms wall clock; "
          "cpu ms in brackets)\n")
    print(f"load average at start: {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores\n")
    names = ["paper 0,28,0", "paper 0,28,0 1280x1024", "paper 0,28,0 1920x1080"]
    print("| image | detect full | detect 1024 | detect 640 | cornerSubPix 11 | fit 11 | fit 15 | "
          "old default total | new default total (detect_corners, fit 15) |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")

    def tm(f, *a, **kw):
        wall, cpu = [], []
        for _ in range(5):
            t, c = time.perf_counter(), time.process_time()
            out = f(*a, **kw)
            wall.append(time.perf_counter() - t)
            cpu.append(time.process_time() - c)
        return out, f"{1000 * np.median(wall):.0f} ({1000 * np.median(cpu):.0f})"

    for name in names:
        stack, _ = render(name, cache)
        w = stack[ps.white]
        _, t_full = tm(detect_old, w, BOARD)
        _, t1024 = tm(detect_small(1024), w, BOARD)
        c640, t640 = tm(detect_small(640), w, BOARD)
        start = corners.refine_corners(w, c640, BOARD, method="subpix", window=4)
        _, tsp = tm(corners.refine_corners, w, c640, BOARD, method="subpix", window=11)
        _, tf11 = tm(corners.fit_corners, w, start, BOARD, window=11)
        _, tf15 = tm(corners.fit_corners, w, start, BOARD, window=15)
        _, told = tm(lambda img: refine_old({"white": img}, detect_old(img, BOARD), BOARD), w)
        _, tnew = tm(corners.detect_corners, w, BOARD)
        H, W = w.shape
        print(f"| {W}x{H} | {t_full} | {t1024} | {t640} | {tsp} | {tf11} | {tf15} | {told} | {tnew} |")


def old_find_board(stack, ps, size):
    """procam's previous find_board: classic then SB (exhaustive + accuracy) at full size on the white,
    white - black and black frames."""
    white, black = stack[ps.white], stack[ps.black]
    for img in (white, np.clip(white.astype(np.float32) - black.astype(np.float32), 0, None), black):
        for det in (detect_old, detect_sb(SB_FLAGS["SB+exh+acc"])):
            if det(img, size) is not None:
                return True
    return False


def section_wrong_board(cache, ps, quick):
    print("\n## 5. wrong --board: time to fail and the message (pipeline.find_board)\n")
    print("| image | --board | seconds | message (after the pose name) | old chain seconds |")
    print("| --- | --- | --- | --- | --- |")
    for name in ("paper 0,28,0", "paper 0,28,0 1280x1024"):
        stack, _ = render(name, cache)
        H, W = stack.shape[1:]
        for size in ((11, 7), (9, 5)):
            t = time.perf_counter()
            try:
                pipeline.find_board(stack, ps, size, name="pose")
                msg = "(found!)"
            except Exception as e:  # noqa: BLE001 - the message is what is measured
                msg = str(e).split(": ", 1)[-1]
            dt = time.perf_counter() - t
            old = "-"
            if not quick and size == (11, 7):
                t = time.perf_counter()
                old_find_board(stack, ps, size)
                old = f"{time.perf_counter() - t:.1f}"
            print(f"| {W}x{H} | {size[0]}x{size[1]} | {dt:.2f} | {msg} | {old} |")


def section_homography(extra, names):
    windows = [20, 30, 40, 60, 80, 100]
    estimators = correspond.ESTIMATORS
    err = {(w, e): [] for w in windows for e in estimators}
    tim = {(w, e): [] for w in windows for e in estimators}
    for n in names:
        _, truth, maps = extra[n]
        cam_t = np.array(truth["corners"]["camera_distorted"])
        proj_t = np.array(truth["corners"]["projector"])
        for w in windows:
            for e in estimators:
                t = time.perf_counter()
                p, _ = correspond.projector_corners(cam_t, maps, correspond.CornerOptions(window=w, estimator=e))
                tim[(w, e)].append(time.perf_counter() - t)
                err[(w, e)].append(rms(p, proj_t))
    print(f"\n## 6. projector corners: local-homography window and estimator (true camera corners as input; "
          f"renders: {', '.join(names)})\n")
    print("| window px | estimator | mean RMS proj px | worst RMS proj px | corners kept | ms per pose |")
    print("| --- | --- | --- | --- | --- | --- |")
    for w in windows:
        for e in estimators:
            r = np.array([x[0] for x in err[(w, e)]])
            kept = sum(x[1] for x in err[(w, e)])
            print(f"| {w} | {e} | {np.nanmean(r):.4f} | {np.nanmax(r):.4f} | {kept}/{60 * len(r)} | "
                  f"{1000 * np.mean(tim[(w, e)]):.0f} |")


def section_pipeline(extra, names, ps):
    print("\n## 7. default pipeline (detect + decode + correspond)\n")
    print("| render | camera RMS px | projector RMS px | corners | seconds |")
    print("| --- | --- | --- | --- | --- |")
    for n in names:
        stack, truth, _ = extra[n]
        cam_t = np.array(truth["corners"]["camera_distorted"])
        proj_t = np.array(truth["corners"]["projector"])
        t = time.perf_counter()
        view, _ = pipeline.view_from_stack(stack, ps, Board(*BOARD, 24.0))
        dt = time.perf_counter() - t
        print(f"| {n} | {rms(view.cam_pts, cam_t)[0]:.4f} | {rms(view.proj_pts, proj_t)[0]:.4f} | "
              f"{rms(view.proj_pts, proj_t)[1]}/60 | {dt:.2f} |")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="4 renders instead of 16; skip the old wrong-board timing")
    ap.add_argument("--cache", type=Path, default=None, help="keep the renders in this folder (npz)")
    ap.add_argument("--data", type=Path, default=Path(__file__).resolve().parents[2] / "shared" / "data"
                    / "opencv-left-right", help="OpenCV's left/right photographs")
    args = ap.parse_args()
    names = QUICK if args.quick else list(SCENES)
    ps = patterns.pattern_set(1920, 1080)
    res, extra = section_renders(names, args.cache, ps)
    print(header("corners: camera and projector corners against simulator truth, real photographs, speed"))
    print("renders: procam.simulate presets, 46 images each (1920x1080 projector), board 10x6; "
          "name = preset, camera-frame pose (psi, nu, phi) deg, changes from the preset.\n")
    print_options(res, names)
    section_real(args.data)
    section_speed(args.cache, ps)
    section_wrong_board(args.cache, ps, args.quick)
    section_homography(extra, names[:4])
    section_pipeline(extra, names, ps)


if __name__ == "__main__":
    main()
