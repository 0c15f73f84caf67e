"""Benchmark (issue 38): does the single-pose ± hold on a close scanner rig?  Each suspect kind alone and combined.

The second real rig: a structured-light scanner, camera 1688x1352, projector 1824x1140 (lens shift: v0p at the
panel's last row), 3-step phase shift of 16 fringes, a 13x9 board (inner corners) of 10 mm squares 330-400 mm
from the devices, turned up to 38 deg, in some poses lit by the projector on part of the board only.  The rig
here (``tests/sim_scanner.py``): f_c 2400 px, f_p 2300 px, the projector 110 mm beside the camera converging on the
board (``wide``: 190 mm, about 28 deg), a wall 250 mm behind the board (decoded in ``wall`` only); OpenCV k1 -0.05
on the projector, division k1 -2e-8 on the camera.  The fast path (``tests/sim_dense.py``: exact geometry plus decode-like noise; two renders of the rig are
in docs/accuracy.md, section 5).

Kinds (each case a board pose drawn at random, seeded: |psi| + |nu| from 15 to 45 deg, each at most 38 deg, the
board 330-400 mm away):

* ``wall``: the scanner rig as above with the wall behind the board lit and decoded (as on the first rig);
* ``base``: the scanner rig as the scanner's captures have it: nothing decoded behind the board (the board alone);
* ``harmonic``: a third harmonic of the fringe left by a projector gamma (0.25 px, ``sim_dense.harmonic``);
* ``partly``: the projector lights the board up to a panel column that leaves about half of its corners lit;
* ``edge``: the samples within two windows of the lit board's edge off by 0.6 px, pointing out of it;
* ``wide``: a wide camera-projector convergence (190 mm baseline);
* ``all``: every kind at once;
* ``rim``: the board half lit and its rim 1.5 px off (a window half dark decodes that far off).

Paths: ``both`` (camera and projector from the pose), ``cam known`` (the true camera given), ``proj known`` (the
true projector given).  Columns: per parameter the 90th percentile and the largest of |error| / ± (z), the
count of |z| > 3, the same count and the largest z of procam before issue 38 (:data:`BEFORE`: no rim test, no
batch means), the poses whose rim disagreed with the rest of the board (left out), the verdicts; the errors
are against the simulator's truth.

``--study N``: the calibration study instead (:func:`study`): N cases spanning the far narrow rig (75 mm squares
near 3 m, the wall behind the board decoded) and the close scanner (10 mm squares, nothing behind), Gray and
3-step phase decoders, the board whole or partly lit, a decoder's error of 0-0.6 px at the lit board's rim.

    python benchmarks/sigma_rigs.py [--n 8] [--seed 0] [--kinds base,harmonic,...]
    python benchmarks/sigma_rigs.py --study 104
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(ROOT / "tests"))
from _common import header  # noqa: E402
from sim_dense import dense_view  # noqa: E402
from sim_scanner import far_rig, scanner  # noqa: E402

from procam import models, simulate  # noqa: E402
from procam import single_pose as sp  # noqa: E402
from procam.single_pose import dense  # noqa: E402

KINDS = ("wall", "base", "harmonic", "partly", "edge", "wide", "all", "rim")
PATHS = ("both", "cam known", "proj known")
PARAMS = ("f_c", "f_p", "u0p", "v0p", "R", "T")
#: The dense fit as it was before issue 38: no rim test, no batch means.
BEFORE = dense.DenseOptions(rim_windows=0, batch_windows=0)
#: The intrinsics each path estimates.
ESTIMATED = {"both": ("f_c", "f_p", "u0p", "v0p"), "cam known": ("f_p", "u0p", "v0p"), "proj known": ("f_c",)}


def case(kind: str, rng) -> tuple:
    """(scene, dense_view keyword arguments) of one case of ``kind``."""
    base = scanner(190.0 if kind in ("wide", "all") else 110.0)
    while True:
        psi, nu = (float(v) for v in rng.uniform(-38, 38, 2))
        if 15 <= abs(psi) + abs(nu) <= 45 and max(abs(psi), abs(nu)) <= 38:
            break
    scene = simulate.with_board_pose(base, (psi, nu, float(rng.uniform(-10, 10))),
                                     distance=float(rng.uniform(330, 400)))
    kw = {"background": kind == "wall"}
    if kind in ("harmonic", "all"):
        kw["harmonic_px"] = 0.25
    if kind in ("edge", "all"):
        kw["edge_bias_px"] = 0.6
    if kind == "rim":
        kw["edge_bias_px"] = 1.5
    if kind in ("partly", "all", "rim"):
        c = simulate.corner_truth(scene)["projector"][:, 0]
        kw["lit"] = (0, float(np.quantile(c, float(rng.uniform(0.45, 0.6)))))
    return scene, kw


def errors(cal, scene, path: str) -> dict:
    """|error| / ± of each parameter this path estimates (R: the largest over its three angles, T: over its
    components)."""
    z = {}
    Kc, Kp = np.asarray(scene.K_cam), np.asarray(scene.K_proj)
    s = cal.std
    est = {"f_c": cal.camera.K[0, 0] - Kc[0, 0], "f_p": cal.projector.K[0, 0] - Kp[0, 0],
           "u0p": cal.projector.K[0, 2] - Kp[0, 2], "v0p": cal.projector.K[1, 2] - Kp[1, 2]}
    for name in ESTIMATED[path]:
        # a parameter the path holds at an assumption (the paper's u0p = W/2) has no ±: its z is infinite
        e = est[name]
        z[name] = abs(e) / s[name] if s.get(name) else (0.0 if abs(e) < 1e-9 else float("inf"))
    dR = (models.euler_deg(cal.R) - models.euler_deg(np.asarray(scene.R)) + 180.0) % 360.0 - 180.0
    z["R"] = float(np.max(np.abs(dR) / np.asarray(s["R_euler_deg"])))
    z["T"] = float(np.max(np.abs(np.asarray(cal.T) - np.asarray(scene.T)) / np.asarray(s["T"])))
    return z


def run_case(scene, kw, seed: int, paths=PATHS, before: bool = True) -> dict:
    """{path: {parameter: z, "verdict": ..., "before": {parameter: z without the rim test} (``before``)}} of one
    case (a failed fit: {"failed": why})."""
    view = dense_view(scene, seed=seed, **kw)
    truth = simulate.truth_calibration(scene)
    out = {}
    for path in paths:
        opts = {"cam known": {"known_camera": truth.camera}, "proj known": {"known_projector": truth.projector}}
        cals = []
        # procam before issue 38 (no rim test, no batch means), and now
        for o in ((BEFORE,) if before else ()) + (dense.DenseOptions(),):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                try:
                    cals.append(sp.calibrate(view, dense=o, **opts.get(path, {})))
                except Exception as e:          # noqa: BLE001 -- a failed pose is a row, not the end of the table
                    cals.append(str(e)[:80])
        if isinstance(cals[-1], str):
            out[path] = {"failed": cals[-1]}
            continue
        cal = cals[-1]
        out[path] = {**errors(cal, scene, path), "verdict": cal.verdict,
                     "before": errors(cals[0], scene, path) if before and not isinstance(cals[0], str) else {},
                     "rim": cal.info["dense"].rim_left_out > 0 if cal.info.get("dense") else False,
                     "lit": int(np.isfinite(view.proj_pts).all(1).sum())}
    return out


def _cells(ok, key=None):
    cells, big, total = [], 0, 0
    for p in PARAMS:
        z = np.array([(r if key is None else r[key])[p] for r in ok if p in r], float)
        if not len(z):
            cells.append("-")
            continue
        cells.append(f"{np.percentile(z, 90):.2f} / {z.max():.1f}")
        big += int((z > 3).sum())
        total += len(z)
    return cells, f"{big}/{total}"


def table(rows_by_kind: dict, paths=PATHS) -> None:
    """Per kind and path: z90 / max |z| per parameter, the count of |z| > 3 now and before issue 38 (:data:`BEFORE`),
    the poses whose rim disagreed (left out), the verdicts."""
    print("| kind | path | n | " + " | ".join(f"z90 / max {p}" for p in PARAMS)
          + " | |z| > 3 | before: |z| > 3 (max) | rim | verdicts |")
    print("|" + " --- |" * (len(PARAMS) + 7))
    for kind, rows in rows_by_kind.items():
        for path in paths:
            ok = [r[path] for r in rows if "failed" not in r[path]]
            failed = len(rows) - len(ok)
            cells, big = _cells(ok)
            before = [max((v for k, v in r["before"].items() if k in PARAMS), default=0.0) for r in ok]
            _, big0 = _cells(ok, "before")
            v = {}
            for r in ok:
                v[r["verdict"]] = v.get(r["verdict"], 0) + 1
            print(f"| {kind} | {path} | {len(ok)}{f' (+{failed} failed)' if failed else ''} | " + " | ".join(cells)
                  + f" | {big} | {big0} ({max(before, default=0):.1f}) | {sum(r['rim'] for r in ok)} | "
                  + f"{', '.join(f'{k} {n}' for k, n in sorted(v.items()))} |")


#: The study's decoders on the fast path: the noise of a window mean of the decoded samples (px), of the projector
#: corners, and the third harmonic a 3-step phase decode leaves after its gamma correction (px).
DECODERS = {"gray": {"sigma_sample": 0.03, "sigma_proj": 0.05, "harmonic_px": 0.0},
            "phase": {"sigma_sample": 0.015, "sigma_proj": 0.03, "harmonic_px": 0.1}}


def study_case(i: int, rng) -> tuple:
    """Case ``i`` of the study: (label, scene, dense_view keyword arguments). The rig (the far narrow rig: 75 mm
    squares near 3 m, the wall behind lit; the close scanner: 10 mm squares at 330-400 mm, nothing behind), the
    decoder (Gray or 3-step phase) and the lighting (whole or part of the board) cycle with ``i``; the pose, the
    lit part and the decoder's error at the lit board's rim (0-0.6 px) are drawn. Both rigs at half their pixels
    (the same angles of view; the decoders' errors in those pixels)."""
    rig, decoder, partly = ("far", "scanner")[i % 2], ("gray", "phase")[(i // 2) % 2], bool((i // 4) % 2)
    while True:
        psi, nu = (float(v) for v in rng.uniform(-38, 38, 2))
        if 15 <= abs(psi) + abs(nu) <= 45:
            break
    if rig == "far":
        scene = simulate.with_board_pose(far_rig(), (psi, nu, float(rng.uniform(-10, 10))),
                                         distance=float(rng.uniform(2800, 3300)))
    else:
        scene = simulate.with_board_pose(scanner(float(rng.uniform(90, 190))), (psi, nu, float(rng.uniform(-10, 10))),
                                         distance=float(rng.uniform(330, 400)))
    scene = scene.scaled(0.5)        # half the pixels, the same angles of view: a quarter of the time
    kw = {**DECODERS[decoder], "background": rig == "far", "edge_bias_px": float(rng.uniform(0, 0.6))}
    if partly:
        c = simulate.corner_truth(scene)["projector"][:, 0]
        kw["lit"] = (0, float(np.quantile(c, float(rng.uniform(0.45, 0.7)))))
    return f"{rig} {decoder} {'partly' if partly else 'whole'}", scene, kw


def study(n: int, seed: int) -> None:
    """The calibration study of the ± (issue 38): ``n`` cases of :func:`study_case`, every path (procam as it is;
    no before-column: half the time); per path and parameter, over the poses procam writes (good or weak), the
    90th percentile of |z|, the largest, and how many exceed 3.5."""
    rng = np.random.default_rng([seed, 38])
    rows, labels = [], []
    for i in range(n):
        label, scene, kw = study_case(i, rng)
        rows.append(run_case(scene, kw, int(rng.integers(1 << 30)), before=False))
        labels.append(label)
        zs = {p: {**{k: round(float(v), 2) for k, v in r.items() if k in PARAMS}, "verdict": r["verdict"]}
              for p, r in rows[-1].items() if "failed" not in r}
        print(f"case {i}: {label}: {zs}", flush=True)      # as it goes: a long study shows its progress
    print(f"\n## The study: {n} cases (fast path), |error| / ± per path\n")
    print("The poses procam writes (rated good or weak); a pose rated degenerate or failed is refused (exit code 3),"
          " its largest |z| in the last column.\n")
    print("| path | written | " + " | ".join(f"z90 / max {p}" for p in PARAMS) + " | |z| > 3.5 | rim left out | "
          "verdicts | refused: largest |z| |")
    print("|" + " --- |" * (len(PARAMS) + 6))
    for path in PATHS:
        done = [r[path] for r in rows if "failed" not in r[path]]
        ok = [r for r in done if r["verdict"] in ("good", "weak")]
        refused = [max(v for k, v in r.items() if k in PARAMS) for r in done if r not in ok]
        cells, _ = _cells(ok)
        big = sum(v > 3.5 for r in ok for k, v in r.items() if k in PARAMS)
        v = {}
        for r in done:
            v[r["verdict"]] = v.get(r["verdict"], 0) + 1
        print(f"| {path} | {len(ok)} of {len(rows)} | " + " | ".join(cells) + f" | {big} | "
              + f"{sum(r['rim'] for r in done)} | {', '.join(f'{k} {c}' for k, c in sorted(v.items()))} | "
              + f"{max(refused, default=float('nan')):.1f} |")
    print("\nper kind, the largest |z| of a written pose over the paths and parameters:\n")
    for label in sorted(set(labels)):
        zs = [max((v for p in PATHS if "failed" not in r[p] and r[p]["verdict"] in ("good", "weak")
                   for k, v in r[p].items() if k in PARAMS), default=0.0)
              for r, lb in zip(rows, labels) if lb == label]
        print(f"- {label}: {len(zs)} cases, {max(zs):.2f}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", type=int, default=8, help="cases per kind")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--kinds", default=",".join(KINDS))
    ap.add_argument("--study", type=int, default=0, help="run the calibration study of this many cases instead")
    a = ap.parse_args()
    if a.study:
        print(header("the calibration study of the single-pose ± over two rigs' kinds (issue 38)"))
        study(a.study, a.seed)
        return
    print(header("the single-pose ± on a close scanner rig, per suspect kind (issue 38)"))
    results = {}
    for kind in a.kinds.split(","):
        rng = np.random.default_rng([a.seed, KINDS.index(kind)])
        rows = []
        for _ in range(a.n):
            scene, kw = case(kind, rng)
            rows.append(run_case(scene, kw, int(rng.integers(1 << 30))))
        results[kind] = rows
    table(results)


if __name__ == "__main__":
    main()
