"""Benchmark: do the phase families at least halve the Gray family's projector corner error, end to end?

The paper's rig (``procam.simulate.preset("paper")``, the board at the recommended pose) rendered with every
pattern family -- Gray; ``phase``, ``heterodyne`` and ``gray-phase`` with N = 3, 4 and 6 steps and, where the
family has one to choose, two fringe periods -- under two camera read noises and two projector gammas, decoded by
procam's pipeline as ``procam calibrate`` does (``procam.pipeline.view_from_stack``: the detected camera corners,
the family's decoder, the corners' projector coordinates), against the simulator's truth:

* ``corner``: RMS (over the valid corners, all seeds) of the distance between the corners' projector coordinates
  and the true ones (``procam.simulate.corner_truth``, the board's canonical order), *end to end* (with the
  detected camera corners) and *at the true camera corners* (the decoder's own share);
* ``f_p``: the single-pose projector focal length (``procam.method.calibrate`` on the one view) against the
  scene's ``K_proj``, RMS over the seeds, and its stated ``±``;
* each against the Gray family's in the same condition of the same run (``vs Gray``).

    python benchmarks/phase_corners.py              # 16 sequences x 4 conditions, seed 1 (about 7 min)
    python benchmarks/phase_corners.py --quick      # Gray and N=4 of each family, 2 conditions (about 1 min)
    python benchmarks/phase_corners.py --seeds 3    # the grid over three seeds (about 20 min)
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

from procam import method, patterns, pipeline, simulate  # noqa: E402
from procam.board import Board  # noqa: E402
from procam.errors import ProcamError  # noqa: E402


def sequences(quick: bool):
    """(label, family, keywords of procam.patterns.pattern_set): Gray first (the reference), then each phase
    family at N = 3, 4, 6 (quick: N = 4 at the family's default period)."""
    out = [("gray", "gray", {})]
    for n in ((4,) if quick else (3, 4, 6)):
        out.append((f"phase N={n} P=16,128 + cue", "phase", dict(steps=n, periods=(16, 128))))
        if not quick:
            out.append((f"phase N={n} P=64 + cue", "phase", dict(steps=n, period=64)))
        out.append((f"heterodyne N={n} 70/64/59", "heterodyne", dict(steps=n)))
        out.append((f"gray-phase N={n} P=16", "gray-phase", dict(steps=n, period=16)))
        if not quick:
            out.append((f"gray-phase N={n} P=32", "gray-phase", dict(steps=n, period=32)))
    return sorted(out, key=lambda s: ("gray", "phase", "heterodyne", "gray-phase").index(s[1]))


#: (label, camera read noise DN, projector gamma): two noises x two gammas.
CONDITIONS = [("1.5 DN, gamma 2.2", 1.5, 2.2), ("1.5 DN, gamma 1.0", 1.5, 1.0),
              ("3 DN, gamma 2.2", 3.0, 2.2), ("3 DN, gamma 1.0", 3.0, 1.0)]
QUICK_CONDITIONS = CONDITIONS[:2]


def _rms(x) -> float:
    x = np.asarray(x, float)
    return float(np.sqrt(np.mean(x ** 2))) if x.size else float("nan")


def measure(renderer, ps, board, truth, true_fp, label, seed):
    """One render decoded: per-corner errors end to end and at the true camera corners ((n_corners,) projector px,
    NaN where the corner has no projector coordinate), the single-pose f_p error and its stated ± (px); or the
    error's text."""
    rng = np.random.default_rng(seed)
    stack = np.stack([renderer.frame(k, rng) for k in range(ps.count)])
    try:
        view, _ = pipeline.view_from_stack(stack, ps, board, name=label, keep_maps=False)
        at_truth, _ = pipeline.view_from_stack(stack, ps, board, name=label, keep_maps=False,
                                               cam_pts=truth["camera_distorted"].copy())
    except ProcamError as e:
        return str(e).splitlines()[0][:80]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a weak pose's warnings are the table's subject here, not raised
        try:
            cal = method.calibrate([view], method="single-pose")
            dfp, sfp = cal.projector.K[0, 0] - true_fp, float((cal.std or {}).get("f_p", np.nan))
        except ProcamError:
            dfp, sfp = np.nan, np.nan

    def errors(v):
        return np.where(v.valid, np.linalg.norm(v.proj_pts - truth["projector"], axis=1), np.nan)

    return dict(e2e=errors(view), at_t=errors(at_truth), dfp=dfp, sfp=sfp)


def _rms_valid(e) -> float:
    return _rms(e[np.isfinite(e)])


def ratio(m, gray, key) -> float:
    """RMS of ``m``'s corner errors over Gray's, both over the corners that both decoded (every seed)."""
    both = np.isfinite(m[key]) & np.isfinite(gray[key])
    return _rms(m[key][both]) / _rms(gray[key][both]) if both.any() else float("nan")


def run(args):
    base = simulate.preset("paper")
    board = Board(base.board_cols, base.board_rows, base.square)
    truth = simulate.corner_truth(base)
    true_fp = float(np.asarray(base.K_proj)[0, 0])
    renderer = simulate.Renderer(base)
    seqs = sequences(args.quick)
    conditions = QUICK_CONDITIONS if args.quick else CONDITIONS
    seeds = list(range(1, args.seeds + 1))
    results = {}  # (condition, label) -> aggregated dict or error text
    t0 = time.perf_counter()
    for cname, noise, gamma in conditions:
        r0 = renderer.photometry(read_noise=noise, proj_gamma=gamma)
        for label, family, kw in seqs:
            ps = patterns.pattern_set(*base.proj_size, family=family, **kw)
            r = r0.with_patterns(ps)
            got = [measure(r, ps, board, truth, true_fp, label, s) for s in seeds]
            fails = [g for g in got if isinstance(g, str)]
            ok = [g for g in got if not isinstance(g, str)]
            if not ok:
                results[cname, label] = (ps.count, fails[0])
                continue
            # a failed seed counts as every corner missing
            pad = np.full(board.n_corners, np.nan)
            results[cname, label] = (ps.count, dict(
                e2e=np.concatenate([pad if isinstance(g, str) else g["e2e"] for g in got]),
                at_t=np.concatenate([pad if isinstance(g, str) else g["at_t"] for g in got]),
                dfp=_rms([g["dfp"] for g in ok]), sfp=float(np.mean([g["sfp"] for g in ok])), fails=len(fails)))
            m = results[cname, label][1]
            print(f"  [{time.perf_counter() - t0:5.0f} s] {cname} | {label}: corner {_rms_valid(m['e2e']):.4f} px, "
                  f"at truth {_rms_valid(m['at_t']):.4f} px, f_p {m['dfp']:.1f} px", file=sys.stderr)
    return base, board, true_fp, seqs, conditions, seeds, results


def table(base, board, true_fp, seqs, conditions, seeds, results):
    n = board.n_corners * len(seeds)
    print(f"Preset `paper`: {base.cam_size[0]}x{base.cam_size[1]} camera, {base.proj_size[0]}x{base.proj_size[1]} "
          f"projector, {board.n_corners} corners, projector defocus {base.proj_defocus} px, true f_p {true_fp:.1f} px; "
          f"seeds {', '.join(map(str, seeds))}. *corners*: those with a projector coordinate, of {n} ({board.n_corners} "
          "per seed); corner RMS in projector px over them, *end to end* (the detected camera corners) and *at true "
          "cam.* (the true camera corners: the decoder's own share); *vs Gray*: the RMS over Gray's on the corners "
          "both have; f_p: the RMS error over the seeds and the mean stated ±, *vs Gray* their ratios to Gray's.\n")
    print("| condition | sequence | frames | corners | corner RMS end to end | vs Gray | at true cam. | vs Gray | "
          "f_p error px | vs Gray | f_p ± px | vs Gray |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for cname, *_ in conditions:
        gray = results[cname, "gray"][1]
        for label, *_ in seqs:
            count, m = results[cname, label]
            if isinstance(m, str):
                print(f"| {cname} | {label} | {count} | failed: {m} |||||||||")
                continue
            g = None if isinstance(gray, str) else gray
            note = f" ({m['fails']} seed(s) failed)" if m["fails"] else ""
            cells = [f"{int(np.isfinite(m['e2e']).sum())}{note}"]
            for k in ("e2e", "at_t"):
                cells += [f"{_rms_valid(m[k]):.4f}", f"{ratio(m, g, k):.2f}" if g else "-"]
            for k in ("dfp", "sfp"):
                cells += [f"{m[k]:.1f}", f"{m[k] / g[k]:.2f}" if g and g[k] > 0 else "-"]
            print(f"| {cname} | {label} | {count} | " + " | ".join(cells) + " |")
    print()
    print("Summary over the conditions: the corner error's ratio to Gray's (min-max; *halves* where every "
          "condition's is at most 0.5 with every seed decoded), and the f_p error and stated ± (min-max, px; Gray's: "
          + ", ".join(f"{results[c, 'gray'][1]['dfp']:.1f} ± {results[c, 'gray'][1]['sfp']:.1f}" for c, *_ in conditions
                      if not isinstance(results[c, "gray"][1], str)) + ").\n")
    print("| sequence | end to end vs Gray | halves end to end | at true cam. vs Gray | halves at true cam. | "
          "f_p error px | f_p ± px |")
    print("|---|---|---|---|---|---|---|")
    rng = (lambda xs, f: f"{f.format(min(xs))}-{f.format(max(xs))}" if xs else "-")
    for label, family, _ in seqs:
        if family == "gray":
            continue
        ms = [(results[c, label][1], results[c, "gray"][1]) for c, *_ in conditions]
        ms = [(m, g) for m, g in ms if not isinstance(m, str) and not isinstance(g, str)]
        complete = len(ms) == len(conditions) and not any(m["fails"] for m, _ in ms)
        cells = []
        for k in ("e2e", "at_t"):
            rs = [ratio(m, g, k) for m, g in ms]
            cells += [rng(rs, "{:.2f}"), "yes" if complete and max(rs) <= 0.5 else
                      ("no (a decode failed)" if not complete else "no")]
        cells += [rng([m["dfp"] for m, _ in ms], "{:.0f}"), rng([m["sfp"] for m, _ in ms], "{:.0f}")]
        print(f"| {label} | " + " | ".join(cells) + " |")
    print()


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="Gray and N=4 of each family under two conditions")
    ap.add_argument("--seeds", type=int, default=1, help="renders per sequence and condition (seeds 1..SEEDS)")
    args = ap.parse_args()
    t = time.perf_counter()
    print(header("phase_corners: projector corner error and single-pose f_p, the phase families against Gray"))
    table(*run(args))
    print(f"({time.perf_counter() - t:.0f} s)")


if __name__ == "__main__":
    main()
