"""Rig calibration figures (the numbers in docs/rigs.md): accuracy against the simulator's truth over noise seeds,
and time and memory of a 4-projector rig at 5 poses with 1920x1080 devices.

* accuracy: the presets two_projectors and two_cameras, 3 board poses (tests/rig_sim.py's), corner fast path with
  sigma_cam / sigma_proj px noise; per seed the worst |error| / std over every device's f, fy, u0, v0 and every
  relative pose's angles and T, and the device-to-device translation error as % of the baseline (the projectors'
  for two_projectors, the cameras' for two_cameras).
* scale: one camera and 4 projectors (all 1920x1080, converging on a wall at 2.2 m), 5 board poses: the joint
  calibration from the corner fast path (time, peak RSS of its own process), and one pair's capture rendered and
  decoded at 1920x1080 (time, peak RSS) -- the 20 pairs of a full run take 20 times that one's render and decode.

Usage::

    python benchmarks/rigs.py [--seeds 6] [--sigma-cam 0.02] [--sigma-proj 0.03] [--skip-render]
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import json
import resource
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent / "tests"))
sys.path.insert(0, str(HERE.parent / "src"))

from _common import header  # noqa: E402


def accuracy(name, seed, s_cam, s_proj):
    from procam import models
    from procam.errors import ProcamWarning
    from procam.rig import calibrate_rig
    from rig_sim import fast_views

    rig, poses = fast_views(name, 3, s_cam, s_proj, seed=1000 * seed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ProcamWarning)
        t = time.perf_counter()
        rc = calibrate_rig(poses)
        dt = time.perf_counter() - t
    z = 0.0
    for d in rc.devices:
        K = rig.device(d.name).K
        for key, i, j in (("f", 0, 0), ("fy", 1, 1), ("u0", 0, 2), ("v0", 1, 2)):
            z = max(z, abs(d.device.K[i, j] - K[i, j]) / d.std[key])
    for key, r in rc.relative.items():
        a, b = key.split("->")
        R, T = rig.relative_pose(a, b)
        z = max(z, np.max(np.abs(r.angles_deg - models.euler_deg(R)) / r.std_angles_deg),
                np.max(np.abs(r.T - T) / r.std_T))
    _, T = rig.relative_pose("left", "right")
    err = 100 * np.linalg.norm(rc.relative["left->right"].T - T) / np.linalg.norm(T)
    r = rc.relative["left->right"]
    return z, err, 100 * np.linalg.norm(r.std_T) / r.baseline, dt, rc.verdict


def four_projector_rig():
    from procam import simulate as sim
    from procam.simulate.lens import _K

    K = _K(2300.0, 1.0, 959.5, 539.5)
    cam = sim.Device("cam", "camera", (1920, 1080), K)
    projs = []
    for i, x in enumerate((-450.0, -150.0, 150.0, 450.0)):
        ang = np.degrees(np.arctan2(x, 2200.0))  # turned towards the middle (as the presets: -x turns to +x)
        R = sim.euler_matrix((0.0, ang, 0.0))
        projs.append(sim.Device(f"p{i + 1}", "projector", (1920, 1080), _K(2400.0, 1.0, 959.5, 1000.0), R=R,
                                T=-R @ np.array([x, 60.0, 0.0])))
    base = sim.Rig((cam,), tuple(projs), sim.Scene(background=sim.Background.wall(2200.0), square=40.0), "four")
    return base


def scale_calibration():
    from procam import simulate as sim
    from procam.errors import ProcamWarning
    from procam.rig import RigPoseViews, calibrate_rig
    from procam.view import View

    base = four_projector_rig()
    poses = []
    t0 = time.perf_counter()
    for j, a in enumerate(((18, 14, 0), (-16, 18, 6), (12, -16, -6), (-14, -14, 4), (20, -10, 8))):
        r = base.with_board_pose(a)
        views = {}
        for i, (c, p) in enumerate(r.pairs()):
            sc = r.scene(c, p)
            obj, cam, proj = sim.correspondences(sc, 0.02, 0.03, seed=10 * j + i)
            views[(c, p)] = View(obj, cam, proj, f"pose{j + 1}", sc.cam_size, sc.proj_size)
        poses.append(RigPoseViews(f"pose{j + 1}", ("cam",), tuple(d.name for d in base.projectors), views))
    t_sim = time.perf_counter() - t0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ProcamWarning)
        t = time.perf_counter()
        rc = calibrate_rig(poses)
        dt = time.perf_counter() - t
    _, T = base.relative_pose("p1", "p4")
    err = 100 * np.linalg.norm(rc.relative["p1->p4"].T - T) / np.linalg.norm(T)
    return {"placement_s": t_sim, "calibrate_s": dt, "verdict": rc.verdict, "p1_p4_err_pct": err,
            "devices": len(rc.devices)}


def scale_render():
    from procam import pipeline
    from procam import simulate as sim
    from procam.board import Board

    r = four_projector_rig().with_board_pose((18, 14, 0))
    t = time.perf_counter()
    sc = r.scene("cam", "p2")
    stack, _ = sim.render(sc, seed=1)
    t_render = time.perf_counter() - t
    t = time.perf_counter()
    view, _ = pipeline.view_from_stack(stack, sim.Renderer(sc).pattern_set, Board(10, 6, 40.0), keep_maps=False)
    t_dec = time.perf_counter() - t
    return {"render_s": t_render, "decode_s": t_dec, "corners": int(view.valid.sum()), "stack_mb": stack.nbytes / 2**20}


def child(phase):
    out = {"calibrate": scale_calibration, "render": scale_render}[phase]()
    out["peak_rss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(json.dumps(out))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, default=6)
    ap.add_argument("--sigma-cam", type=float, default=0.02)
    ap.add_argument("--sigma-proj", type=float, default=0.03)
    ap.add_argument("--skip-render", action="store_true")
    ap.add_argument("--phase", default=None)
    a = ap.parse_args()
    if a.phase:
        return child(a.phase)
    print(header("rig calibration on the simulator"))
    print(f"accuracy: 3 poses, corner fast path, sigma {a.sigma_cam} px camera / {a.sigma_proj} px projector\n")
    print("| rig | seed | worst abs(err)/std | left->right T err (% baseline) | norm of T's std (% baseline) | time (s) | verdict |")
    print("|---|---|---|---|---|---|---|")
    for name in ("two_projectors", "two_cameras"):
        for s in range(a.seeds):
            z, err, sd, dt, v = accuracy(name, s, a.sigma_cam, a.sigma_proj)
            print(f"| {name} | {s} | {z:.2f} | {err:.3f} | {sd:.3f} | {dt:.2f} | {v} |")
    phases = ["calibrate"] + ([] if a.skip_render else ["render"])
    print("\nscale: 1 camera + 4 projectors, 1920x1080 each, 5 poses (each phase in its own process)\n")
    for ph in phases:
        res = subprocess.run([sys.executable, __file__, "--phase", ph], capture_output=True, text=True, check=False)
        line = res.stdout.strip().splitlines()[-1] if res.stdout.strip() else res.stderr.strip()[-300:]
        print(f"- {ph}: {line}")


if __name__ == "__main__":
    main()
