"""Issue 36's attacks on rigs and result files, each a user's mistake that must be refused or said, never
silently read: a rig or multi-pose capture that holds one device's frames twice, a rig file whose device blocks
escape the validator, a kamino410 file with its image shape transposed, a key given twice, an option a rig
calibration would ignore, a datasheet number the data contradict."""

from __future__ import annotations

import functools
import json

import numpy as np
import pytest

from conftest import run_cli, verdict_warnings
from rig_sim import fast_views


@functools.lru_cache(maxsize=None)
def _rig():
    from procam.rig import calibrate_rig

    _, poses = fast_views("two_projectors", 3)
    with verdict_warnings():
        return calibrate_rig(poses)


def _reflect(R):
    return (np.asarray(R) @ np.diag([1.0, 1.0, -1.0])).tolist()


# ------------------------------------------------------------------------------------------------
# item 7: every block of a rig file goes through the one validator


@pytest.mark.parametrize("edit, field", [
    (lambda d: d["projectors"]["right"].__setitem__("R", _reflect(d["projectors"]["right"]["R"])),
     "projectors.right.R"),
    (lambda d: d["cameras"]["cam"]["K"][0].__setitem__(0, -5.0), "cameras.cam.K"),
    (lambda d: d["projectors"]["left"].__setitem__("distortion", {"model": "fisheye"}),
     "projectors.left.distortion.model"),
    (lambda d: d["projectors"]["left"].__setitem__("image_size", [1, 800]), "projectors.left.image_size"),
    (lambda d: d["relative"]["left->right"].__setitem__("R", _reflect(d["relative"]["left->right"]["R"])),
     "relative.left->right.R"),
    (lambda d: d["cameras"]["cam"].__setitem__("T", [5.0, 0.0, 0.0]), "cameras.cam.T"),
])
def test_a_rig_files_device_blocks_are_validated_like_a_pair_files(tmp_path, edit, field):
    """A projector R that is a reflection (det -1), a negative focal length, an unknown distortion model, a 1-pixel
    image, a relative R that is no rotation, a reference camera away from the reference frame: each refused by
    ``load_rig_calibration`` and ``procam report`` (exit 2) naming the file and the field, no page written."""
    from procam.errors import CalibrationFileError
    from procam.io import load_rig_calibration, save_rig_calibration

    path = save_rig_calibration(_rig(), tmp_path / "rig.json")
    load_rig_calibration(path)                         # as written: read
    doc = json.loads(path.read_text())
    edit(doc)
    path.write_text(json.dumps(doc))
    with pytest.raises(CalibrationFileError, match=f"{path}: {field.replace('>', '.')}"):
        load_rig_calibration(path)
    page = tmp_path / "rig.html"
    code, out, err = run_cli(["report", path, "-o", page])
    assert code == 2 and f"{path.name}: {field}" in err and "Traceback" not in out + err and not page.exists()
    from procam.io import load_calibration

    with pytest.raises(CalibrationFileError, match=f"{path}: {field.replace('>', '.')}"):
        load_calibration(path, pair="cam/left")          # one pair of a corrupt rig file: refused too


# ------------------------------------------------------------------------------------------------
# item 11: a key given twice


def test_a_key_given_twice_is_refused_in_json_yaml_and_xml(tmp_path):
    """Two different cam_K entries (OpenCV reads the first without a word), two "camera" blocks in procam's JSON,
    a device named twice in a rig file: refused naming the file and the key."""
    from procam import io, simulate
    from procam.errors import CalibrationFileError

    cal = simulate.truth_calibration(simulate.preset("paper"))
    for suffix in (".yml", ".xml"):
        good = io.save_opencv_yaml(cal, tmp_path / f"c{suffix}")
        io.load_calibration(good)
        text = good.read_text()
        if suffix == ".yml":
            block = text[text.index("cam_K:"):text.index("cam_kc:")]
            twice = text + block.replace("data: [ ", "data: [ 2")          # fx 1539 -> 21539
        else:
            block = text[text.index("<cam_K"):text.index("</cam_K>") + len("</cam_K>")]
            twice = text.replace("</opencv_storage>", block.replace("<data>", "<data>\n  2") + "</opencv_storage>")
        bad = tmp_path / f"twice{suffix}"
        bad.write_text(twice)
        with pytest.raises(CalibrationFileError, match=f"{bad}: cam_K is given twice"):
            io.load_calibration(bad)
        with pytest.raises(CalibrationFileError, match="cam_K is given twice"):
            io.load_camera_intrinsics(bad)
    path = io.save_calibration(cal, tmp_path / "c.json")
    text = path.read_text()
    i = text.index('"camera"')
    bad = tmp_path / "twice.json"
    bad.write_text(text[:i] + '"camera": null, ' + text[i:])
    with pytest.raises(CalibrationFileError, match=f"{bad}: key 'camera' is given twice"):
        io.load_calibration(bad)
    from procam.io import load_rig_calibration, save_rig_calibration

    rig = save_rig_calibration(_rig(), tmp_path / "rig.json")
    text = rig.read_text()
    i = text.index('"projectors": {') + len('"projectors": {')
    j = text.index('"right":', i)
    rig.write_text(text[:i] + text[j:text.index('"relative"')].rstrip().rstrip(",").rstrip("}").rstrip() + ","
                   + text[i:])
    with pytest.raises(CalibrationFileError, match="key 'right' is given twice"):
        load_rig_calibration(rig)


# ------------------------------------------------------------------------------------------------
# item 10: kamino410's img_shape written as (width, height)


def test_a_kamino410_file_with_img_shape_as_width_height_is_refused_not_read_as_a_turned_camera(tmp_path):
    """Their img_shape is [height, width]; [1280, 800] for the paper's 1280x800 camera would read as an 800x1280
    camera, and be exported so.  The principal point (674, 512) tells: refused by every reader of the file, with
    both readings and the fix; the file as written (and a square or a centred 4:3 camera) reads as before."""
    from procam import io, simulate
    from procam.errors import CalibrationFileError

    cal = simulate.truth_calibration(simulate.preset("paper"))
    path = io.save_kamino410(cal, tmp_path / "calibration_result.xml")
    assert io.load_calibration(path).camera.image_size == (1280, 800)
    text = path.read_text()
    assert "<data>\n    800. 1280.</data>" in text
    bad = tmp_path / "transposed.xml"
    bad.write_text(text.replace("<data>\n    800. 1280.</data>", "<data>\n    1280. 800.</data>", 1))
    for read in (io.load_calibration, io.load_kamino410, io.load_camera_intrinsics):
        with pytest.raises(CalibrationFileError, match=r"img_shape \[1280, 800\] reads as a 800x1280 camera .* "
                                                       r"principal point \(674, 512\) .* 1280x800 camera"):
            read(bad)
    code, out, err = run_cli(["export", bad, "--format", "yaml", "-o", tmp_path / "out.yml"])
    assert code == 2 and "img_shape" in err and not (tmp_path / "out.yml").exists()
    from procam.calibration import Device

    for size in ((1024, 768), (800, 800)):                 # centred principal points: read as written
        K = np.array([[900.0, 0, (size[0] - 1) / 2], [0, 900, (size[1] - 1) / 2], [0, 0, 1]])
        p = io.save_kamino410(cal.replace(camera=Device(K, size)), tmp_path / f"k{size[0]}.xml")
        assert io.load_calibration(p).camera.image_size == size


# ------------------------------------------------------------------------------------------------
# item 6: one capture seen twice


def _pose(folder, seed):
    """A pose folder of 4 small seeded frames and a patterns.json: refused before anything decodes it."""
    import cv2

    folder.mkdir(parents=True)
    rng = np.random.default_rng(seed)
    for i in range(4):
        cv2.imwrite(str(folder / f"{i:02d}.png"), rng.integers(0, 255, (24, 32), dtype=np.uint8))
    (folder / "patterns.json").write_text("{}")
    return folder


def _rig_pose(root, right):
    """A rig pose folder of one camera and projectors left and right; ``right(left_folder, right_folder)`` makes the
    right pair's folder."""
    from procam import capture

    root.mkdir()
    (root / "rig.json").write_text(json.dumps(capture.rig_manifest(["cam"], ["left", "right"])))
    right(_pose(root / "left", 1), root / "right")
    return root


@pytest.mark.parametrize("how", ["link", "copy"])
def test_a_rig_pair_that_is_another_pairs_capture_is_refused_naming_both(tmp_path, how):
    """right/ a symlink of left/ (or a copy of it) calibrated as two projectors 0.00 mm apart, verdict good:
    now exit 2 before any decoding, naming both folders; two distinct pairs pass the check."""
    import shutil

    make = (lambda a, b: b.symlink_to(a, target_is_directory=True)) if how == "link" else shutil.copytree
    pose = _rig_pose(tmp_path / "rig1", make)
    out = tmp_path / "rig.json"
    code, stdout, err = run_cli(["calibrate", pose, "--board", "10x6", "--square", "24", "-o", out])
    why = "one folder once links are resolved" if how == "link" else "the same 4 frames, byte for byte, a copy or a link"
    assert code == 2 and f"{pose / 'right'}: this pair folder is given twice (also as {pose / 'left'}: {why})" \
        in err
    assert len(err.strip().splitlines()) == 1 and not out.exists()
    from procam import capture
    from procam.errors import CaptureError

    with pytest.raises(CaptureError, match="given twice"):
        capture.read_rig_pose(pose)
    fine = _rig_pose(tmp_path / "rig2", lambda a, b: _pose(b, 2))
    assert [p.projector for p in capture.read_rig_pose(fine).pairs] == ["left", "right"]


def test_a_rig_json_of_the_wrong_shape_is_a_one_line_error_and_its_reference_is_kept(tmp_path):
    """No cameras (an internal error before), names given as one string (split into letters), pairs that are not an
    object, a reference that is no camera (it was replaced by the first camera without a word): one line naming
    rig.json. A reference that is another of the cameras is the rig's reference."""
    from procam import capture
    from procam.errors import CaptureError

    root = _rig_pose(tmp_path / "rig", lambda a, b: _pose(b, 2))
    good = json.loads((root / "rig.json").read_text())
    for change, words in (({"cameras": []}, "a rig needs at least one camera and one projector"),
                          ({"projectors": []}, "a rig needs at least one camera and one projector"),
                          ({"cameras": "cam"}, "cameras must be a list of names, got 'cam'"),
                          ({"pairs": "x"}, "pairs must be an object"),
                          ({"reference": "nobody"}, "reference 'nobody' is not one of the cameras")):
        (root / "rig.json").write_text(json.dumps({**good, **change}))
        with pytest.raises(CaptureError, match=f"rig.json: {words}"):
            capture.read_rig_pose(root)
    two = capture.rig_manifest(["a", "b"], ["left"], {"left": ["a", "left"], "right": ["b", "left"]})
    (root / "rig.json").write_text(json.dumps({**two, "reference": "b"}))
    assert capture.read_rig_pose(root).cameras == ("b", "a")


def test_a_pose_folder_given_twice_as_a_copy_is_refused_for_multi_pose_and_rig_poses(tmp_path):
    """A multi-pose list with one pose twice under two names (a copy, a link), and two rig poses that are one:
    refused, naming both, before any decoding."""
    import shutil

    a = _pose(tmp_path / "pose1", 1)
    _pose(tmp_path / "pose2", 2)
    shutil.copytree(a, tmp_path / "pose3")
    (tmp_path / "pose4").symlink_to(a, target_is_directory=True)
    for other, why in (("pose3", "the same 4 frames"), ("pose4", "one folder once links are resolved")):
        code, _, err = run_cli(["calibrate", a, tmp_path / "pose2", tmp_path / other, "--board", "10x6",
                                "--square", "24", "-o", tmp_path / "c.json"])
        assert code == 2 and f"{tmp_path / other}: this pose folder is given twice (also as {a}: {why}" in err
    r1 = _rig_pose(tmp_path / "rig1", lambda x, y: _pose(y, 2))
    shutil.copytree(r1, tmp_path / "rig2")
    code, _, err = run_cli(["calibrate", r1, tmp_path / "rig2", "--board", "10x6", "--square", "24",
                            "-o", tmp_path / "rig.json"])
    assert code == 2 and "given twice" in err and str(tmp_path / "rig2") in err and str(r1) in err


# ------------------------------------------------------------------------------------------------
# item 9: an option the calibration would ignore


@pytest.mark.parametrize("args, opt, path", [
    (["--throw-ratio", "1.26"], "--throw-ratio", "rig single-pose"),
    (["--lens-shift", "0,50"], "--lens-shift", "rig single-pose"),
    (["--projector-intrinsics", "{tmp}/p.json"], "--projector-intrinsics", "rig single-pose"),
    (["--camera", "{tmp}/p.json"], "--camera", "rig single-pose"),
    (["--no-refine"], "--no-refine", "rig single-pose"),
    (["--cam-dist", "k1"], "--cam-dist", "rig single-pose"),
    (["--throw-ratio", "1.26", "{rig2}"], "--throw-ratio", "rig multi-pose"),
    (["--cod", "paper", "{rig2}"], "--cod", "rig multi-pose"),
    (["--background", "off", "{rig2}"], "--background", "rig multi-pose"),
])
def test_an_option_a_rig_calibration_would_ignore_is_refused(tmp_path, args, opt, path):
    """--throw-ratio and --projector-intrinsics were silently ignored on a rig (and --camera sent the rig down the
    pair path): every option that does not apply to the calibration the command runs is refused, exit 2, saying
    what it is and which calibration this is, before any work."""
    from procam import io, simulate

    io.save_calibration(simulate.truth_calibration(simulate.preset("paper")), tmp_path / "p.json")
    r1 = _rig_pose(tmp_path / "rig1", lambda a, b: _pose(b, 2))
    r2 = tmp_path / "rig2"
    r2.mkdir()
    args = [a.format(tmp=tmp_path, rig2=r2) for a in args]
    out = tmp_path / "rig.json"
    code, _, err = run_cli(["calibrate", r1, *args, "--board", "10x6", "--square", "24", "-o", out])
    assert code == 2 and err.startswith(f"error: {opt} is ") and f"this is a {path} calibration, which would " \
        "ignore it: leave it out" in err, err
    assert len(err.strip().splitlines()) == 1 and not out.exists()


@pytest.mark.parametrize("args, opt, path", [
    (["--cod", "paper"], "--cod", "multi-pose"),
    (["--background", "off"], "--background", "multi-pose"),
    (["--throw-ratio", "1.26"], "--throw-ratio", "multi-pose"),
    (["--camera", "{tmp}/p.json"], "--camera", "multi-pose"),
    (["--cam-dist", "k1", "--method", "single"], "--cam-dist", "single-pose"),
    (["--proj-dist", "k1", "--method", "single"], "--proj-dist", "single-pose"),
    (["--no-refine", "--method", "single"], "--no-refine", "single-pose"),
    (["--proj-dist", "k1", "--camera-only"], "--proj-dist", "camera-only (several photos)"),
    (["--background", "off", "--camera-only"], "--background", "camera-only (several photos)"),
])
def test_an_option_the_multi_or_single_pose_path_would_ignore_is_refused(tmp_path, args, opt, path):
    """The same check on the ordinary paths: --cod and --background were ignored by a multi-pose calibration,
    --cam-dist, --proj-dist and --no-refine by a single-pose one."""
    from procam import io, simulate

    io.save_calibration(simulate.truth_calibration(simulate.preset("paper")), tmp_path / "p.json")
    poses = [_pose(tmp_path / f"pose{i}", i) for i in (1, 2)]
    if "--method" in args:
        poses = poses[:1]
    args = [a.format(tmp=tmp_path) for a in args]
    code, _, err = run_cli(["calibrate", *poses, *args, "--board", "10x6", "--square", "24", "-o", tmp_path / "c.json"])
    assert code == 2 and err.startswith(f"error: {opt} is ") and f"this is a {path} calibration" in err, err


# ------------------------------------------------------------------------------------------------
# item 15: a datasheet number the data contradict is named, not the pose


@pytest.mark.parametrize("throw_ratio, tol, contradicted", [(2.0, 0.001, True), (None, 0.001, False),
                                                            (1.5, 0.02, False)])
def test_a_tight_datasheet_prior_the_data_contradict_is_blamed_not_the_pose(throw_ratio, tol, contradicted):
    """--throw-ratio 2.0+-0.001 on a projector of throw ratio 1.26: the prior holds f_p (the fit's ± is the
    prior's) and the other priors give way (alpha_p 40 sigma off its assumed 1): failed, and the reason names the
    datasheet's number, its value and what the data want, not 'turn the board'.  The true throw ratio at the same
    tolerance holds the fit without a pull; a loose wrong one (1.5 +- 0.02) is outweighed by the data (the
    estimate is the data's, within 1 %; the conflict is said by the fit's warning, as before)."""
    import warnings

    from procam import simulate
    from procam import single_pose as sp
    from procam.single_pose import dense
    from sim_dense import dense_view

    scene = simulate.preset("lensshift")                 # throw ratio 2421 / 1920 = 1.261
    W = scene.proj_size[0]
    tr = throw_ratio or scene.K_proj[0][0] / W
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cal = sp.calibrate(dense_view(scene, seed=7, background=False),
                           dense=dense.DenseOptions(prior=dense.ProjectorPrior(throw_ratio=tr, throw_ratio_std=tol)))
    reasons = " ".join(cal.verdict_reasons)
    if contradicted:
        assert cal.verdict == "failed" and "turn the board" not in reasons, reasons
        assert "the data contradict the datasheet's throw ratio 2 ± 0.001" in reasons
        assert "the data want a smaller throw ratio" in reasons and "the pose is not the cause" in reasons
        assert "alpha_p" in reasons and "check the datasheet's number" in reasons
    else:
        assert "contradict" not in reasons and cal.verdict != "failed"
        assert abs(cal.projector.K[0, 0] - scene.K_proj[0][0]) < 0.01 * scene.K_proj[0][0]


def test_a_rig_yaml_never_writes_a_key_twice(tmp_path):
    """A rig whose reference camera is named cam wrote cam_K twice (procam's reference-pair key and the device's):
    now once (the same numbers); a second projector named proj, whose proj_K would differ from the reference pair's,
    is refused before anything is written."""
    import dataclasses

    import cv2

    from procam.errors import CalibrationFileError
    from procam.io.opencv import _top_level_keys
    from procam.io.rig import save_rig_calibration

    rc = _rig()
    y = save_rig_calibration(rc, tmp_path / "rig.yml")
    keys = _top_level_keys(y)
    assert len(keys) == len(set(keys)) and "cam_R" in keys and "right_K" in keys
    fs = cv2.FileStorage(str(y), cv2.FILE_STORAGE_READ)
    assert np.array_equal(fs.getNode("cam_K").mat(), rc.cameras[0].device.K)
    fs.release()
    renamed = dataclasses.replace(rc, projectors=(rc.projectors[0], dataclasses.replace(rc.projectors[1], name="proj")))
    with pytest.raises(CalibrationFileError, match="device 'proj' would write proj_K"):
        save_rig_calibration(renamed, tmp_path / "two.yml")
    assert not (tmp_path / "two.yml").exists()
