import json

import cv2
import numpy as np
import pytest
from conftest import rms, run_cli

from procam.board import Board
from procam import board, correspond, decode, patterns, pipeline
from procam.board import corners
from procam.errors import BoardNotFoundError, CorrespondenceError

PS = patterns.pattern_set(1920, 1080)


def _truth(truth):
    c = truth["corners"]
    return np.array(c["camera_distorted"]), np.array(c["projector"]), np.array(c["board"])


def test_object_points_and_canonical_order():
    obj = board.object_points(10, 6, 24.0)
    assert obj.shape == (60, 3) and np.allclose(obj.mean(0), 0)
    assert np.allclose(obj[1] - obj[0], [24, 0, 0]) and np.allclose(obj[10] - obj[0], [0, 24, 0])
    # a grid seen upside down / mirrored in its numbering comes back in the same canonical order
    gx, gy = np.meshgrid(np.arange(10) * 30.0 + 100, np.arange(6) * 30.0 + 50)
    canon = np.column_stack([gx.ravel(), gy.ravel()])
    for shuffled in (canon[::-1], canon.reshape(6, 10, 2)[::-1].reshape(-1, 2),
                     canon.reshape(6, 10, 2)[:, ::-1].reshape(-1, 2)):
        assert np.array_equal(corners.canonical_order(shuffled, 10, 6), canon)


def test_corners_and_projector_points_against_truth(paper_capture):
    folder, stack, truth, _ = paper_capture
    cam_t, proj_t, obj_t = _truth(truth)
    view, maps = pipeline.view_from_stack(stack, PS, Board(10, 6, 24.0))
    assert np.allclose(view.obj_pts, obj_t)
    assert view.valid.all()
    assert rms(view.cam_pts, cam_t) <= 0.1  # camera px
    assert rms(view.proj_pts, proj_t) <= 0.2  # projector px
    d = view.diagnostics
    assert np.all(d["reason"] == 0) and np.all(d["pixels"] > 0.25 * 60 * 60)
    assert np.all(d["residual_px"] < 1.0) and np.all(d["inliers"] > 100)


@pytest.mark.parametrize("estimator", correspond.ESTIMATORS)
def test_estimators_all_work(paper_capture, estimator):
    _, stack, truth, _ = paper_capture
    cam_t, proj_t, _ = _truth(truth)
    maps = decode.decode(stack, PS)
    proj, diag = correspond.projector_corners(cam_t, maps, correspond.CornerOptions(estimator=estimator))
    assert rms(proj, proj_t) < 0.2


def test_the_trimmed_fit_in_batches_of_corners_is_the_fit_of_all_at_once(paper_capture, monkeypatch):
    """Corners fitted in batches (their windows' pixels bounded: a 1000 px window held 9.6 GB for 60 corners at
    once) give the same projector corners and diagnostics (to the last bits of the sums: BLAS picks its kernel by
    the product's size); a board of the default window's size is one batch."""
    _, stack, truth, _ = paper_capture
    cam_t = _truth(truth)[0]
    maps = decode.decode(stack, PS)
    opts = correspond.CornerOptions()
    whole = correspond.projector_corners(cam_t, maps, opts)
    assert len(cam_t) * opts.window ** 2 <= correspond.TRIMMED_BATCH  # the board at the default window: one batch
    monkeypatch.setattr(correspond, "TRIMMED_BATCH", 7 * opts.window ** 2)  # 9 batches of 7 corners
    batched = correspond.projector_corners(cam_t, maps, opts)
    np.testing.assert_allclose(batched[0], whole[0], rtol=0, atol=1e-9)
    for k in ("reason", "pixels", "window_pixels", "inliers"):
        assert np.array_equal(whole[1][k], batched[1][k]), k
    np.testing.assert_allclose(batched[1]["residual_px"], whole[1]["residual_px"], rtol=1e-9)


def test_partially_lit_board_works_corner_by_corner(paper_capture):
    _, stack, truth, _ = paper_capture
    cam_t, proj_t, _ = _truth(truth)
    st = stack.copy()
    # an occluder between projector and board: the right part of the board gets no projector light
    x_cut = int(np.median(cam_t[:, 0]))
    for k in range(PS.count):
        if k != PS.white:
            st[k, :, x_cut:] = stack[PS.black, :, x_cut:]
    view, _ = pipeline.view_from_stack(st, PS, Board(10, 6, 24.0))
    reason = view.diagnostics["reason"]
    far_left = cam_t[:, 0] < x_cut - 40
    far_right = cam_t[:, 0] > x_cut + 40
    assert np.all(reason[far_left] == 0) and np.all(reason[far_right] == 2)
    assert np.all(np.isnan(view.proj_pts[far_right]))
    assert rms(view.proj_pts[view.valid], proj_t[view.valid]) < 0.2
    # with too few corners left, the pose fails and says how many and why
    st[:, :, :] = st[:, :, :]
    for k in range(PS.count):
        if k != PS.white:
            st[k] = stack[PS.black]
    with pytest.raises(CorrespondenceError, match=r"only 0 of 60 corners.*too few decoded pixels"):
        pipeline.view_from_stack(st, PS, Board(10, 6, 24.0))


def test_board_near_the_image_border(paper_capture):
    _, stack, truth, _ = paper_capture
    cam_t, proj_t, _ = _truth(truth)
    # crop the frames so the left board column sits 12 px from the image edge
    x0 = int(cam_t[:, 0].min()) - 12
    st = np.ascontiguousarray(stack[:, :, x0:])
    maps = decode.decode(st, PS)
    cam = cam_t - [x0, 0]
    proj, diag = correspond.projector_corners(cam, maps)
    edge = cam[:, 0] < 20
    assert edge.sum() >= 1
    ok = diag["reason"] == 0
    assert ok[~edge].all()
    # the window is clipped at the border: edge corners either still work (accurately) or say why
    assert set(np.unique(diag["reason"][edge])) <= {0, 3}
    assert rms(proj[ok], proj_t[ok]) < 0.2


def test_board_not_found_message(paper_capture):
    _, stack, _, _ = paper_capture
    # a board of another size is in view: the message names the right --board
    with pytest.raises(BoardNotFoundError, match=r"9x6 inner corners not found.*use --board 10x6"):
        pipeline.view_from_stack(stack, PS, Board(9, 6, 24.0), name="pose1")


def test_cli_correspond(paper_capture, tmp_path):
    folder, _, truth, _ = paper_capture
    out = tmp_path / "corr.json"
    code, stdout, err = run_cli(["correspond", folder, "--board", "10x6", "--square", "24", "--projector",
                                 "1920x1080", "-o", out, "--png", tmp_path / "corr.png"])
    assert code == 0, err
    data = json.loads(out.read_text())
    cam_t, proj_t, _ = _truth(truth)
    assert rms(data["camera_points"], cam_t) < 0.1
    assert rms(data["projector_points"], proj_t) < 0.2
    assert len(data["corners"]) == 60 and data["corners"][0]["reason"] == "ok"
    assert cv2.imread(str(tmp_path / "corr.png")) is not None
    code, _, err = run_cli(["correspond", folder, "--board", "9x6", "--square", "24", "-o", out])
    assert code == 2 and "not found" in err
