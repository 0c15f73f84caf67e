"""Same inputs -> the same bytes, for every command: two runs, and OpenBLAS with one thread against two.

Outputs are compared file by file (hidden manifests included).  A capture's ``capture.json`` records the
time of every frame, so it is the one file left out (its frames and patterns.json are compared).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import run_cli
from test_bad_inputs import render_poses

from procam import io

SRC = Path(__file__).resolve().parents[1] / "src"
BOARD = ["--board", "10x6", "--square", "24"]


@pytest.fixture(scope="module")
def rig(tmp_path_factory):
    """Three small rendered poses and their true calibration."""
    from procam.simulate import truth_calibration
    from sim_small import small_scene

    root = tmp_path_factory.mktemp("rig")
    poses = render_poses(root)
    calib = io.save_calibration(truth_calibration(small_scene()), root / "truth.json")
    return poses, calib


def commands(poses, calib, out: Path) -> list[list]:
    """Every command with every output it can write, into ``out``."""
    p1 = poses[0]
    return [
        ["patterns", "-p", "64x48", "-o", out / "patterns"],
        ["decode", p1, "-o", out / "maps.npz", "--png", out / "decode.png"],
        ["correspond", p1, *BOARD, "-o", out / "corr.json", "--png", out / "corr.png"],
        ["calibrate", p1, *BOARD, "-o", out / "single.json", "--yaml", out / "single.yml", "--png", out / "single.png"],
        ["calibrate", *poses, *BOARD, "-o", out / "multi.json", "--yaml", out / "multi.yml", "--png", out / "multi.svg"],
        ["evaluate", calib, *poses, *BOARD, "-o", out / "eval.json"],
        ["reconstruct", calib, p1, "-o", out / "cloud.ply", "--board", "10x6", "--residuals", out / "plane.png"],
        ["export", calib, "--format", "opengl", "-o", out / "gl.json", "--near", "10", "--far", "5000"],
        ["export", calib, "--format", "kamino410", "-o", out / "kamino.xml"],
        ["export", calib, "--format", "maps", "-o", out / "maps", "--rectify"],
        ["study", "projector", "-o", out / "study", "--grid", "0,15", "--trials", "2", "--slice-grid", "15",
         "--model-error", "none"],
        ["experiment", *poses, *BOARD, "-o", out / "experiment"],
    ]


def tree(folder: Path, skip=("capture.json",)) -> dict:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file() and p.name not in skip}


def assert_same(a: Path, b: Path):
    ta, tb = tree(a), tree(b)
    assert sorted(ta) == sorted(tb)
    differ = [k for k in ta if ta[k] != tb[k]]
    assert not differ, f"not byte-identical: {differ}"


def test_multi_pose_calibration_twice_gives_the_same_bytes(rig, tmp_path):
    """OpenCV's threads used to change the last digits (and the winning start) from run to run."""
    poses, _ = rig
    for run in ("a", "b"):
        rc, _, err = run_cli(["calibrate", *poses, *BOARD, "-o", tmp_path / f"{run}.json", "--yaml",
                              tmp_path / f"{run}.yml"])
        assert rc == 0, err
    for suffix in (".json", ".yml"):
        assert (tmp_path / f"a{suffix}").read_bytes() == (tmp_path / f"b{suffix}").read_bytes()


@pytest.mark.slow
def test_every_command_twice_gives_the_same_bytes(rig, tmp_path):
    poses, calib = rig
    for run in ("a", "b"):
        out = tmp_path / run
        out.mkdir()
        for args in commands(poses, calib, out):
            rc, _, err = run_cli(args)
            assert rc == 0, (args, err)
    assert len(tree(tmp_path / "a")) > 40
    assert_same(tmp_path / "a", tmp_path / "b")
    doc = json.loads((tmp_path / "a" / "multi.json").read_text())
    assert doc["info"]["frozen"]["cam_init"] in ("opencv", "zhang")


_RUNNER = """
import json, sys
from procam.cli import main
for args in json.loads(sys.argv[1]):
    try:
        main(args)
    except SystemExit as e:
        if e.code:
            sys.exit(f"{args}: exit {e.code}")
"""


@pytest.mark.slow
def test_blas_threads_do_not_change_the_bytes(rig, tmp_path):
    """The numeric commands in fresh interpreters with OPENBLAS_NUM_THREADS=1 and =2 (and OpenCV's default
    threads): the same bytes."""
    poses, calib = rig
    for n in ("1", "2"):
        out = tmp_path / f"blas{n}"
        out.mkdir()
        args = [[str(a) for a in c] for c in commands(poses, calib, out) if c[0] != "patterns"]
        env = dict(os.environ, OPENBLAS_NUM_THREADS=n, OMP_NUM_THREADS=n, MPLBACKEND="Agg",
                   PYTHONPATH=os.pathsep.join([str(SRC), os.environ.get("PYTHONPATH", "")]))
        res = subprocess.run([sys.executable, "-c", _RUNNER, json.dumps(args)], env=env, capture_output=True,
                             text=True, timeout=900, check=False)
        assert res.returncode == 0, res.stderr[-2000:]
    assert_same(tmp_path / "blas1", tmp_path / "blas2")


@pytest.mark.slow
@pytest.mark.parametrize("cmd", ["simulate", "demo", "capture"])
def test_rendering_commands_twice(cmd, tmp_path):
    out = tmp_path / "out"  # one path for both runs: the demo's calibration names its capture folder
    args = {"simulate": ["simulate", out, "--seed", "5"], "demo": ["demo", out],
            "capture": ["capture", out, "--virtual", "--projector", "64x48"]}[cmd]
    for run in ("a", "b"):
        rc, _, err = run_cli(args)
        assert rc == 0, err
        out.rename(tmp_path / run)
    assert_same(tmp_path / "a", tmp_path / "b")


def test_one_thread_holds_while_any_caller_is_inside():
    """Leave-one-out refits run two at a time: the first to finish must not restore OpenCV's threads under
    the other (which would then sum in another order); the last to finish restores them."""
    import threading

    import cv2

    from procam._threads import deterministic

    before = cv2.getNumThreads()
    cv2.setNumThreads(3)
    try:
        a_in, a_out, seen = threading.Event(), threading.Event(), []

        def first():
            with deterministic():
                a_in.set()
                a_out.wait(10)

        t = threading.Thread(target=first)
        t.start()
        a_in.wait(10)
        with deterministic():  # the second caller enters while the first is inside ...
            a_out.set()
            t.join(10)  # ... and the first leaves
            seen.append(cv2.getNumThreads())
        assert seen == [1] and cv2.getNumThreads() == 3
    finally:
        cv2.setNumThreads(before)


def test_a_phase_decode_gives_the_same_bits_wherever_its_buffers_lie():
    """OpenCV's magnitude rounded the last bit of some pixels by where its inputs and output lay in memory: a phase
    decode's confidence differed by one float32 ulp at thousands of pixels between runs.  Here the heap is shifted
    between decodes (arrays of odd sizes kept alive), as another run's allocations would."""
    from test_phase import panel

    from procam import patterns
    from procam.decode.phase import PhaseOptions, decode_phase

    ps = patterns.pattern_set(320, 200, family="phase", steps=8, period=16)
    stack = panel(ps, noise=2.0, seed=4)
    runs, junk = [], []
    for k in range(6):
        junk.append(np.empty(1000 * k + 7 * k + 3, np.uint8))
        res = decode_phase(stack, ps, PhaseOptions(gamma=1.0), band=16)
        runs.append(b"".join(a.tobytes() for a in (res.confidence, res.modulation_col, res.modulation_row,
                                                   res.col, res.row, res.sigma_col)))
    assert all(r == runs[0] for r in runs[1:])


def render_phase_poses(root: Path) -> list:
    """The three poses of ``render_poses`` rendered with phase fringes (procam's default phase sequence)."""
    from sim_small import small_scene
    from test_bad_inputs import POSE_ANGLES

    from procam import patterns, simulate

    ps = patterns.pattern_set(*small_scene().proj_size, family="phase")
    folders = []
    for k, a in enumerate(POSE_ANGLES):
        stack, truth = simulate.render(simulate.with_board_pose(small_scene(), a), order=ps, seed=k)
        simulate.write_capture(root / f"pose{k + 1}", stack, truth, order=ps)
        folders.append(root / f"pose{k + 1}")
    return folders


def decode_calibrate_export(poses, out: Path) -> list[list]:
    """decode, calibrate and export with every output they can write, into ``out``."""
    p1, cal = poses[0], out / "multi.json"
    exp = ["export", cal, "--format"]
    return [
        ["decode", p1, "-o", out / "maps.npz", "--png", out / "decode.png"],
        ["calibrate", p1, *BOARD, "-o", out / "single.json", "--yaml", out / "single.yml", "--png", out / "single.png"],
        ["calibrate", *poses, *BOARD, "-o", cal, "--yaml", out / "multi.yml", "--png", out / "multi.svg",
         "--report", out / "multi.html"],
        exp + ["opengl", "-o", out / "gl.json", "--near", "10", "--far", "5000"],
        exp + ["blender", "-o", out / "blender.json"],
        exp + ["unity", "-o", out / "unity.json"],
        exp + ["kamino410", "-o", out / "kamino.xml"],
        exp + ["yaml", "-o", out / "opencv.xml"],
        exp + ["maps", "-o", out / "maps", "--rectify"],
        exp + ["projector-view", "--pose", p1, "--maps", out / "maps.npz", "-o", out / "view.png"],
    ]


@pytest.mark.slow
@pytest.mark.parametrize("family", ["gray", "phase"])
def test_decode_calibrate_and_export_give_the_same_bytes_in_two_interpreters(family, rig, tmp_path_factory, tmp_path):
    """Every output of decode, calibrate and export, Gray and phase, each run in a fresh interpreter (another heap,
    other addresses: the phase decode's confidence used to differ by one ulp between runs)."""
    poses = rig[0] if family == "gray" else render_phase_poses(tmp_path_factory.mktemp("phase"))
    for run in ("a", "b"):
        out = tmp_path / run
        out.mkdir()
        args = [[str(a) for a in c] for c in decode_calibrate_export(poses, out)]
        env = dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=os.pathsep.join([str(SRC), os.environ.get("PYTHONPATH", "")]))
        res = subprocess.run([sys.executable, "-c", _RUNNER, json.dumps(args)], env=env, capture_output=True,
                             text=True, timeout=900, check=False)
        assert res.returncode == 0, res.stderr[-2000:]
    assert len(tree(tmp_path / "a")) > 20
    assert_same(tmp_path / "a", tmp_path / "b")
