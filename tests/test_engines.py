"""Engine exports: 3-D points projected through each engine's own camera land where the calibration's pinhole part
puts them (<= 0.05 px), for the camera and the projector, on horizontal, vertical, ceiling and lens-shifted rigs.

Blender: the real client (``bpy``, the ``.[blender]`` extra) and its own projection
(``bpy_extras.object_utils.world_to_camera_view``); without ``bpy``, Blender's view-plane equations.  Unity: its
documented rules (physical camera, gate fit None, worldToCameraMatrix, screen points), implemented here apart from
the export.  Pixel centres: procam ``(x, y)`` has its origin at the centre of the top-left pixel; Blender's
normalised frame and Unity's screen have theirs at the bottom-left corner of the image.
"""

import importlib.util
import json

import numpy as np
import pytest

from procam import datasheet, models, simulate
from procam.export import blender, frames, opengl, unity
from procam.simulate import truth_calibration

RIGS = ("paper", "vertical", "ceiling", "lensshift")
TOL_PX = 0.05


def _rig(name):
    sc = simulate.preset(name)
    calib = truth_calibration(sc, approximate=True)
    c = simulate.corner_truth(sc)
    Xc = c["board"] @ np.asarray(sc.R_board).T + sc.t_board          # board corners in the camera frame
    return calib, Xc


def _pinhole(calib, name, Xc):
    """The calibration's pinhole projection (no distortion) of camera-frame points into device ``name``."""
    if name == "camera":
        return models.project(calib.camera.K, np.eye(3), np.zeros(3), Xc)
    return models.project(calib.projector.K, calib.R, calib.T, Xc)


def _h(X):
    return np.column_stack([X, np.ones(len(X))])


# ---------------------------------------------------------------------------------------------------
# Blender
# ---------------------------------------------------------------------------------------------------

def _blender_viewplane_pixels(dev_doc, X_blender):
    """Blender's projection by its view-plane equations (BKE_camera_params_compute_viewplane, sensor fit
    horizontal): world points -> procam pixels."""
    d, r = dev_doc["data"], dev_doc["render"]
    W, H = r["resolution_x"], r["resolution_y"]
    ycor = r["pixel_aspect_y"] / r["pixel_aspect_x"]
    local = (np.linalg.inv(np.array(dev_doc["matrix_world"])) @ _h(X_blender).T).T[:, :3]
    # view plane in x-pixel units at distance -z: x = X / (-Z) * lens / sensor_width * W
    fac = d["lens"] / d["sensor_width"] * W
    xv, yv = local[:, 0] / -local[:, 2] * fac, local[:, 1] / -local[:, 2] * fac
    xmin = -0.5 * W + d["shift_x"] * W
    ymax = 0.5 * ycor * H + d["shift_y"] * W
    return np.column_stack([xv - xmin - 0.5, (ymax - yv) / ycor - 0.5])


@pytest.mark.parametrize("rig", RIGS)
@pytest.mark.parametrize("world", ["camera", "projector"])
def test_blender_view_plane_equations_project_like_the_pinhole(rig, world):
    calib, Xc = _rig(rig)
    doc = blender.blender_document(calib, world=world)
    Xb = (np.array(doc["world_from_camera"]) @ _h(Xc).T).T[:, :3]
    for name in ("camera", "projector"):
        pix = _blender_viewplane_pixels(doc["devices"][name], Xb)
        assert np.abs(pix - _pinhole(calib, name, Xc)).max() < 1e-6


def _load_script(path):
    spec = importlib.util.spec_from_file_location("procam_blender_script", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.fixture(scope="module")
def bpy():
    return pytest.importorskip("bpy", reason="Blender's Python module is not installed (pip install 'procam[blender]')")


@pytest.mark.parametrize("rig", RIGS)
def test_blender_cameras_made_by_the_script_project_like_the_pinhole_in_real_blender(bpy, rig, tmp_path):
    """The exported JSON and script, run in Blender's own Python module: ``world_to_camera_view`` of every board
    corner, for both devices, within 0.05 px of the calibration's pinhole projection (float32 in Blender)."""
    import mathutils
    from bpy_extras.object_utils import world_to_camera_view

    from procam import io
    from conftest import run_cli
    import procam.cli.export  # noqa: F401

    calib, Xc = _rig(rig)
    path = io.save_calibration(calib, tmp_path / "calib.json")
    code, out, err = run_cli(["export", path, "--format", "blender", "-o", tmp_path / "rig.json"])
    assert code == 0, err
    doc = json.loads((tmp_path / "rig.json").read_text())
    script = _load_script(tmp_path / "rig.py")
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    objs = script.create_cameras(str(tmp_path / "rig.json"))
    Xb = (np.array(doc["world_from_camera"]) @ _h(Xc).T).T[:, :3]
    for name in ("camera", "projector"):
        script.use_device(doc, name)
        assert scene.camera is objs[name] and scene.render.resolution_x == getattr(calib, name).image_size[0]
        W, H = getattr(calib, name).image_size
        uv = np.array([tuple(world_to_camera_view(scene, objs[name], mathutils.Vector(p)))[:2] for p in Xb])
        pix = np.column_stack([uv[:, 0] * W - 0.5, (1.0 - uv[:, 1]) * H - 0.5])
        err_px = np.abs(pix - _pinhole(calib, name, Xc)).max()
        assert err_px <= TOL_PX, (name, err_px)
        # the object is a camera Blender draws as the rig is: rigid, not mirrored
        M = np.array(objs[name].matrix_world)
        assert np.linalg.det(M[:3, :3]) == pytest.approx(1.0, abs=1e-5) and objs[name].data.lens > 0
    # the image corners land on the frame's corners (pixel edges): the conventions stated in the JSON
    cam = objs["camera"]
    script.use_device(doc, "camera")
    Kinv = np.linalg.inv(calib.camera.K)
    W, H = calib.camera.image_size
    corner = Kinv @ [-0.5, H - 0.5, 1.0] * 700.0           # bottom-left corner of the bottom-left pixel
    Xw = np.array(doc["world_from_camera"]) @ [*corner, 1.0]
    uv = world_to_camera_view(scene, cam, mathutils.Vector(Xw[:3]))
    assert uv[0] == pytest.approx(0.0, abs=1e-5) and uv[1] == pytest.approx(0.0, abs=1e-5)


def test_blender_numbers_are_the_datasheet_numbers():
    """shift_x is the datasheet's horizontal lens shift (a fraction), shift_y the vertical one in image widths,
    lens / sensor_width the throw ratio; fy != fx goes into the pixel aspect (both >= 1, as Blender wants)."""
    K = datasheet.intrinsic_matrix(1920, 1080, throw_ratio=1.4, shift_h=-4.0, shift_v=55.0, aspect=1.01)
    from procam.calibration import Device

    cam = blender.blender_camera(Device(K, (1920, 1080)))
    d, r = cam["data"], cam["render"]
    assert d["lens"] / d["sensor_width"] == pytest.approx(1.4)
    assert d["shift_x"] == pytest.approx(-0.04) and d["shift_y"] == pytest.approx(0.55 * 1080 / 1920 / 1.01)
    assert r["pixel_aspect_x"] == pytest.approx(1.01) and r["pixel_aspect_y"] == 1.0 and d["sensor_fit"] == "HORIZONTAL"
    K2 = K.copy()
    K2[1, 1] = K[0, 0] / 1.02
    r2 = blender.blender_camera(Device(K2, (1920, 1080)))["render"]
    assert r2["pixel_aspect_x"] == 1.0 and r2["pixel_aspect_y"] == pytest.approx(1.02)


# ---------------------------------------------------------------------------------------------------
# Unity
# ---------------------------------------------------------------------------------------------------

def _unity_screen_pixels(dev_doc, X_unity):
    """Unity's documented chain, written from its documentation apart from the export: the frustum of the
    physical camera (FocalLengthToFieldOfView per side, lens shift in sensor sizes, gate fit None stretches the
    sensor onto the image), worldToCameraMatrix = scale(1, 1, -1) * worldToLocal, WorldToScreenPoint's pixels
    from the bottom-left corner -> procam pixels."""
    p = dev_doc["physical"]
    W, H = dev_doc["resolution"]
    f, (sx, sy), (lx, ly) = p["focalLength"], p["sensorSize"], p["lensShift"]
    assert p["gateFit"] == "None"
    tan_h, tan_v = np.tan(np.radians(0.5 * 2 * np.degrees(np.arctan(sx / (2 * f))))), sy / (2 * f)
    L = np.array(dev_doc["transform"]["localToWorldMatrix"])
    view = np.diag([1.0, 1.0, -1.0, 1.0]) @ np.linalg.inv(L)
    eye = (view @ _h(X_unity).T).T[:, :3]
    # the frustum window at distance 1: x in [(-1/2 + lx), (1/2 + lx)] * 2 tan_h, same in y
    xn = eye[:, 0] / -eye[:, 2] / (2 * tan_h) + 0.5 - lx      # 0 .. 1 across the image
    yn = eye[:, 1] / -eye[:, 2] / (2 * tan_v) + 0.5 - ly
    return np.column_stack([xn * W - 0.5, H - yn * H - 0.5])


@pytest.mark.parametrize("rig", RIGS)
@pytest.mark.parametrize("world", ["camera", "projector"])
def test_unity_physical_cameras_project_like_the_pinhole(rig, world):
    calib, Xc = _rig(rig)
    doc = json.loads(json.dumps(unity.unity_document(calib, world=world, unit="mm")))
    s = doc["metres_per_unit"]
    # the Unity world of the camera frame's points: through the camera's own transform (camera local = S X_cam)
    cam_L = np.array(doc["camera"]["transform"]["localToWorldMatrix"])
    X_unity = (cam_L @ _h(s * Xc * [1, -1, 1]).T).T[:, :3]
    for name in ("camera", "projector"):
        d = doc[name]
        pix = _unity_screen_pixels(d, X_unity)
        assert np.abs(pix - _pinhole(calib, name, Xc)).max() <= TOL_PX
        # the documented matrix form of the same camera is the export's projectionMatrix (OpenGL form)
        P = unity.unity_projection(d["physical"], d["nearClipPlane"], d["farClipPlane"])
        np.testing.assert_allclose(P, d["projectionMatrix"], rtol=1e-10, atol=1e-12)
        M = np.array(d["transform"]["rotation_matrix"])
        assert np.linalg.det(M) == pytest.approx(1.0) and d["physical"]["focalLength"] > 0
        assert all(v > 0 for v in d["physical"]["sensorSize"])


def test_unity_transform_quaternion_and_euler_angles_are_the_rotation():
    from scipy.spatial.transform import Rotation

    calib, _ = _rig("ceiling")
    doc = unity.unity_document(calib)
    t = doc["projector"]["transform"]
    M = np.array(t["rotation_matrix"])
    np.testing.assert_allclose(Rotation.from_quat(t["rotation"]).as_matrix(), M, atol=1e-12)
    ex, ey, ez = np.radians(t["eulerAngles"])          # Unity: z, then x, then y about the world axes
    Rz = Rotation.from_rotvec([0, 0, ez]).as_matrix()
    Rx = Rotation.from_rotvec([ex, 0, 0]).as_matrix()
    Ry = Rotation.from_rotvec([0, ey, 0]).as_matrix()
    np.testing.assert_allclose(Ry @ Rx @ Rz, M, atol=1e-12)
    # the projector hangs upside-down: its up (Unity local +y) points down in the world
    assert (M @ [0, 1, 0])[1] < -0.9
    np.testing.assert_allclose(t["position"], np.array(doc["mounting"]["projector_position"]) * [1, -1, 1] * 1e-3)


def test_unity_lens_shift_is_the_datasheet_shift_and_the_fov_its_formula():
    sc = simulate.preset("lensshift")
    calib = truth_calibration(sc, approximate=True)
    d = unity.physical_camera(calib.projector)
    view = datasheet.datasheet_view(calib.projector.K, calib.projector.image_size)
    assert d["lensShift"] == pytest.approx([view.shift_h_pct / 100, view.shift_v_pct / 100])
    W, H = calib.projector.image_size
    # FocalLengthToFieldOfView of the sensor's height is the angle the panel's height spans about the lens axis
    fov_v = 2 * np.degrees(np.arctan(d["sensorSize"][1] / (2 * d["focalLength"])))
    assert fov_v == pytest.approx(2 * np.degrees(np.arctan(H / 2 / calib.projector.K[1, 1])))


# ---------------------------------------------------------------------------------------------------
# OpenGL / TouchDesigner, and what no export does: mirror the rig
# ---------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("rig", RIGS)
def test_opengl_matrices_project_like_the_pinhole_on_every_rig(rig):
    calib, Xc = _rig(rig)
    doc = opengl.opengl_document(calib, 100.0, 10000.0)
    for name in ("camera", "projector"):
        P, V = np.array(doc[name]["projection"]), np.array(doc[name]["view"])
        pix, depth = opengl.clip_to_pixels((P @ V @ _h(Xc).T).T, getattr(calib, name).image_size)
        assert np.abs(pix - _pinhole(calib, name, Xc)).max() < 1e-6 and np.all((depth > 0) & (depth < 1))


@pytest.mark.parametrize("rig", ["vertical", "ceiling"])
def test_no_export_of_a_ceiling_or_vertical_rig_mirrors_anything(rig):
    """Every device transform of every engine export is a rotation (det +1) with positive focal lengths, and the
    projector's image keeps its handedness: its panel's right and down, seen through the export, are the
    calibration's (a mirror would swap one)."""
    calib, Xc = _rig(rig)
    bdoc = blender.blender_document(calib)
    udoc = unity.unity_document(calib)
    gdoc = opengl.opengl_document(calib, 100.0, 10000.0)
    for name in ("camera", "projector"):
        for M in (np.array(bdoc["devices"][name]["matrix_world"])[:3, :3],
                  np.array(udoc[name]["transform"]["rotation_matrix"]),
                  np.array(gdoc[name]["view"])[:3, :3] @ np.diag([1, -1, -1])):
            assert np.linalg.det(M) == pytest.approx(1.0, abs=1e-9)
        assert bdoc["devices"][name]["data"]["lens"] > 0 and udoc[name]["physical"]["focalLength"] > 0
        P = np.array(gdoc[name]["projection"])
        assert P[0, 0] > 0 and P[1, 1] > 0
    # handedness of the projector's image: three points a step right / down of a board point stay right / down
    X0 = Xc[len(Xc) // 2]
    R, T = calib.R, calib.T
    Xp = R @ X0 + T
    step = [R.T @ (Xp + d) - R.T @ T for d in ([10.0, 0, 0], [0, 10.0, 0])]
    p0, pr, pd = _pinhole(calib, "projector", np.array([X0, step[0], step[1]]))
    Xb = (np.array(bdoc["world_from_camera"]) @ _h(np.array([X0, step[0], step[1]])).T).T[:, :3]
    q0, qr, qd = _blender_viewplane_pixels(bdoc["devices"]["projector"], Xb)
    def cross(a, b):
        return a[0] * b[1] - a[1] * b[0]

    assert np.sign(cross(pr - p0, pd - p0)) == np.sign(cross(qr - q0, qd - q0)) != 0


def test_frames_units_and_worlds():
    calib, _ = _rig("paper")
    assert frames.metres_per_unit("mm") == 1e-3 and frames.metres_per_unit("in") == pytest.approx(0.0254)
    with pytest.raises(ValueError, match="unknown length unit"):
        frames.metres_per_unit("furlong")
    with pytest.raises(ValueError, match="world must be one of"):
        frames.device_poses(calib, "board")
    poses = frames.device_poses(calib, "projector")
    np.testing.assert_allclose(poses["camera"][0], calib.R.T)
    np.testing.assert_allclose(poses["projector"][0], np.eye(3))
