"""Benchmark: the phase families against the Gray family, accuracy at the paper's rig and decode speed.

Part 1 (accuracy, the ``paper`` preset rendered by the simulator): for each sequence (family x steps x
frequencies) at the base condition, and for Gray and the families' defaults under each other condition (camera
read noise, projector gamma, projector defocus; one changed at a time from the base), against the simulator's truth:

* ``pixel``: RMS of the decoded projector coordinate on the board's lit pixels (2 px from its edges; both axes),
  and the fraction of them decoded (the Gray family's coordinate is the whole projector pixel: its error is the
  quantisation, 0.29 px);
* ``wall``: the fraction of the lit wall behind the board decoded (what the single-pose background check uses);
* ``corner``: RMS of the corners' projector coordinates (the pipeline's: the local homography for Gray, the local
  fit of the sub-pixel map for the phase families) with the detected camera corners, and at the true camera
  corners (the decoder's own share);
* ``f_p``: the single-pose projector focal length's error and its stated ``±`` (``procam.single_pose.calibrate``
  as a user runs it: the dense samples on the board and behind it), and the projector model it chose with the
  samples' counts.

Part 2 (speed, a 1688x1352 camera): every family's default sequence warped onto the camera (a tilted view of
the projected image, defocus, gamma 2.2, 1.5 DN noise), decoded in one run: seconds per frame and the ratio to
the Gray decode per frame (median of ``--repeat`` runs).

    python benchmarks/phase.py                 # both parts (about 10 minutes on one core)
    python benchmarks/phase.py --quick         # Gray and the defaults at the base condition only
    python benchmarks/phase.py --skip-accuracy --repeat 5
    python benchmarks/phase.py --skip-accuracy --repeat 8 --base aff1dfd   # and against an older decoder
    python benchmarks/phase.py --skip-accuracy --command     # and `procam decode` on folders, as a user runs it

Part 2c (``--command``): the same stacks written as capture folders (PNG frames and patterns.json) and decoded by
``procam decode FOLDER -o maps.npz`` in a fresh process each time: what a user waits for, reading the frames,
starting Python and writing the maps included.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import header  # noqa: E402

from procam import decode, patterns, pipeline, simulate, single_pose  # noqa: E402
from procam.board import Board  # noqa: E402
from procam.errors import ProcamError  # noqa: E402

#: (label, family, keywords of procam.patterns.pattern_set); the first of each family is procam's default.
SEQUENCES = [
    ("gray", "gray", {}),
    ("phase N=8 P=16,128 + cue", "phase", dict(steps=8, periods=(16, 128))),
    ("phase N=8 P=64 + cue", "phase", dict(steps=8, period=64)),
    ("phase N=4 P=64 + cue", "phase", dict(steps=4, period=64)),
    ("heterodyne N=8 70/64/59", "heterodyne", dict(steps=8)),
    ("heterodyne N=4 70/64/59", "heterodyne", dict(steps=4)),
    ("gray-phase N=4 P=16 compl.", "gray-phase", dict(steps=4, period=16)),
    ("gray-phase N=8 P=16 compl.", "gray-phase", dict(steps=8, period=16)),
    ("gray-phase N=3 P=32 compl.", "gray-phase", dict(steps=3, period=32)),
    ("gray-phase N=4 P=16 plain", "gray-phase", dict(steps=4, period=16, complementary=False)),
]
#: (label, read noise DN, projector gamma, projector defocus px); the first is the base, the others change one.
CONDITIONS = [
    ("base: 1.5 DN, gamma 2.2, defocus 0.5", 1.5, 2.2, 0.5),
    ("noise 0.5 DN", 0.5, 2.2, 0.5),
    ("noise 3 DN", 3.0, 2.2, 0.5),
    ("gamma 1.0", 1.5, 1.0, 0.5),
    ("defocus 2 px", 1.5, 2.2, 2.0),
]


def _rms(x) -> float:
    x = np.asarray(x, float)
    return float(np.sqrt(np.mean(x ** 2))) if x.size else float("nan")


def _pixel_error(maps, tm, board_px):
    """RMS (both axes) of the decoded coordinate on the board's lit interior, and the fraction decoded."""
    ok = board_px & maps.valid_col & maps.valid_row
    err = np.concatenate([(maps.col - tm.col)[ok], (maps.row - tm.row)[ok]])
    return _rms(err), ok.sum() / max(board_px.sum(), 1)


def _fp(view, truth_fp):
    """Single-pose f_p error, its stated +-, and how the projector was fitted (the dense samples' model and counts,
    or the background check's outcome); warnings are the table's subject here, not raised."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            cal = single_pose.calibrate(view)
        except ProcamError as e:
            return float("nan"), float("nan"), f"failed: {e}"[:40]
    pose = cal.poses[0] if cal.poses else {}
    pm = pose.get("projector_model")
    if pm:
        how = (f"{pm['model']}; {pm['n_board_samples']} board + {pm['n_background_samples']} background samples"
               f"{'' if pm['background_used'] else ' (background unused)'}")
    else:
        bg = pose.get("background") or {}
        how = "background check: " + (bg.get("status", "-") if isinstance(bg, dict) else getattr(bg, "status", "-"))
    return cal.projector.K[0, 0] - truth_fp, float((cal.std or {}).get("f_p", float("nan"))), how


def accuracy(args):
    from scipy.ndimage import binary_erosion

    base = simulate.preset("paper")
    board = Board(base.board_cols, base.board_rows, base.square)
    truth = simulate.corner_truth(base)
    true_fp = simulate.truth_calibration(base).projector.K[0, 0]
    tm = simulate.true_projector_maps(base)
    board_px = binary_erosion(tm.lit_board, iterations=2)
    wall_px = binary_erosion(tm.lit & ~tm.board & (tm.surface >= 1), iterations=2)
    conditions = CONDITIONS if not args.quick else CONDITIONS[:1]
    rows = []
    renderers = {}
    for cname, noise, gamma, defocus in conditions:
        if defocus not in renderers:
            renderers[defocus] = simulate.Renderer(base.replace(proj_defocus=defocus))
        r0 = renderers[defocus].photometry(read_noise=noise, proj_gamma=gamma)
        # every sequence at the base condition; Gray and each family's defaults under the others
        every = cname == CONDITIONS[0][0] and not args.quick
        sequences = SEQUENCES if every else [s for s in SEQUENCES if s[0] in QUICK]
        for label, family, kw in sequences:
            ps = patterns.pattern_set(*base.proj_size, family=family, **kw)
            r = r0.with_patterns(ps)
            rng = np.random.default_rng(args.seed)
            stack = np.stack([r.frame(k, rng) for k in range(ps.count)])
            t = time.perf_counter()
            try:
                view, maps = pipeline.view_from_stack(stack, ps, board, name=label)
            except ProcamError as e:
                rows.append((cname, label, ps.count, None, str(e)[:80]))
                continue
            t_view = time.perf_counter() - t
            at_truth, _ = pipeline.view_from_stack(stack, ps, board, name=label,
                                                   cam_pts=truth["camera_distorted"].copy())
            px_rms, px_cov = _pixel_error(maps, tm, board_px)
            wall = (wall_px & maps.valid_col & maps.valid_row).sum() / max(wall_px.sum(), 1)
            v = view.valid
            corner = _rms(np.linalg.norm(view.proj_pts - truth["projector"], axis=1)[v])
            corner_t = _rms(np.linalg.norm(at_truth.proj_pts - truth["projector"], axis=1)[at_truth.valid])
            dfp, sfp, status = _fp(view, true_fp)
            rows.append((cname, label, ps.count, dict(px=px_rms, cov=px_cov, wall=wall, n=int(v.sum()), corner=corner,
                                                      corner_t=corner_t, dfp=dfp, sfp=sfp, bg=status,
                                                      t=t_view), ""))
            print(f"  {cname} | {label}: corner {corner:.4f} px, at truth {corner_t:.4f} px, f_p {dfp:+.1f} px",
                  file=sys.stderr)
    print(f"## Part 1: accuracy at the paper's rig (preset `paper`, {base.cam_size[0]}x{base.cam_size[1]} camera, "
          f"{base.proj_size[0]}x{base.proj_size[1]} projector, {board.n_corners} corners, seed {args.seed}; "
          f"true f_p {true_fp:.1f} px)\n")
    for cname, *_ in conditions:
        print(f"### {cname}\n")
        print("| sequence | frames | pixel RMS px | board decoded | wall decoded | corners | corner RMS px | "
              "at true camera corners px | vs Gray | f_p error px | f_p ± px | projector fit |")
        print("|---|---|---|---|---|---|---|---|---|---|---|---|")
        gray = next((m for c, lab, _, m, _ in rows if c == cname and lab == "gray" and m), None)
        for c, label, count, m, err in rows:
            if c != cname:
                continue
            if m is None:
                print(f"| {label} | {count} | failed: {err} ||||||||||")
                continue
            ratio = f"{m['corner_t'] / gray['corner_t']:.2f}" if gray else "-"
            print(f"| {label} | {count} | {m['px']:.3f} | {100 * m['cov']:.0f} % | {100 * m['wall']:.0f} % | {m['n']} | "
                  f"{m['corner']:.4f} | {m['corner_t']:.4f} | {ratio} | {m['dfp']:+.1f} | {m['sfp']:.1f} | {m['bg']} |")
        print()


#: Gray and each family's default sequence (and the earlier defaults of phase and heterodyne, which lose the wall).
QUICK = ("gray", "phase N=8 P=16,128 + cue", "phase N=8 P=64 + cue", "heterodyne N=8 70/64/59",
         "heterodyne N=4 70/64/59", "gray-phase N=4 P=16 compl.")


def _speed_stack(ps, cam, rng):
    """The sequence ``ps`` as a 1688x1352 camera sees it: a tilted view, defocus, gamma 2.2, 1.5 DN noise."""
    import cv2

    W, H = ps.width, ps.height
    src = np.float32([[130, 80], [1560, 150], [1520, 1280], [170, 1200]])
    dst = np.float32([[0, 0], [W - 1, 0], [W - 1, H - 1], [0, H - 1]])
    Hm = cv2.getPerspectiveTransform(src, dst)
    yy, xx = np.mgrid[:cam[1], :cam[0]].astype(np.float32)
    vign = 1.0 - 0.3 * (((xx - cam[0] / 2) / (cam[0] / 2)) ** 2 + ((yy - cam[1] / 2) / (cam[1] / 2)) ** 2)
    out = np.empty((ps.count, cam[1], cam[0]), np.uint8)
    for k, p in enumerate(patterns.frames(ps)):
        p = cv2.GaussianBlur((p.astype(np.float32) / 255.0) ** 2.2, (0, 0), 0.8)
        img = cv2.warpPerspective(p, Hm, cam, flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP, borderValue=0)
        img = (0.03 + 0.97 * img) * 180 * vign + 15 + rng.normal(0, 1.5, img.shape)
        out[k] = np.clip(np.round(img), 0, 255).astype(np.uint8)
    return out


def _base_package(rev: str, tmp: Path):
    """procam's source at commit ``rev`` imported beside the current one, as the package ``procam_base`` (the
    package imports itself relatively, so the renamed copy is self-contained)."""
    import importlib
    import io
    import subprocess
    import tarfile

    root = Path(__file__).resolve().parent.parent
    data = subprocess.run(["git", "archive", rev, "src/procam"], cwd=root, capture_output=True, check=True).stdout
    tarfile.open(fileobj=io.BytesIO(data)).extractall(tmp, filter="data")
    (tmp / "src" / "procam").rename(tmp / "procam_base")
    sys.path.insert(0, str(tmp))
    return importlib.import_module("procam_base.decode"), importlib.import_module("procam_base.patterns")


def _speed_base(args, stacks):
    """Per frame against the Gray decode, this commit's decoders and those of ``args.base`` alternated in one
    process on the same stacks (the fastest of ``args.repeat`` rounds each: the least disturbed by other jobs)."""
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        base_decode, base_patterns = _base_package(args.base, Path(tmp))
        versions = {"this commit": (decode, patterns), f"base {args.base}": (base_decode, base_patterns)}
        times = {}
        for _ in range(args.repeat):
            for family, (label, ps, st) in stacks.items():
                kw = next(kw for lab, fam, kw in SEQUENCES if lab == label)
                for name, (dec, pat) in versions.items():
                    ps_v = pat.pattern_set(1920, 1080, family=family, **kw)
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore")
                        t = time.perf_counter()
                        dec.decode_with(st, ps_v, dec.DecodeOptions(), extras=False)
                        times.setdefault((name, family), []).append((time.perf_counter() - t) / ps.count)
    print(f"## Part 2b: against {args.base}, in one process (per frame, fastest of {args.repeat} rounds, default "
          "options)\n")
    print("| sequence | " + " | ".join(f"{n}: ms per frame | {n}: vs its Gray" for n in versions) + " |")
    print("|---|" + "---|---|" * len(versions))
    for family, (label, ps, _) in stacks.items():
        cells = []
        for name in versions:
            best, gray = min(times[name, family]), min(times[name, "gray"])
            cells.append(f"{1000 * best:.2f} | {best / gray:.2f}")
        print(f"| {label} | " + " | ".join(cells) + " |")
    print()


def _speed_command(args, stacks):
    """Per frame against the Gray decode, the ``procam decode`` command on capture folders (fresh processes,
    interleaved; the median of ``args.repeat`` runs)."""
    import shutil
    import subprocess
    import tempfile

    from procam.capture.write import write_sequence

    exe = shutil.which("procam")
    if exe is None:
        print("## Part 2c: skipped (no `procam` command on PATH)\n")
        return
    with tempfile.TemporaryDirectory() as tmp:
        folders = {}
        for family, (_, ps, st) in stacks.items():
            folders[family] = Path(tmp) / family
            write_sequence(folders[family], st, ps, writer="benchmark")
        times = {f: [] for f in stacks}
        for _ in range(args.repeat):
            for family, folder in folders.items():
                t = time.perf_counter()
                subprocess.run([exe, "decode", str(folder), "-o", str(Path(tmp) / f"{family}.npz")], check=True,
                               capture_output=True)
                times[family].append(time.perf_counter() - t)
    gray_pf = np.median(times["gray"]) / stacks["gray"][1].count
    print(f"## Part 2c: `procam decode FOLDER -o maps.npz`, fresh process, PNG frames (median of {args.repeat} runs, "
          "interleaved)\n")
    print("| sequence | frames | seconds | ms per frame | per frame vs Gray |")
    print("|---|---|---|---|---|")
    for family, ts in times.items():
        label, ps, _ = stacks[family]
        m = np.median(ts)
        print(f"| {label} | {ps.count} | {m:.2f} | {1000 * m / ps.count:.1f} | {m / ps.count / gray_pf:.2f} |")
    print()


def speed(args):
    cam = (1688, 1352)
    rng = np.random.default_rng(args.seed)
    stacks = {}
    for label, family, kw in SEQUENCES:
        if family not in stacks:  # each family's default sequence (the first listed)
            ps = patterns.pattern_set(1920, 1080, family=family, **kw)
            stacks[family] = (label, ps, _speed_stack(ps, cam, rng))
    if args.base:
        _speed_base(args, stacks)
    if args.command:
        _speed_command(args, stacks)
    times = {(f, m): [] for f in stacks for m in (("simple", "robust") if f == "gray" else ("auto", "none"))}
    valid = {}
    for _ in range(args.repeat):  # interleaved: every decoder sees the same machine load
        for (family, mode), ts in times.items():
            _, ps, st = stacks[family]
            opts = decode.DecodeOptions(method=mode) if family == "gray" else decode.DecodeOptions(
                gamma=mode if mode == "auto" else "none")
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # --gamma none warns of the uncorrected gamma: not the subject
                t = time.perf_counter()
                res = decode.decode_with(st, ps, opts, extras=False)
                ts.append(time.perf_counter() - t)
            valid[family, mode] = (res.valid_col & res.valid_row).mean()
    gray_pf = np.median(times["gray", "robust"]) / stacks["gray"][1].count
    print(f"## Part 2: decode speed, {cam[0]}x{cam[1]} camera, 1920x1080 projector (median of {args.repeat} "
          "runs, interleaved)\n")
    print("| sequence | decoder | frames | seconds | ms per frame | per frame vs Gray robust | decoded |")
    print("|---|---|---|---|---|---|---|")
    for (family, mode), ts in times.items():
        label, ps, _ = stacks[family]
        m = np.median(ts)
        what = f"method {mode}" if family == "gray" else f"gamma {mode}"
        print(f"| {label} | {what} | {ps.count} | {m:.3f} | {1000 * m / ps.count:.1f} | "
              f"{m / ps.count / gray_pf:.2f} | {100 * valid[family, mode]:.0f} % |")
    print()


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--quick", action="store_true", help="the default sequences at the base condition only")
    ap.add_argument("--skip-accuracy", action="store_true")
    ap.add_argument("--skip-speed", action="store_true")
    ap.add_argument("--base", help="speed: also alternate with the decoders of this commit in one process")
    ap.add_argument("--command", action="store_true", help="speed: also time `procam decode` on capture folders")
    args = ap.parse_args()
    print(header("phase: the phase families against Gray codes (accuracy vs the simulator's truth, decode speed)"))
    if not args.skip_accuracy:
        accuracy(args)
    if not args.skip_speed:
        speed(args)


if __name__ == "__main__":
    main()
