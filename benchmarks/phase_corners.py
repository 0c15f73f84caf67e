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

    python benchmarks/phase_corners.py              # 16 sequences x 4 conditions, seed 1 (about 10 min)
    python benchmarks/phase_corners.py --quick      # Gray and N=4 of each family, 2 conditions (about 1 min)
    python benchmarks/phase_corners.py --seeds 3    # the full grid over three seeds
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
    """One render decoded: per-corner errors end to end and at the true camera corners (projector px, valid
    corners only), the single-pose f_p error and its stated ± (px), the seconds taken; or the error's text."""
    rng = np.random.default_rng(seed)
    stack = np.stack([renderer.frame(k, rng) for k in range(ps.count)])
    t = time.perf_counter()
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
    return dict(e2e=np.linalg.norm(view.proj_pts - truth["projector"], axis=1)[view.valid],
                at_t=np.linalg.norm(at_truth.proj_pts - truth["projector"], axis=1)[at_truth.valid],
                n=int(view.valid.sum()), dfp=dfp, sfp=sfp, t=time.perf_counter() - t)


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
            results[cname, label] = (ps.count, dict(
                e2e=_rms(np.concatenate([g["e2e"] for g in ok])), at_t=_rms(np.concatenate([g["at_t"] for g in ok])),
                n=min(g["n"] for g in ok), dfp=_rms([g["dfp"] for g in ok]), sfp=float(np.mean([g["sfp"] for g in ok])),
                fails=len(fails)))
            m = results[cname, label][1]
            print(f"  [{time.perf_counter() - t0:5.0f} s] {cname} | {label}: corner {m['e2e']:.4f} px, at truth "
                  f"{m['at_t']:.4f} px, f_p {m['dfp']:.1f} px", file=sys.stderr)
    return base, board, true_fp, seqs, conditions, seeds, results


def table(base, board, true_fp, seqs, conditions, seeds, results):
    print(f"Preset `paper`: {base.cam_size[0]}x{base.cam_size[1]} camera, {base.proj_size[0]}x{base.proj_size[1]} "
          f"projector, {board.n_corners} corners, projector defocus {base.proj_defocus} px, true f_p {true_fp:.1f} px; "
          f"seeds {', '.join(map(str, seeds))}. Corner RMS in projector px over the valid corners (*end to end*: "
          "detected camera corners; *at true cam.*: the true camera corners); f_p: RMS error over the seeds and "
          "the mean stated ±.\n")
    print("| condition | sequence | frames | corners | corner RMS end to end | vs Gray | at true cam. | vs Gray | "
          "f_p error px | vs Gray | f_p ± px | vs Gray |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for cname, *_ in conditions:
        gcount, gray = results[cname, "gray"]
        for label, *_ in seqs:
            count, m = results[cname, label]
            if isinstance(m, str):
                print(f"| {cname} | {label} | {count} | failed: {m} |||||||||")
                continue
            ok = not isinstance(gray, str)
            ratio = (lambda k: f"{m[k] / gray[k]:.2f}" if ok and gray[k] > 0 else "-")
            note = f" ({m['fails']} seed(s) failed)" if m["fails"] else ""
            print(f"| {cname} | {label} | {count} | {m['n']}{note} | {m['e2e']:.4f} | {ratio('e2e')} | "
                  f"{m['at_t']:.4f} | {ratio('at_t')} | {m['dfp']:.1f} | {ratio('dfp')} | {m['sfp']:.1f} | {ratio('sfp')} |")
    print()
    print("Summary: the corner error's ratio to Gray's over the conditions (min-max); *halves* where every "
          "condition's ratio is at most 0.5.\n")
    print("| sequence | end to end vs Gray | halves end to end | at true cam. vs Gray | halves at true cam. |")
    print("|---|---|---|---|---|")
    for label, family, _ in seqs:
        if family == "gray":
            continue
        cells = []
        for k in ("e2e", "at_t"):
            rs = [results[c, label][1][k] / results[c, "gray"][1][k] for c, *_ in conditions
                  if not isinstance(results[c, label][1], str) and not isinstance(results[c, "gray"][1], str)]
            failed = len(rs) < len(conditions)
            cells += [f"{min(rs):.2f}-{max(rs):.2f}" if rs else "-",
                      "no (failed)" if failed else ("yes" if max(rs) <= 0.5 else "no")]
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
