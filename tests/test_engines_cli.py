"""The export command end to end: every command reads every calibration format procam writes or reads, the engine
files on disk, the projector's view of a rendered pose, and what the command refuses."""

import json
import os
import re

import cv2
import numpy as np
import pytest

from procam import io
from procam.export import opengl
from procam.simulate import truth_calibration
from sim_small import small_capture
from conftest import run_cli

import procam.cli  # noqa: F401  (registers every command)

FORMATS = ("procam.json", "procam.yml", "procam.xml", "kamino410-procam.xml", "kamino410-theirs.xml")


def _write_theirs(calib, path):
    """kamino410/procam-calibration's calibration_result.xml as their calibrate.py writes it: no projector size."""
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_WRITE)
    W, H = calib.camera.image_size
    fs.write("img_shape", np.array([[float(H)], [float(W)]]))
    fs.write("rms", 0.3)
    fs.write("cam_int", np.asarray(calib.camera.K, float))
    from procam.distortion import opencv_from_division

    d = calib.camera.distortion
    coeffs, _ = opencv_from_division(calib.camera.K, d.center, d.k1, d.k2, calib.camera.image_size)
    fs.write("cam_dist", np.asarray(coeffs, float).reshape(1, 5))
    fs.write("proj_int", np.asarray(calib.projector.K, float))
    fs.write("proj_dist", np.zeros((1, 5)))
    fs.write("rotation", np.asarray(calib.R, float))
    fs.write("translation", np.asarray(calib.T, float).reshape(3, 1))
    fs.release()
    return path


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """The small rendered pose as a capture folder, and its true calibration in every format."""
    from procam import simulate

    root = tmp_path_factory.mktemp("formats")
    scene, stack, truth, _ = small_capture()
    pose = root / "pose"
    simulate.write_capture(pose, stack, truth)
    calib = truth_calibration(scene)
    paths = {"procam.json": io.save_calibration(calib, root / "calib.json"),
             "procam.yml": io.save_calibration(calib, root / "calib.yml"),
             "procam.xml": io.save_calibration(calib, root / "calib.xml"),
             "kamino410-procam.xml": io.save_kamino410(calib, root / "calibration_result.xml"),
             "kamino410-theirs.xml": _write_theirs(calib, root / "theirs.xml")}
    return root, pose, calib, paths


@pytest.mark.parametrize("fmt", FORMATS)
def test_every_command_reads_every_calibration_format(files, fmt, tmp_path):
    """export, report, evaluate and reconstruct read procam's JSON, YAML and XML and kamino410's XML (procam's and
    their tool's, which has no projector size: the pose's patterns.json gives it) through the one reader."""
    root, pose, calib, paths = files
    path = paths[fmt]
    size = ["--projector", "1920x1080"] if fmt == "kamino410-theirs.xml" else []   # their files do not store it
    code, out, err = run_cli(["export", path, "--format", "opengl", "-o", tmp_path / "gl.json", "--near", "100",
                              "--far", "3000", *size])
    assert code == 0, err
    assert "does not store the projector size" not in out
    if size:
        code, out, err = run_cli(["export", path, "--format", "opengl", "-o", tmp_path / "gl0.json", "--near", "100",
                                  "--far", "3000"])
        assert code == 0 and "does not store the projector size" in out and "--projector WIDTHxHEIGHT" in out
    doc = json.loads((tmp_path / "gl.json").read_text())
    np.testing.assert_allclose(doc["projector"]["projection"],
                               opengl.opengl_projection(calib.projector.K, calib.projector.image_size, 100, 3000))
    np.testing.assert_allclose(doc["camera"]["K"], calib.camera.K)
    assert doc["calibration"] == path.name                   # a name, not an absolute path
    code, out, err = run_cli(["report", path, "-o", tmp_path / "r.html"])
    assert code == 0, err
    code, out, err = run_cli(["evaluate", path, pose, "--board", "10x6", "--square", "24", "-o", tmp_path / "ev.json"])
    assert code == 0, err
    ev = json.loads((tmp_path / "ev.json").read_text())
    assert ev["stereo_rms"] < 0.1 and ev["calibration"] == os.path.relpath(path, tmp_path)   # not absolute
    pytest.importorskip("plyfile", reason="plyfile is not installed (pip install 'procam[ply]')")
    code, out, err = run_cli(["reconstruct", path, pose, "-o", tmp_path / "cloud.ply"])
    assert code == 0, err
    assert len(io.read_ply(tmp_path / "cloud.ply")[0]) > 10000


def test_export_yaml_round_trips_through_the_one_reader(files, tmp_path):
    root, pose, calib, paths = files
    for name in ("calib_out.yml", "calib_out.xml"):
        code, out, err = run_cli(["export", paths["procam.json"], "--format", "yaml", "-o", tmp_path / name])
        assert code == 0, err
        back = io.load_calibration(tmp_path / name)
        np.testing.assert_allclose(back.projector.K, calib.projector.K)
        np.testing.assert_allclose(back.T, calib.T)
        assert back.camera.image_size == calib.camera.image_size and back.projector.image_size == (1920, 1080)
        assert back.camera.distortion.model == "opencv"          # the division model as its OpenCV fit
    code, out, err = run_cli(["export", paths["procam.json"], "--format", "yaml", "-o", tmp_path / "c.json"])
    assert code == 2 and ".yml or .yaml or .xml" in err


def test_engine_exports_write_their_files_and_distortion_maps(files, tmp_path):
    """blender writes the JSON and its script, every engine export the distortion maps of the devices that have
    lens distortion (the small rig's camera: division model), named in the document by file name; the ST map
    holds the remap table to 16 bits."""
    from procam.export.maps import st_map_lookup

    root, pose, calib, paths = files
    for fmt in ("blender", "unity", "opengl"):
        out = tmp_path / fmt / "rig.json"
        args = ["export", paths["procam.json"], "--format", fmt, "-o", out, "--unit", "mm"] if fmt != "opengl" else \
            ["export", paths["procam.json"], "--format", fmt, "-o", out, "--near", "10", "--far", "5000"]
        code, o, err = run_cli(args)
        assert code == 0, err
        doc = json.loads(out.read_text())
        assert doc["distortion_maps"] == {"camera": {"what": "undistort", "remap": "rig_camera_undistort.npz",
                                                     "st_map": "rig_camera_undistort_st.png"}}
        names = sorted(p.name for p in out.parent.iterdir())
        want = ["rig.json", "rig_camera_undistort.npz", "rig_camera_undistort_st.png"] + (["rig.py"] if fmt ==
                                                                                            "blender" else [])
        assert names == sorted(want)
        assert "lens distortion, which the engine camera cannot hold" in o
    with np.load(tmp_path / "unity" / "rig_camera_undistort.npz") as m:
        mx, my = m["map_x"], m["map_y"]
    st = cv2.imread(str(tmp_path / "unity" / "rig_camera_undistort_st.png"), cv2.IMREAD_UNCHANGED)[..., ::-1]
    sx, sy, ok = st_map_lookup(st, calib.camera.image_size)
    assert ok.mean() > 0.95
    assert np.abs(sx - mx)[ok].max() < 0.01 and np.abs(sy - my)[ok].max() < 0.01
    script = (tmp_path / "blender" / "rig.py").read_text()
    assert script.startswith("# procam") and "def create_cameras" in script
    # a second export overwrites procam's files, never a file it did not write
    code, o, err = run_cli(["export", paths["procam.json"], "--format", "blender", "-o", tmp_path / "blender" /
                            "rig.json"])
    assert code == 0, err
    (tmp_path / "x").mkdir()
    (tmp_path / "x" / "rig.py").write_text("print('mine')\n")
    code, o, err = run_cli(["export", paths["procam.json"], "--format", "blender", "-o", tmp_path / "x" / "rig.json"])
    assert code == 2 and "procam did not write it" in err and not (tmp_path / "x" / "rig.json").exists()


def test_projector_view_of_a_rendered_pose(files, tmp_path):
    """The camera's white frame seen from the projector: the board's corners detected in it lie at their true
    projector pixels (0.5 px RMS), the mask covers the board and leaves out what the camera does not see; the
    same from the decoded maps file."""
    from procam.board.corners import detect_corners

    root, pose, calib, paths = files
    scene, stack, truth, maps = small_capture()
    code, out, err = run_cli(["export", paths["procam.json"], "--format", "projector-view", "--pose", pose,
                              "-o", tmp_path / "view.png"])
    assert code == 0, err
    img = cv2.imread(str(tmp_path / "view.png"), cv2.IMREAD_GRAYSCALE)
    mask = cv2.imread(str(tmp_path / "view_mask.png"), cv2.IMREAD_GRAYSCALE) > 0
    assert img.shape == (1080, 1920) and mask.shape == (1080, 1920)
    found = detect_corners(img, (10, 6))
    assert found is not None
    err_px = np.hypot(*(found - np.array(truth["corners"]["projector"])).T)
    assert np.sqrt(np.mean(err_px ** 2)) < 0.5 and err_px.max() < 1.0
    inside = np.rint(np.array(truth["corners"]["projector"])).astype(int)
    assert mask[inside[:, 1], inside[:, 0]].all() and 0.2 < mask.mean() < 0.95 and not img[~mask].any()
    assert run_cli(["decode", pose, "-o", tmp_path / "maps.npz"])[0] == 0
    code, out, err = run_cli(["export", paths["procam.json"], "--format", "projector-view", "--pose", pose,
                              "--maps", tmp_path / "maps.npz", "-o", tmp_path / "view2.png"])
    assert code == 0 and "warning" not in out, err
    assert np.array_equal(cv2.imread(str(tmp_path / "view2.png"), cv2.IMREAD_GRAYSCALE), img)


def test_projector_view_refuses_another_captures_maps(files, tmp_path):
    """The decoded maps say which capture they are of: another pose's maps of the same sizes were taken as this
    pose's (a wrong view, exit 0); a file that does not say (an older procam's) is taken with a warning."""
    from procam import simulate

    root, pose, calib, paths = files
    _, stack, truth, maps = small_capture()
    other = tmp_path / "other"
    simulate.write_capture(other, np.roll(stack, 7, axis=2), truth)  # the board elsewhere: another capture
    assert run_cli(["decode", other, "-o", tmp_path / "other.npz"])[0] == 0
    export = ["export", paths["procam.json"], "--format", "projector-view", "--pose", pose, "-o", tmp_path / "v.png"]
    code, out, err = run_cli(export + ["--maps", tmp_path / "other.npz"])
    assert code == 2 and "its maps were decoded from another capture, not" in err and err.count("\n") == 1, err
    assert not (tmp_path / "v.png").exists()
    io.save_decoded_maps(tmp_path / "old.npz", maps)  # no source recorded
    code, out, err = run_cli(export + ["--maps", tmp_path / "old.npz"])
    assert code == 0 and "does not say which capture it was decoded from" in out, err
    assert io.load_decoded_maps(tmp_path / "other.npz")["source"].startswith("sha256:")
    import dataclasses

    from procam import capture

    nothing = np.zeros_like(maps.valid_col)  # this pose's maps, none of their pixels decoded: the maps are to blame
    io.save_decoded_maps(tmp_path / "none.npz", dataclasses.replace(maps, valid_col=nothing, valid_row=nothing),
                         capture.load_capture(pose).fingerprint)
    (tmp_path / "v.png").unlink()
    code, out, err = run_cli(export + ["--maps", tmp_path / "none.npz"])
    assert code == 2 and err.startswith(f"error: --maps {tmp_path / 'none.npz'}: its maps mark no pixel decoded"), err
    assert err.count("\n") == 1 and not (tmp_path / "v.png").exists()
    from procam.calibration import Device

    small = calib.replace(projector=Device(calib.projector.K, (1280, 720), calib.projector.distortion))
    io.save_calibration(small, tmp_path / "p720.json")  # another rig's calibration: the view ignored it
    code, out, err = run_cli(["export", tmp_path / "p720.json", *export[2:]])
    assert code == 2 and "but the calibration's projector is 1280x720" in err and err.count("\n") == 1, err


@pytest.mark.parametrize("args, phrase", [
    (["--format", "projector-view", "-o", "v.png"], "needs --pose"),
    (["--format", "opengl", "-o", "g.json", "--near", "10"], "--near and --far together"),
    (["--format", "blender", "-o", "b.json", "--near", "10", "--far", "nan"], "finite with 0 < near < far"),
    (["--format", "unity", "-o", "u.json", "--rectify"], "--rectify belongs to --format maps"),
    (["--format", "maps", "-o", "m", "--pose", "x"], "--pose belongs to --format projector-view"),
    (["--format", "unity", "-o", "u.json", "--unit", "furlong"], "--unit"),
    (["--format", "blender", "-o", "b.txt"], "must end in .json"),
    # an option of another format is refused, never taken and ignored
    (["--format", "maps", "-o", "m", "--scale", "2"], "--scale is the rectified images' focal length"),
    (["--format", "opengl", "-o", "g.json", "--near", "10", "--far", "99", "--scale", "2"],
     "--scale belongs to --format maps, not opengl"),
    (["--format", "opengl", "-o", "g.json", "--near", "10", "--far", "99", "--unit", "cm"],
     "--unit belongs to --format blender or unity, not opengl"),
    (["--format", "maps", "-o", "m", "--world", "projector"], "--world belongs to --format opengl or blender or unity"),
    (["--format", "kamino410", "-o", "k.xml", "--order", "moreno"], "--order belongs to --format projector-view"),
    (["--format", "yaml", "-o", "k.xml", "--step", "2"], "--step belongs to --format projector-view"),
    (["--format", "yaml", "-o", "k.xml", "--projector", "321x123"], "stores a"),
    # a depth range too thin for a projection matrix
    (["--format", "opengl", "-o", "g.json", "--near", "1", "--far", "1.0000000000000002"], "hardly beyond near"),
    (["--format", "unity", "-o", "u.json", "--near", "100", "--far", "100.001"], "hardly beyond near"),
])
def test_export_refuses_bad_options_in_one_line(files, tmp_path, args, phrase):
    root, pose, calib, paths = files
    args = [a if not isinstance(a, str) or a not in ("v.png", "g.json", "b.json", "u.json", "m", "b.txt", "k.xml")
            else tmp_path / a for a in args]
    code, out, err = run_cli(["export", paths["procam.json"], *args])
    assert code == 2 and phrase in err and len(err.strip().splitlines()) == 1, err
    assert [p.name for p in tmp_path.iterdir()] == []


# ---------------------------------------------------------------------------------------------------
# the smaller things (issue 26, item 6)
# ---------------------------------------------------------------------------------------------------

def _help(command):
    code, out, err = run_cli([command, "--help"])
    assert code == 0, err
    return out


def test_help_shows_no_bool_metavar_and_lists_every_choice():
    """No command's --help shows ``<bool>`` for a flag, and every option with a closed set of values lists them
    (``<a|b|c>``, from procam.choices) instead of ``<str>``."""
    from procam import choices, simulate
    from procam.cli import app

    assert choices.SIM_PRESETS == simulate.PRESETS
    commands = [c.name for c in app.registered_commands]
    assert len(commands) >= 15
    texts = {c: _help(c) for c in commands}
    for c, t in texts.items():
        assert "<bool>" not in t, c
    assert "--preset <paper|ideal|lensshift|hard|vertical|ceiling>" in texts["simulate"]
    assert "--frame <camera|projector>" in texts["simulate"] and "--order <opencv|moreno>" in texts["simulate"]
    assert "--preset <paper|ideal|lensshift|hard|vertical|ceiling>" in texts["demo"]
    # the argument's line: typer 0.28 writes "device:<camera|projector>", 0.29 "device <camera|projector>"
    assert re.search(r"\n\s+device[ :]<camera\|projector>", texts["study"]), texts["study"]
    assert "--cam-dist <auto|none|k1|k1k2|k1k2p1p2|k1k2p1p2k3|rational>" in texts["experiment"]
    assert "--format <" + "|".join(choices.EXPORT_FORMATS) + ">" in texts["export"].replace("\n", "").replace(" ", "") \
        .replace("--format<", "--format <")
    for c in ("simulate", "demo", "study", "experiment"):
        for word in ("--preset <str>", "--frame <str>", "--order <str>", "device <str>", "device:<str>",
                     "--cam-dist <str>"):
            assert word not in texts[c], (c, word)
    code, out, err = run_cli(["simulate", "x", "--preset", "moon"])
    assert code == 2 and "moon" in err and len(err.strip().splitlines()) == 1


def test_readme_advise_line_runs_and_json_lines_are_alone_on_stdout(tmp_path):
    """README's ``procam advise --board 10x6`` needs no --square (as capture and check); with --json every stdout
    line is one JSON object, the session's text goes to stderr, and time_s counts from the session's first frame."""
    import re
    from pathlib import Path

    readme = (Path(__file__).resolve().parents[1] / "README.md").read_text()
    line = next(x for x in readme.splitlines() if x.startswith("procam advise"))
    args = re.split(r"\s+#", line)[0].split()[1:]
    code, out, err = run_cli([*args, "--camera", "virtual", "--json", "--max-frames", "3"])
    assert code == 0, err
    lines = out.splitlines()
    docs = [json.loads(x) for x in lines]                  # every line is JSON: nothing else on stdout
    assert [d["frame"] for d in docs] == [0, 1, 2]
    assert docs[0]["time_s"] == 0.0 and 0 <= docs[2]["time_s"] < 60


def test_advise_time_s_is_seconds_since_the_first_frame():
    from procam.acquire.live import advise

    class Frame:
        def __init__(self, t):
            self.image, self.timestamp = np.zeros((8, 8), np.uint8), t

    class Camera:
        def __init__(self):
            self.k = 0

        def grab(self):
            self.k += 1
            return Frame(86400.0 * 30 + 0.25 * self.k)      # a camera clock counting since the machine booted

    class Advisor:
        def update(self, img, t):
            from types import SimpleNamespace

            return SimpleNamespace(time_s=t, ready=False)

    res = advise(Camera(), Advisor(), max_frames=5)
    assert res.advice.time_s == pytest.approx(1.0) and res.t0 == pytest.approx(86400.0 * 30 + 0.25)
    again = advise(Camera(), Advisor(), max_frames=2, t0=res.t0)      # a later pose of the same session
    assert again.advice.time_s == pytest.approx(0.25)


def test_check_picture_wraps_its_message_at_word_boundaries():
    """The overlay's reasons are wrapped between words to the picture's width, never cut mid-word."""
    from types import SimpleNamespace

    import cv2

    from procam.check import overlay_lines

    reason = "camera: " + " ".join(["the board is turned too little about the vertical axis"] * 4)
    check = SimpleNamespace(verdict="weak", reasons=(reason,))
    lines = overlay_lines(check, 400)
    assert len(lines) > 2 and lines[0] == "verdict: weak"
    assert " ".join(lines[1:]).split() == reason.split(": ", 1)[1].split()      # every word whole, in order
    for t in lines[1:]:
        assert cv2.getTextSize(t, cv2.FONT_HERSHEY_SIMPLEX, 0.5, 1)[0][0] <= 400


def test_text_goes_to_stderr_while_stdout_carries_json(capsys):
    """``capture --advise --json`` and ``advise --json`` print their text lines (the devices, the pre-flight, the
    files written, the quick calibration) through text_on_stderr, so stdout holds the JSON lines alone (the whole
    capture session is tests/test_advisor.py's slow test)."""
    from procam.cli._app import say, text_on_stderr, warn
    from procam.cli._live import tell

    with text_on_stderr(True):
        say("wrote 36 frames")
        warn("a warning")
        tell("info", "quick calibration of pose01")
    said = capsys.readouterr()
    assert said.out == "" and "wrote 36 frames" in said.err and "quick calibration" in said.err
    with text_on_stderr(False):
        say("plain")
    assert capsys.readouterr().out == "plain\n"
