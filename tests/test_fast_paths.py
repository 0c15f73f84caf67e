"""The fast paths of issue 12 give the answers of the straightforward code they replace.

Each test holds the straightforward version (or calls the library's) and compares: the histogram scores of
the swapped-bit check against sorting, ...
"""

from __future__ import annotations

import numpy as np
import pytest

from procam import correspond, decode, patterns
from procam.decode import plausibility


# --------------------------------------------------------------------------------------------
# plausibility: smoothness scores from histograms == from sorting
# --------------------------------------------------------------------------------------------

def _scores_by_sorting(v, axis):
    """The swapped-bit check's scores as first written (np.median, np.mean on the float differences)."""
    d = np.diff(v, axis=axis)
    d = d[np.isfinite(d)]
    if d.size == 0:
        return 0.0, 0
    ad = np.abs(d)
    slope = float(np.median(ad))
    rough = float(np.mean(np.minimum(np.abs(ad - slope), 8.0 + 4.0 * slope)))
    breaks = int(np.count_nonzero(np.abs(d - np.median(d)) > 2.5 + 1.5 * slope))
    return rough, breaks


def _swap_scores_by_sorting(maps, sample=4):
    ps = maps.pattern_set
    out = {}
    for axis, vals, dropped, nbits, offset, cam_axis in (
            ("col", maps.col, maps.dropped_col, ps.col_bits, ps.col_offset, 1),
            ("row", maps.row, maps.dropped_row, ps.row_bits, ps.row_offset, 0)):
        v = vals[::sample, :] if cam_axis == 1 else vals[:, ::sample]
        ok = np.isfinite(v) & ((dropped[::sample, :] if cam_axis == 1 else dropped[:, ::sample]) == 0)
        if ok.sum() < 2000:
            out[axis] = None
            continue
        v = np.where(ok, v, np.nan)
        code = np.rint((np.nan_to_num(v) - (ps.step - 1) / 2.0) / ps.step).astype(np.int64) + offset
        flipped = []
        for b in range(nbits - 1):
            v2 = np.where(ok, ((code ^ ((1 << (b + 1)) - 1)) - offset) * ps.step + (ps.step - 1) / 2.0, np.nan)
            flipped.append(_scores_by_sorting(v2, cam_axis))
        out[axis] = {"n": int(ok.sum()), "scores": _scores_by_sorting(v, cam_axis), "flipped": flipped}
    return out


def _assert_same_scores(maps):
    fast, slow = plausibility.swap_scores(maps), _swap_scores_by_sorting(maps)
    assert fast.keys() == slow.keys()
    for axis in fast:
        if slow[axis] is None:
            assert fast[axis] is None
            continue
        assert fast[axis]["n"] == slow[axis]["n"]
        for (r1, b1), (r2, b2) in zip([fast[axis]["scores"]] + fast[axis]["flipped"],
                                      [slow[axis]["scores"]] + slow[axis]["flipped"]):
            assert b1 == b2
            assert r1 == pytest.approx(r2, rel=1e-6, abs=1e-9)  # the maps are float32: so was the mean


def _synthetic_maps(w, h, step, seed, swap=None, lo_frac=0.0):
    """Decoded maps of a projector seen through a smooth warp, with some pixels invalid or coarse."""
    rng = np.random.default_rng(seed)
    ps = patterns.pattern_set(w, h, step=step)
    H, W = 240, 320
    yy, xx = np.mgrid[:H, :W].astype(float)
    col = (xx * (w / W) * (1 + 0.1 * np.sin(yy / 50)) + rng.normal(0, 0.6, (H, W))) // 1
    row = (yy * (h / H) * (1 + 0.05 * np.cos(xx / 70)) + rng.normal(0, 0.6, (H, W))) // 1
    maps = {}
    for name, v, size, nbits, off in (("col", col, w, ps.col_bits, ps.col_offset),
                                      ("row", row, h, ps.row_bits, ps.row_offset)):
        code = np.clip(v, 0, size - 1).astype(np.int64) // step + off
        if swap is not None and swap[0] == name:
            code ^= (1 << (swap[1] + 1)) - 1
        px_lo = np.maximum((code - off) * step, 0)
        px_hi = np.minimum((code - off) * step + step - 1, size - 1)  # the edge block is clipped
        val = ((px_lo + px_hi) / 2.0).astype(np.float32)
        bad = rng.random((H, W)) < 0.1 + lo_frac
        val[bad] = np.nan
        dropped = np.where(rng.random((H, W)) < 0.05, 2, 0).astype(np.uint8)
        maps[name], maps["d" + name] = val, dropped
    z = np.zeros((H, W), np.uint8)
    return decode.DecodeResult(maps["col"], maps["row"], np.isfinite(maps["col"]), np.isfinite(maps["row"]), z, z,
                               np.zeros((H, W), np.float32), None, None, ps, maps["dcol"], maps["drow"])


@pytest.mark.parametrize("step", [1, 2, 3, 8])
@pytest.mark.parametrize("swap", [None, ("col", 0), ("col", 3), ("row", 5)])
def test_swap_scores_equal_sorting_on_synthetic_maps(step, swap):
    _assert_same_scores(_synthetic_maps(1024 // (step if step > 2 else 1), 768, step, seed=step, swap=swap))


def test_swap_scores_equal_sorting_when_too_few_pixels_decode():
    _assert_same_scores(_synthetic_maps(1024, 768, 1, seed=5, lo_frac=0.89))


@pytest.mark.parametrize("pair", [None, 0, 6, 14, 24, 34])
def test_swap_scores_equal_sorting_on_a_render(paper_capture, pair):
    _, stack, _, _ = paper_capture
    ps = patterns.pattern_set(1920, 1080)
    st = stack
    if pair is not None:
        st = stack.copy()
        st[[pair, pair + 1]] = st[[pair + 1, pair]]
    _assert_same_scores(decode.decode(st, ps))


# --------------------------------------------------------------------------------------------
# local homographies: the trimmed least-squares fit of all corners at once against RANSAC
# --------------------------------------------------------------------------------------------

def _window_sets(n, outliers, seed, half=30, noise=0.3):
    """``n`` windows of ``2 half`` px: true homographies, their (quantised, noisy) images, a fraction
    ``outliers`` of points replaced by gross errors (as a wrongly decoded high bit gives)."""
    rng = np.random.default_rng(seed)
    d = np.arange(-half, half, dtype=float)
    gx, gy = np.meshgrid(d, d)
    src = np.column_stack([gx.ravel(), gy.ravel()])
    Hs, dst, mask = [], [], []
    for _ in range(n):
        H = np.array([[0.7 + 0.2 * rng.random(), 0.1 * rng.normal(), 500 * rng.random()],
                      [0.1 * rng.normal(), 0.7 + 0.2 * rng.random(), 400 * rng.random()],
                      [2e-4 * rng.normal(), 2e-4 * rng.normal(), 1.0]])
        p = np.column_stack([src, np.ones(len(src))]) @ H.T
        p = np.round(p[:, :2] / p[:, 2:] + rng.normal(0, noise, (len(src), 2)))  # decoded codes are integers
        bad = rng.random(len(src)) < outliers
        p[bad] += rng.choice([-1, 1], (int(bad.sum()), 2)) * rng.uniform(5, 300, (int(bad.sum()), 2))
        Hs.append(H)
        dst.append(p)
        mask.append(rng.random(len(src)) < 0.9)
    return src, np.array(Hs), np.array(dst), np.array(mask)


def _image_of(H, pt):
    q = H @ np.array([pt[0], pt[1], 1.0])
    return q[:2] / q[2]


@pytest.mark.parametrize("outliers", [0.0, 0.05, 0.15])
def test_trimmed_fit_is_as_accurate_as_ransac_with_outliers(outliers):
    import cv2

    src, Hs, dst, mask = _window_sets(40, outliers, seed=int(outliers * 100))
    do = np.array([d[m].mean(0) for d, m in zip(dst, mask)])
    Hm, inl, settled, rms = correspond.fit_homographies(src, dst - do[:, None], mask, 3.0)
    assert settled.all()
    centre = np.array([0.3, -0.2])  # a corner between pixels
    err_t, err_r = [], []
    for i in range(len(Hs)):
        truth = _image_of(Hs[i], centre)
        err_t.append(np.linalg.norm(_image_of(Hm[i], centre) + do[i] - truth))
        Hr, m = cv2.findHomography(src[mask[i]], dst[i][mask[i]], cv2.RANSAC, 3.0)
        err_r.append(np.linalg.norm(_image_of(Hr, centre) - truth))
        # the points kept are RANSAC's inliers, give or take a few on the threshold
        assert np.count_nonzero(inl[i][mask[i]] != m.ravel().astype(bool)) <= 0.01 * mask[i].sum()
    assert np.sqrt(np.mean(np.square(err_t))) <= 1.05 * np.sqrt(np.mean(np.square(err_r))) + 1e-3
    assert max(err_t) < 0.1
    assert np.all(rms < 1.0)


def test_trimmed_fit_leaves_a_window_on_two_planes_to_ransac():
    src, _, dst, mask = _window_sets(2, 0.0, seed=7)
    mixed = dst[0].copy()
    other = src[:, 0] > 8  # the right part of the window sees another plane (the wall behind the board)
    mixed[other] = dst[1][other]
    _, _, settled, _ = correspond.fit_homographies(src, mixed[None], mask[:1], 3.0)
    assert not settled[0]


def test_trimmed_projector_corners_agree_with_ransac_on_a_render(paper_capture):
    _, stack, truth, _ = paper_capture
    maps = decode.decode(stack, patterns.pattern_set(1920, 1080))
    cam = np.array(truth["corners"]["camera_distorted"])
    exact = np.array(truth["corners"]["projector"])
    out = {}
    for est in ("trimmed", "ransac"):
        p, diag = correspond.projector_corners(cam, maps, correspond.CornerOptions(estimator=est))
        assert (diag["reason"] == 0).all()
        out[est] = (p, diag)
    rms = {e: np.sqrt(np.mean(np.sum((p - exact) ** 2, 1))) for e, (p, _) in out.items()}
    assert rms["trimmed"] <= 1.02 * rms["ransac"]
    assert np.max(np.abs(out["trimmed"][0] - out["ransac"][0])) < 0.02
    assert np.array_equal(out["trimmed"][1]["pixels"], out["ransac"][1]["pixels"])
    np.testing.assert_allclose(out["trimmed"][1]["residual_px"], out["ransac"][1]["residual_px"], rtol=0.05)


def test_trimmed_projector_corners_near_the_border_and_unlit(paper_capture):
    """Windows cut by the image border, corners in unlit parts and NaN corners get the same reasons as with
    RANSAC."""
    _, stack, truth, _ = paper_capture
    maps = decode.decode(stack, patterns.pattern_set(1920, 1080))
    H, W = maps.col.shape
    cam = np.array([[5.0, 5.0], [W - 20.3, 300.2], [W / 2, H - 12.7], [np.nan, 3.0], [1.0, H / 2],
                    *np.array(truth["corners"]["camera_distorted"])[:5]])
    res = {e: correspond.projector_corners(cam, maps, correspond.CornerOptions(estimator=e))
           for e in ("trimmed", "ransac")}
    np.testing.assert_array_equal(res["trimmed"][1]["reason"], res["ransac"][1]["reason"])
    ok = res["ransac"][1]["reason"] == 0
    assert np.max(np.abs(res["trimmed"][0][ok] - res["ransac"][0][ok])) < 0.05


# --------------------------------------------------------------------------------------------
# decode: integer thresholds compare like the float ones
# --------------------------------------------------------------------------------------------

@pytest.mark.parametrize("dtype", [np.uint8, np.uint16, np.int16, np.int32])
@pytest.mark.parametrize("t", [0.0, 0.5, 3.0, 7.3, 10.0, 25.5, 254.9, 255.0, 1e9, -3.5])
def test_integer_thresholds_compare_like_floats(dtype, t):
    info = np.iinfo(dtype)
    x = np.random.default_rng(1).integers(max(info.min, -1000), min(info.max, 70000), 5000, endpoint=True,
                                          dtype=np.int64).astype(dtype)
    ti = decode._int_threshold(t, dtype)
    np.testing.assert_array_equal(x >= ti, x >= t)
    np.testing.assert_array_equal(x < ti, x < t)


# --------------------------------------------------------------------------------------------
# streaming: poses read ahead in background threads give what load_capture reads itself
# --------------------------------------------------------------------------------------------

def _small_poses(tmp_path, n=3):
    from conftest import camera_view_of_patterns, write_stack

    folders = []
    for k in range(n):
        folder = tmp_path / f"pose{k}"
        write_stack(folder, camera_view_of_patterns(64, 48, seed=k))
        folders.append(folder)
    return folders


def test_prefetched_captures_equal_load_capture(tmp_path):
    from procam import capture, stream

    folders = _small_poses(tmp_path)
    ps = (64, 48)
    with stream.Prefetcher(folders, ahead=1) as pf:
        fast = [capture.load_capture(f, ps, reader=pf.read) for f in folders]
    for f, cap in zip(folders, fast):
        ref = capture.load_capture(f, ps)
        assert np.array_equal(cap.stack, ref.stack) and cap.stack.dtype == ref.stack.dtype
        assert cap.files == ref.files and cap.warnings == ref.warnings


def test_prefetcher_reads_other_files_itself_and_out_of_order(tmp_path):
    from procam import stream
    from procam.io import files as _files
    from procam.io import images as _images

    folders = _small_poses(tmp_path)
    files = [_files.list_images(f) for f in folders]
    with stream.Prefetcher(folders, ahead=2) as pf:
        np.testing.assert_array_equal(pf.read(files[2]), _images.read_images(files[2]))  # read ahead
        np.testing.assert_array_equal(pf.read(files[0][:5]), _images.read_images(files[0][:5]))  # not a folder's
        np.testing.assert_array_equal(pf.read(files[1]), _images.read_images(files[1]))


@pytest.mark.parametrize("by", ["threads", "child"])
@pytest.mark.parametrize("damage", ["corrupt", "size", "depth"])
def test_prefetcher_errors_are_read_images_errors(tmp_path, damage, by, request):
    """Read by threads or by the forked child (procam.io.child_reader), a pose with a frame that cannot be read, or
    of another size or depth, raises read_images' own error."""
    import cv2

    from procam import stream
    from procam.io import files as _files
    from procam.io import images as _images
    from procam.errors import CaptureError

    folders = _small_poses(tmp_path, 2)
    victim = _files.list_images(folders[1])[7]
    if damage == "corrupt":
        victim.write_bytes(b"not a png")
    elif damage == "size":
        cv2.imwrite(str(victim), np.zeros((40, 64), np.uint8))
    else:
        cv2.imwrite(str(victim), np.zeros((48, 64), np.uint16))
    with pytest.raises(CaptureError) as ref:
        _images.read_images(_files.list_images(folders[1]))
    child = request.getfixturevalue("forked_reader") if by == "child" else None
    with stream.Prefetcher(folders, child=child) as pf:
        np.testing.assert_array_equal(pf.read(_files.list_images(folders[0])), _images.read_images(
            _files.list_images(folders[0])))
        with pytest.raises(CaptureError) as got:
            pf.read(_files.list_images(folders[1]))
    assert str(got.value) == str(ref.value)


def test_views_from_folders_streams_the_same_views(paper_capture, tmp_path):
    """Two poses through views_from_folders (read ahead) give the views view_from_folder gives."""
    import shutil

    from procam import pipeline
    from procam.board import Board

    folder = paper_capture[0]
    second = tmp_path / "again"
    shutil.copytree(folder, second)
    brd = Board(10, 6, 24.0)
    views = pipeline.views_from_folders([folder, second], brd)
    for f, v in zip([folder, second], views):
        ref, _ = pipeline.view_from_folder(f, brd)
        np.testing.assert_array_equal(v.cam_pts, ref.cam_pts)
        np.testing.assert_array_equal(v.proj_pts, ref.proj_pts)
        assert v.name == ref.name and v.diagnostics["warnings"] == ref.diagnostics["warnings"]


# --------------------------------------------------------------------------------------------
# procam experiment: progress when stderr is a pipe
# --------------------------------------------------------------------------------------------

def test_experiment_prints_one_plain_line_per_step_when_piped(tmp_path, monkeypatch):
    """Not a terminal (CliRunner's stderr, a pipe, a log): every finished step is a line on stderr."""
    from procam import pipeline, simulate
    from procam.view import View
    from conftest import run_cli

    base = simulate.preset("paper")
    views = {}
    for k, a in enumerate([(15, -35, 0), (-15, 20, 5), (10, 25, -5)]):
        sc = simulate.with_board_pose(base, a, distance=650.0)
        obj, cam, proj = simulate.correspondences(sc, 0.1, 0.2, k)
        (tmp_path / f"pose{k + 1}").mkdir()
        views[f"pose{k + 1}"] = View(obj, cam, proj, f"pose{k + 1}", sc.cam_size, sc.proj_size)

    def fake(folder, board, projector=None, order=None, **kw):
        return views[folder.name if hasattr(folder, "name") else str(folder).rsplit("/", 1)[-1]], None

    monkeypatch.setattr(pipeline, "view_from_folder", fake)
    code, _, err = run_cli(["experiment", *[tmp_path / n for n in views], "-o", tmp_path / "out", "--board", "10x6",
                            "--square", "24", "--projector", "1920x1080"])
    assert code == 0, err
    lines = err.splitlines()
    assert [ln for ln in lines if ln.startswith("decoding")] == [f"decoding {k}/3: pose{k}" for k in (1, 2, 3)]
    calib = [ln for ln in lines if ln.startswith("calibrating")]
    assert len(calib) >= 4 and calib[-1].startswith("calibrating 4/4")


# --------------------------------------------------------------------------------------------
# start-up: what procam --help and procam calibrate import
# --------------------------------------------------------------------------------------------

def _fresh(script: str, *args, timeout: float = 300):
    """``python -c script ARGS`` in a fresh interpreter, this checkout's procam first on its path: the finished
    process (text output)."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(Path(__file__).resolve().parents[1] / "src"), env.get("PYTHONPATH", "")])
    return subprocess.run([sys.executable, "-c", script, *map(str, args)], env=env, capture_output=True, text=True,
                          timeout=timeout)


#: Runs ``procam ARGS...`` (argv[2:]) through the console-script entry point and reports, as the last line of
#: stderr, its exit code and which of the comma-separated modules of argv[1] it imported.
_LOADED = """
import json, sys
watched, sys.argv[1:] = sys.argv[1].split(","), sys.argv[2:]
from procam.cli import main
code = 0
try:
    main(sys.argv[1:])
except SystemExit as e:
    code = e.code
print(json.dumps({"code": code, "loaded": [m for m in watched if m in sys.modules]}), file=sys.stderr)
"""


def test_help_and_calibrate_import_no_matplotlib_simulator_or_scipy_for_help(ideal_capture, tmp_path):
    """`procam --help` imports neither matplotlib, the simulator nor scipy; `procam calibrate` without --png or
    --report imports no matplotlib or simulator (fresh interpreters, through the console-script entry point)."""
    import json

    heavy = "matplotlib,procam.simulate,procam.plots,procam.paper,scipy"
    folder = ideal_capture[0]
    runs = [(["--help"], []), (["calibrate", "--help"], []),
            (["calibrate", str(folder), "--board", "10x6", "--square", "24", "-o", str(tmp_path / "c.json")],
             ["scipy"])]
    for args, allowed in runs:
        res = _fresh(_LOADED, heavy, *args)
        report = json.loads(res.stderr.strip().splitlines()[-1])
        assert report["code"] in (0, None) and set(report["loaded"]) <= set(allowed), (args, res.stderr[-2000:])


def test_decode_imports_neither_the_corner_pipeline_nor_the_other_familys_decoder(ideal_capture, tmp_path):
    """`procam decode` finds no corners: it imports neither the pose pipeline nor the board's corner detection nor
    the correspondences; a Gray capture's decode imports nothing of the phase decoder, a phase capture's does (issue
    35: nothing paid at start-up that a decode does not need). Fresh interpreters, the decoded maps written."""
    import json
    from pathlib import Path

    from sim_small import small_scene

    from procam import simulate

    scene = small_scene()
    ps = patterns.pattern_set(*scene.proj_size, family="phase")
    stack, truth = simulate.render(scene, ps, seed=4)
    simulate.write_capture(tmp_path / "phase", stack, truth, ps)
    watched = ("procam.pipeline,procam.board,procam.correspond,procam.view,procam.decode.plausibility,"
               "procam.decode.phase.decoder,scipy,matplotlib")
    for folder, shape, loaded in ((ideal_capture[0], ideal_capture[1].shape[1:], []),
                                  (tmp_path / "phase", stack.shape[1:], ["procam.decode.phase.decoder"])):
        out = tmp_path / f"{Path(folder).name}.npz"
        res = _fresh(_LOADED, watched, "decode", folder, "-o", out)
        report = json.loads(res.stderr.strip().splitlines()[-1])
        assert report["code"] in (0, None) and report["loaded"] == loaded, (folder, res.stderr[-2000:])
        with np.load(out) as maps:
            assert maps["col"].shape == shape


def test_version_imports_no_command_line_and_a_command_registers_only_itself():
    """`procam --version` answers before typer (and pydantic) are imported; `procam calibrate --help` builds only
    the calibrate command and imports no pydantic, nor does parsing a calibrate command line; `procam --help` builds
    every command (fresh interpreters, the console-script entry point)."""
    import json

    script = """
import json, sys
from procam.cli import main
code = 0
try:
    main(sys.argv[1:])
except SystemExit as e:
    code = e.code
cmds = sorted(m.rsplit(".", 1)[1] for m in sys.modules if m.startswith("procam.cli.") and not m.rsplit(".", 1)[1].startswith("_"))
print(json.dumps({"code": code, "typer": "typer" in sys.modules, "pydantic": "pydantic" in sys.modules,
                  "commands": cmds}), file=sys.stderr)
"""
    from procam.cli import COMMANDS

    def run(*args):
        res = _fresh(script, *args)
        return res.stdout, json.loads(res.stderr.strip().splitlines()[-1])

    out, rep = run("--version")
    assert out.strip().startswith("procam ") and rep == {"code": 0, "typer": False, "pydantic": False, "commands": []}
    out, rep = run("calibrate", "--help")
    assert rep["code"] in (0, None) and rep["commands"] == ["calibrate"] and "--board" in out
    assert not rep["pydantic"]  # typer 0.29 coerces a --help flag not given through pydantic (0.1 s to import)
    # a command line is parsed without pydantic: typer 0.29's per-option TypeAdapters (pydantic's import and the
    # adapters: 0.15-0.25 s of every command) are why pyproject caps typer below 0.29
    out, rep = run("calibrate", "no-such-pose", "--board", "10x6", "--square", "-24", "-o", "c.json")
    assert rep["code"] == 2 and rep["commands"] == ["calibrate"] and not rep["pydantic"], rep
    out, rep = run("--help")
    assert rep["code"] in (0, None) and rep["commands"] == sorted(COMMANDS.values()) and all(c in out for c in COMMANDS)


def test_the_console_script_skips_pythons_final_collection_and_a_caller_keeps_it():
    """The console script (``main()``, no arguments) moves the objects alive at exit to the permanent generation,
    so Python's final collection does not walk scipy's and numpy's module objects; an in-process caller
    (``main(argv)``) keeps its collector untouched, at exit too. An exit handler registered before main runs after
    main's (handlers run last registered first), and reports the frozen count then."""
    script = """
import atexit, gc, sys
atexit.register(lambda: print("frozen", gc.get_freeze_count(), file=sys.stderr))
from procam.cli import main
try:
    how, sys.argv[1:] = sys.argv[1], sys.argv[2:]
    main() if how == "console" else main(sys.argv[1:])
except SystemExit:
    pass
print("after", gc.get_freeze_count(), file=sys.stderr)
"""
    def counts(how, *args):
        res = _fresh(script, how, *args)
        lines = dict(line.split() for line in res.stderr.splitlines() if line.startswith(("frozen", "after")))
        assert res.returncode == 0 and res.stdout.startswith("procam "), res.stderr
        return int(lines["after"]), int(lines["frozen"])

    # nothing is frozen while the command runs or after it returns; only at exit, and only for the console script
    after, at_exit = counts("console", "--version")
    assert after == 0 and at_exit > 1000
    assert counts("caller", "--version") == (0, 0)


def test_prefetcher_reads_at_most_ahead_poses_beyond_the_one_in_use(tmp_path):
    """Memory stays bounded: with ahead=1 the pose in use and the next one, never more."""
    from procam import stream
    from procam.io import files as _files

    folders = _small_poses(tmp_path, 4)
    with stream.Prefetcher(folders, ahead=1) as pf:
        assert pf._next == 1  # the first pose, from the start
        for k, f in enumerate(folders):
            pf.read(_files.list_images(f))
            assert pf._next == min(len(folders), k + 2)


def test_prefetcher_reads_each_frame_once_beside_procams_own_outputs(tmp_path, monkeypatch):
    """A pose folder that also holds an image procam wrote (listed in its manifest) is read ahead all the same:
    the prefetcher asks for the files load_capture asks for, so no frame is read twice."""
    from pathlib import Path

    import cv2

    from procam import capture, stream
    from procam.io import files as _files
    from procam.io import images as _images

    folders = _small_poses(tmp_path, 2)
    for f in folders:
        _files.write_image(f / "overlay.png", np.zeros((48, 64), np.uint8))
        _files.record_files(f, {"overlay.png": "output"}, writer="check")
    reads = []
    real = _images.read_image
    monkeypatch.setattr(_images, "read_image", lambda p, *a, **k: (reads.append(Path(p).name), real(p, *a, **k))[1])
    with stream.Prefetcher(folders, ahead=1) as pf:
        caps = [capture.load_capture(f, (64, 48), reader=pf.read) for f in folders]
    n = len(caps[0].files)
    assert "overlay.png" not in reads and all(c.stack.shape[0] == n for c in caps)
    assert sorted(reads) == sorted(2 * [p.name for p in caps[0].files])  # each frame once
    assert cv2.imread(str(folders[0] / "overlay.png")) is not None


def test_a_phase_captures_response_is_fitted_once_for_the_check_and_the_decode(tmp_path, monkeypatch):
    """The description check decodes the capture's sample and the decode fits the same sample again: the projector's
    response is fitted once per capture, and the decode is the one a fresh fit gives, to the bit."""
    from sim_small import small_scene

    from procam import capture, decode, patterns, simulate
    from procam.decode.phase import decoder, response

    scene = small_scene()
    ps = patterns.pattern_set(*scene.proj_size, family="phase")
    stack, truth = simulate.render(scene, ps, seed=4)
    simulate.write_capture(tmp_path / "pose", stack, truth, ps)
    calls = []
    real = response.fit_response

    def counting(*a, **k):
        calls.append(1)
        return real(*a, **k)

    monkeypatch.setattr(response, "fit_response", counting)
    decoder._PASS1.clear()
    cap = capture.load_capture(tmp_path / "pose")  # the description check decodes the sample
    res = decode.decode(cap.stack, cap.pattern_set)
    assert len(calls) == 1
    decoder._PASS1.clear()
    fresh = decode.decode(cap.stack, cap.pattern_set)
    assert len(calls) == 2
    for k in ("col", "row", "valid_col", "valid_row", "confidence"):
        np.testing.assert_array_equal(getattr(res, k), getattr(fresh, k))


# --------------------------------------------------------------------------------------------
# the CLI's allocator settings: freed memory reused, not faulted in afresh
# --------------------------------------------------------------------------------------------

_FAULTS = """
import resource, sys
import numpy as np
if sys.argv[1] == "keep":
    from procam.cli._app import keep_freed_memory
    keep_freed_memory()
r0 = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
for i in range(40):  # arrays of 8 to 14 MB made and freed, as a decode's and a corner fit's temporaries
    a = np.ones(1_000_000 + 250_000 * (i % 4))
    b = a * 2
    del a, b
print(resource.getrusage(resource.RUSAGE_SELF).ru_minflt - r0)
"""


def test_keep_freed_memory_saves_the_page_faults_of_the_next_arrays():
    """With glibc, keep_freed_memory lets the allocator reuse freed blocks: the same arrays made and freed again
    take a small part of the page faults of the default settings (each in a fresh process)."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    import procam

    if "CS_GNU_LIBC_VERSION" not in os.confstr_names or not os.confstr("CS_GNU_LIBC_VERSION"):
        pytest.skip("glibc only")
    env = dict(os.environ, PYTHONPATH=str(Path(procam.__file__).parents[1]))
    faults = {how: int(subprocess.run([sys.executable, "-c", _FAULTS, how], env=env, capture_output=True, text=True,
                                      check=True).stdout) for how in ("default", "keep")}
    assert faults["keep"] < faults["default"] / 3, faults


def test_calibrate_and_decode_keep_freed_memory(tmp_path, monkeypatch):
    """The commands that read whole captures (decode, calibrate) set the allocator up first thing."""
    from conftest import camera_view_of_patterns, run_cli, write_stack

    from procam.cli import calibrate, decode

    calls = []
    for module in (calibrate, decode):
        monkeypatch.setattr(module, "keep_freed_memory", lambda m=module.__name__: calls.append(m))
    write_stack(tmp_path / "pose", camera_view_of_patterns(64, 48))
    assert run_cli(["decode", tmp_path / "pose", "--projector", "64x48"])[0] == 0
    code, _, err = run_cli(["calibrate", tmp_path / "pose", "--board", "10x6", "--square", "24", "--projector",
                            "64x48", "-o", tmp_path / "c.json"])
    assert code == 2 and "not found" in err  # no board in these frames: read and refused all the same
    assert calls == ["procam.cli.decode", "procam.cli.calibrate"]


def test_calibrate_reads_its_pose_folders_before_its_command_line_is_parsed(ideal_capture, tmp_path):
    """`procam calibrate POSE ...` (and `procam decode POSE`) starts reading the pose folders before typer (and
    pydantic) are imported, and the command takes that reader instead of making its own; a command line that is not
    what it looked like (an unknown option, --help) leaves no reader behind (fresh interpreters, the console-script
    entry point)."""
    import json

    from conftest import run_cli

    script = """
import json, sys, threading
import procam.stream as stream
made = []
init, close = stream.Prefetcher.__init__, stream.Prefetcher.close
def tracked_init(self, *a, **k):
    made.append({"typer": "typer" in sys.modules, "closed": False})
    self._k = len(made) - 1
    init(self, *a, **k)
def tracked_close(self):
    made[self._k]["closed"] = True
    close(self)
stream.Prefetcher.__init__, stream.Prefetcher.close = tracked_init, tracked_close
from procam.cli import main
code = 0
try:
    main(sys.argv[1:])
except SystemExit as e:
    code = e.code
readers = [t.name for t in threading.enumerate() if t.name.startswith("procam-read")]
print(json.dumps({"code": code, "made": made, "readers": readers}), file=sys.stderr)
"""
    folder = str(ideal_capture[0])

    def run(command, *args):
        res = _fresh(script, command, folder, *args)
        return json.loads(res.stderr.strip().splitlines()[-1])

    rep = run("calibrate", "--board", "10x6", "--square", "24", "-o", str(tmp_path / "c.json"))
    assert rep["code"] in (0, None) and (tmp_path / "c.json").is_file()
    assert rep["made"] == [{"typer": False, "closed": True}] and rep["readers"] == []
    rep = run("calibrate", "--board", "10x6", "--square", "24", "-o", str(tmp_path / "d.json"), "--no-such-option")
    assert rep["code"] == 2 and rep["made"] == [{"typer": False, "closed": True}] and rep["readers"] == []
    assert not (tmp_path / "d.json").exists()
    rep = run("calibrate", "--help")
    assert rep["code"] in (0, None) and rep["made"] == [] and rep["readers"] == []
    # procam decode FOLDER likewise, the maps the same bytes as those of the folder read after the parsing
    rep = run("decode", "-o", str(tmp_path / "early.npz"))
    assert rep["code"] in (0, None) and rep["made"] == [{"typer": False, "closed": True}] and rep["readers"] == []
    assert run_cli(["decode", folder, "-o", tmp_path / "late.npz"])[0] == 0
    assert (tmp_path / "early.npz").read_bytes() == (tmp_path / "late.npz").read_bytes()
