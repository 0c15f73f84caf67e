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
    (lambda d: d["projectors"]["right"].__setitem__("R", _reflect(d["projectors"]["right"]["R"])), "projectors.right.R"),
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
    from procam.io.rig import load_rig_calibration, save_rig_calibration

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
    from procam.io.rig import load_rig_calibration, save_rig_calibration

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
