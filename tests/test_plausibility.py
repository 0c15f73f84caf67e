"""Captures that pass every frame check but are not a plausible picture of the projector (issue: no silent
wrong answer): a wrong projector size, a pattern swapped with its inverse, a mirrored camera. Each must stop
with one line that blames the capture, before any calibration is written."""

from __future__ import annotations

import shutil

import numpy as np
import pytest
from conftest import run_cli, write_stack

from procam import patterns, pipeline
from procam.board import Board
from procam.errors import CaptureError

B = Board(10, 6, 24.0)
PS = patterns.pattern_set(1920, 1080)


@pytest.fixture(scope="module")
def stack(paper_capture):
    return paper_capture[1]


def test_clean_capture_passes(stack):
    view, _ = pipeline.view_from_stack(stack, PS, B)
    assert view.valid.all() and view.diagnostics["warnings"] == []


@pytest.mark.parametrize("size", [(1500, 1080), (1920, 1050), (1100, 600)])
def test_wrong_projector_size_names_the_size_the_codes_point_to(stack, size):
    ps = patterns.pattern_set(*size)
    if ps.count != PS.count:
        pytest.skip("another bit count: the image count check catches it")
    with pytest.raises(CaptureError, match=r"the projector is larger than .*about 1920x1080 — check --projector"):
        pipeline.view_from_stack(stack, ps, B)


#: Pairs every run checks (column and row bits, most and least significant); the rest with ``-m slow``.
FAST_PAIRS = (0, 8, 14, 22, 30, 36)


@pytest.mark.parametrize("pair", [p if p in FAST_PAIRS else pytest.param(p, marks=pytest.mark.slow)
                                  for p in range(0, 42, 2)])
def test_a_pattern_swapped_with_its_inverse_is_named(stack, pair):
    if pair in (20, 42):
        pytest.skip("the least significant pair: swapped, the corners move by ~0.06 px (harmless, not flagged)")
    st = stack.copy()
    st[[pair, pair + 1]] = st[[pair + 1, pair]]
    with pytest.raises(CaptureError, match=rf"images #{pair} and #{pair + 1} \((column|row) bit \d+\) look swapped"):
        pipeline.view_from_stack(st, PS, B)


@pytest.mark.parametrize("flip", ["left-right", "top-bottom"])
def test_a_mirrored_camera_is_called_mirrored(stack, flip):
    st = np.ascontiguousarray(stack[:, :, ::-1] if flip == "left-right" else stack[:, ::-1, :])
    with pytest.raises(CaptureError, match="mirror images of each other.*camera image looks mirrored"):
        pipeline.view_from_stack(st, PS, B)


def _calibrate(folder, tmp_path, *extra):
    out = tmp_path / "calib.json"
    code, stdout, stderr = run_cli(["calibrate", folder, "--board", "10x6", "--square", "24", "-o", out, *extra])
    return code, stderr, out


def test_cli_wrong_projector_size(paper_capture, tmp_path):
    code, err, out = _calibrate(paper_capture[0], tmp_path, "--projector", "1500x1080")
    assert code == 2 and len(err.strip().splitlines()) == 1 and "about 1920x1080" in err and "Traceback" not in err
    assert not out.exists()


def test_cli_swapped_frames_are_named_by_file(paper_capture, tmp_path):
    folder = tmp_path / "pose"
    shutil.copytree(paper_capture[0], folder)
    (folder / "08.png").rename(folder / "tmp.png")
    (folder / "09.png").rename(folder / "08.png")
    (folder / "tmp.png").rename(folder / "09.png")
    code, err, out = _calibrate(folder, tmp_path)
    assert code == 2 and len(err.strip().splitlines()) == 1 and "#8 (08.png) and #9 (09.png)" in err
    assert not out.exists()


def test_cli_mirrored_camera(paper_capture, tmp_path):
    folder = tmp_path / "mirrored"
    write_stack(folder, np.ascontiguousarray(paper_capture[1][:, :, ::-1]))
    shutil.copy(paper_capture[0] / "patterns.json", folder / "patterns.json")
    code, err, out = _calibrate(folder, tmp_path)
    assert code == 2 and len(err.strip().splitlines()) == 1 and "camera image looks mirrored" in err
    assert not out.exists()
