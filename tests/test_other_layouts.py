"""Other tools' calibration result files (issue 34, item 3): every layout of procam.io.layouts.RESULT_LAYOUTS,
with and without distortion, written with cv2.FileStorage as the tool writes it and read back through the one
reader (load_calibration, load_camera_intrinsics, load_projector_intrinsics) exactly; the commands that take a
calibration or a camera read them; ambiguous, unknown and bad files are refused naming the file."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from conftest import run_cli
from procam import io
from procam.errors import CalibrationFileError

KC = np.array([[1012.25, 0.0, 641.5], [0.0, 1013.5, 398.0], [0.0, 0.0, 1.0]])
KP = np.array([[1480.75, 0.0, 639.5], [0.0, 1481.125, 780.5], [0.0, 0.0, 1.0]])
R = cv2.Rodrigues(np.array([0.12, -0.21, 0.035]))[0]
T = np.array([-212.5, 13.25, 31.0])
DC = (-0.1234, 0.0567, 0.0012, -0.0008, -0.0123)
DP = (0.0456, -0.0123, -0.0005, 0.0007, 0.0)
CAM_SIZE = (1280, 800)

#: name -> (suffix, {key: value} as the tool writes it, without distortion; {key: value} of its distortion; the
#: camera size the file stores or None; the projector size or None).
LAYOUTS = {
    "cammat": (".yml", {"CamMat": KC, "ProMat": KP, "R": R, "T": T.reshape(3, 1)},
               {"CamDist": np.array([DC]), "ProDist": np.array([DP])}, None, None),
    "cammat-xml": (".xml", {"CamMat": KC, "ProMat": KP, "R": R, "T": T.reshape(3, 1)},
                   {"CamDisCoeffs": np.array([DC]).T, "ProDisCoeffs": np.array([DP]).T}, None, None),
    "slstudio": (".xml", {"Kc": KC, "Kp": KP, "Rp": R, "Tp": T.reshape(3, 1), "cam_error": 0.25,
                          "proj_error": 0.5, "stereo_error": 0.75, "frameWidth": 1280, "frameHeight": 800,
                          "screenResX": 1280, "screenResY": 1600},
                 {"kc": np.array([DC]).T, "kp": np.array([DP]).T}, CAM_SIZE, (1280, 1600)),
    "slstudio-unset-screen": (".xml", {"Kc": KC, "kc": np.zeros((5, 1)), "Kp": KP, "kp": np.zeros((5, 1)),
                                       "Rp": R, "Tp": T.reshape(3, 1), "frameWidth": 1280, "frameHeight": 800,
                                       "screenResX": 0, "screenResY": 0},
                              {"kc": np.array([DC]).T, "kp": np.array([DP]).T}, CAM_SIZE, None),
    "stereo": (".yml", {"K1": KC, "K2": KP, "R": R, "T": T.reshape(3, 1),
                        "image_size": np.array([[1280, 800]], np.int32)},
               {"D1": np.array([DC]), "D2": np.array([DP])}, CAM_SIZE, None),
    "stereo-args": (".xml", {"cameraMatrix1": KC, "cameraMatrix2": KP, "R": R, "T": T.reshape(3, 1),
                             "image_width": 1280, "image_height": 800},
                    {"distCoeffs1": np.array([DC]), "distCoeffs2": np.array([DP])}, CAM_SIZE, None),
    "stereo-sample": (".yml", {"M1": KC, "M2": KP, "R": R, "T": T.reshape(3, 1)},
                      {"D1": np.array([DC]), "D2": np.array([DP])}, None, None),
    "matlab": (".yml", {"K1": KC, "K2": KP, "R": R, "T": T.reshape(1, 3),
                        "imageSize": np.array([[800, 1280]], float)},      # MATLAB's ImageSize: [rows, columns]
               {"D1": np.array([DC]), "D2": np.array([DP])}, CAM_SIZE, None),
}


def write(path, keys: dict):
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_WRITE)
    for k, v in keys.items():
        fs.write(k, v)
    fs.release()
    return path


def layout_file(tmp_path, name, dist: bool):
    suffix, keys, dkeys, _, _ = LAYOUTS[name]
    return write(tmp_path / f"{name}{suffix}", {**keys, **(dkeys if dist else {})})


@pytest.mark.parametrize("dist", [False, True], ids=["no-distortion", "distortion"])
@pytest.mark.parametrize("name", list(LAYOUTS))
def test_round_trip(tmp_path, name, dist):
    """K, distortion, R, T read back exactly; a size the file stores is read, one it does not is assumed from the
    principal point, listed and warned about; the camera and the projector through their readers too."""
    path = layout_file(tmp_path, name, dist)
    _, _, _, cam_size, proj_size = LAYOUTS[name]
    c = io.load_calibration(path)
    assert np.array_equal(c.camera.K, KC) and np.array_equal(c.projector.K, KP)
    assert np.array_equal(c.R, R) and np.array_equal(c.T, T)
    want = ("opencv", DC, DP) if dist else ("none", (), ())
    assert (c.camera.distortion.model, c.camera.distortion.coeffs, c.projector.distortion.coeffs) == want
    assert c.projector.distortion.model == want[0]
    assert c.camera.image_size == (cam_size or (1283, 796))
    assert c.projector.image_size == (proj_size or (1279, 1561))
    assumed = [k for k, s in (("cam_size", cam_size), ("proj_size", proj_size)) if s is None]
    assert c.info.get("image_size_assumed", []) == assumed
    assert len(c.warnings) == len(assumed) and all("does not store the" in w for w in c.warnings)
    assert c.verdict == "unknown"
    if name == "slstudio":
        assert (c.cam_rms, c.proj_rms, c.stereo_rms) == (0.25, 0.5, 0.75)

    cam = io.load_camera_intrinsics(path, CAM_SIZE)
    assert np.array_equal(cam.K, KC) and cam.distortion == c.camera.distortion and cam.image_size == CAM_SIZE
    proj = io.load_projector_intrinsics(path, (1280, 1600) if proj_size else (1300, 1500))
    assert np.array_equal(proj.K, KP) and proj.distortion == c.projector.distortion
    assert proj.image_size == ((1280, 1600) if proj_size else (1300, 1500))


def test_every_layout_of_the_table_is_round_tripped():
    """The tests above cover every row of the table, and every key name of its device fields."""
    from procam.io.layouts import RESULT_LAYOUTS

    written = set().union(*(set(k) | set(d) for _, k, d, _, _ in LAYOUTS.values()))
    for lay in RESULT_LAYOUTS:
        for keys in (lay.cam_K, lay.cam_dist, lay.proj_K, lay.proj_dist, lay.R, lay.T):
            assert set(keys) <= written, (lay.name, keys)


def test_a_stored_size_is_checked(tmp_path):
    """A camera file of another resolution is refused, and so is one whose size pair the principal point cannot
    order (the pair of a square-ish image with the principal point far from both centres)."""
    path = layout_file(tmp_path, "slstudio", True)
    with pytest.raises(CalibrationFileError, match="intrinsics are for 1280x800 images, the images are 640x400"):
        io.load_camera_intrinsics(path, (640, 400))
    K = KC.copy()
    K[:2, 2] = (300.0, 300.0)
    odd = write(tmp_path / "odd.yml", {"K1": K, "K2": KP, "R": R, "T": T, "image_size": np.array([[1280, 800]])})
    with pytest.raises(CalibrationFileError, match=r"odd.yml: image_size \[1280, 800\] may be \[width, height\]"):
        io.load_calibration(odd)


@pytest.mark.parametrize("keys, match", [
    ({"CamMat": KC, "ProMat": KP, "K1": KC, "K2": KP, "R": R, "T": T},
     r"ambiguous: holds the device matrices of 2 layouts \(structured-light CamMat/ProMat, OpenCV stereo"),
    ({"K1": KC, "cameraMatrix1": KC, "K2": KP, "R": R, "T": T},
     "K1 and cameraMatrix1 are two names of one field"),
    ({"camera": KC, "projector": KP, "R": R, "T": T},
     r"no camera-projector calibration of a known layout \(keys found: camera, projector, R, T\).*SLStudio"),
    ({"Kc": KC, "Kp": KP, "Rp": R}, r"missing Tp; the SLStudio calibration.xml layout has the keys"),
    ({"Kc": KC, "Kp": KP, "Rp": R * 2, "Tp": T}, "Rp is not a rotation matrix"),
    ({"CamMat": KC, "CamDist": np.array([[0.1, 0.2, 0.3]]), "ProMat": KP, "R": R, "T": T},
     "CamDist must have 4, 5, 8, 12, 14 OpenCV coefficients, got 3"),
    ({"K1": KC, "K2": -KP, "R": R, "T": T}, "K2 focal lengths must be positive"),
])
def test_bad_files_are_refused(tmp_path, keys, match):
    path = write(tmp_path / "other.yml", keys)
    with pytest.raises(CalibrationFileError, match=match):
        io.load_calibration(path)


def test_a_key_given_twice_is_refused(tmp_path):
    path = tmp_path / "twice.yml"
    path.write_text("%YAML:1.0\n---\nCamMat: [1000, 0, 640, 0, 1000, 400, 0, 0, 1]\n"
                    "CamMat: [900, 0, 640, 0, 900, 400, 0, 0, 1]\n")
    with pytest.raises(CalibrationFileError, match="twice.yml: CamMat is given twice"):
        io.load_camera_intrinsics(path, CAM_SIZE)


# --------------------------------------------------------------------------------------------------
# the commands
# --------------------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def pose(tmp_path_factory):
    """A small rendered pose (640x400 camera without distortion: the layouts' OpenCV model holds it) and its
    truth."""
    from test_bad_inputs import render_pose

    folder = tmp_path_factory.mktemp("pose") / "pose"
    truth = render_pose(folder, (15.0, 12.0, 0.0), cam_dist_coeffs=(0.0, 0.0))
    return folder, truth


def true_keys(truth) -> dict:
    """The small rig's true K, R, T (no distortion) as a dict of arrays."""
    return {"Kc": np.array(truth["camera"]["K"], float), "Kp": np.array(truth["projector"]["K"], float),
            "R": np.array(truth["extrinsics"]["R"], float), "T": np.array(truth["extrinsics"]["T"], float)}


def test_calibrate_uses_the_camera_of_a_cammat_file(pose, tmp_path):
    """The issue's file: 'procam calibrate POSE --camera result.yml' with the tool's CamMat (and a CamDist) uses that
    camera, held fixed (it was refused: 'no camera matrix found')."""
    folder, truth = pose
    k = true_keys(truth)
    cam = write(tmp_path / "Result.yml", {"CamMat": k["Kc"], "CamDist": np.array([[-0.02, 0.0, 0.0, 0.0, 0.0]]),
                                          "ProMat": k["Kp"], "R": k["R"], "T": k["T"].reshape(3, 1)})
    out = tmp_path / "calib.json"
    code, _, err = run_cli(["calibrate", folder, "--board", "10x6", "--square", "24", "-o", out, "--camera", cam])
    assert code == 0, err
    c = io.load_calibration(out)
    assert np.array_equal(c.camera.K, k["Kc"])
    assert c.camera.distortion.model == "opencv" and c.camera.distortion.coeffs == (-0.02, 0.0, 0.0, 0.0, 0.0)


def test_calibrate_uses_the_projector_of_a_cammat_file(pose, tmp_path):
    """--projector-intrinsics with the tool's file (no sizes stored: the pose's projector size is taken): the
    projector held at the file's K, R, T from the pose within 1 board unit of the truth."""
    folder, truth = pose
    k = true_keys(truth)
    proj = write(tmp_path / "Result.yml", {"CamMat": k["Kc"], "ProMat": k["Kp"], "R": k["R"],
                                           "T": k["T"].reshape(3, 1)})
    out = tmp_path / "calib.json"
    code, _, err = run_cli(["calibrate", folder, "--board", "10x6", "--square", "24", "-o", out,
                            "--projector-intrinsics", proj])
    assert code == 0, err
    c = io.load_calibration(out)
    assert np.array_equal(c.projector.K, k["Kp"]) and c.projector.image_size == tuple(truth["projector"]["size"])
    assert np.abs(c.T - k["T"]).max() < 1.0


def test_evaluate_report_export_read_the_layouts(pose, tmp_path):
    """evaluate (SLStudio XML, no sizes stored: the pose's are taken), report (CamMat YAML) and export (OpenCV
    stereo YAML) read other tools' files.  The true calibration in SLStudio's keys evaluates to the render's
    noise (stereo RMS 0.03 px; an R read transposed, 14 degrees off, would be tens of pixels)."""
    import json

    folder, truth = pose
    k = true_keys(truth)
    sl = write(tmp_path / "calibration.xml", {"Kc": k["Kc"], "kc": np.zeros((5, 1)), "Kp": k["Kp"],
                                              "kp": np.zeros((5, 1)), "Rp": k["R"], "Tp": k["T"].reshape(3, 1)})
    ev = tmp_path / "ev.json"
    code, out, err = run_cli(["evaluate", sl, folder, "--board", "10x6", "--square", "24", "-o", ev])
    assert code == 0, err
    assert "calibration.xml does not store the camera size; the pose's 640x400 is used" in out
    doc = json.loads(ev.read_text())
    assert doc["format"] == "procam-evaluation" and doc["method"] == "slstudio"
    assert doc["stereo_rms"] < 0.2
    assert np.abs(np.array(doc["poses"][0]["T"]) - k["T"]).max() < 0.5

    cm = write(tmp_path / "Result.yml", {"CamMat": k["Kc"], "ProMat": k["Kp"], "R": k["R"],
                                         "T": k["T"].reshape(3, 1)})
    page = tmp_path / "report.html"
    code, _, err = run_cli(["report", cm, folder, "--board", "10x6", "--square", "24", "-o", page])
    assert code == 0, err
    assert page.stat().st_size > 1000
    code, out, err = run_cli(["export", cm, "--format", "opengl", "-o", tmp_path / "cm.json", "--near", "100",
                            "--far", "5000", "--projector", "x".join(map(str, truth["projector"]["size"]))])
    assert code == 0, err
    assert "Result.yml does not store the camera size; assumed" in out + err   # never a silent guess

    st = write(tmp_path / "stereo.yml", {"K1": k["Kc"], "D1": np.zeros((1, 5)), "K2": k["Kp"], "D2": np.zeros((1, 5)),
                                         "R": k["R"], "T": k["T"].reshape(3, 1),
                                         "image_size": np.array([list(truth["camera"]["size"])], np.int32)})
    gl = tmp_path / "gl.json"
    code, _, err = run_cli(["export", st, "--format", "opengl", "-o", gl, "--near", "100", "--far", "5000",
                            "--projector", "x".join(map(str, truth["projector"]["size"]))])
    assert code == 0, err
    doc = json.loads(gl.read_text())
    assert doc["camera"]["image_size"] == list(truth["camera"]["size"]) and np.array_equal(doc["camera"]["K"], k["Kc"])
    assert doc["projector"]["image_size"] == list(truth["projector"]["size"])
    view = np.diag([1.0, -1.0, -1.0]) @ np.hstack([k["R"], k["T"].reshape(3, 1)])   # OpenGL eye of R, T
    np.testing.assert_allclose(np.array(doc["projector"]["view"])[:3], view, atol=1e-12)


def test_a_bad_file_exits_2_naming_it(pose, tmp_path):
    folder, truth = pose
    bad = write(tmp_path / "Result.yml", {"CamMat": true_keys(truth)["Kc"], "K1": true_keys(truth)["Kc"]})
    for args in (["calibrate", folder, "--board", "10x6", "--square", "24", "-o", tmp_path / "c.json",
                  "--camera", bad],
                 ["evaluate", bad, folder, "--board", "10x6", "--square", "24"],
                 ["export", bad, "--format", "opengl", "-o", tmp_path / "gl.json", "--near", "100", "--far", "5000"]):
        code, out, err = run_cli(args)
        assert code == 2, (args[0], out, err)
        text = out + err
        assert str(bad) in text and "Traceback" not in text
        assert not (tmp_path / "c.json").exists() and not (tmp_path / "gl.json").exists()


def test_the_docs_examples_are_read(tmp_path):
    """Every example of docs/file-formats.md's section on other tools' files is read, as the layout it shows."""
    import re
    from pathlib import Path

    text = (Path(__file__).parents[1] / "docs" / "file-formats.md").read_text()
    section = text[text.index("### Other tools' result files"):]
    section = section[:section.index("\n## ")]
    blocks = re.findall(r"```(yaml|xml)\n(.*?)```", section, re.S)
    methods = []
    for i, (kind, body) in enumerate(blocks):
        path = tmp_path / f"example{i}.{'yml' if kind == 'yaml' else 'xml'}"
        path.write_text(body)
        c = io.load_calibration(path)
        assert np.allclose(c.camera.K, KC) and np.allclose(c.projector.K, KP) and np.array_equal(c.T, T)
        assert np.allclose(c.R, R, atol=1e-4) and np.allclose(c.camera.distortion.coeffs, DC)
        methods.append(c.method)
    assert methods == ["cammat-promat", "slstudio", "opencv-stereo"]
