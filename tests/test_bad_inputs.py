"""Bad inputs and faults, tried as a careless or unlucky user would (issue 17).

Every case runs the CLI and asserts: exit code 2, exactly one line on stderr, no traceback, the words that
say what is wrong, and nothing left behind or overwritten (checksums of the user's files before and after,
no temporary files).  Families: data loss, arguments, calibration files, capture folders, output paths,
messages, papercuts; a property test of random numbers through the CLI.
"""

from __future__ import annotations

import errno
import hashlib
import json
import os
import re
import shutil
from pathlib import Path

import cv2
import numpy as np
import pytest
from conftest import camera_view_of_patterns, run_cli, write_stack

from procam import capture, io, patterns, simulate
from procam.io import files as _files
from procam.errors import CalibrationError, OutputError

BOARD = ["--board", "10x6", "--square", "24"]


# ------------------------------------------------------------------------------------------------
# helpers
def snapshot(*folders) -> dict:
    """{path: sha256} of every file under ``folders`` (hidden ones too)."""
    out = {}
    for folder in folders:
        folder = Path(folder)
        if folder.is_file():
            out[str(folder)] = hashlib.sha256(folder.read_bytes()).hexdigest()
            continue
        for p in sorted(folder.rglob("*")):
            if p.is_file() and not p.is_symlink():
                out[str(p)] = hashlib.sha256(p.read_bytes()).hexdigest()
    return out


def leftovers(folder) -> list[str]:
    """Temporary files or write probes left under ``folder``."""
    return [str(p) for p in Path(folder).rglob("*") if ".tmp" in p.name or p.name.startswith(".procam-probe")]


#: A plain progress line of ``procam experiment`` ("decoding 2/3: pose2").
PROGRESS = re.compile(r"^(decoding|calibrating) \d+/\d+: ")


def bad(args, *needles, code=2) -> str:
    """Run the CLI; assert exit ``code``, one line on stderr, no traceback, and ``needles`` in it."""
    rc, out, err = run_cli(args)
    # progress lines (a long command's plain progress when stderr is not a terminal) are not errors
    lines = [line for line in err.splitlines() if line.strip() and not PROGRESS.match(line)]
    assert rc == code, (args, rc, out, err)
    assert len(lines) == 1, (args, err)
    assert "Traceback" not in err and "libpng" not in err, (args, err)
    for n in needles:
        assert n in err, (args, n, err)
    return err


def user_folder(path, names) -> Path:
    """A folder of the user's own files (not procam's): small PNGs named ``names``."""
    path = Path(path)
    path.mkdir(parents=True, exist_ok=True)
    for i, n in enumerate(names):
        cv2.imwrite(str(path / n), np.full((8, 8), i, np.uint8))
    return path


def render_pose(folder, angles, seed=0, **changes):
    """A small rendered capture (640x400 camera) at ``angles`` into ``folder``; returns the truth."""
    from sim_small import small_scene

    scene = simulate.with_board_pose(small_scene().replace(**changes), angles)
    stack, truth = simulate.render(scene, seed=seed)
    simulate.write_capture(folder, stack, truth)
    return truth


POSE_ANGLES = ((15.0, 12.0, 0.0), (-12.0, 15.0, 5.0), (14.0, -12.0, -5.0))


def render_poses(root) -> list:
    """Three small rendered poses of the same rig (``POSE_ANGLES``, seeds 0-2) as ``root/pose1..3``."""
    folders = [root / f"pose{k + 1}" for k in range(len(POSE_ANGLES))]
    for k, (folder, a) in enumerate(zip(folders, POSE_ANGLES)):
        render_pose(folder, a, seed=k)
    return folders


@pytest.fixture(scope="module")
def poses(tmp_path_factory):
    """Three small rendered poses of the same rig (procam simulate's layout, with a manifest)."""
    return render_poses(tmp_path_factory.mktemp("poses"))


@pytest.fixture(scope="module")
def calib_file(tmp_path_factory):
    """The small rig's true calibration as procam JSON."""
    from procam.simulate import truth_calibration
    from sim_small import small_scene

    path = tmp_path_factory.mktemp("calib") / "calib.json"
    io.save_calibration(truth_calibration(small_scene()), path)
    return path


def copy_pose(src, dst) -> Path:
    """A user's copy of a pose: only the images (no patterns.json, no manifest)."""
    dst = Path(dst)
    dst.mkdir(parents=True)
    for p in Path(src).glob("*.png"):
        shutil.copy(p, dst / p.name)
    return dst


# ------------------------------------------------------------------------------------------------
# family 1: data loss -- never delete or overwrite a file procam did not write
USER_NAMES = {"plain": [f"{i}.png" for i in range(42)], "padded": [f"{i:02d}.png" for i in range(42)]}


@pytest.mark.parametrize("names", sorted(USER_NAMES))
@pytest.mark.parametrize("force", [False, True])
def test_simulate_never_touches_the_users_captures(tmp_path, names, force):
    folder = user_folder(tmp_path / "mine", USER_NAMES[names])
    before = snapshot(folder)
    bad(["simulate", folder, *(["--force"] if force else [])], str(folder),
        "overwrite" if force else "procam did not write")
    assert snapshot(folder) == before and not leftovers(tmp_path)


@pytest.mark.parametrize("cmd", ["patterns", "demo", "study", "export-maps", "experiment"])
def test_folder_writers_refuse_a_folder_of_the_users(tmp_path, cmd, calib_file, poses):
    folder = user_folder(tmp_path / "mine", ["notes.png", "0.png"])
    (folder / "notes.txt").write_text("mine")
    before = snapshot(folder)
    args = {"patterns": ["patterns", "-p", "64x32", "-o", folder],
            "demo": ["demo", folder],
            "study": ["study", "camera", "-o", folder, "--grid", "0", "--trials", "1", "--no-slices"],
            "export-maps": ["export", calib_file, "--format", "maps", "-o", folder],
            "experiment": ["experiment", *poses, *BOARD, "-o", folder]}[cmd]
    bad(args, str(folder), "procam did not write", "--force")
    assert snapshot(folder) == before and not leftovers(tmp_path)


def test_force_writes_next_to_the_users_files_and_removes_only_its_own(tmp_path):
    folder = user_folder(tmp_path / "mine", ["0.png", "99.png", "pattern_x.png"])
    (folder / "notes.txt").write_text("mine")
    before = snapshot(folder)
    rc, _, err = run_cli(["patterns", "-p", "1920x1080", "-o", folder, "--force"])
    assert rc == 0, err
    assert len(list(folder.glob("pattern_*.png"))) == 46 + 1
    rc, _, err = run_cli(["patterns", "-p", "64x32", "-o", folder, "--force"])  # shorter: stale frames go
    assert rc == 0, err
    assert sorted(p.name for p in folder.glob("pattern_*.png")) == sorted(
        [f"pattern_{i:02d}.png" for i in range(24)] + ["pattern_x.png"])
    after = snapshot(folder)
    assert {k: after[k] for k in before} == before and not leftovers(tmp_path)
    assert capture.load_capture(folder).pattern_set.count == 24  # the manifest says which images are the sequence


def test_rerun_into_own_output_needs_no_force_but_another_commands_does(tmp_path):
    out = tmp_path / "pat"
    assert run_cli(["patterns", "-p", "64x32", "-o", out])[0] == 0
    assert run_cli(["patterns", "-p", "128x64", "-o", out])[0] == 0
    before = snapshot(out)
    bad(["simulate", out], "output of 'procam patterns'", "--force")
    assert snapshot(out) == before


def test_a_camera_capture_is_never_written_into(tmp_path):
    out = tmp_path / "cap"
    rc, _, err = run_cli(["capture", out, "--virtual", "--projector", "64x48"])
    assert rc == 0, err
    before = snapshot(out)
    for args in (["simulate", out, "--force"], ["patterns", "-p", "64x48", "-o", out, "--force"]):
        bad(args, "camera capture")
    assert snapshot(out) == before and not leftovers(tmp_path)


def test_outputs_into_a_pose_folder(poses, tmp_path):
    # a user's capture (no manifest): an image written there would be read as a frame
    mine = copy_pose(poses[0], tmp_path / "mine")
    before = snapshot(mine)
    bad(["calibrate", mine, *BOARD, "-p", "1920x1080", "-o", tmp_path / "c.json", "--png", mine / "residuals.png"],
        "residuals.png", "read as a frame")
    bad(["decode", mine, "-p", "1920x1080", "--png", mine / "05.png"], "05.png", "capture")
    bad(["correspond", mine, *BOARD, "-p", "1920x1080", "-o", mine / "c.json", "--png", mine / "00.png"], "00.png")
    assert snapshot(mine) == before
    # procam's own pose folder (manifest): the figure is recorded as an output and ignored when reading the pose
    own = tmp_path / "own"
    shutil.copytree(poses[0], own)
    rc, _, err = run_cli(["decode", own, "--png", own / "decode.png"])
    assert rc == 0, err
    rc, out, err = run_cli(["decode", own])
    assert rc == 0 and "46 images" in out and "warning" not in out, (out, err)
    bad(["correspond", own, *BOARD, "-o", own / "patterns.json"], "is patterns.json of", "an input of this command")


def test_single_file_outputs_never_overwrite_the_users_files(tmp_path, calib_file, poses):
    notes = tmp_path / "notes.json"
    notes.write_text('{"mine": true}')
    ply, xml = tmp_path / "scan.ply", tmp_path / "k.xml"
    ply.write_text("ply\nformat ascii 1.0\nend_header\n")
    xml.write_text("<data>mine</data>")
    fig = user_folder(tmp_path / "figs", ["plot.png"]) / "plot.png"
    before = snapshot(notes, ply, xml, fig)
    bad(["calibrate", poses[0], *BOARD, "-o", notes], "notes.json", "procam did not write")
    bad(["evaluate", calib_file, poses[0], *BOARD, "-o", notes], "procam did not write")
    bad(["reconstruct", calib_file, poses[0], "-o", ply], "procam did not write")
    bad(["export", calib_file, "--format", "kamino410", "-o", xml], "procam did not write")
    bad(["decode", poses[0], "--png", fig], "procam did not write")
    bad(["evaluate", calib_file, poses[0], *BOARD, "-o", calib_file], "is also an input")
    bad(["calibrate", poses[0], *BOARD, "-o", tmp_path / "c.yml", "--yaml", tmp_path / "c.yml"], "different files")
    assert snapshot(notes, ply, xml, fig) == before
    # procam's own earlier output is overwritten on a re-run
    out = tmp_path / "gl.json"
    for _ in range(2):
        rc, _, err = run_cli(["export", calib_file, "--format", "opengl", "-o", out, "--near", "10", "--far", "1000"])
        assert rc == 0, err


def test_a_second_run_writes_over_its_own_figures_pictures_and_page(tmp_path, calib_file, poses):
    """A PDF figure, the check's overlay picture as JPEG and the report: the same command twice succeeds (each
    carries procam's mark, a PDF's at its end; tests/test_files.py has every format), and the same names of the
    user's are refused."""
    runs = [["decode", poses[0], "--png", tmp_path / "d.pdf"], ["check", poses[0], *BOARD, "--png", tmp_path / "c.jpg"],
            ["report", calib_file, "-o", tmp_path / "r.html"]]
    for args in runs:
        for _ in range(2):
            rc, _, err = run_cli(args)
            assert rc == 0, (args, err)
    assert (tmp_path / "d.pdf").stat().st_size > 1 << 16  # the PDF's Creator lies beyond the first 64 KiB
    mine = tmp_path / "mine"
    mine.mkdir()
    for name in ("d.pdf", "c.jpg", "r.html"):
        shutil.copy(tmp_path / name, mine / name)
    (mine / "d.pdf").write_bytes((mine / "d.pdf").read_bytes().replace(b"/Creator (procam)", b"/Creator (editor)"))
    (mine / "r.html").write_text("<html><head><title>my notes</title></head></html>")
    cv2.imwrite(str(mine / "c.jpg"), np.zeros((8, 8), np.uint8))
    before = snapshot(mine)
    bad(["decode", poses[0], "--png", mine / "d.pdf"], "procam did not write")
    bad(["check", poses[0], *BOARD, "--png", mine / "c.jpg"], "procam did not write")
    bad(["report", calib_file, "-o", mine / "r.html"], "procam did not write")
    bad(["check", poses[0], *BOARD, "--png", tmp_path / "o.pdf"], "must end in")  # the overlay is a picture
    assert snapshot(mine) == before


def test_remove_stale_deletes_only_listed_frames(tmp_path):
    user_folder(tmp_path, ["44.png", "pattern_44.png"])
    ps = patterns.pattern_set(37, 19)
    with pytest.raises(OutputError, match="procam did not write"):
        capture.write_sequence(tmp_path, patterns.generate(37, 19), ps)
    paths = capture.write_sequence(tmp_path, patterns.generate(37, 19), ps, force=True)
    assert capture.remove_stale(tmp_path, paths[:3]) == [p for p in paths[3:]]
    assert (tmp_path / "44.png").exists() and (tmp_path / "pattern_44.png").exists()


def test_stale_temp_files_of_dead_processes_are_cleaned(tmp_path, calib_file):
    dead = 2**22 + 12345  # above Linux's default pid_max: no such process
    stale = tmp_path / f".gl.tmp{dead}.json"
    stale.write_text("half")
    busy = tmp_path / f".notes.tmp{os.getppid()}.json"  # a temporary file of a running process (our parent)
    busy.write_text("in progress")
    rc, _, err = run_cli(["export", calib_file, "--format", "opengl", "-o", tmp_path / "gl.json", "--near", "10",
                          "--far", "1000"])
    assert rc == 0, err
    assert not stale.exists() and busy.exists()
    assert _files.remove_stale_temps(tmp_path) == []


# ------------------------------------------------------------------------------------------------
# family 2: arguments -- every number checked before any work (one line, exit 2)
ARGUMENT_CASES = [
    # patterns
    (["patterns", "-p", "100000x100000", "-o", "{tmp}/p"], ["--projector"]),
    (["patterns", "-p", "16384x16384", "-o", "{tmp}/p"], ["larger than any projector"]),
    (["patterns", "-p", "0x0", "-o", "{tmp}/p"], ["--projector"]),
    (["patterns", "-p", "64x32", "--step", "5000", "-o", "{tmp}/p"], ["--step"]),
    (["patterns", "-p", "64x32", "--step", "40", "-o", "{tmp}/p"], ["--step 40", "fewer than 2 codes"]),
    (["patterns", "-p", "64x32", "--step", "nan", "-o", "{tmp}/p"], ["--step"]),
    (["patterns", "-p", "64x32", "--order", "zigzag", "-o", "{tmp}/p"], ["--order"]),
    # simulate
    (["simulate", "{tmp}/s", "--seed", "-1"], ["--seed"]),
    (["simulate", "{tmp}/s", "--seed", str(2**40)], ["--seed"]),
    (["simulate", "{tmp}/s", "--pose", "nan,0,0"], ["--pose", "finite"]),
    (["simulate", "{tmp}/s", "--pose", "inf,0"], ["--pose", "finite"]),
    (["simulate", "{tmp}/s", "--pose", "1,2,3,4"], ["--pose"]),
    (["simulate", "{tmp}/s", "--pose", "85,0,0"], ["--pose", "80"]),
    (["simulate", "{tmp}/s", "--pose", "0,0,1e9"], ["--pose", "phi"]),
    (["simulate", "{tmp}/s", "--noise", "nan"], ["--noise"]),
    (["simulate", "{tmp}/s", "--noise", "-1"], ["--noise"]),
    (["simulate", "{tmp}/s", "--noise", "inf"], ["--noise"]),
    (["simulate", "{tmp}/s", "--distance", "-500"], ["--distance"]),
    (["simulate", "{tmp}/s", "--distance", "nan"], ["--distance"]),
    (["simulate", "{tmp}/s", "--bits", "12"], ["--bits"]),
    (["simulate", "{tmp}/s", "--preset", "best"], ["--preset"]),
    (["simulate", "{tmp}/s", "--frame", "world"], ["--frame"]),
    # study
    (["study", "camera", "-o", "{tmp}/st", "--grid", "0:1:1e-12"], ["grid", "at most 1000"]),
    (["study", "camera", "-o", "{tmp}/st", "--grid", "nan"], ["grid", "finite"]),
    (["study", "camera", "-o", "{tmp}/st", "--grid", "0:inf:1"], ["grid"]),
    (["study", "camera", "-o", "{tmp}/st", "--grid", ",".join(str(i / 100) for i in range(1200))], ["at most 1000"]),
    (["study", "camera", "-o", "{tmp}/st", "--psi", "90"], ["(-89, 89)"]),
    (["study", "camera", "-o", "{tmp}/st", "--distance", "-500"], ["--distance"]),
    (["study", "camera", "-o", "{tmp}/st", "--noise", "nan"], ["--noise"]),
    (["study", "camera", "-o", "{tmp}/st", "--trials", "-1"], ["--trials"]),
    (["study", "camera", "-o", "{tmp}/st", "-j", "0"], ["--jobs"]),
    (["study", "camera", "-o", "{tmp}/st", "--seed", "-3"], ["--seed"]),
    (["study", "camera", "-o", "{tmp}/st", "--grid", "-80:80:0.2", "--trials", "100000"], ["days"]),
    (["study", "lens", "-o", "{tmp}/st"], ["'camera', 'projector'"]),
    # calibrate / correspond / decode
    (["calibrate", "{pose}", "--board", "99999999999x6", "--square", "24", "-o", "{tmp}/c.json"], ["--board"]),
    (["calibrate", "{pose}", "--board", "10x6", "--square", "1e300", "-o", "{tmp}/c.json"], ["--square"]),
    (["calibrate", "{pose}", "--board", "10x6", "--square", "nan", "-o", "{tmp}/c.json"], ["--square"]),
    (["calibrate", "{pose}", "--board", "10x6", "--square", "-24", "-o", "{tmp}/c.json"], ["--square"]),
    (["calibrate", "{pose}", *BOARD, "--shadow-threshold", "nan", "-o", "{tmp}/c.json"], ["--shadow-threshold"]),
    (["calibrate", "{pose}", *BOARD, "--window", "0", "-o", "{tmp}/c.json"], ["--window"]),
    (["calibrate", "{pose}", *BOARD, "--refine-window", "-1", "-o", "{tmp}/c.json"], ["--refine-window"]),
    (["calibrate", "{pose}", *BOARD, "--cod", "center", "-o", "{tmp}/c.json"], ["--cod"]),
    (["calibrate", "{pose}", *BOARD, "--step", "0", "-o", "{tmp}/c.json"], ["--step"]),
    (["calibrate", "{pose}", *BOARD, "-p", "1e3x10", "-o", "{tmp}/c.json"], ["--projector"]),
    (["correspond", "{pose}", *BOARD, "--contrast-threshold", "-1", "-o", "{tmp}/c.json"], ["--contrast-threshold"]),
    (["decode", "{pose}", "--shadow-threshold", "nan"], ["--shadow-threshold"]),
    (["decode", "{pose}", "--shadow-threshold", "inf"], ["--shadow-threshold"]),
    (["decode", "{pose}", "--contrast-threshold", "256"], ["--contrast-threshold"]),
    # export / reconstruct / experiment / demo / capture
    (["export", "{calib}", "--format", "opengl", "-o", "{tmp}/g.json", "--near", "1e-300", "--far", "1000"], ["--near"]),
    (["export", "{calib}", "--format", "opengl", "-o", "{tmp}/g.json", "--near", "1", "--far", "inf"], ["--far"]),
    (["export", "{calib}", "--format", "maps", "-o", "{tmp}/m", "--scale", "0"], ["--scale"]),
    (["export", "{calib}", "--format", "maps", "-o", "{tmp}/m", "--scale", "nan"], ["--scale"]),
    (["reconstruct", "{calib}", "{pose}", "-o", "{tmp}/r.ply", "--max-residual", "nan"], ["--max-residual"]),
    (["reconstruct", "{calib}", "{pose}", "-o", "{tmp}/r.ply", "--board", "2x2"], ["--board"]),
    (["experiment", "{tmp}/a", "{tmp}/b", "{tmp}/c", *BOARD, "-o", "{tmp}/e", "--min-set", "1"], ["--min-set"]),
    (["experiment", *[f"{{tmp}}/p{i}" for i in range(20)], *BOARD, "-o", "{tmp}/e"], ["pose sets", "--min-set"]),
    (["experiment", "{tmp}/a", "{tmp}/b", "{tmp}/c", *BOARD, "-o", "{tmp}/e", "--cam-dist", "fisheye"],
     ["--cam-dist"]),
    (["experiment", "{pose}", "{pose}/.", "{tmp}/c", *BOARD, "-o", "{tmp}/e"], ["given twice"]),
    (["calibrate", "{pose}", "{pose}", *BOARD, "-o", "{tmp}/c.json"], ["given twice"]),
    (["evaluate", "{calib}", "{pose}", "{pose}", *BOARD], ["given twice"]),
    (["demo", "{tmp}/d", "--seed", "-1"], ["--seed"]),
    (["demo", "{tmp}/d", "--preset", "best"], ["--preset"]),
    (["capture", "{tmp}/cap", "--virtual", "--seed", "-1"], ["--seed"]),
    (["capture", "{tmp}/cap", "--virtual", "--settle-ms", "nan"], ["--settle-ms"]),
    (["capture", "{tmp}/cap", "--virtual", "--poses", "0"], ["--poses"]),
    (["capture", "{tmp}/cap", "--virtual", "--projector", "99999x99999"], ["--projector"]),
]


@pytest.mark.parametrize("args,needles", ARGUMENT_CASES, ids=[" ".join(map(str, a[:4])) + f" #{i}"
                                                               for i, (a, _) in enumerate(ARGUMENT_CASES)])
def test_bad_arguments(args, needles, tmp_path, poses, calib_file):
    fill = {"tmp": str(tmp_path), "pose": str(poses[0]), "calib": str(calib_file)}
    before = snapshot(poses[0], calib_file)
    bad([a.format(**fill) if isinstance(a, str) else a for a in args], *needles)
    assert snapshot(poses[0], calib_file) == before
    assert not [p for p in tmp_path.iterdir()], "nothing is written before the arguments are checked"


def test_pipeline_api_takes_only_a_board():
    from procam import ProcamError, pipeline

    for b in [(0, 0), (10, 6), "10x6"]:
        with pytest.raises(ProcamError, match="procam.Board"):
            pipeline.view_from_folder("nowhere", b)
    with pytest.raises(ProcamError, match="inner corners"):
        pipeline.view_from_folder("nowhere", (0, 0, 1.0))


# ------------------------------------------------------------------------------------------------
# family 3: calibration files -- every field checked, naming the file and the field
def _edit_json(src, dst, fn):
    d = json.loads(Path(src).read_text())
    fn(d)
    Path(dst).write_text(json.dumps(d))
    return dst


JSON_EDITS = {
    "K 2x2": (lambda d: d["camera"].__setitem__("K", [[1, 0], [0, 1]]), "camera.K must be a 3x3 matrix, got 2x2"),
    "NaN in K": (lambda d: d["camera"]["K"][0].__setitem__(0, float("nan")), "camera.K holds NaN"),
    "NaN in R": (lambda d: d.__setitem__("R", [[float("nan")] * 3] * 3), "R holds NaN"),
    "NaN in T": (lambda d: d["T"].__setitem__(1, float("nan")), "T holds NaN"),
    "camera null": (lambda d: d.__setitem__("camera", None), "camera is missing"),
    "K 1e308": (lambda d: d["camera"]["K"][0].__setitem__(0, 1e308), "focal lengths"),
    "negative f": (lambda d: d["projector"]["K"][1].__setitem__(1, -900.0), "projector.K focal lengths"),
    "K string": (lambda d: d["camera"].__setitem__("K", "hello"), "camera.K must be a 3x3 matrix"),
    "bad bottom row": (lambda d: d["camera"]["K"].__setitem__(2, [0, 0, 2]), "camera.K must be [[fx"),
    "unknown model": (lambda d: d["camera"].__setitem__("distortion", {"model": "fisheye", "coeffs": [1, 2, 3, 4]}),
                      "camera.distortion.model must be none, division or opencv"),
    "coeffs length": (lambda d: d["camera"].__setitem__("distortion", {"model": "opencv", "coeffs": [0.1, 0.2, 0.3]}),
                      "camera.distortion.coeffs"),
    "division centre": (lambda d: d["camera"].__setitem__("distortion", {"model": "division", "center": [1],
                                                                         "k1": 0.0}), "camera.distortion.center"),
    "image size": (lambda d: d["camera"].__setitem__("image_size", [0, -1]), "camera.image_size"),
    "R not a rotation": (lambda d: d.__setitem__("R", [[2, 0, 0], [0, 1, 0], [0, 0, 1]]), "R is not a rotation"),
    "T zero": (lambda d: d.__setitem__("T", [0, 0, 0]), "T has length 0"),
    "T 2 numbers": (lambda d: d.__setitem__("T", [1, 2]), "T must be 3 numbers"),
    "projector missing": (lambda d: d.__setitem__("projector", None), "projector is missing"),
    "rms string": (lambda d: d.__setitem__("stereo_rms_px", "small"), "stereo_rms_px must be a number"),
    "views garbage": (lambda d: d.__setitem__("views", [{"x": 1}]), "views are not procam correspondences"),
    "a view's board": (lambda d: d.__setitem__("views", [{"board_points": [[0, 0, 0]], "camera_points": [[0, 0]],
                                                          "projector_points": [[0, 0]],
                                                          "board": {"cols": 0, "rows": 6, "square": 24.0}}]),
                       "views are not procam correspondences (views[0]: board 0x6: columns of inner corners"),
    "not procam": (lambda d: d.__setitem__("format", "other"), "not a procam calibration"),
}


@pytest.mark.parametrize("case", sorted(JSON_EDITS))
@pytest.mark.parametrize("cmd", ["evaluate", "export", "reconstruct"])
def test_bad_calibration_json(case, cmd, calib_file, poses, tmp_path):
    fn, needle = JSON_EDITS[case]
    path = _edit_json(calib_file, tmp_path / "bad.json", fn)
    args = {"evaluate": ["evaluate", path, poses[0], *BOARD],
            "export": ["export", path, "--format", "kamino410", "-o", tmp_path / "k.xml"],
            "reconstruct": ["reconstruct", path, poses[0], "-o", tmp_path / "r.ply"]}[cmd]
    bad(args, "bad.json", needle)
    assert not (tmp_path / "k.xml").exists() and not (tmp_path / "r.ply").exists()


def _yaml(path, **mats):
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_WRITE)
    for k, v in mats.items():
        fs.write(k, v)
    fs.release()
    return path


YAML_CASES = {
    "R 2x2": ({"R": np.eye(2)}, "R must be a 3x3 matrix, got 2x2"),
    "K NaN": ({"cam_K": np.array([[np.nan, 0, 320], [0, 700, 200], [0, 0, 1]])}, "cam_K holds NaN"),
    "T zero": ({"T": np.zeros((3, 1))}, "T has length 0"),
    "kc 3": ({"cam_kc": np.zeros((1, 3)) + 0.1}, "cam_kc must have"),
    "missing proj_K": ({"proj_K": None}, "missing proj_K"),
}


@pytest.mark.parametrize("case", sorted(YAML_CASES))
def test_bad_calibration_yaml(case, tmp_path, poses):
    good = {"cam_K": np.array([[700.0, 0, 320], [0, 700, 200], [0, 0, 1]]), "cam_kc": np.zeros((1, 5)),
            "proj_K": np.array([[2400.0, 0, 960], [0, 2400, 1000], [0, 0, 1]]), "proj_kc": np.zeros((1, 5)),
            "R": np.eye(3), "T": np.array([[-170.0], [-40], [-60]]), "cam_size": np.array([[640, 400]], np.int32),
            "proj_size": np.array([[1920, 1080]], np.int32)}
    change, needle = YAML_CASES[case]
    mats = {k: v for k, v in {**good, **change}.items() if v is not None}
    path = _yaml(tmp_path / "bad.yml", **mats)
    bad(["evaluate", path, poses[0], *BOARD], "bad.yml", needle)


@pytest.mark.parametrize("content", [b"%YAML:1.0\n---\ncam_K: [1, 2\n  {{{ nope\n", b"\x00\x01\x02 random \xff\xfe",
                                     b"", b"<opencv_storage><R>1 2</opencv_storage"])
@pytest.mark.parametrize("suffix", [".yml", ".xml"])
def test_garbage_calibration_files(content, suffix, tmp_path, poses):
    path = tmp_path / f"garbage{suffix}"
    path.write_bytes(content)
    bad(["evaluate", path, poses[0], *BOARD], f"garbage{suffix}")


def test_calibration_file_without_sizes_says_so(tmp_path, poses):
    """A file without sizes (other tools' files store none) takes the pose's, and says so (issue 34, item 3: it was
    refused, '2 (u0, v0) was assumed', which no user of another tool's file can mend)."""
    path = _yaml(tmp_path / "nosize.yml", cam_K=np.array([[700.0, 0, 330], [0, 700, 210], [0, 0, 1]]),
                 proj_K=np.array([[2400.0, 0, 960], [0, 2400, 1000], [0, 0, 1]]), R=np.eye(3),
                 T=np.array([[-170.0], [-40], [-60]]))
    rc, out, err = run_cli(["evaluate", path, poses[0], *BOARD])
    assert rc == 0, err
    assert "nosize.yml does not store the camera size; the pose's 640x400 is used" in out
    assert "nosize.yml does not store the projector size; the pose's 1920x1080 is used" in out


# ------------------------------------------------------------------------------------------------
# family 4: capture folders -- name the file that is wrong, and what is wrong with it
@pytest.fixture(scope="module")
def other_pose(tmp_path_factory):
    """A pose of the same rig at other angles (the source of 'foreign' frames)."""
    folder = tmp_path_factory.mktemp("other") / "pose"
    render_pose(folder, (-15.0, -11.0, 3.0), seed=7)
    return folder


def _pose_case(case, src, other, dst):
    """A user's copy of ``src`` (images only) broken as ``case`` says."""
    copy_pose(src, dst)
    if case == "foreign frame":
        shutil.copy(other / "10.png", dst / "10.png")
    elif case == "foreign resolved frame":
        shutil.copy(other / "03.png", dst / "03.png")
    elif case == "foreign pair":
        for n in ("06.png", "07.png"):
            shutil.copy(other / n, dst / n)
    elif case == "foreign white":
        shutil.copy(other / "44.png", dst / "44.png")
    elif case == "missing middle":
        (dst / "12.png").unlink()
    elif case == "missing black":
        (dst / "45.png").unlink()
    elif case == "missing first":
        (dst / "00.png").unlink()
    elif case == "extra duplicate":
        shutil.copy(dst / "10.png", dst / "10b.png")
    elif case == "extra figure":
        cv2.imwrite(str(dst / "residuals.png"), np.zeros((300, 500, 3), np.uint8))
    elif case == "folder named like a frame":
        (dst / "07.png").unlink()
        (dst / "07.png").mkdir()
    elif case == "symlink loop":
        (dst / "07.png").unlink()
        os.symlink("07.png", dst / "07.png")
    elif case == "dangling symlink":
        (dst / "07.png").unlink()
        os.symlink("gone.png", dst / "07.png")
    elif case == "truncated png":
        data = (dst / "07.png").read_bytes()
        (dst / "07.png").write_bytes(data[: len(data) // 2])
    elif case == "damaged png":
        data = bytearray((dst / "07.png").read_bytes())
        data[len(data) // 2] ^= 0xFF
        (dst / "07.png").write_bytes(bytes(data))
    elif case == "empty png":
        (dst / "07.png").write_bytes(b"")
    elif case == "text named png":
        (dst / "07.png").write_text("not an image")
    elif case == "over-exposed":
        for p in dst.glob("*.png"):
            img = cv2.imread(str(p), cv2.IMREAD_UNCHANGED)
            cv2.imwrite(str(p), np.clip(img.astype(int) * 4, 0, 255).astype(np.uint8))
    elif case == "all saturated":
        for p in dst.glob("*.png"):
            cv2.imwrite(str(p), np.full((400, 640), 255, np.uint8))
    elif case == "16-bit among 8-bit":
        img = cv2.imread(str(dst / "07.png"), cv2.IMREAD_UNCHANGED)
        cv2.imwrite(str(dst / "07.png"), img.astype(np.uint16) * 257)
    elif case == "bad patterns.json":
        (dst / "patterns.json").write_text("{not json")
    else:
        raise ValueError(case)
    return dst


CAPTURE_CASES = {
    "foreign frame": ["10.png", "does not belong to this capture"],
    "foreign resolved frame": ["03.png", "does not belong to this capture"],
    "foreign pair": ["06.png", "07.png", "do not belong to this capture"],
    "foreign white": ["44.png", "white", "does not belong"],
    "missing middle": ["found 45", "#12", "missing", "after 11.png"],
    "missing black": ["found 45", "#45 (black)", "missing"],
    "missing first": ["found 45", "#0", "missing", "at the start"],
    "extra duplicate": ["found 47", "10b.png", "one frame too many"],
    "extra figure": ["found 47", "residuals.png (500x300, 8-bit) is not part of the sequence"],
    "folder named like a frame": ["07.png", "is a folder"],
    "symlink loop": ["07.png", "loops"],
    "dangling symlink": ["07.png", "does not exist"],
    "truncated png": ["07.png", "truncated"],
    "damaged png": ["07.png", "damaged"],
    "empty png": ["07.png", "cannot be read"],
    "text named png": ["07.png", "cannot be read"],
    "over-exposed": ["over-exposed", "reduce the exposure"],
    "all saturated": ["saturated", "reduce the exposure"],
    "16-bit among 8-bit": ["07.png", "16-bit"],
    "bad patterns.json": ["patterns.json", "not valid JSON"],
}


@pytest.mark.parametrize("case", sorted(CAPTURE_CASES))
def test_bad_capture_folders(case, poses, other_pose, tmp_path):
    folder = _pose_case(case, poses[0], other_pose, tmp_path / "pose")
    before = snapshot(folder)
    bad(["decode", folder, "-p", "1920x1080"], *CAPTURE_CASES[case])
    assert snapshot(folder) == before and not leftovers(tmp_path)


def test_a_listed_frame_that_is_gone_is_named(poses, tmp_path):
    folder = tmp_path / "pose"
    shutil.copytree(poses[0], folder)
    (folder / "12.png").unlink()
    bad(["decode", folder], "12.png", "listed in the folder's manifest", "missing")


def test_missing_empty_and_file_instead_of_folder(tmp_path):
    (tmp_path / "empty").mkdir()
    (tmp_path / "file.png").write_bytes(b"x")
    bad(["decode", tmp_path / "nope", "-p", "64x48"], "no such folder")
    bad(["decode", tmp_path / "empty", "-p", "64x48"], "no images found")
    bad(["decode", tmp_path / "file.png", "-p", "64x48"], "not a folder")


def test_a_capture_too_large_for_memory_is_refused(tmp_path, monkeypatch):
    write_stack(tmp_path, camera_view_of_patterns(64, 48))
    monkeypatch.setattr(_files, "available_memory", lambda: 100_000)
    bad(["decode", tmp_path, "-p", "64x48"], "need about", "memory")


# ------------------------------------------------------------------------------------------------
# family 5: output paths -- checked up front, the user's path named (never a hidden temporary name)
def test_unwritable_and_impossible_outputs(tmp_path, poses, calib_file):
    afile = tmp_path / "afile"
    afile.write_text("x")
    cases = [
        (["calibrate", poses[0], *BOARD, "-o", "/proc/nope/c.json"], ["cannot create the folder"]),
        (["calibrate", poses[0], *BOARD, "-o", tmp_path], ["is a folder; give a file name"]),
        (["calibrate", poses[0], *BOARD, "-o", tmp_path / "d.json"], None),  # placeholder, replaced below
        (["experiment", *poses, *BOARD, "-o", afile], ["-o", "not a folder"]),
        (["study", "camera", "-o", afile, "--grid", "0"], ["not a folder"]),
        (["export", calib_file, "--format", "maps", "-o", afile], ["give a folder"]),
        (["simulate", afile], ["not a folder"]),
        (["patterns", "-p", "64x32", "-o", afile / "sub"], ["not a folder"]),
        (["decode", poses[0], "-o", afile / "m.npz"], ["afile"]),
    ]
    (tmp_path / "d.json").mkdir()
    cases[2] = (["calibrate", poses[0], *BOARD, "-o", tmp_path / "d.json"], ["is a folder"])
    for args, needles in cases:
        bad(args, *needles)
    assert afile.read_text() == "x" and not leftovers(tmp_path)


def test_decode_names_its_maps_file_as_given_or_adds_npz_only_to_a_bare_name(tmp_path, poses):
    """``-o maps`` writes maps.npz; an existing folder or another suffix is refused (they were written as
    ``folder.npz`` beside it and ``x.npz``, a name the user did not give)."""
    (tmp_path / "existdir").mkdir()
    bad(["decode", poses[0], "-o", tmp_path / "existdir"], "is a folder; give a file name")
    bad(["decode", poses[0], "-o", tmp_path / "x.txt"], "must end in .npz")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["existdir"]
    code, out, err = run_cli(["decode", poses[0], "-o", tmp_path / "maps"])
    assert code == 0 and (tmp_path / "maps.npz").is_file(), err


def test_loop_link_as_output(tmp_path, poses):
    os.symlink("loop.json", tmp_path / "loop.json")
    bad(["correspond", poses[0], *BOARD, "-o", tmp_path / "loop.json"], "loop.json", "link")


@pytest.mark.parametrize("code,words", [(errno.ENOSPC, "the disk is full"), (errno.EROFS, "read-only"),
                                        (errno.EACCES, "permission denied")])
def test_a_failing_write_names_the_users_path(code, words, tmp_path, poses, monkeypatch):
    """Disk full, read-only or forbidden at the moment of writing: the message names the user's file."""
    real = os.replace

    def failing(src, dst):
        if ".tmp" in str(src):
            raise OSError(code, os.strerror(code), str(src))
        return real(src, dst)

    monkeypatch.setattr(_files.os, "replace", failing)
    out = tmp_path / "out" / "maps.npz"
    err = bad(["decode", poses[0], "-o", out], words)
    assert str(out) in err and ".tmp" not in err
    assert not leftovers(tmp_path) and not out.exists()


@pytest.mark.parametrize("code,words", [(errno.EROFS, "read-only"), (errno.ENOSPC, "the disk is full")])
def test_unwritable_target_is_found_before_any_work(code, words, tmp_path, poses, monkeypatch):
    import tempfile

    def refuse(*a, **k):
        raise OSError(code, os.strerror(code))

    monkeypatch.setattr(tempfile, "mkstemp", refuse)
    for args in (["calibrate", poses[0], *BOARD, "-o", tmp_path / "c.json"],
                 ["experiment", *poses, *BOARD, "-o", tmp_path / "rep"],
                 ["simulate", tmp_path / "sim"], ["study", "camera", "-o", tmp_path / "st"]):
        bad(args, words)


def test_disk_almost_full_is_found_before_any_work(tmp_path, poses, monkeypatch):
    from collections import namedtuple

    usage = namedtuple("usage", "total used free")
    monkeypatch.setattr(shutil, "disk_usage", lambda p: usage(10**9, 10**9 - 1000, 1000))
    bad(["calibrate", poses[0], *BOARD, "-o", tmp_path / "c.json"], "free on the disk")


# ------------------------------------------------------------------------------------------------
# family 6: messages that blame the right thing
def test_small_board_single_pose_says_the_board_is_small(tmp_path):
    truth = render_pose(tmp_path / "b3", (15.0, 12.0, 0.0), board_cols=3, board_rows=3, square=60.0)
    assert truth["board"]["cols"] == 3
    bad(["calibrate", tmp_path / "b3", "--board", "3x3", "--square", "60", "-o", tmp_path / "c.json"],
        "the board has only 9 inner corners", "several poses")
    assert not (tmp_path / "c.json").exists()


@pytest.mark.slow
def test_small_board_calibrates_from_several_poses(tmp_path):
    folders = []
    for k, a in enumerate(POSE_ANGLES):
        render_pose(tmp_path / f"b{k}", a, seed=k, board_cols=3, board_rows=3, square=60.0)
        folders.append(tmp_path / f"b{k}")
    rc, out, err = run_cli(["calibrate", *folders, "--board", "3x3", "--square", "60", "-o", tmp_path / "c.json"])
    assert rc == 0, err
    assert "9 of 9 corners" in out and io.load_calibration(tmp_path / "c.json").method == "multi-pose"


def test_too_few_points_for_a_distortion_model_names_the_terms():
    from procam import multi_pose

    square = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.0]])
    five = np.vstack([square, [[0.5, 0.5, 0]]])
    with pytest.raises(CalibrationError, match=r"20 equations .* 21 unknowns .* k1, k2, p1, p2, k3.*--cam-dist k1k2\b"):
        multi_pose.check_counts([five, five])
    multi_pose.check_counts([five, five], "k1k2", "k1k2")  # 20 equations > 18 unknowns
    with pytest.raises(CalibrationError, match=r"16 equations per device, not more than the 16 unknowns of a fit with the none model.*larger board$"):
        multi_pose.check_counts([square, square], "none", "none")
    with pytest.raises(CalibrationError, match="lie on one line"):
        multi_pose.check_counts([square[:1].repeat(5, 0) + np.arange(5)[:, None] * [1, 0, 0], square])
    with pytest.raises(CalibrationError, match="needs 4 per pose"):
        multi_pose.check_counts([square[:3], square])


def test_markup_in_names_is_printed_as_is(tmp_path):
    folder = tmp_path / "cap[red]"
    err = bad(["decode", folder, "-p", "64x48"], "cap[red]", "no such folder")
    assert "[red]" in err
    write_stack(tmp_path / "pose[bold]x", camera_view_of_patterns(64, 48))
    rc, out, err = run_cli(["decode", tmp_path / "pose[bold]x", "-p", "64x48"])
    assert rc == 0 and "pose[bold]x" in out, err


@pytest.mark.slow
def test_simulate_margin_warning_has_no_sentinel(tmp_path):
    rc, out, err = run_cli(["simulate", tmp_path / "s", "--pose", "10,10", "--distance", "50"])
    assert rc == 0, err
    assert "warning" in out and "1000000000" not in out


# ------------------------------------------------------------------------------------------------
# family 7: papercuts -- every choice of every option works through the CLI
def test_version():
    import procam

    rc, out, _ = run_cli(["--version"])
    assert rc == 0 and out.strip() == f"procam {procam.__version__}"


@pytest.mark.parametrize("cod", ["auto", pytest.param("paper", marks=pytest.mark.slow),
                                 pytest.param("image-center", marks=pytest.mark.slow)])
def test_every_cod_choice(cod, poses, tmp_path):
    rc, _, err = run_cli(["calibrate", poses[0], *BOARD, "--cod", cod, "-o", tmp_path / "c.json"])
    assert rc in (0, 3), err  # 3: a degenerate verdict (the lead's --force); never a traceback
    assert "Traceback" not in err


@pytest.mark.parametrize("model", ["none", "k1", "k1k2", "k1k2p1p2", "k1k2p1p2k3", "rational"])
def test_every_distortion_model(model, poses, tmp_path):
    rc, _, err = run_cli(["calibrate", *poses, *BOARD, "--cam-dist", model, "--proj-dist", model, "--no-refine",
                            "-o", tmp_path / "c.json"])
    if model == "rational":
        # 8 radial terms per device from 3 small poses without the joint refinement: impossible R, T (stereo RMS
        # beyond any decoding noise), which the plausibility gates call failed -- not written, exit 3, one line
        assert rc == 3 and "failed calibration, not written" in err and "stereo RMS" in err, err
        assert not (tmp_path / "c.json").exists() and len(err.strip().splitlines()) == 1
        return
    assert rc == 0, err


@pytest.mark.parametrize("opt", ["--decode", "--detector", "--estimator"])
def test_every_pose_option_choice(opt, poses, tmp_path):
    from procam.board import corners
    from procam import correspond, decode

    allowed = {"--decode": decode.METHODS, "--detector": corners.DETECTORS, "--estimator": correspond.ESTIMATORS}[opt]
    rc, _, err = run_cli(["correspond", poses[0], *BOARD, "-o", tmp_path / "ref.json"])
    assert rc == 0, err
    ref = json.loads((tmp_path / "ref.json").read_text())
    for v in allowed:
        rc, _, err = run_cli(["correspond", poses[0], *BOARD, opt, v, "-o", tmp_path / "c.json"])
        assert rc == 0, (v, err)
        got = json.loads((tmp_path / "c.json").read_text())
        used = {"--decode": got["options"]["decode"]["method"], "--detector": got["options"]["detector"],
                "--estimator": got["options"]["corners"]["estimator"]}[opt]
        assert used == v
        # every choice finds the same corners of the same pose, to a fraction of a pixel in both devices
        for key, tol in (("camera_points", 0.5), ("projector_points", 2.0)):
            a = np.array(got[key], float)
            b = np.array(ref[key], float)
            both = np.isfinite(a).all(1) & np.isfinite(b).all(1)
            assert both.sum() >= 0.9 * np.isfinite(b).all(1).sum(), (v, key)
            assert np.median(np.linalg.norm(a[both] - b[both], axis=1)) < tol, (v, key)


@pytest.mark.parametrize("order", ["opencv", "moreno"])
def test_every_order_choice(order, tmp_path):
    rc, _, err = run_cli(["patterns", "-p", "64x48", "--order", order, "-o", tmp_path / "p"])
    assert rc == 0, err
    rc, _, err = run_cli(["decode", tmp_path / "p", "--order", order, "-o", tmp_path / "maps.npz"])
    assert rc == 0, err
    # the patterns themselves, seen pixel for pixel, decode to every projector pixel's own coordinates
    maps = io.load_decoded_maps(tmp_path / "maps.npz")
    yy, xx = np.mgrid[0:48, 0:64]
    assert maps["valid_col"].all() and maps["valid_row"].all()
    np.testing.assert_allclose(maps["col"], xx, atol=1e-6)
    np.testing.assert_allclose(maps["row"], yy, atol=1e-6)


# ------------------------------------------------------------------------------------------------
# property: random numbers through the CLI never give a traceback
def test_random_numbers_never_give_a_traceback(tmp_path, calib_file):
    from hypothesis import HealthCheck, given, settings
    from hypothesis import strategies as st

    mine = user_folder(tmp_path / "mine", ["0.png"])
    notes = tmp_path / "notes.json"
    notes.write_text("{}")
    missing = tmp_path / "missing"
    number = st.one_of(st.floats(allow_nan=True, allow_infinity=True).map(repr),
                       st.integers(min_value=-10**30, max_value=10**30).map(str),
                       st.sampled_from(["0", "-0", "1e-300", "1e300", "nan", "-inf", "", "1,5", "0x10", "12abc"]))
    # each command stops at a refused folder or a missing input when every number is valid: all fast
    templates = [
        ["decode", missing, "--shadow-threshold", "{0}", "--contrast-threshold", "{1}", "--step", "{2}"],
        ["calibrate", missing, "--board", "10x6", "--square", "{0}", "--window", "{1}", "--refine-window", "{2}",
         "-o", tmp_path / "c.json"],
        ["simulate", mine, "--distance", "{0}", "--noise", "{1}", "--seed", "{2}"],
        ["simulate", mine, "--pose", "{0},{1},{2}"],
        ["study", "camera", "-o", mine, "--trials", "{0}", "--noise", "{1}", "--distance", "{2}"],
        ["study", "camera", "-o", mine, "--grid", "{0}:{1}:{2}"],
        ["export", missing / "c.json", "--format", "opengl", "-o", tmp_path / "gl.json", "--near", "{0}", "--far", "{1}"],
        ["export", calib_file, "--format", "maps", "-o", mine, "--scale", "{0}"],
        ["reconstruct", calib_file, missing, "-o", tmp_path / "r.ply", "--max-residual", "{0}"],
        ["patterns", "-p", "{0}x{1}", "--step", "{2}", "-o", mine],
        ["capture", mine, "--virtual", "--settle-ms", "{0}", "--gain", "{1}", "--seed", "{2}"],
        ["demo", mine, "--seed", "{0}"],
    ]

    @settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
    @given(k=st.integers(0, len(templates) - 1), a=number, b=number, c=number)
    def check(k, a, b, c):
        args = [x.format(a, b, c) if isinstance(x, str) else x for x in templates[k]]
        rc, _, err = run_cli(args)
        lines = [line for line in err.splitlines() if line.strip()]
        assert rc == 2 and len(lines) == 1 and "Traceback" not in err, (args, rc, err)

    before = snapshot(mine, notes)
    check()
    assert snapshot(mine, notes) == before and not leftovers(tmp_path)


@pytest.mark.parametrize("cmd", ["experiment", "simulate", "study"])
def test_ctrl_c_prints_one_line_and_leaves_no_output_folder(cmd, poses, tmp_path, monkeypatch):
    from procam.paper import experiment, study

    def interrupt(*a, **k):
        raise KeyboardInterrupt

    module, attr = {"experiment": (experiment, "run"), "simulate": (simulate, "render"),
                    "study": (study, "run_study")}[cmd]
    monkeypatch.setattr(module, attr, interrupt)
    out = tmp_path / "out"
    args = {"experiment": ["experiment", *poses, *BOARD, "-o", out], "simulate": ["simulate", out],
            "study": ["study", "camera", "-o", out, "--grid", "0", "--trials", "1"]}[cmd]
    bad(args, "interrupted", code=130)
    assert not out.exists() and not leftovers(tmp_path)


def test_procam_debug_shows_the_internal_error_itself(tmp_path, monkeypatch):
    """PROCAM_DEBUG=1 lets an internal error through with its own traceback (the command group's handlers of
    typer's errors must not fail on it instead)."""
    def boom(*a, **k):
        raise RuntimeError("boom from the renderer")

    monkeypatch.setattr(simulate, "render", boom)
    monkeypatch.setenv("PROCAM_DEBUG", "1")
    with pytest.raises(RuntimeError, match="boom from the renderer"):
        run_cli(["simulate", tmp_path / "out"])
    monkeypatch.delenv("PROCAM_DEBUG")
    code, _, err = run_cli(["simulate", tmp_path / "out2"])
    assert code != 0 and "internal error (RuntimeError: boom from the renderer)" in err
