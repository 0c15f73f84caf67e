"""procam app (issue 37): the More projectors step (a rig pose one projector after another, its calibration, the
blend masks) and the Devices step's exposure check (the capture's pre-flight before a capture), driven with
starlette's TestClient on the virtual devices (the simulator's two-projector rig)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from conftest import job_result

pytest.importorskip("starlette", reason="the app's extra is not installed (pip install \".[app]\")")
pytest.importorskip("uvicorn", reason="the app's extra is not installed (pip install \".[app]\")")

TOKEN = "test-token-0123456789"
H = {"X-Procam-Token": TOKEN}


@pytest.fixture
def client(tmp_path):
    from starlette.testclient import TestClient

    from procam import app

    c = TestClient(app.make(tmp_path / "project", virtual=True, token=TOKEN), base_url="http://127.0.0.1:8000")
    assert c.post("/api/board", headers=H, json={"cols": 10, "rows": 6, "square": 24}).status_code == 200
    yield c
    app.shutdown(c.app, 120)


def _run(c, path, body=None):
    r = c.post(path, headers=H, json=body or {})
    assert r.status_code == 202, r.text
    return job_result(c, r.json(), H)


def _small_rig_pose(project: Path, name="rig1", seed=3):
    """A rig pose of the simulator's two projectors at 256x144 (camera 320x200), captured by the library as
    ``procam capture --virtual --rig left,right`` does, and made the project's rig pose."""
    from procam.acquire import CaptureOptions
    from procam.acquire.orchestrate import Devices
    from procam.acquire.rig import RigProjector, capture_rig_pose

    capture_rig_pose(project / name, [RigProjector("left"), RigProjector("right")],
                     Devices(virtual=True, seed=seed, proj_size=(256, 144), cam_size=(320, 200)),
                     CaptureOptions(settle_s=0.0))
    return project / name


def test_the_exposure_check_is_the_capture_s_pre_flight_on_the_live_camera(client):
    """Devices: the pre-flight alone, before a capture: its levels are checks.preflight's on the projector's white,
    black and white again as the virtual camera sees them (same scene, same noise), said in words; a board that is
    not the one in view is refused as the capture refuses it."""
    from procam.acquire import checks
    from procam.acquire.cameras import VirtualLiveCamera
    from procam.board.corners import detect_corners

    devices = client.app.state.procam.devices
    j = _run(client, "/api/exposure")
    assert j["state"] == "done", j
    r = j["result"]
    assert r["ok"] and r["levels"]["region"] == "board" and r["levels"]["board_found"]
    assert r["lines"][0].startswith("pre-flight: white ") and "of full scale on the board" in r["lines"][0]
    w, h = devices.projector_size
    live = VirtualLiveCamera(devices.scene, seed=devices.seed)  # the app's live camera, as it was before the check
    w1, b, w2 = (live.grab(np.full((h, w), v, np.uint8)).image for v in (255, 0, 255))
    want = checks.preflight(w1, b, w2, board_corners=detect_corners(w1, (10, 6)))
    for key in ("white_level", "dark_level", "contrast", "white_saturated", "region_fraction"):
        assert r["levels"][key] == pytest.approx(want.to_dict()[key], abs=1e-9), key
    assert r["lines"][0] == (f"pre-flight: white {want.white_level:.0%} of full scale on the board "
                             f"({want.white_saturated:.1%} saturated), black {want.dark_level:.0%}, contrast "
                             f"{want.contrast:.0%}")
    # a board of 12x8 inner corners is not the one in view: refused with the capture's own words
    client.post("/api/board", headers=H, json={"cols": 12, "rows": 8, "square": 24})
    j = _run(client, "/api/exposure")
    assert j["state"] == "failed" and "12x8 inner corners not found in the pre-flight white frame" in j["error"]


def test_the_rig_steps_refuse_what_procam_knows_is_wrong(client):
    project = Path(client.app.state.procam.project.root)
    for path in ("/api/rig/calibrate", "/api/rig/blend"):
        r = client.post(path, headers=H, json={})
        assert r.status_code == 400 and "no rig pose yet: capture one" in r.json()["error"], path
    for spec, words in (("left", "at least two projectors"), ("a,b,c", "the virtual rig has two projectors"),
                        ("left,left", "unique"), ("9x,y", "device name"), (7, "NAME=DISPLAY")):
        r = client.post("/api/rig/capture", headers=H, json={"projectors": spec})
        assert r.status_code == 400 and words in r.json()["error"] and "\n" not in r.json()["error"], spec
    assert client.get("/api/state", headers=H).json()["job"] is None
    # a rig pose whose capture did not finish (a cancelled or failed projector: no rig.json)
    (project / "rig1" / "left").mkdir(parents=True)
    client.app.state.procam.project.state["rig"] = {"name": "rig1", "projectors": ["left", "right"], "verdicts": {}}
    for path in ("/api/rig/calibrate", "/api/rig/blend"):
        r = client.post(path, headers=H, json={})
        assert r.status_code == 400 and "rig1 was not captured whole (no rig.json)" in r.json()["error"], path
    # a projector whose instant verdict is degenerate: not calibrated
    _small_rig_pose(project, "rig2")
    client.app.state.procam.project.state["rig"] = {"name": "rig2", "projectors": ["left", "right"],
                                                    "verdicts": {"left": "good", "right": "degenerate"}}
    r = client.post("/api/rig/calibrate", headers=H, json={})
    assert r.status_code == 400 and "projector right is degenerate; turn the board" in r.json()["error"]
    assert not (project / "rig-calib.json").exists()
    assert rig_next_name(client) == "rig3"  # a new capture never goes over an earlier (or unfinished) one


def rig_next_name(client):
    from procam.app.rig import next_rig_name

    return next_rig_name(client.app.state.procam.project)


def test_blend_masks_sum_to_one_where_the_projectors_overlap(client):
    """The blend of the project's rig pose written into blend/ is procam blend's (rig.blend.blend_masks on the
    decoded maps, exactly): at camera pixels both projectors light, alpha_left at the left projector's pixel +
    alpha_right at the right's is 1 (median); a file of the user's in blend/ stops the step with nothing written."""
    from procam import capture, decode
    from procam.rig.blend import blend_masks

    project = Path(client.app.state.procam.project.root)
    pose = _small_rig_pose(project)
    client.app.state.procam.project.state["rig"] = {"name": "rig1", "projectors": ["left", "right"],
                                                    "verdicts": {"left": "weak", "right": "weak"}}
    (project / "blend").mkdir()
    (project / "blend" / "alpha_right.png").write_bytes(b"my own picture")
    j = _run(client, "/api/rig/blend")
    assert j["state"] == "failed" and "alpha_right.png: a file procam did not write" in j["error"]
    assert sorted(p.name for p in (project / "blend").iterdir()) == ["alpha_right.png"]
    assert (project / "blend" / "alpha_right.png").read_bytes() == b"my own picture"
    (project / "blend" / "alpha_right.png").unlink()
    j = _run(client, "/api/rig/blend")
    assert j["state"] == "done", j
    assert sorted(j["result"]["written"]) == ["blend/alpha_left.png", "blend/alpha_right.png", "blend/blend.npz",
                                              "blend/overlap_left.png", "blend/overlap_right.png"]
    npz = np.load(project / "blend" / "blend.npz")
    alpha = {n: npz[f"alpha_{n}"].astype(np.float64) for n in ("left", "right")}
    assert all(0.1 < j["result"]["overlap"][n] < 0.9 for n in alpha)
    maps, sizes, valid = {}, {}, {}
    for p in capture.read_rig_pose(pose).pairs:
        cap = capture.load_capture(p.folder)
        d = decode.decode(cap.stack, cap.pattern_set, extras=False)
        maps[p.projector], valid[p.projector] = (d.col, d.row), d.valid_col & d.valid_row
        sizes[p.projector] = (cap.pattern_set.width, cap.pattern_set.height)
    want = blend_masks(maps, sizes)  # what procam blend makes of this rig pose: the app wrote exactly that
    for n in alpha:
        assert np.array_equal(npz[f"alpha_{n}"], want.alpha[n].astype(np.float32))
        assert np.array_equal(npz[f"overlap_{n}"], want.overlap[n])
    both = valid["left"] & valid["right"]
    assert both.sum() > 500
    total = sum(alpha[n][np.round(maps[n][1][both]).astype(int), np.round(maps[n][0][both]).astype(int)]
                for n in alpha)
    assert np.median(np.abs(total - 1)) < 0.02  # the board's edges in this pose pull the tails (docs/rigs.md)
    import cv2

    png = cv2.imread(str(project / "blend" / "alpha_left.png"), cv2.IMREAD_UNCHANGED)
    assert png.dtype == np.uint16 and np.array_equal(png, np.round(npz["alpha_left"].astype(np.float64) * 65535))


@pytest.mark.slow
def test_the_rig_captured_and_calibrated_in_the_app_meets_the_simulator_s_truth(client):
    """More projectors on the virtual rig (projectors 640x360, the app's 1280x800 camera): one rig pose captured
    one projector after another, calibrated (each projector's f_p within 3 sigma of the truth, or 2 %), the rig's
    files written as procam calibrate writes them, and its blend masks."""
    from procam.io import load_rig_calibration
    from procam.io.files import procam_wrote

    project = Path(client.app.state.procam.project.root)
    assert client.post("/api/devices", headers=H, json={"projector_size": [640, 360]}).status_code == 200
    j = _run(client, "/api/rig/capture", {"projectors": "left,right"})
    assert j["state"] == "done", j
    assert j["result"]["rig"] == "rig1" and set(j["result"]["verdicts"]) == {"left", "right"}
    assert all(v in ("good", "weak") for v in j["result"]["verdicts"].values()), j["result"]["lines"]
    assert j["result"]["checks"] == ["rig1/left.check.png", "rig1/right.check.png"]
    assert [line.split(":")[0] for line in j["result"]["lines"] if ": pre-flight: white" in line] == ["left", "right"]
    assert json.loads((project / "rig1" / "rig.json").read_text())["projectors"] == ["left", "right"]
    j = _run(client, "/api/rig/calibrate")
    assert j["state"] == "done", j
    r = j["result"]
    assert r["trusted"] and r["written"] == ["rig-calib.json", "rig-calib.yml", "rig-calib.png", "rig-calib.html"]
    truth = json.loads((project / "rig1" / "truth.json").read_text())["devices"]
    rc = load_rig_calibration(project / "rig-calib.json")
    for name in ("left", "right"):
        d = rc.device(name)
        f, sf, f_true = d.device.K[0, 0], d.std["f"], truth[name]["f"]
        assert abs(f - f_true) < max(3 * sf, 0.02 * f_true), (name, f, sf, f_true)
        assert r["devices"][name]["f"] == pytest.approx(f)
    base = np.linalg.norm(np.subtract(truth["left"]["center"], truth["right"]["center"]))
    assert abs(rc.relative["left->right"].baseline / base - 1) < 0.02
    assert all(procam_wrote(project / n) for n in r["written"])
    s = client.get("/api/state", headers=H).json()
    assert s["state"]["rig_calibration"] == {"verdict": r["verdict"], "trusted": True}
    assert s["files"]["rig_calibration"] == "rig-calib.json" and s["files"]["rig_report"] == "rig-calib.html"
    j = _run(client, "/api/rig/blend")
    assert j["state"] == "done" and "blend/blend.npz" in j["result"]["written"], j


def test_a_cancelled_rig_capture_is_no_rig_pose(client):
    """Cancel stops the rig capture at its next step: no rig.json, the project has no rig pose, nothing goes on."""
    project = Path(client.app.state.procam.project.root)
    r = client.post("/api/rig/capture", headers=H, json={})
    assert r.status_code == 202, r.text
    assert client.post(f"/api/jobs/{r.json()['id']}/cancel", headers=H, json={}).status_code == 200
    j = job_result(client, r.json(), H)
    assert j["state"] == "cancelled" and j["error"] == "rig capture cancelled"
    assert not list(project.rglob("rig.json")) and not list(project.rglob("*.png"))
    assert client.get("/api/state", headers=H).json()["rig"] is None
    r = client.post("/api/rig/calibrate", headers=H, json={})
    assert r.status_code == 400 and "no rig pose yet" in r.json()["error"]


def test_turning_the_virtual_board_never_waits_for_a_frame(client):
    """A click on turn answers while the camera is busy with a frame (the lock held here, as a slow frame holds it);
    the live camera shows the turned board from its next frame on (benchmarks/app.py found 240 ms before)."""
    import threading

    devices = client.app.state.procam.devices
    before = devices.scene.R_board.copy()
    answered = {}

    def click():
        answered["status"] = client.post("/api/devices", headers=H, json={"turn": 10}).status_code

    with devices.lock:  # a frame in progress
        t = threading.Thread(target=click)
        t.start()
        t.join(5)
        assert answered.get("status") == 200
    assert not np.allclose(devices.scene.R_board, before)
    client.get("/api/preview", headers=H)
    assert devices._live.scene.R_board == pytest.approx(devices.scene.R_board)
