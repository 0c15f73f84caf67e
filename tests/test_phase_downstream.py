"""The commands after calibration on a phase-family capture without a white frame (another tool's capture,
described by a hand-written patterns.json): reconstruct and the projector-view export, against the simulator's
truth. Both read the board's picture from the mean of the fringes where a Gray capture has its white frame."""

import cv2
import numpy as np
import pytest

from procam import simulate
from procam.io import save_calibration
from conftest import run_cli
from test_phase_capture import write_other_tool_capture


@pytest.fixture(scope="module")
def phase_pose(tmp_path_factory):
    """The other tool's capture (no white or black frame) and the simulator's true calibration as a file."""
    root = tmp_path_factory.mktemp("phase_downstream")
    scene = write_other_tool_capture(root / "pose")
    calib = root / "truth.json"
    save_calibration(simulate.truth_calibration(scene), calib)
    return root / "pose", calib, scene


def test_reconstruct_of_a_phase_capture_lies_on_the_true_board(phase_pose, tmp_path):
    plyfile = pytest.importorskip("plyfile", reason="reading the cloud needs the plyfile package")
    assert plyfile
    from procam.io import read_ply

    pose, calib, scene = phase_pose
    code, out, err = run_cli(["reconstruct", calib, pose, "-o", tmp_path / "cloud.ply"])
    assert code == 0, err
    pts, colours, _ = read_ply(tmp_path / "cloud.ply")
    assert colours is not None and len(pts) > 20000
    # in the board's frame: points over the printed squares (inner 80 % of the corner grid, not the wall behind)
    Xb = (pts - scene.t_board) @ scene.R_board
    half_w = 0.4 * (scene.board_cols - 1) * scene.square
    half_h = 0.4 * (scene.board_rows - 1) * scene.square
    on = (np.abs(Xb[:, 0]) < half_w) & (np.abs(Xb[:, 1]) < half_h) & (np.abs(Xb[:, 2]) < 20.0)
    assert on.sum() > 10000
    z = Xb[on, 2]
    # through the true calibration the cloud is on the board plane without bias (a half-pixel error in the
    # description's pixel-centre convention would move it by about 0.4 mm); its scatter is the 3-step decode's
    # noise (about 0.35 px, 0.3 mm here) over the white squares, and the black squares' (0.1 albedo: about 8 times
    # the noise; their fringe orders come from the white squares around them) widen its tail
    assert abs(np.mean(z)) < 0.05
    assert np.median(np.abs(z)) < 0.4 and np.percentile(np.abs(z), 90) < 2.5


def test_projector_view_of_a_phase_capture_shows_the_board_where_the_projector_lights_it(phase_pose, tmp_path):
    pose, calib, scene = phase_pose
    out = tmp_path / "view.png"
    code, text, err = run_cli(["export", calib, "--format", "projector-view", "--pose", pose, "-o", out])
    assert code == 0, err
    assert "mean of the fringes" not in err  # a phase pose without a white frame is not an error
    view = cv2.imread(str(out), cv2.IMREAD_UNCHANGED).astype(np.float64)
    mask = cv2.imread(str(tmp_path / "view_mask.png"), cv2.IMREAD_UNCHANGED) > 0
    assert view.shape[:2] == (1080, 1920) and mask.mean() > 0.2
    # the view at each corner's projector pixel is the camera's picture (the mean of the fringes) at that corner
    from procam.capture import load_capture

    picture = load_capture(pose).white.astype(np.float32)
    truth = simulate.corner_truth(scene)
    seen = cv2.remap(picture, *[np.float32(truth["camera_distorted"][:, i])[None] for i in (0, 1)],
                     cv2.INTER_LINEAR)[0]
    px = np.rint(truth["projector"]).astype(int)
    # 3 steps under a unit cue cannot order the fringes on the dark squares' corners everywhere: the mask says so
    inside = mask[px[:, 1], px[:, 0]]
    assert inside.sum() >= 40
    got = view[px[:, 1], px[:, 0]][inside]
    # corners are where black meets white: a fraction of a projector pixel moves them by many grey levels, so
    # the median agreement, not each corner's
    assert np.median(np.abs(got - seen[inside])) < 4.0
    assert np.ptp(seen) > 20  # the comparison is not of a flat picture
