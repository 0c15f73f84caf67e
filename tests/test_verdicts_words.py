"""A verdict that cannot be fooled (issue 24), its words: the same calibration whatever the board's labelling, one
number one meaning (the fit's ± and a predicted bound labelled, one definition of each angle, priors as priors,
given values as given), diagnoses from the evidence (sequence faults told apart from geometry, bad data from a bad
pose, reconstruct's dropped pixels) and a report that lists what was flagged."""

from __future__ import annotations

import json
import re
import warnings

import numpy as np
import pytest
from conftest import run_cli, verdict_warnings

from procam import multi_pose, patterns, pipeline, simulate, single_pose, summary
from procam.board import Board
from procam.calibration import Calibration, Device, Distortion
from procam.errors import CaptureError, ModelErrorWarning
from procam.view import View


# --------------------------------------------------------------------------------------------------
# 4. invariance: the four labellings of a board (COLSxROWS swapped, origin in another corner)
# --------------------------------------------------------------------------------------------------

def _relabel(obj, cam, proj, cols, rows, how):
    """The same physical corners under another labelling: ``how`` in given / swapped / far-corner /
    swapped-other-corner. Returns (obj, cam, proj, cols, rows, given index of each new corner)."""
    idx = np.arange(cols * rows).reshape(rows, cols)
    perm, c, r = {"given": (idx, cols, rows), "swapped": (idx.T, rows, cols),
                  "far-corner": (idx[::-1, ::-1], cols, rows), "swapped-other-corner": (idx.T[::-1, :], rows, cols)}[how]
    p = perm.ravel()
    s = float(np.min(np.abs(np.diff(np.unique(obj[:, 0])))))
    ii, jj = np.meshgrid(np.arange(c), np.arange(r))
    o = np.column_stack([ii.ravel() * s, jj.ravel() * s, np.zeros(c * r)])
    o[:, :2] -= o[:, :2].mean(axis=0)
    return o, cam[p], proj[p], c, r, p


LABELLINGS = ("given", "swapped", "far-corner", "swapped-other-corner")


def _outlier_pose(seed=7):
    """A real-looking pose of a 9x7 board with a few corners off (the outlier rejection has work to do)."""
    sc = simulate.with_board_pose(simulate.preset("paper").replace(board_cols=9, board_rows=7), (15, -25, 5))
    obj, cam, proj = simulate.correspondences(sc, 0.3, 0.5, seed)
    rng = np.random.default_rng(seed)
    cam[[4, 22, 40, 51]] += rng.normal(0, 2.0, (4, 2))
    proj[[4, 22]] += rng.normal(0, 3.0, (2, 2))
    return sc, obj, cam, proj


def _numbers(c):
    x = [c.camera.K.ravel()]
    if c.projector is not None:
        x += [c.projector.K.ravel(), np.asarray(c.R).ravel(), np.asarray(c.T).ravel()]
    return np.concatenate(x)


def _same(a, b):
    x, y = _numbers(a), _numbers(b)
    assert np.max(np.abs(x - y) / np.maximum(np.abs(x), 1e-3)) <= 1e-6
    assert a.verdict == b.verdict and a.std.keys() == b.std.keys()
    for k in ("f_c", "f_p", "v0p"):
        if k in a.std:
            assert abs(a.std[k] - b.std[k]) <= 1e-6 * abs(a.std[k])


@pytest.mark.parametrize("how", LABELLINGS[1:])
def test_single_pose_is_the_same_whatever_the_boards_labelling(how):
    sc, obj, cam, proj = _outlier_pose()
    with verdict_warnings():
        ref = single_pose.calibrate(View(obj, cam, proj, "pose", sc.cam_size, sc.proj_size))
        o, c, p, *_, given = _relabel(obj, cam, proj, 9, 7, how)
        other = single_pose.calibrate(View(o, c, p, "pose", sc.cam_size, sc.proj_size))
    _same(ref, other)
    # the same physical corners rejected, reported in each labelling's own numbers
    for device in ("camera", "projector"):
        a = sorted(r["index"] for r in ref.poses[0]["rejected_corners"][device])
        b = sorted(int(given[r["index"]]) for r in other.poses[0]["rejected_corners"][device])
        assert a == b
    assert ref.poses[0]["rejected_corners"]["camera"], "the fixture must reject corners"
    # psi, nu are the board's whatever its labelling (phi turns with the labelling's axes)
    np.testing.assert_allclose(ref.poses[0]["camera_angles_deg"][:2], other.poses[0]["camera_angles_deg"][:2], atol=1e-6)


@pytest.mark.parametrize("how", LABELLINGS[1:])
def test_camera_only_photo_and_multi_pose_are_the_same_whatever_the_labelling(how):
    sc, obj, cam, proj = _outlier_pose(3)
    o, c, _, *_ = _relabel(obj, cam, proj, 9, 7, how)
    with verdict_warnings():
        a = single_pose.calibrate_camera_only(obj, cam, sc.cam_size)
        b = single_pose.calibrate_camera_only(o, c, sc.cam_size)
    _same(a, b)
    base = simulate.preset("paper").replace(board_cols=9, board_rows=7)
    given, relabelled = [], []
    for k, ang in enumerate([(20, -15, 0), (-15, 20, 5), (10, 25, -5), (-25, -10, 0)]):
        s = simulate.with_board_pose(base, ang, distance=650.0)
        ob, ca, pr = simulate.correspondences(s, 0.1, 0.2, k)
        given.append(View(ob, ca, pr, f"p{k}", s.cam_size, s.proj_size))
        o2, c2, p2, *_ = _relabel(ob, ca, pr, 9, 7, how if k % 2 else "given")  # mixed labellings
        relabelled.append(View(o2, c2, p2, f"p{k}", s.cam_size, s.proj_size))
    with verdict_warnings():
        _same(multi_pose.calibrate(given), multi_pose.calibrate(relabelled))


# --------------------------------------------------------------------------------------------------
# 5. one number, one meaning
# --------------------------------------------------------------------------------------------------

def test_the_fits_plus_minus_and_a_predicted_bound_are_labelled_and_angles_read_as_the_table():
    sc = simulate.with_board_pose(simulate.preset("paper"), (-7, -20, 3))
    obj, cam, proj = simulate.correspondences(sc, 0.1, 0.2, 11)
    with verdict_warnings():
        calib = single_pose.calibrate(View(obj, cam, proj, "pose", sc.cam_size, sc.proj_size))
    rating = calib.poses[0]["advice"]
    for device, d in (("camera", "c"), ("projector", "p")):
        msg = rating[device]["message"]
        for m in re.finditer(rf"f_{d} ±[\d.]+ %( [a-z]+)?", msg):  # every relative ± says what it is
            assert "predicted at this pose" in msg[m.start():m.start() + 80] or \
                   "from the fit" in msg[m.start():m.start() + 40] or \
                   "with what the assumed" in msg[m.start():m.start() + 40], msg
    # the angle the message quotes is the pose table's, sign and all
    ca = calib.poses[0]["camera_angles_deg"]
    assert f"psi_c = {ca[0]:.1f}" in rating["camera"]["message"] and ca[0] < 0
    row = summary.pose_table(calib).rows[0]
    assert row[1].startswith(f"{ca[0]:.1f}, ")
    # R's Euler angles are named apart from a board's
    names = [r[0] for r in summary.parameter_table(calib).rows]
    assert "R ψ_R (deg, XYZ Euler of R)" in names and "R psi (deg)" not in names


def _single_pose_like(alpha=0.9989, alpha_std=0.0009, model="u0p"):
    K = np.array([[1235.4, 0, 505.8], [0, 1235.4 * alpha, 544.2], [0, 0, 1.0]])
    cam = Device(np.array([[788.0, 0, 342.6], [0, 787.8, 262.9], [0, 0, 1.0]]), (640, 400),
                 Distortion("division", (342.6, 262.9), -1.1e-7, 0.0))
    return Calibration(camera=cam, projector=Device(K, (960, 540)), R=np.eye(3), T=np.array([-170.0, -40.0, -65.0]),
                       method="single-pose", std={"f_c": 4.8, "fy_c": 4.2, "f_p": 7.0, "fy_p": 6.3, "u0p": 2.0,
                                                  "alpha_p": alpha_std, "v0p": 3.1},
                       info={"background_model": model})


def test_a_prior_is_said_as_a_prior_and_a_given_value_as_given():
    words = summary.projector_assumptions(_single_pose_like())
    assert words[1].startswith("alpha_p = fy_p / f_p = 0.9989 ± 0.0009 rests on a PRIOR of 1 ± 0.003")
    assert not any("alpha_p = 1 (fy_p = f_p) is ASSUMED" in w for w in words)
    fy = [r for r in summary.parameter_table(_single_pose_like()).rows if r[0].startswith("fy")][0]
    assert fy[2].endswith("(prior alpha_p = 1 ± 0.003)") and "assumed" not in fy[2]
    # the paper's model kept as is: assumed, and said so
    kept = _single_pose_like(alpha=1.0, alpha_std=None, model="single-pose")
    kept = kept.replace(std={k: v for k, v in kept.std.items() if k != "alpha_p"})
    assert "alpha_p = 1 (fy_p = f_p) is ASSUMED" in summary.projector_assumptions(kept)
    # given intrinsics: "(given)", never "± 0.00"
    given = _single_pose_like().replace(method="single-pose, camera given",
                                        std={"f_c": 0.0, "fy_c": 0.0, "u0c": 0.0, "v0c": 0.0, "f_p": 7.0})
    cells = [c for r in summary.parameter_table(given).rows for c in r[1:]]
    assert not any("± 0.00" in c for c in cells)
    assert [r[1] for r in summary.parameter_table(given).rows][:4] == ["788.00 (given)", "787.80 (given)",
                                                                      "342.60 (given)", "262.90 (given)"]


# --------------------------------------------------------------------------------------------------
# 6. diagnoses from the evidence
# --------------------------------------------------------------------------------------------------

PS = patterns.pattern_set(1920, 1080)
B = Board(10, 6, 24.0)


def test_a_sequence_captured_rows_first_is_not_blamed_on_the_projector_size(paper_capture):
    stack = paper_capture[1]
    cp, rp = PS.pair_indices("col").ravel(), PS.pair_indices("row").ravel()
    rows_first = stack.copy()
    rows_first[:len(rp)] = stack[rp]
    rows_first[len(rp):len(rp) + len(cp)] = stack[cp]
    with pytest.raises(CaptureError, match="captured rows first") as e:
        pipeline.view_from_stack(rows_first, PS, B)
    assert "--projector is not the problem" in str(e.value) and "the projector is larger" not in str(e.value)
    # the projector's size given the other way round: the same codes, but the maps change as a side-by-side rig's
    with pytest.raises(CaptureError, match=r"given the wrong way round.*fit a 1920x1080 projector, not 1080x1920; "
                                           r"pass --projector 1920x1080"):
        pipeline.view_from_stack(stack, patterns.pattern_set(1080, 1920), B)


def test_every_swapped_pattern_pair_is_named(paper_capture):
    stack = paper_capture[1].copy()
    pairs = PS.pair_indices("col")
    for b in (6, 8):  # two column pairs (MSB first: column bits 4 and 2)
        a, i = pairs[b]
        stack[[a, i]] = stack[[i, a]]
    with pytest.raises(CaptureError) as e:
        pipeline.view_from_stack(stack, PS, B)
    msg = str(e.value)
    assert "2 pairs of images" in msg and "(column bit 4)" in msg and "(column bit 2)" in msg
    assert "turn the board" not in msg


def test_corners_far_noisier_than_a_decode_blame_the_data_not_the_pose():
    """Two column-bit pairs swapped, as the corners see them (the decoded column jumps inside blocks of 16 and 32
    codes): ~15 px of corner noise at a pose whose |nu_p| is 43 deg. The rating must not ask to turn the board."""
    sc = simulate.with_board_pose(simulate.preset("paper"), (20, -35, 0), frame="projector")
    obj, cam, proj = simulate.correspondences(sc, 0.1, 0.2, 4)
    x = np.floor(proj[:, 0]).astype(int)
    proj[:, 0] = (x ^ ((1 << 4) - 1) ^ ((1 << 5) - 1)) + (proj[:, 0] - x)
    with verdict_warnings():
        calib = single_pose.calibrate(View(obj, cam, proj, "pose", sc.cam_size, sc.proj_size))
    msg = calib.poses[0]["advice"]["projector"]["message"]
    assert calib.verdict != "good" and calib.poses[0]["advice"]["projector"]["bad_data"]
    assert "the data, not the pose" in msg and "check the decoded maps" in msg and "turn the board" not in msg


def test_reconstruct_accounts_for_every_dropped_pixel():
    from sim_small import small_capture

    from procam import reconstruct as rc

    scene, _, _, maps = small_capture()
    right = simulate.truth_calibration(scene)
    with warnings.catch_warnings():
        warnings.simplefilter("error", ModelErrorWarning)
        cloud = rc.reconstruct(right, maps)
    lines, warns, misfit = rc.dropped_lines(cloud)
    a = cloud.accounting
    assert a["decoded"] == a["kept"] + a["disagree"] + a["not_in_front"] and warns == [] and misfit == ""
    assert a["median_disagreement_px"] < 0.5 and any("median" in ln for ln in lines)
    moved = right.replace(T=np.asarray(right.T) + [12.0, 0.0, 0.0])  # the projector moved since the calibration
    with pytest.warns(ModelErrorWarning, match="the point cloud must not be trusted"):
        cloud = rc.reconstruct(moved, maps)
    lines, warns, misfit = rc.dropped_lines(cloud)
    a = cloud.accounting
    assert misfit == warns[0]
    for kw in ({"use": "col"}, {"use": "row"}, {"max_residual_px": 50.0}):  # one coordinate, or a lax limit: the
        with pytest.warns(ModelErrorWarning, match="the point cloud must not be trusted"):  # disagreement still
            other = rc.reconstruct(moved, maps, **kw)  # measures the fit (they gave exit 0, a cloud 11 % too near)
        assert rc.dropped_lines(other).misfit and other.accounting["median_disagreement_px"] > 2.0, kw
    with warnings.catch_warnings():
        warnings.simplefilter("error", ModelErrorWarning)
        for kw in ({"use": "col"}, {"max_residual_px": 50.0}):
            assert rc.dropped_lines(rc.reconstruct(right, maps, **kw)).misfit == ""
    assert a["disagree"] > 0.5 * a["decoded"] and a["median_disagreement_px"] > 2.0
    assert len(warns) == 1 and "the calibration does not describe this camera and projector" in warns[0]
    assert re.search(r"dropped, projector column and row disagree by more than 2 px: \d+ \(\d+%\)", "\n".join(lines))


def test_cli_reconstruct_prints_the_dropped_pixels(tmp_path):
    pytest.importorskip("plyfile")
    from sim_small import small_capture

    from procam import io

    scene, stack, truth, _ = small_capture()
    folder = tmp_path / "pose"
    simulate.write_capture(folder, stack, truth)
    calib = simulate.truth_calibration(scene)
    io.save_calibration(calib.replace(T=np.asarray(calib.T) + [12.0, 0.0, 0.0]), tmp_path / "moved.json")
    code, out, err = run_cli(["reconstruct", tmp_path / "moved.json", folder, "-o", tmp_path / "c.ply"])
    assert code == 3, err  # written, and said in the table, the file, the exit code: the cloud is not trusted
    assert "dropped, projector column and row disagree" in out and "column/row disagreement" in out
    assert "decoded pixels" in out and "were dropped: the median column/row disagreement" in out
    assert "NOT TRUSTED" in out and "not trusted:" in err and "c.ply" in err
    header = (tmp_path / "c.ply").read_bytes().split(b"end_header")[0]
    assert b"comment NOT TRUSTED: " in header and b"does not describe this camera and projector" in header
    io.save_calibration(calib, tmp_path / "right.json")  # the rig's own calibration: trusted, exit 0
    code, out, err = run_cli(["reconstruct", tmp_path / "right.json", folder, "-o", tmp_path / "r.ply"])
    assert code == 0, err
    assert "NOT TRUSTED" not in out and b"NOT TRUSTED" not in (tmp_path / "r.ply").read_bytes()[:2000]


# --------------------------------------------------------------------------------------------------
# 7. the report: what was flagged, every pose in the coverage figure
# --------------------------------------------------------------------------------------------------

def test_the_report_lists_what_was_flagged_and_shows_every_pose():
    from procam.report import build_report

    sc = simulate.with_board_pose(simulate.preset("paper"), simulate.RECOMMENDED_POSE)
    obj, cam, proj = simulate.correspondences(sc, 0.15, 0.3, 21)
    cam[[3, 17, 33, 48]] += np.array([[4.0, -3.0], [-5.0, 2.0], [3.0, 4.0], [-4.0, -4.0]])
    view = View(obj, cam, proj, "poseA", sc.cam_size, sc.proj_size,
                diagnostics={"warnings": ["poseA: 3 % of the white frame is saturated"]})
    sc2 = simulate.with_board_pose(simulate.preset("paper"), (-20, 30, 10))
    other = View(*simulate.correspondences(sc2, 0.15, 0.3, 22), "poseB", sc2.cam_size, sc2.proj_size)
    with verdict_warnings():
        calib = single_pose.calibrate(view)
        page = build_report(calib, [other], name="a.json")
    verdict = re.search(r'<section id="verdict"[^>]*>(.*?)</section>', page, re.S).group(1)
    assert "Flagged (" in verdict and "Nothing was flagged" not in verdict
    assert "4 camera corners rejected as outliers" in verdict
    assert "3 % of the white frame is saturated" in verdict  # a warning the command line printed
    if calib.info.get("principal_point_source") == "image-center":
        assert "principal point is a prior" in verdict
    coverage = re.search(r'<section id="coverage"[^>]*>(.*?)</section>', page, re.S).group(1)
    assert coverage.count("<img") == 1
    # a clean calibration: nothing flagged, and it says so
    clean = View(*simulate.correspondences(sc, 0.1, 0.2, 3), "clean", sc.cam_size, sc.proj_size)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ok = single_pose.calibrate(clean)
        if ok.verdict == "good" and not ok.warnings:
            assert "Nothing was flagged" in build_report(ok, name="ok.json")


def test_report_coverage_shows_the_calibrated_pose_beside_the_given_ones(monkeypatch):
    from procam.report import page as report_page

    sc = simulate.with_board_pose(simulate.preset("paper"), simulate.RECOMMENDED_POSE)
    view = View(*simulate.correspondences(sc, 0.1, 0.2, 5), "calibrated", sc.cam_size, sc.proj_size)
    sc2 = simulate.with_board_pose(simulate.preset("paper"), (-20, 30, 10))
    other = View(*simulate.correspondences(sc2, 0.1, 0.2, 6), "held-out", sc2.cam_size, sc2.proj_size)
    with verdict_warnings():
        calib = single_pose.calibrate(view)
    seen = {}

    def spy(calib, views, decodes):
        seen["names"] = [v.name for v in views]
        return ""

    monkeypatch.setattr(report_page, "coverage_section", spy)
    with verdict_warnings():
        report_page.build_report(calib, [other], name="c.json")
    assert seen["names"] == ["calibrated", "held-out"]


@pytest.mark.parametrize("command", [["reconstruct", "CAL", "POSE", "-o", "c.ply"],
                                     ["export", "CAL", "--format", "opengl", "--near", "10", "--far", "5000", "-o",
                                      "g.json"],
                                     ["export", "CAL", "--format", "yaml", "-o", "c.yml"]])
def test_a_calibration_written_with_force_is_not_trusted_downstream(tmp_path, command):
    """calibrate --force writes a degenerate calibration, "marked as such": reconstruct and export used it with exit
    0 and no word (a cloud 39 times too far).  They still write, and say it: a warning, exit 3, the file marked
    where its format can hold it."""
    pytest.importorskip("plyfile")
    from sim_small import small_capture

    from procam import io

    scene, stack, truth, _ = small_capture()
    simulate.write_capture(tmp_path / "pose", stack, truth)
    calib = simulate.truth_calibration(scene)
    io.save_calibration(calib.replace(verdict="degenerate", verdict_reasons=("the pose is fronto-parallel",)),
                        tmp_path / "deg.json")
    io.save_calibration(calib, tmp_path / "good.json")
    args = [tmp_path / "pose" if a == "POSE" else tmp_path / a if "." in a and a[0].isalpha() else a for a in command]
    code, out, err = run_cli([tmp_path / "deg.json" if a == "CAL" else a for a in args])
    assert code == 3 and "not trusted:" in err and "its verdict is degenerate" in out + err, err
    assert "the pose is fronto-parallel" in out
    written = args[-1].read_bytes()
    if args[-1].suffix == ".ply":
        assert b"comment NOT TRUSTED: " in written.split(b"end_header")[0]
    if args[-1].suffix == ".json":
        assert "its verdict is degenerate" in json.loads(written)["not_trusted"]
    args[-1].unlink()
    code, out, err = run_cli([tmp_path / "good.json" if a == "CAL" else a for a in args])
    assert code == 0 and "not trusted" not in out + err and "verdict is" not in out, err
