"""procam.datasheet: throw ratio and lens shift against their definitions, and the exact round trip."""

import functools

import numpy as np
import pytest

from procam import datasheet, models


@pytest.mark.parametrize("tr, sh, sv", [(1.5, 0.0, 50.0), (0.8, -3.0, 58.0), (2.1, 5.5, -12.0)])
def test_datasheet_numbers_round_trip_exactly(tr, sh, sv):
    K = datasheet.intrinsic_matrix(1920, 1080, throw_ratio=tr, shift_h=sh, shift_v=sv)
    v = datasheet.datasheet_view(K, (1920, 1080))
    assert v.throw_ratio == pytest.approx(tr, abs=1e-12)
    assert v.shift_h_pct == pytest.approx(sh, abs=1e-9) and v.shift_v_pct == pytest.approx(sv, abs=1e-9)
    assert v.offset_pct == pytest.approx(2 * sv) and v.aspect == 1.0


def test_throw_ratio_is_distance_over_image_width():
    """A screen square to the lens axis at distance D: the image the panel throws on it is D / throw ratio wide."""
    K = datasheet.intrinsic_matrix(1280, 800, throw_ratio=1.2, shift_v=50.0)
    D = 2000.0
    left = np.linalg.solve(K, [-0.5, 400.0, 1.0]) * D          # rays through the panel's left and right edges
    right = np.linalg.solve(K, [1279.5, 400.0, 1.0]) * D
    assert D / (right[0] - left[0]) == pytest.approx(1.2)


def test_half_shift_puts_the_bottom_edge_on_the_axis_and_the_image_above():
    K = datasheet.intrinsic_matrix(1920, 1080, throw_ratio=1.0, shift_v=50.0)
    assert K[1, 2] == pytest.approx(1080 - 0.5)          # the axis through the bottom edge of the panel
    # every panel row projects above the axis (y < 0 in the projector frame: up)
    ys = (np.arange(1080) - K[1, 2]) / K[1, 1]
    assert np.all(ys <= 0)


def test_field_of_view_of_a_centred_lens():
    K = models.intrinsic_matrix(1000.0, 499.5, 299.5)
    v = datasheet.datasheet_view(K, (1000, 600))
    assert v.fov_h_deg == pytest.approx(2 * np.degrees(np.arctan(0.5)))
    assert v.fov_v_deg == pytest.approx(2 * np.degrees(np.arctan(0.3)))
    assert v.shift_h_pct == pytest.approx(0.0) and v.shift_v_pct == pytest.approx(0.0)


# ---------------------------------------------------------------------------------------------------
# a calibration's datasheet view: the numbers of a simulated lens-shifted projector recovered within their ±
# ---------------------------------------------------------------------------------------------------

POSES = [(15, 12, 0), (-10, 20, 5), (20, -15, -5), (5, 25, 10), (-20, -10, 0)]
KEYS = ("throw_ratio", "shift_h_pct", "shift_v_pct", "offset_pct", "fov_h_deg", "fov_v_deg")


@functools.lru_cache(maxsize=None)
def _fast_path_calibration(seed=0):
    from conftest import verdict_warnings
    from procam import multi_pose, simulate
    from procam.view import View

    sc = simulate.preset("lensshift")
    views = []
    for k, p in enumerate(POSES):
        s = simulate.with_board_pose(sc, p)
        obj, cam, proj = simulate.correspondences(s, sigma_cam=0.1, sigma_proj=0.2, seed=100 * seed + k)
        views.append(View(obj, cam, proj, f"p{k}", s.cam_size, s.proj_size))
    with verdict_warnings():
        return sc, multi_pose.calibrate(views)


def _check_recovered(sc, calib, k_sigma):
    truth = datasheet.datasheet_view(sc.K_proj, sc.proj_size)
    got = datasheet.calibration_datasheet(calib)
    z = {}
    for key in KEYS:
        s = got.std[key]
        assert s > 0, key
        z[key] = abs(getattr(got, key) - getattr(truth, key)) / s
    assert max(z.values()) <= k_sigma, z
    return truth, got, z


def test_lens_shifted_projector_datasheet_numbers_are_recovered_within_their_pm():
    """The ``lensshift`` preset's projector (throw ratio 2421 / 1920 = 1.261, lens shift -1.12 % horizontally and
    +58.0 % vertically: the image above the lens axis) from a multi-pose calibration of five poses (corner fast
    path, 0.1 / 0.2 px noise): every datasheet number within 3 sigma of its calibration's ±, which is small enough
    to tell a datasheet's steps (0.01 throw ratio, 1 % shift)."""
    sc, calib = _fast_path_calibration()
    truth, got, z = _check_recovered(sc, calib, 3.0)
    assert truth.throw_ratio == pytest.approx(2421 / 1920) and truth.shift_v_pct == pytest.approx(58.05, abs=0.01)
    assert got.std["throw_ratio"] < 0.005 and got.std["shift_v_pct"] < 0.5 and got.std["shift_h_pct"] < 0.5
    assert got.std["offset_pct"] == pytest.approx(2 * got.std["shift_v_pct"])


def test_datasheet_pm_propagates_the_parameter_pm():
    """The ± of each number is the first-order propagation of the calibration's f, fy, u0, v0 ± (finite
    differences of datasheet_view), and a number whose input has no ± (an assumed u0p) has none."""
    from procam.calibration import Calibration, Device

    K = datasheet.intrinsic_matrix(1920, 1080, throw_ratio=1.3, shift_h=2.0, shift_v=45.0)
    dev = Device(K, (1920, 1080))
    std = {"f_p": 3.0, "fy_p": 2.0, "u0p": 4.0, "v0p": 5.0}
    calib = Calibration(dev, dev, np.eye(3), np.array([100.0, 0, 0]), "multi-pose", std=std)
    got = datasheet.calibration_datasheet(calib)

    def moved(i, j, d):
        K2 = K.copy()
        K2[i, j] += d
        return datasheet.datasheet_view(K2, (1920, 1080))

    for key in KEYS:
        var = 0.0
        for (i, j), s in (((0, 0), 3.0), ((1, 1), 2.0), ((0, 2), 4.0), ((1, 2), 5.0)):
            h = 1e-3
            var += ((getattr(moved(i, j, h), key) - getattr(moved(i, j, -h), key)) / (2 * h) * s) ** 2
        assert got.std[key] == pytest.approx(np.sqrt(var), rel=1e-5), key
    no_u0 = datasheet.calibration_datasheet(calib.replace(std={"f_p": 3.0, "v0p": 5.0}))
    assert "shift_h_pct" not in no_u0.std and "throw_ratio" in no_u0.std
    assert datasheet.calibration_datasheet(calib.replace(projector=None)) is None


@pytest.mark.slow
def test_lens_shifted_projector_datasheet_numbers_from_rendered_poses(tmp_path):
    """The same from five rendered Gray-code captures (decoded, corners detected, projector corners from local
    homographies), multi-pose: every number within 3 sigma of the calibration's ±. The fast sibling is the corner
    fast path above."""
    from conftest import verdict_warnings
    from procam import multi_pose, pipeline, simulate
    from procam.board import Board

    sc = simulate.preset("lensshift")
    folders = []
    for k, p in enumerate(POSES):
        s = simulate.with_board_pose(sc, p)
        stack, truth = simulate.render(s, seed=10 + k)
        simulate.write_capture(tmp_path / f"pose{k}", stack, truth)
        folders.append(tmp_path / f"pose{k}")
    with verdict_warnings():
        views = pipeline.views_from_folders(folders, Board(sc.board_cols, sc.board_rows, sc.square))
        calib = multi_pose.calibrate(views)
    _check_recovered(sc, calib, 3.0)


# ---------------------------------------------------------------------------------------------------
# the datasheet view and the mounting in the text summary, the JSON and the report
# ---------------------------------------------------------------------------------------------------

def test_datasheet_view_and_mounting_are_in_the_text_summary_the_json_and_the_report(capsys):
    from procam import simulate, summary
    from procam.cli import _show
    from procam.io.procam import calibration_to_dict
    from procam.report import build_report

    sc, calib = _fast_path_calibration()
    got = datasheet.calibration_datasheet(calib)
    table = summary.datasheet_table(calib)
    rows = {r[0].split(" (")[0]: r for r in table.rows}
    assert table.header == ("datasheet", "camera", "projector")
    assert rows["throw ratio"][2] == f"{got.throw_ratio:.3f} ± {got.std['throw_ratio']:.3f}"
    assert rows["lens shift, vertical"][2].startswith(f"{got.shift_v_pct:.2f} ± ")
    doc = calibration_to_dict(calib)
    assert doc["datasheet"]["projector"]["throw_ratio"] == pytest.approx(got.throw_ratio)
    assert doc["datasheet"]["projector"]["std"]["shift_v_pct"] == pytest.approx(got.std["shift_v_pct"])
    assert doc["mounting"]["projector_upside_down"] is False
    _show.print_calibration(calib)
    out = capsys.readouterr().out
    assert "as a projector datasheet prints it" in out and "throw ratio" in out and "mounting: projector upright" in out
    html = build_report(calib, None, name="t")
    assert "As a projector datasheet prints it" in html and rows["throw ratio"][2] in html
    ceiling = simulate.truth_calibration(simulate.preset("ceiling"))
    assert "upside-down relative to the camera" in build_report(ceiling, None, name="c")


def test_mounting_words_for_ceiling_vertical_and_portrait_rigs():
    from procam import simulate
    from procam.calibration import Device
    from procam.mounting import mounting

    m = mounting(simulate.truth_calibration(simulate.preset("ceiling")))
    assert m.upside_down and abs(abs(m.roll_deg) - 180) < 1 and "350 above" in m.where()
    m = mounting(simulate.truth_calibration(simulate.preset("vertical")))
    assert m.turn.startswith("upright") and abs(m.roll_deg) < 1e-6 and "600 below" in m.where()
    # a portrait projector: the paper's panel turned a quarter turn clockwise about its axis, 1080 wide, 1920 tall
    sc = simulate.preset("paper")
    calib = simulate.truth_calibration(sc)
    Rz = np.array([[0.0, 1, 0], [-1, 0, 0], [0, 0, 1]])          # projector x axis = camera +y (down)
    K = np.array(sc.K_proj, float)
    portrait = calib.replace(projector=Device(K[[1, 0, 2]][:, [1, 0, 2]], (1080, 1920)), R=Rz @ calib.R,
                             T=Rz @ calib.T)
    m = mounting(portrait)
    assert m.roll_deg == pytest.approx(90.0, abs=1.0) and "quarter turn clockwise" in m.turn and m.projector_portrait
    assert any("projector's image is portrait" in line for line in m.lines())
    d = m.to_dict()
    assert d["projector_portrait"] and not d["projector_upside_down"]
    assert mounting(calib.replace(projector=None, R=None, T=None)).lines() == []
