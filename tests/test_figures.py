"""The residual figure shows what the tables print (issue 15 item 4); the experiment figures hold every point."""

from __future__ import annotations

import functools
import re

import numpy as np
import pytest

from procam import multi_pose, simulate, single_pose
from procam.plots.residuals import arrow_scale, nice_length, residual_figure
from procam.residuals import calibration_residuals, pose_residuals
from procam.stats import rms
from procam.verdict import calibration_verdict
from procam.view import View
from procam.errors import DegeneratePoseWarning, WeakPoseWarning
from conftest import expect_warning

POSES = [(15, 12, 0), (-10, 20, 5), (20, -15, -5), (5, 25, 10)]


@functools.lru_cache(maxsize=None)
def _single_with_outliers():
    sc = simulate.with_board_pose(simulate.preset("paper"), simulate.RECOMMENDED_POSE)
    obj, cam, proj = simulate.correspondences(sc, 0.1, 0.2, seed=0)
    cam[5] += 3.0   # one camera and one projector corner far off: the solver rejects them
    proj[7] += 5.0
    view = View(obj, cam, proj, "/some/long/path/pose1", sc.cam_size, sc.proj_size)
    with expect_warning(WeakPoseWarning):          # the rejected corners leave f_c weakly determined
        return single_pose.calibrate(view), view


@functools.lru_cache(maxsize=None)
def _multi():
    sc = simulate.preset("paper")
    views = []
    for k, p in enumerate(POSES):
        s = simulate.with_board_pose(sc, p)
        obj, cam, proj = simulate.correspondences(s, 0.1, 0.2, seed=10 + k)
        views.append(View(obj, cam, proj, f"/data/session/pose{k + 1}", s.cam_size, s.proj_size))
    return multi_pose.calibrate(views)


def _panel_rms(ax) -> float:
    return float(re.search(r"RMS (\d+\.\d+) px", ax.get_title()).group(1))


def test_single_pose_residuals_are_the_calibrations():
    calib, view = _single_with_outliers()
    r = calibration_residuals(calib)[0]
    rej_c = [c["index"] for c in calib.poses[0]["rejected_corners"]["camera"]]
    rej_p = [c["index"] for c in calib.poses[0]["rejected_corners"]["projector"]]
    assert rej_c == [5] and rej_p == [7]
    assert np.flatnonzero(~r["cam_used"]).tolist() == [5] and np.flatnonzero(~r["proj_used"]).tolist() == [7]
    assert rms(r["cam_res"][r["cam_used"]]) == pytest.approx(calib.cam_rms, rel=1e-12)
    assert rms(r["proj_res"][r["proj_used"]]) == pytest.approx(calib.proj_rms, rel=1e-12)
    # the rejected corners keep their (large) residuals, and the old measure that pooled them disagrees
    assert np.linalg.norm(r["cam_res"][5]) > 2.0 and np.linalg.norm(r["proj_res"][7]) > 4.0
    assert rms(pose_residuals(calib, [view])[0]["cam_res"]) > 2 * calib.cam_rms


def test_multi_pose_residuals_are_the_calibrations():
    calib = _multi()
    per = calibration_residuals(calib)
    assert [p["source"] for p in per] == ["multi-pose"] * 4
    assert rms([p["cam_res"][p["cam_used"]] for p in per]) == pytest.approx(calib.cam_rms, rel=1e-9)
    assert rms([p["proj_res"][p["proj_used"]] for p in per]) == pytest.approx(calib.proj_rms, rel=1e-9)
    for p, pose in zip(per, calib.poses):
        assert rms(p["cam_res"]) == pytest.approx(pose["cam_rms"], rel=1e-9)


def test_residual_figure_title_rms_is_the_tables_and_rejected_corners_are_marked():
    from matplotlib.quiver import QuiverKey

    calib, view = _single_with_outliers()
    fig = residual_figure(calibration_residuals(calib), calib.camera.image_size, calib.projector.image_size,
                          verdict=calibration_verdict(calib).line())
    cam_ax, proj_ax = fig.axes[0], fig.axes[1]
    assert _panel_rms(cam_ax) == float(f"{calib.cam_rms:.3f}")  # what the summary table prints
    assert _panel_rms(proj_ax) == float(f"{calib.proj_rms:.3f}")
    assert "59 corners" in cam_ax.get_title() and "1 rejected" in cam_ax.get_title()
    for ax, idx, pts in ((cam_ax, 5, view.cam_pts), (proj_ax, 7, view.proj_pts)):
        marked = [ln for ln in ax.get_lines() if ln.get_marker() == "x" and "rejected" in ln.get_label()]
        assert len(marked) == 1
        assert np.allclose(np.column_stack(marked[0].get_data()), pts[[idx]])
        # a key arrow of a round length says what the arrows mean
        keys = [a for a in ax.get_children() if isinstance(a, QuiverKey)]
        assert len(keys) == 1 and re.match(r"[\d.]+ px \(arrows x[\d.]+\)", keys[0].text.get_text())
        # short pose names in the legend
        assert "pose1" in [t.get_text() for t in ax.get_legend().get_texts()]
    title = fig._suptitle.get_text()
    assert title.startswith("verdict: weak")


def test_degenerate_pose_figure_does_not_look_clean():
    sc = simulate.with_board_pose(simulate.preset("paper"), (20, 0.3, 0))
    obj, cam, proj = simulate.correspondences(sc, 0.1, 0.2, seed=0)
    with expect_warning(DegeneratePoseWarning):
        calib = single_pose.calibrate(View(obj, cam, proj, "flat", sc.cam_size, sc.proj_size))
    fig = residual_figure(calibration_residuals(calib), calib.camera.image_size, calib.projector.image_size,
                          title="flat.json", verdict=calibration_verdict(calib).line())
    t = fig._suptitle
    assert t.get_text().startswith("flat.json\nverdict: degenerate: ") and "camera: degenerate pose" in t.get_text()
    from procam.style import VERDICT_COLOURS

    assert t.get_color() == VERDICT_COLOURS["degenerate"] and t.get_weight() == "bold"


def test_automatic_arrow_scale_and_key_length():
    r = np.linspace(0.01, 0.2, 100)
    k = arrow_scale(r, 1000.0)
    assert np.percentile(r, 95) * k == pytest.approx(50.0)  # 5 % of the width
    assert [nice_length(x) for x in (0.26, 0.09, 3.7, 7.0, 12.0)] == [0.2, 0.05, 2.0, 5.0, 10.0]
    # good data (0.1 px) are drawn visibly: the 95th-percentile arrow is 5 % of the image, not 10 px
    calib = _multi()
    fig = residual_figure(calibration_residuals(calib), calib.camera.image_size, calib.projector.image_size)
    q = [c for c in fig.axes[0].get_children() if type(c).__name__ == "Quiver"][0]
    drawn = np.hypot(q.U, q.V)
    assert np.percentile(drawn, 50) > 0.01 * calib.camera.image_size[0]
    assert fig.axes[0].get_legend().get_texts()[0].get_text() == "pose1"


def test_old_call_still_works():
    pts = np.array([[10.0, 20.0], [30.0, 40.0]])
    fig = residual_figure([{"name": "a/b", "cam_pts": pts, "cam_res": pts * 0.01}], (64, 48), scale=100)
    assert _panel_rms(fig.axes[0]) == pytest.approx(float(f"{np.sqrt(np.mean(np.sum((pts * 0.01) ** 2, 1))):.3f}"))


# ---------------------------------------------------------------------------------------------------
# the experiment's figures
# ---------------------------------------------------------------------------------------------------

@functools.lru_cache(maxsize=None)
def _experiment(n):
    from procam.paper import experiment

    angles = [(15, -35, 0), (-15, 20, 5), (10, 25, -5), (-25, 15, 0)]
    base = simulate.preset("paper")
    views = []
    for k, a in enumerate(angles[:n]):
        sc = simulate.with_board_pose(base, a, distance=650.0)
        obj, cam, proj = simulate.correspondences(sc, 0.1, 0.2, k)
        views.append(View(obj, cam, proj, f"/long/path/pose{k + 1}", sc.cam_size, sc.proj_size))
    return experiment.run(views, (1920, 1080))


@pytest.mark.parametrize("n", [3, 4])
def test_focal_error_figure_clips_no_point(n):
    from procam.plots.experiment import focal_error_figure

    fig = focal_error_figure(_experiment(n))
    fig.canvas.draw()
    for ax in fig.axes:
        x, y = ax.get_lines()[0].get_data()
        (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
        assert np.all((x >= x0) & (x <= x1) & (y >= y0) & (y <= y1))
        # each label inside the axes box
        box = ax.get_window_extent()
        for t in ax.texts:
            e = t.get_window_extent()
            assert box.x0 <= e.x0 and e.x1 <= box.x1 and box.y0 <= e.y0 and e.y1 <= box.y1, t.get_text()


def test_single_set_sigma_t_figure_reads():
    from procam.plots.experiment import sigma_t_figure

    res = _experiment(3)
    assert len(res.sets) == 1
    fig = sigma_t_figure(res)
    assert len(fig.axes) == 1  # no colour bar of one colour
    labels = [t.get_text() for t in fig.axes[0].get_xticklabels()]
    assert labels == ["set 1 {1,2,3} (reference, Set A)", "pose 1 alone", "pose 2 alone", "pose 3 alone"]
    ys = np.concatenate([ln.get_ydata() for ln in fig.axes[0].get_lines()])
    y0, y1 = fig.axes[0].get_ylim()
    assert np.all((ys > y0) & (ys < y1))
    many = sigma_t_figure(_experiment(4))
    assert len(many.axes) == 2  # sets of 3 and 4 poses: the colour bar says which
