"""A forked child process reads the poses of a multi-pose calibrate (issue 35): the same stacks as read_images
(and the same errors: tests/test_fast_paths.py reads its damaged poses both ways), its shared buffers reused, and
the child reaped on every way out."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading

import numpy as np
import pytest

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the child reader forks: Linux only")


def _poses(tmp_path, n=3, dtype=np.uint8):
    from conftest import camera_view_of_patterns, write_stack

    folders = []
    for k in range(n):
        folder = tmp_path / f"pose{k}"
        stack = camera_view_of_patterns(64, 48, seed=k)
        if dtype == np.uint16:
            stack = stack.astype(np.uint16) * 257 + np.uint16(k)
        write_stack(folder, stack)
        folders.append(folder)
    return folders


@pytest.fixture
def child(forked_reader):
    return forked_reader


def _files(folder):
    from procam import capture
    from procam.io import files

    return capture.sequence_files(folder, files.list_images(folder))[0]


def _reaped(pid: int) -> bool:
    try:
        os.waitpid(pid, os.WNOHANG)
    except ChildProcessError:
        return True
    return False


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16])
def test_the_child_reads_the_stacks_read_images_reads(tmp_path, child, dtype):
    from procam.io import images
    from procam.stream import Prefetcher

    folders = _poses(tmp_path, 3, dtype)
    pid = child.pid
    with Prefetcher(folders, child=child) as pf:
        assert pf._pool is None  # no reader threads here
        for folder in folders:
            names = _files(folder)
            got, ref = pf.read(names), images.read_images(names)
            assert got.dtype == ref.dtype == dtype
            np.testing.assert_array_equal(got, ref)
            del got
    assert _reaped(pid), "the child was not reaped when the Prefetcher closed"


def test_load_capture_through_the_child_equals_load_capture(tmp_path, child):
    from procam import capture
    from procam.stream import Prefetcher

    folders = _poses(tmp_path, 3)
    with Prefetcher(folders, child=child) as pf:
        caps = [capture.load_capture(f, (64, 48), reader=pf.read) for f in folders]
    for f, cap in zip(folders, caps):
        ref = capture.load_capture(f, (64, 48))
        np.testing.assert_array_equal(cap.stack, ref.stack)
        assert cap.files == ref.files and cap.warnings == ref.warnings


def test_stacks_no_one_refers_to_are_filled_again(tmp_path, child):
    """Five poses read one after the other, each let go: two shared buffers in all (the pose in use and the next),
    not one per pose; a stack the caller keeps is never written again."""
    from procam.io import images
    from procam.stream import Prefetcher

    folders = _poses(tmp_path, 5)
    with Prefetcher(folders, child=child) as pf:
        kept = pf.read(_files(folders[0]))
        first = kept.copy()
        for folder in folders[1:]:
            stack = pf.read(_files(folder))
            np.testing.assert_array_equal(stack, images.read_images(_files(folder)))
            del stack
        np.testing.assert_array_equal(kept, first)
        assert child._buffers <= 3, child._buffers


def test_a_child_that_dies_leaves_the_reading_here(tmp_path, child):
    from procam.io import images
    from procam.stream import Prefetcher

    folders = _poses(tmp_path, 3)
    with Prefetcher(folders, child=child) as pf:
        os.kill(child.pid, signal.SIGKILL)
        for folder in folders:
            np.testing.assert_array_equal(pf.read(_files(folder)), images.read_images(_files(folder)))


def test_no_fork_beside_running_threads():
    """Beside a running thread the command line reads with threads instead (a fork copies the locks other threads
    hold)."""
    from procam.io.child_reader import ChildReader

    stop = threading.Event()
    t = threading.Thread(target=stop.wait)
    t.start()
    try:
        assert ChildReader.start() is None
    finally:
        stop.set()
        t.join()


def test_the_command_line_forks_the_child_first_thing(tmp_path):
    """In a fresh ``procam`` process the reader is forked before numpy is imported (one thread running), and a
    calibrate read by it writes the file a calibrate read by threads writes, to the byte."""
    from conftest import run_cli
    from test_bad_inputs import render_poses

    code = ("import sys, procam.cli\n"
            "from procam.io.child_reader import ChildReader\n"
            "r = ChildReader.start()\n"
            "print(r is not None, 'numpy' in sys.modules)\n"
            "r.close()\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert out.stdout.split() == ["True", "False"], out.stderr
    poses = render_poses(tmp_path / "poses")
    args = ["calibrate", *map(str, poses), "--board", "10x6", "--square", "24"]
    code_, _, err = run_cli([*args, "-o", str(tmp_path / "threads.yaml")])  # in this process: reader threads
    assert code_ == 0, err
    entry = "import sys; from procam.cli import main; sys.exit(main())"  # the console script's entry point
    done = subprocess.run([sys.executable, "-c", entry, *args, "-o", str(tmp_path / "child.yaml")],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "child.yaml").read_bytes() == (tmp_path / "threads.yaml").read_bytes()


def test_a_pose_of_other_images_is_read_here(tmp_path, child):
    """The child reads PNGs into stacks sized from their headers; a pose of other images (BMP here) is read by this
    process, the same stack read_images gives, and the PNG poses around it still by the child."""
    from conftest import camera_view_of_patterns, write_stack

    from procam.io import images
    from procam.stream import Prefetcher

    folders = _poses(tmp_path, 2)
    bmp = tmp_path / "bmp"
    write_stack(bmp, camera_view_of_patterns(64, 48, seed=5), ext=".bmp")
    order = [folders[0], bmp, folders[1]]
    with Prefetcher(order, child=child) as pf:
        for folder in order:
            np.testing.assert_array_equal(pf.read(_files(folder)), images.read_images(_files(folder)))
    assert child._tickets == 2  # the two PNG poses only


def test_read_images_into_a_given_stack_reads_the_same_and_refuses_another_frame(tmp_path):
    """read_images(out=) (the child's reading): the same pixels as a new stack, into the given memory; a frame of
    another size or bit depth is the same CaptureError; a stack of another length a ValueError."""
    import cv2

    from procam.errors import CaptureError
    from procam.io import images

    rng = np.random.default_rng(5)
    files = []
    for k in range(4):
        files.append(tmp_path / f"{k:02d}.png")
        cv2.imwrite(str(files[-1]), rng.integers(0, 255, (24, 32), dtype=np.uint8))
    out = np.zeros((4, 24, 32), np.uint8)
    got = images.read_images(files, out=out)
    assert got is out and np.array_equal(out, images.read_images(files))
    cv2.imwrite(str(tmp_path / "big.png"), rng.integers(0, 255, (24, 40), dtype=np.uint8))
    cv2.imwrite(str(tmp_path / "deep.png"), rng.integers(0, 65535, (24, 32), dtype=np.uint16))
    for odd, word in (("big.png", "size 40x24 differs"), ("deep.png", "16-bit image among 8-bit")):
        with pytest.raises(CaptureError, match=word):
            images.read_images([*files[:3], tmp_path / odd], out=out)
    with pytest.raises(ValueError, match="holds 4 frames"):
        images.read_images(files[:3], out=out)
