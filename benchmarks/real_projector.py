"""Benchmark: a real projector from one pose (lens shift, off-centre u0p, lens distortion), against the truth.

Projectors drawn at random (seeded) with ``v0p`` = 1.0-1.15 H, ``u0p`` off the panel centre by 0-3 % of W and
OpenCV ``k1`` from -0.15 to 0 (``k2 = -0.15 k1``), each at a board pose drawn from the paper's grid (psi, nu of
the board in the camera, each -30..30 deg, |psi| + |nu| >= 10), the wall behind the board; the fast path (the
simulator's exact geometry plus the noise of a decoded window mean, ``tests/sim_dense.py``; rendered poses are in
the test suite). Per configuration:

* ``wall``: the dense fit with the background (the default);
* ``board``: the background hidden;
* ``datasheet``: board only, with the datasheet's throw ratio (+-0.02) and lens shift (+-2 %) as priors, each
  off the truth by a random error of its own tolerance;
* ``hard``: the ``hard`` preset's lenses (higher radial terms, decentred by a few pixels) and its room corner with
  objects instead of one wall;
* ``today``: the method before the dense fit (the paper's projector, u0p lifted by the background).

Columns: median |error| of f_p (%), u0p, v0p (px), k1 (% of |k1|, where k1 != 0), the 90th percentile of
|error / reported std| (z) for f_p, u0p, v0p, the fraction rated good, and over the poses rated good the largest
f_p error (%) and principal-point error (px); milliseconds per calibration.

``--timing``: ``procam calibrate`` of one rendered pose of a 1920x1080 camera, this checkout against ``--base``
(median of ``--repeat`` fresh processes each, alternating).

    python benchmarks/real_projector.py [--n 40] [--seed 0] [--timing --base REF --repeat 3]
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(ROOT / "tests"))
from _common import header  # noqa: E402
from sim_dense import dense_view  # noqa: E402

from procam import datasheet, simulate  # noqa: E402
from procam import single_pose as sp  # noqa: E402
from procam.single_pose import dense  # noqa: E402

CONFIGS = ("wall", "board", "datasheet", "hard", "today")


def _case(rng, config):
    W, H = 1920, 1080
    if config == "hard":
        base = simulate.preset("hard")
    else:
        k1 = float(rng.uniform(-0.15, 0.0))
        K = np.array([[2421.0, 0, W / 2 - 0.5 + float(rng.uniform(-0.03, 0.03)) * W],
                      [0, 2421.0, float(rng.uniform(1.0, 1.15)) * H], [0, 0, 1]])
        base = simulate.preset("lensshift").replace(K_proj=K, proj_dist_coeffs=(k1, -0.15 * k1, 0.0, 0.0, 0.0))
    while True:
        psi, nu = (float(v) for v in rng.uniform(-30, 30, 2))
        if abs(psi) + abs(nu) >= 10:
            break
    scene = simulate.with_board_pose(base, (psi, nu, 0.0))
    return scene


def _options(config, scene, rng):
    if config == "today":
        return {"dense": None}
    if config in ("board", "datasheet"):
        bg = sp.background.BackgroundOptions(mode="off")
        if config == "board":
            return {"background": bg}
        t = datasheet.datasheet_view(scene.K_proj, scene.proj_size)
        prior = dense.ProjectorPrior(throw_ratio=t.throw_ratio + 0.02 * float(rng.standard_normal()),
                                     throw_ratio_std=0.02,
                                     shift_h_pct=t.shift_h_pct + 2 * float(rng.standard_normal()),
                                     shift_v_pct=t.shift_v_pct + 2 * float(rng.standard_normal()), shift_std_pct=2.0)
        return {"background": bg, "dense": dense.DenseOptions(prior=prior)}
    return {}


def run(config, n, seed):
    rng = np.random.default_rng(seed)
    rows = []
    for i in range(n):
        scene = _case(rng, config)
        view = dense_view(scene, seed=int(rng.integers(1 << 30)), background=config != "board")
        kw = _options(config, scene, rng)
        t = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                cal = sp.calibrate(view, **kw)
            except Exception as e:          # noqa: BLE001 -- a failed pose is a row, not the end of the table
                rows.append({"failed": str(e)})
                continue
        ms = 1000 * (time.perf_counter() - t)
        Kp, Kt = cal.projector.K, np.asarray(scene.K_proj)
        k1 = cal.projector.distortion.coeffs[0] if cal.projector.distortion.model == "opencv" else 0.0
        k1t = scene.proj_dist_coeffs[0] if scene.proj_dist_coeffs else 0.0
        e = {"f_p": Kp[0, 0] - Kt[0, 0], "u0p": Kp[0, 2] - Kt[0, 2], "v0p": Kp[1, 2] - Kt[1, 2]}
        rows.append({"f_pct": 100 * abs(e["f_p"]) / Kt[0, 0], "u0p": abs(e["u0p"]), "v0p": abs(e["v0p"]),
                     "k1_pct": 100 * abs(k1 - k1t) / abs(k1t) if k1t else float("nan"),
                     "z": [abs(e[k]) / cal.std[k] if cal.std.get(k) else float("nan") for k in e],
                     "good": cal.verdict == "good", "ms": ms})
    return rows


def table(results):
    print("| configuration | n | f_p median err (%) | u0p median (px) | v0p median (px) | k1 median (% of |k1|) | "
          "z90 f_p | z90 u0p | z90 v0p | rated good | good: max f_p err (%) | good: max pp err (px) | ms |")
    print("|" + " --- |" * 13)
    for config, rows in results.items():
        ok = [r for r in rows if "failed" not in r]
        if not ok:
            print(f"| {config} | 0 | | | | | | | | | | | |")
            continue
        z = np.array([r["z"] for r in ok], float)
        good = [r for r in ok if r["good"]]
        med = {k: float(np.nanmedian([r[k] for r in ok])) for k in ("f_pct", "u0p", "v0p", "k1_pct", "ms")}
        z90 = [float(np.nanpercentile(z[:, j], 90)) if np.isfinite(z[:, j]).any() else float("nan") for j in range(3)]
        gf = max((r["f_pct"] for r in good), default=float("nan"))
        gp = max((max(r["u0p"], r["v0p"]) for r in good), default=float("nan"))
        print(f"| {config} | {len(ok)}{f' (+{len(rows) - len(ok)} failed)' if len(rows) > len(ok) else ''} | "
              f"{med['f_pct']:.3f} | {med['u0p']:.1f} | {med['v0p']:.1f} | {med['k1_pct']:.1f} | {z90[0]:.2f} | "
              f"{z90[1]:.2f} | {z90[2]:.2f} | {len(good)}/{len(ok)} | {gf:.2f} | {gp:.1f} | {med['ms']:.0f} |")


def timing(base, repeat):
    """``procam calibrate`` of one rendered pose of a 1920x1080 camera: this checkout against ``base``."""
    import os
    import statistics
    import subprocess
    import tempfile

    procam = [sys.executable, "-c", "import sys; from procam.cli import main; sys.argv[0] = 'procam'; main()"]
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        scene = simulate.preset("lensshift").scaled(1.5)        # a 1920x1200 camera, the same field of view
        scene = simulate.with_board_pose(scene, simulate.RECOMMENDED_POSE)
        stack, truth = simulate.render(scene, seed=1)
        simulate.write_capture(tmp / "pose", stack, truth)
        wt = tmp / "base"
        subprocess.run(["git", "worktree", "add", "--detach", str(wt), base], cwd=ROOT, check=True,
                       capture_output=True)
        try:
            times = {"base": [], "this": []}
            for _ in range(repeat):
                for side, src in (("base", wt / "src"), ("this", ROOT / "src")):
                    out = tmp / f"c-{side}.json"
                    out.unlink(missing_ok=True)
                    t = time.perf_counter()
                    r = subprocess.run(procam + ["calibrate", str(tmp / "pose"), "--board", "10x6", "--square",
                                                 "24", "-o", str(out), "--force"], capture_output=True, text=True,
                                       env={**os.environ, "PYTHONPATH": str(src)})
                    times[side].append(time.perf_counter() - t)
                    if r.returncode not in (0, 3):
                        raise SystemExit(f"{side}: {r.stderr[-400:]}")
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(wt)], cwd=ROOT, capture_output=True)
    b, t = statistics.median(times["base"]), statistics.median(times["this"])
    print(f"\nprocam calibrate, one pose, camera {scene.cam_size[0]}x{scene.cam_size[1]}, projector 1920x1080 "
          f"(median of {repeat} fresh processes): {base} {b:.2f} s, this checkout {t:.2f} s, ratio {t / b:.2f}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", type=int, default=40, help="cases per configuration")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--configs", default=",".join(CONFIGS))
    ap.add_argument("--timing", action="store_true")
    ap.add_argument("--base", default="HEAD~1")
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    print(header("a real projector from one pose"))
    results = {c: run(c, a.n, a.seed) for c in a.configs.split(",")}
    table(results)
    if a.timing:
        timing(a.base, a.repeat)


if __name__ == "__main__":
    main()
