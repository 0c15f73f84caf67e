"""procam calibrate starts reading the pose folders before anything else (issue 35): the reader threads stop on
every way out -- a refused option, a failed pose, a written calibration -- and the result is the one read the
ordinary way."""

from __future__ import annotations

import json
import threading

import pytest
from conftest import run_cli, within

BOARD = ["--board", "10x6", "--square", "24"]


def _readers() -> list:
    return [t.name for t in threading.enumerate() if t.name.startswith("procam-read") and t.is_alive()]


@pytest.fixture(scope="module")
def poses(tmp_path_factory):
    from test_bad_inputs import render_poses

    return render_poses(tmp_path_factory.mktemp("ahead"))


@pytest.mark.parametrize("case", ["refused option", "refused output", "failed pose", "written"])
def test_the_reader_threads_stop_on_every_way_out(poses, tmp_path, case):
    args = ["calibrate", *map(str, poses), *BOARD, "-o", tmp_path / "calib.json"]
    if case == "refused option":
        args += ["--throw-ratio", "1.2"]  # a single-pose prior: refused for a multi-pose calibration
    elif case == "refused output":
        args[-1] = tmp_path / "calib.txt"
    elif case == "failed pose":
        args[1 + len(poses):3 + len(poses)] = ["--board", "7x5"]  # no 7x5 board in any pose
        args += ["--strict"]
    assert not _readers()
    code, _, err = run_cli(args)
    assert code == (0 if case == "written" else 2), err
    assert not _readers(), f"{case}: reader threads left running"
    if case == "written":
        assert json.loads((tmp_path / "calib.json").read_text())["method"] == "multi-pose"
    else:
        assert not (tmp_path / "calib.json").exists()


def test_the_poses_read_ahead_give_the_views_read_one_by_one(poses):
    """The Prefetcher started first thing hands over the very stacks read_images reads."""
    import numpy as np

    from procam import capture
    from procam.io import files, images
    from procam.stream import Prefetcher

    with Prefetcher(poses) as pf:
        for folder in poses:
            names, _ = capture.sequence_files(folder, files.list_images(folder))
            np.testing.assert_array_equal(pf.read(names), images.read_images(names))


def test_a_multi_pose_calibrate_does_not_import_the_single_pose_solver(poses, tmp_path):
    """procam calibrate of several poses imports what a multi-pose calibration uses (issue 35: imports only where
    used); the single-pose solver (0.08 CPU-s to import) only for one pose, a rig or --camera-only."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    import procam

    code = ("import sys; from procam.cli import main; sys.argv[0] = 'procam'\n"
            "try:\n    main(sys.argv[1:])\nexcept SystemExit as e:\n    assert e.code in (0, None), e.code\n"
            "print(sorted(m for m in sys.modules if m.startswith('procam.single_pose')))")
    env = dict(os.environ, PYTHONPATH=str(Path(procam.__file__).parents[1]))
    res = subprocess.run([sys.executable, "-c", code, "calibrate", *map(str, poses), *BOARD, "-o",
                          str(tmp_path / "calib.json")], env=env, capture_output=True, text=True, check=True)
    assert res.stdout.strip().splitlines()[-1] == "[]", res.stdout[-500:]
    assert json.loads((tmp_path / "calib.json").read_text())["method"] == "multi-pose"


def test_a_stack_is_filled_again_only_when_nothing_refers_to_it(poses):
    """A pose's stack that the caller has let go of is filled with a later pose (no fresh memory to map); one the
    caller still refers to (through a view of one frame) is never written again."""
    from procam import capture
    from procam.io import files
    from procam.stream import Prefetcher

    folders = [*poses, *poses]  # six poses: the same three twice
    names = [capture.sequence_files(f, files.list_images(f))[0] for f in folders]
    ids = []
    with Prefetcher(folders) as pf:
        for n in names:
            ids.append(id(pf.read(n)))  # dropped at once
    assert len(set(ids)) < len(folders)
    kept, copies = [], []
    with Prefetcher(folders) as pf:
        for n in names:
            stack = pf.read(n)
            kept.append(stack[0])  # a view keeps its stack
            copies.append(stack.copy())
            del stack
        assert len({id(v.base) for v in kept}) == len(folders)
        for k, (view, copy) in enumerate(zip(kept, copies)):
            assert (view == copy[0]).all(), f"pose {k}: its stack was filled again while a view of it was kept"


@pytest.mark.parametrize("case", ["written", "failed pose"])
def test_the_collector_runs_less_often_during_a_calibrate_and_as_before_after_it(poses, tmp_path, monkeypatch, case):
    """procam calibrate raises the cyclic collector's thresholds while it runs (its start-up's objects are not
    scanned hundreds of times) and puts the caller's back on every way out."""
    import gc

    import procam.cli as cli

    seen = []
    register = cli.register
    monkeypatch.setattr(cli, "register", lambda names=None: seen.append(gc.get_threshold()) or register(names))
    before = gc.get_threshold()
    gc.set_threshold(1000, 11, 12)
    try:
        args = ["calibrate", *map(str, poses), *BOARD, "-o", str(tmp_path / "calib.json")]
        if case == "failed pose":
            args[1 + len(poses):3 + len(poses)] = ["--board", "7x5"]
            args += ["--strict"]
        with pytest.raises(SystemExit) as e:
            cli.main(args)
        assert e.value.code == (0 if case == "written" else 2)
        assert gc.get_threshold() == (1000, 11, 12)
    finally:
        gc.set_threshold(*before)
    assert seen == [cli.COLLECT_AFTER]


def test_a_header_asking_for_more_than_memory_is_an_error_not_a_wait(tmp_path):
    """A pose whose first PNG's header says 300000 x 300000 (its checksum right): the reader cannot make a stack of
    that size, and read() says what is wrong (the ordinary read's error, naming the file) instead of waiting for a
    frame that never comes; the image alone is refused with OpenCV's reason in one line."""
    import zlib

    import cv2
    import numpy as np

    from procam.errors import CaptureError
    from procam.io import images
    from procam.stream import Prefetcher

    for k in range(4):
        assert cv2.imwrite(str(tmp_path / f"{k:02d}.png"), np.full((8, 8), 40 * k, np.uint8))
    data = (tmp_path / "00.png").read_bytes()
    ihdr = (300000).to_bytes(4, "big") * 2 + data[24:29]
    crc = (zlib.crc32(b"IHDR" + ihdr) & 0xFFFFFFFF).to_bytes(4, "big")
    (tmp_path / "00.png").write_bytes(data[:16] + ihdr + crc + data[33:])
    names = sorted(tmp_path.glob("*.png"))
    with pytest.raises(CaptureError, match=r"00\.png: cannot be read as an image \(OpenCV: .*\)"):
        images.read_image(names[0])
    def read():
        with Prefetcher([tmp_path]) as pf:
            return pf.read(names)

    got = within(30, read)  # not a wait for a frame that never comes
    assert isinstance(got, CaptureError) and str(got).startswith(str(names[0])), got
    assert not _readers()
