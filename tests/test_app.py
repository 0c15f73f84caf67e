"""procam app (issue 37): the guided calibration in a browser.

API-level tests drive the server with starlette's TestClient on the virtual devices (the simulator); the browser
tests drive the page in the system's Chromium through Playwright (skipped with a reason where either is absent).
The whole virtual flow in the browser is slow (a rendered capture); a smoke test of the page runs by default.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import threading
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
from conftest import job_result

pytest.importorskip("starlette", reason="the app's extra is not installed (pip install \".[app]\")")
pytest.importorskip("uvicorn", reason="the app's extra is not installed (pip install \".[app]\")")

TOKEN = "test-token-0123456789"
BASE = "http://127.0.0.1:8000"
H = {"X-Procam-Token": TOKEN}


def _client(folder, **kw):
    from starlette.testclient import TestClient

    from procam import app

    return TestClient(app.make(folder, virtual=True, token=TOKEN, **kw), base_url=BASE)


@pytest.fixture
def client(tmp_path):
    c = _client(tmp_path / "project")
    yield c
    from procam import app

    app.shutdown(c.app, 120)


def _advice(c):
    """A live-view frame (JSON) whose advice is of that very frame (the advisor runs beside the frames)."""
    p = c.get("/api/preview", headers=H).json()
    c.app.state.procam.live.wait(30)
    return {**p, "advice": c.app.state.procam.live.latest}


# ---------------------------------------------------------------------------------------------------------------
# security
# ---------------------------------------------------------------------------------------------------------------
def test_every_request_without_the_token_is_refused(client):
    project = Path(client.app.state.procam.project.root)
    fresh = (project / "procam-app.json").read_bytes()  # written when the folder became a project
    (project / "mine.txt").write_text("secret")
    gets = ["/", "/api/state", "/api/preview", "/static/app.js", "/files/mine.txt", "/api/jobs/1"]
    posts = ["/api/board", "/api/devices", "/api/camera", "/api/capture", "/api/calibrate", "/api/world",
             "/api/export", "/api/jobs/1/cancel", "/api/exposure", "/api/rig/capture", "/api/rig/calibrate",
             "/api/rig/blend"]
    for bad in ({}, {"X-Procam-Token": "wrong"}, {"X-Procam-Token": TOKEN[:-1]}):
        for path in gets:
            r = client.get(path, headers=bad)
            assert r.status_code == 403 and r.text.startswith("refused: no valid token"), (path, bad, r.text)
        for path in posts:
            r = client.post(path, headers=bad, json={"cols": 5, "rows": 4, "square": 10})
            assert r.status_code == 403, (path, bad)
    assert client.get("/?token=wrong").status_code == 403
    assert not (project / "board.svg").exists() and (project / "procam-app.json").read_bytes() == fresh
    # with the token: the page (in the query, as the printed address has it) and the API (in the header)
    assert client.get(f"/?token={TOKEN}").status_code == 200
    assert client.get("/api/state", headers=H).json()["root"] == str(project)
    assert client.get(f"/files/mine.txt?token={TOKEN}").text == "secret"


def test_a_foreign_host_is_refused(client):
    """DNS rebinding: a page of evil.example whose name now points at 127.0.0.1 sends Host: evil.example."""
    state = Path(client.app.state.procam.project.root) / "procam-app.json"
    fresh = state.read_bytes()
    for host in ("evil.example", "evil.example:8000", "127.0.0.1.evil.example:8000", ""):
        r = client.get("/api/state", headers={**H, "Host": host})
        assert r.status_code == 400 and "root" not in r.text, host
        r = client.post("/api/board", headers={**H, "Host": host}, json={"cols": 5, "rows": 4, "square": 10})
        assert r.status_code == 400, host
    assert state.read_bytes() == fresh
    for host in ("127.0.0.1:8000", "localhost:8000", "[::1]:8000"):
        assert client.get("/api/state", headers={**H, "Host": host}).status_code == 200


def test_a_post_from_a_foreign_origin_is_refused(client):
    """A cross-site request from another page the user has open: refused even with the token."""
    body = {"cols": 5, "rows": 4, "square": 10}
    state = Path(client.app.state.procam.project.root) / "procam-app.json"
    fresh = state.read_bytes()
    for headers in ({"Origin": "http://evil.example"}, {"Origin": "http://127.0.0.1:9999"},
                    {"Origin": "null"}, {"Sec-Fetch-Site": "cross-site"}):
        r = client.post("/api/board", headers={**H, **headers}, json=body)
        assert r.status_code == 403 and "another site" in r.text, headers
    assert state.read_bytes() == fresh
    r = client.post("/api/board", headers={**H, "Origin": BASE, "Sec-Fetch-Site": "same-origin"}, json=body)
    assert r.status_code == 200 and r.json()["board"] == {"cols": 5, "rows": 4, "square": 10.0}


def test_paths_outside_the_project_are_refused(client, tmp_path):
    project = Path(client.app.state.procam.project.root)
    secret = tmp_path / "secret.json"
    secret.write_text('{"K": "secret"}')
    (project / "link.json").symlink_to(secret)
    (project / "inside").mkdir()
    for name in ("link.json", "inside/../../secret.json", "%2e%2e/secret.json", "..%2fsecret.json",
                 "%2Ftmp%2Fsecret.json", "inside/%2e%2e/%2e%2e/secret.json"):
        r = client.get(f"/files/{name}", headers=H)
        assert r.status_code in (400, 404) and "secret" not in r.text.replace("secret.json", ""), (name, r.text)
    for name in ("../secret.json", str(secret), "link.json"):
        r = client.post("/api/camera", headers=H, json={"action": "file", "name": name})
        assert r.status_code == 400 and "outside the project folder" in r.json()["error"] or \
            "inside the project folder" in r.json()["error"], (name, r.text)
    assert client.get("/api/state", headers=H).json()["state"]["camera_file"] is None
    # a page in the project folder (the report, or anything dropped there) is shown as a sandbox of its own
    (project / "page.html").write_text("<script>fetch('/api/state')</script>")
    r = client.get(f"/files/page.html?token={TOKEN}")
    assert r.status_code == 200 and "sandbox allow-scripts" in r.headers["content-security-policy"]
    assert r.headers["x-content-type-options"] == "nosniff"


# ---------------------------------------------------------------------------------------------------------------
# the steps
# ---------------------------------------------------------------------------------------------------------------
def test_the_board_is_checked_and_printed_at_true_scale(client):
    project = Path(client.app.state.procam.project.root)
    for body, field in (({"cols": 2, "rows": 6, "square": 24}, "columns"), ({"cols": 10, "rows": 6, "square": -1},
                        "square"), ({"cols": 10.5, "rows": 6, "square": 24}, "cols"),
                        ({"cols": 10, "rows": 6, "square": "24"}, "square"), ({"cols": 10, "rows": 6}, "square")):
        r = client.post("/api/board", headers=H, json=body)
        assert r.status_code == 400 and field in r.json()["error"] and "\n" not in r.json()["error"], body
    r = client.post("/api/board", headers=H, content=b"{not json")
    assert r.status_code == 400 and "not JSON" in r.json()["error"]
    assert sorted(p.name for p in project.iterdir()) == ["procam-app.json"]  # nothing half-written
    assert json.loads((project / "procam-app.json").read_text())["board"] == {"cols": 10, "rows": 6, "square": 24.0}
    r = client.post("/api/board", headers=H, json={"cols": 9, "rows": 6, "square": 20})
    assert r.status_code == 200 and r.json()["file"] == "board.svg"
    svg = ET.parse(project / "board.svg").getroot()
    ns = "{http://www.w3.org/2000/svg}"
    assert svg.get("width") == f"{(9 + 3) * 20}mm"  # 10 squares and a square of margin each side
    squares = [r for r in svg.iter(f"{ns}rect") if r.get("width") == "20"]
    assert len(squares) == (10 * 7 + 1) // 2  # 10 x 7 squares, every other one black, the top-left black
    xs = sorted({float(r.get("x")) for r in squares})
    assert np.allclose(np.diff(xs), 20) and xs[0] == 20
    words = " ".join(t.text for t in svg.iter(f"{ns}text"))
    assert "9x6 inner corners (10 x 7 squares), square 20 mm" in words and "100 %" in words
    from procam.io.files import procam_wrote

    assert procam_wrote(project / "board.svg")
    state = json.loads((project / "procam-app.json").read_text())
    assert state["format"] == "procam-app-project" and state["board"] == {"cols": 9, "rows": 6, "square": 20.0}


def test_a_file_procam_did_not_write_is_never_overwritten(client):
    project = Path(client.app.state.procam.project.root)
    (project / "board.svg").write_text("<svg>the user's own drawing</svg>")
    r = client.post("/api/board", headers=H, json={"cols": 9, "rows": 6, "square": 20})
    assert r.status_code == 400 and "procam did not write" in r.json()["error"]
    assert (project / "board.svg").read_text() == "<svg>the user's own drawing</svg>"


def test_a_step_does_not_go_on_with_what_procam_knows_is_wrong(client):
    project = Path(client.app.state.procam.project.root)
    r = client.post("/api/calibrate", headers=H, json={})
    assert r.status_code == 400 and "no projector pose yet" in r.json()["error"]
    for path, body in (("/api/world", {}), ("/api/export", {"formats": ["blender"]})):
        r = client.post(path, headers=H, json=body)
        assert r.status_code == 400 and "calibrate first" in r.json()["error"], path
    # a pose whose instant verdict is degenerate is not calibrated
    (project / "pose1").mkdir()
    (project / "pose1" / "capture.json").write_text("{}")
    client.app.state.procam.project.state["pose"] = {"name": "pose1", "verdict": "degenerate"}
    r = client.post("/api/calibrate", headers=H, json={})
    assert r.status_code == 400 and "pose1 is degenerate: turn the board" in r.json()["error"]
    assert client.get("/api/state", headers=H).json()["job"] is None and not (project / "calib.json").exists()
    # a calibration file from before, but the latest calibration was not trusted (not written): nothing goes on
    _truth_calibration(project)
    client.app.state.procam.project.state["calibration"] = {"verdict": "degenerate", "trusted": False}
    for path, body in (("/api/world", {}), ("/api/export", {"formats": ["blender"]})):
        r = client.post(path, headers=H, json=body)
        assert r.status_code == 400 and "latest calibration is degenerate and was not written" in r.json()["error"]
    assert not (project / "export").exists()


def test_the_camera_from_photos_and_a_reopened_project_continues_with_it(tmp_path):
    """Camera step: a photo calibrates the camera (camera.json, f within the simulator's
    truth); the app stopped and started again on the folder uses that camera (its advice names it)."""
    from procam import io
    from procam.acquire.cameras import demo_scene

    folder = tmp_path / "project"
    c = _client(folder)
    assert c.post("/api/board", headers=H, json={"cols": 10, "rows": 6, "square": 24}).status_code == 200
    r = c.post("/api/camera", headers=H, json={"action": "photo"})
    assert r.status_code == 202, r.text
    j = job_result(c, r.json(), H)
    assert j["state"] == "done", j
    r = j["result"]
    assert r["photos"] == ["camera/photo01.png"]
    assert r["file"] == "camera.json" and r["enough"] and r["f_std"] < 0.005 * r["f"]
    assert 0.05 < r["coverage"] < 0.5 and len(c.get("/api/state", headers=H).json()["state"]["photos"]["outlines"]) == 1
    f_true = demo_scene((1920, 1080)).K_cam[0][0]
    cam = io.load_camera_intrinsics(folder / "camera.json")
    assert abs(cam.K[0, 0] - f_true) < max(3 * r["f_std"], 0.002 * f_true)
    c.close()
    # started again
    c2 = _client(folder)
    s = c2.get("/api/state", headers=H).json()
    assert s["state"]["camera_file"] == "camera.json" and s["photos"] == ["photo01.png"]
    assert s["state"]["board"] == {"cols": 10, "rows": 6, "square": 24.0}
    advice = _advice(c2)["advice"]
    assert advice["intrinsics"] == "intrinsics from camera.json" and len(advice["corners"]) == 60
    r = c2.post("/api/camera", headers=H, json={"action": "none"})
    assert r.json()["camera_file"] is None


def test_the_live_view_shows_the_board_with_its_corners_and_advice(client):
    from procam.board import corners as _corners

    client.post("/api/board", headers=H, json={"cols": 10, "rows": 6, "square": 24})
    p = _advice(client)
    assert p["advice"]["of_frame"] == p["frame"] == 1
    import base64

    import cv2

    jpeg = base64.b64decode(p["image"].split(",", 1)[1])
    img = cv2.imdecode(np.frombuffer(jpeg, np.uint8), cv2.IMREAD_GRAYSCALE)
    assert img.shape == (800, 1280)
    found, _ = _corners.find_corners([img], (10, 6))
    a = p["advice"]
    assert a["state"] in ("adjust", "good", "ready") and a["message"]
    assert np.abs(np.asarray(a["corners"]) - found.reshape(-1, 2)).max() < 1.0  # the corners drawn are the board's
    # the virtual board turns when told, and the advice follows
    before = a["camera"]["nu"]
    assert client.post("/api/devices", headers=H, json={"turn": 10}).status_code == 200
    after = _advice(client)["advice"]["camera"]["nu"]
    assert abs(abs(after - before) - 10) < 1.5
    r = client.post("/api/devices", headers=H, json={"turn": 90})
    assert r.status_code == 400 and "-45 to 45" in r.json()["error"]


def _truth_calibration(folder):
    """The virtual rig's own calibration (the simulator's truth) written as the project's calib.json."""
    from procam import io, simulate
    from procam.acquire.cameras import VIRTUAL_POSES, demo_scene

    calib = simulate.truth_calibration(demo_scene((1920, 1080), VIRTUAL_POSES[0]))
    io.save_calibration(calib, Path(folder) / "calib.json")
    return io.load_calibration(Path(folder) / "calib.json")


def test_export_writes_the_calibration_for_the_next_tools(client):
    from procam import export

    project = Path(client.app.state.procam.project.root)
    calib = _truth_calibration(project)
    for body, words in (({"formats": ["maya"]}, "export formats"), ({"formats": "blender"}, "export formats"),
                        ({"formats": ["blender"], "near": 10, "far": 5}, "near < far"),
                        ({"formats": ["blender"], "near": "x"}, "export near"),
                        ({"formats": ["opengl"], "near": 1, "far": 1.0000000000000002}, "hardly beyond near")):
        r = client.post("/api/export", headers=H, json=body)
        assert r.status_code == 400 and words in r.json()["error"], body
    assert not (project / "export").exists()
    r = client.post("/api/export", headers=H, json={"formats": ["blender", "yaml"], "near": 100, "far": 10000})
    assert r.status_code == 202
    j = job_result(client, r.json(), H)
    assert j["state"] == "done", j
    assert {"export/blender.json", "export/blender.py", "export/calib.yml"} <= set(j["result"]["written"])
    doc = json.loads((project / "export" / "blender.json").read_text())
    fresh = export.blender_document(calib, unit="mm", near_m=0.1, far_m=10.0)
    assert doc["devices"] == json.loads(json.dumps(fresh["devices"]))
    assert client.get("/api/state", headers=H).json()["exports"] == sorted(j["result"]["written"])
    r = client.get(f"/files/export/blender.json?token={TOKEN}&download=1")
    assert r.content == (project / "export" / "blender.json").read_bytes()
    assert r.headers["content-disposition"].startswith("attachment")
    # a file of the user's in the way: the job fails with its one line and the file keeps every byte
    (project / "export" / "unity.json").write_text('{"mine": true}')
    j = job_result(client, client.post("/api/export", headers=H, json={"formats": ["unity"]}).json(), H)
    assert j["state"] == "failed" and "procam did not write" in j["error"]
    assert (project / "export" / "unity.json").read_text() == '{"mine": true}'


@pytest.mark.slow
def test_a_cancelled_capture_leaves_no_pose(client):
    project = Path(client.app.state.procam.project.root)
    client.post("/api/board", headers=H, json={"cols": 10, "rows": 6, "square": 24})
    job = client.post("/api/capture", headers=H, json={}).json()
    t0 = time.monotonic()
    while client.get(f"/api/jobs/{job['id']}", headers=H).json()["done"] < 3:
        assert time.monotonic() - t0 < 120
        time.sleep(0.05)
    for path, body in (("/api/devices", {"pose": 1}), ("/api/board", {"cols": 9, "rows": 6, "square": 24}),
                       ("/api/capture", {}), ("/api/camera", {"action": "none"})):
        r = client.post(path, headers=H, json=body)  # answered at once, not after the capture
        assert r.status_code == 409 and "the capture is running" in r.json()["error"] or \
            "the capture is still running" in r.json()["error"], (path, r.text)
    assert client.get("/api/preview", headers=H).json() == {"busy": True}
    assert client.get("/api/jobs/x", headers=H).status_code == 400
    assert client.post(f"/api/jobs/{job['id']}/cancel", headers=H, json={}).status_code == 200
    j = job_result(client, job, H)
    assert j["state"] == "cancelled" and j["error"] == "capture cancelled"
    assert sorted(p.name for p in project.iterdir()) == ["board.svg", "procam-app.json"]  # no pose, no partial one
    assert client.get("/api/state", headers=H).json()["state"]["pose"] is None
    assert client.post("/api/calibrate", headers=H, json={}).status_code == 400


def test_the_job_runner_reports_cancels_and_refuses_a_second_job():
    from procam.app.jobs import Busy, Jobs
    from procam.errors import ProcamError

    jobs = Jobs()
    go = threading.Event()

    def slow(job):
        for k in range(1000):
            job.step(k, 1000, f"step {k}")
            go.wait(0.01)
        return {"never": True}

    job = jobs.start("capture", slow)
    with pytest.raises(Busy, match="the capture is still running"):
        jobs.start("calibrate", lambda j: {})
    t0 = time.monotonic()
    while job.done < 2:  # running, and reporting
        assert time.monotonic() - t0 < 10
        time.sleep(0.01)
    job.cancel()
    jobs.wait(5)
    assert job.state == "cancelled" and job.result is None and 0 < job.done < 999
    j2 = jobs.start("calibrate", lambda j: (_ for _ in ()).throw(ProcamError("pose1: no board found")))
    jobs.wait(5)
    assert (j2.state, j2.error) == ("failed", "pose1: no board found")
    j3 = jobs.start("export", lambda j: 1 / 0)
    jobs.wait(5)
    assert j3.state == "failed" and j3.error.startswith("internal error (ZeroDivisionError")
    j4 = jobs.start("world check", lambda j: {"rms_px": float("nan"), "per": [1.5, float("inf")], "n": 3})
    jobs.wait(5)
    assert j4.to_dict()["state"] == "done" and j4.to_dict()["result"] == {"rms_px": None, "per": [1.5, None], "n": 3}
    json.dumps(j4.to_dict(), allow_nan=False)  # what the page gets is JSON


# ---------------------------------------------------------------------------------------------------------------
# the command
# ---------------------------------------------------------------------------------------------------------------
def test_procam_app_without_its_extra_says_how_to_install_it(tmp_path, monkeypatch):
    import importlib.util

    from conftest import run_cli

    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == "starlette" else real(name, *a))
    code, _, err = run_cli(["app", tmp_path / "p", "--virtual", "--no-browser"])
    assert code == 2 and err.count("\n") == 1 and 'pip install "procam[app]"' in err and "starlette" in err
    assert not (tmp_path / "p").exists()


def test_procam_app_checks_its_options(tmp_path):
    from conftest import run_cli

    (tmp_path / "file").write_text("x")
    for args, words in ((["--port", "70000"], "--port must be"), (["--camera", "opencv:1", "--virtual"], "leave it out"),
                        ([], "not a folder")):
        code, _, err = run_cli(["app", tmp_path / "file" if not args else tmp_path / "p", "--no-browser", *args])
        assert code == 2 and words in err and err.count("\n") == 1, (args, err)


def test_procam_app_listens_before_it_makes_the_project(tmp_path):
    """A port in use or an address of another machine is a one-line error naming the option, before the address is
    printed and before the project folder is made (it was exit 3 after the address, an empty folder left behind)."""
    import socket

    from conftest import run_cli

    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        code, out, err = run_cli(["app", tmp_path / "p", "--virtual", "--no-browser", "--port", str(port)])
    assert code == 2 and err.startswith(f"error: --port {port}: in use on 127.0.0.1") and err.count("\n") == 1, err
    assert "http://" not in out and not (tmp_path / "p").exists()
    for host in ("no-such-host.invalid", "192.0.2.1"):  # a name that does not resolve; a documentation address
        code, out, err = run_cli(["app", tmp_path / "p", "--virtual", "--no-browser", "--host", host])
        assert code == 2 and err.startswith(f"error: --host {host}: not an address") and err.count("\n") == 1, err
        assert "http://" not in out and not (tmp_path / "p").exists()
    # an IPv6 address is quoted where the message names it (it read "--host 2001:db8::7:" before)
    code, out, err = run_cli(["app", tmp_path / "p", "--virtual", "--no-browser", "--host", "2001:db8::7"])
    assert code == 2 and err.startswith("error: --host '2001:db8::7': not an address") and err.count("\n") == 1, err
    assert not (tmp_path / "p").exists()


def test_procam_app_says_who_can_reach_it():
    """Loopback addresses (IPv4 and IPv6) are this machine only; the URL of an IPv6 address has brackets, as the Host
    header the app then answers to; a wildcard address is every network, and answers to this machine's name and
    address (::1 was warned about as reachable; 0.0.0.0 refused every other machine's Host header)."""
    import socket

    from procam import app

    assert app.address("127.0.0.1") == ("127.0.0.1", app.LOCAL_HOSTS, False)
    assert app.address("localhost") == ("localhost", app.LOCAL_HOSTS, False)
    assert app.address("::1") == ("[::1]", app.LOCAL_HOSTS, False)
    name, hosts, reachable = app.address("0.0.0.0")
    assert (name, reachable) == ("127.0.0.1", True) and hosts[:3] == app.LOCAL_HOSTS
    assert socket.gethostname().lower() in hosts  # other machines reach it by its name, or its address:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        try:
            s.connect(("198.51.100.7", 9))  # any address off this machine: the route's source address
            assert s.getsockname()[0] in hosts
        except OSError:  # no IPv4 route at all
            pass
    assert app.address("::")[0] == "[::1]" and app.address("::")[2]
    assert app.address("0")[::2] == ("127.0.0.1", True)  # the socket's short form of 0.0.0.0 (the URL was http://0:)
    name, hosts, reachable = app.address("192.168.7.9")
    assert name == "192.168.7.9" and "192.168.7.9" in hosts and reachable
    assert app.address("fe80::1")[:1] == ("[fe80::1]",) and "[fe80::1]" in app.address("fe80::1")[1]


def test_procam_app_takes_only_its_own_project_folders(tmp_path):
    """A capture folder (or any folder of other files) is not a project: the app would have written beside the
    user's files; a new folder becomes one at once (its state file), an empty one too, and reopens."""
    from procam.app.project import Project
    from procam.errors import ProcamError

    cap = tmp_path / "pose1"
    cap.mkdir()
    (cap / "capture.json").write_text("{}")
    with pytest.raises(ProcamError, match="pose1: a capture folder, not a project the app made"):
        Project(cap)
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "notes.txt").write_text("x")
    with pytest.raises(ProcamError, match="a folder of other files"):
        Project(tmp_path / "mine")
    assert sorted(p.name for p in cap.iterdir()) == ["capture.json"]
    (tmp_path / "empty").mkdir()
    (tmp_path / "empty" / ".DS_Store").write_text("")
    for folder in (tmp_path / "new", tmp_path / "empty"):
        Project(folder)
        assert (folder / "procam-app.json").is_file()
        (folder / "calib.json").write_text("{}")
        assert Project(folder).root == folder.resolve()  # reopened: the app's own
    from conftest import run_cli

    code, out, err = run_cli(["app", cap, "--virtual", "--no-browser"])
    assert code == 2 and "a capture folder, not a project the app made" in err and "http://" not in out, err


@pytest.mark.parametrize("state, words", [
    ({"board": {"cols": "x"}}, "board cols: give a whole number"), ({"board": {"cols": 10}}, "board rows"),
    ({"board": [10, 6]}, "board cols"), ({"pose": "/tmp/pose1"}, "pose must be an object or null"),
    ({"calibration": 123}, "calibration must be an object"), ({"camera_file": ["x"]}, "camera_file must be a string"),
    ({"projector_size": [0, 5]}, "projector_size must be [width, height]"), ({"version": 99}, "version 99"),
])
def test_a_hand_edited_project_state_is_named_not_an_internal_error(tmp_path, state, words):
    """A board without its rows was an internal error (KeyError) at start; a pose that is a string broke every page
    later (AttributeError); version 99 was read as 1."""
    from procam.app.project import Project
    from procam.errors import ProcamError

    (tmp_path / "procam-app.json").write_text(json.dumps({"format": "procam-app-project", "version": 1, **state}))
    with pytest.raises(ProcamError, match=re.escape(words)) as e:
        Project(tmp_path)
    assert "procam-app.json" in str(e.value) and "\n" not in str(e.value)


def test_one_app_per_project_folder(tmp_path):
    """Two apps on one folder both wrote its state file; a second is now refused while the first runs, and a lock
    left by a process that no longer runs is taken over."""
    import subprocess
    import sys

    from procam.app.project import LOCK, Project
    from procam.errors import ProcamError

    first = Project(tmp_path / "p")
    first.hold()
    lock = tmp_path / "p" / LOCK
    assert lock.read_text() == str(os.getpid())
    with pytest.raises(ProcamError, match=f"another procam app \\(process {os.getpid()}\\) has this project open"):
        Project(tmp_path / "p").hold()
    first.release()
    assert not lock.exists()
    gone = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    lock.write_text(gone.stdout.strip())  # a process that has ended
    second = Project(tmp_path / "p")
    second.hold()
    assert lock.read_text() == str(os.getpid())
    second.release()


def test_procam_app_serves_its_page_and_stops_on_ctrl_c(tmp_path):
    """As a user starts it: the printed address (with its token) answers, one without the token is refused, Ctrl+C
    stops it with exit code 0 and says where the project is."""
    import signal
    import subprocess
    import sys
    import urllib.error
    import urllib.request

    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(Path(__file__).resolve().parents[1] / "src"),
                                                       os.environ.get("PYTHONPATH", "")]))
    proc = subprocess.Popen([sys.executable, "-c", "from procam.cli import main; main()", "app", str(tmp_path / "p"),
                             "--virtual", "--no-browser"], env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    try:
        line = proc.stdout.readline()
        url = re.search(r"(http://127\.0\.0\.1:\d+/)\?token=(\S+)", line)
        assert url, line
        t0 = time.monotonic()
        while True:
            try:
                with urllib.request.urlopen(url.group(0), timeout=5) as r:
                    page = r.read().decode()
                break
            except urllib.error.URLError:
                assert time.monotonic() - t0 < 20
                time.sleep(0.1)
        assert f'content="{url.group(2)}"' in page and "step-pose" in page
        with pytest.raises(urllib.error.HTTPError) as e:
            urllib.request.urlopen(url.group(1) + "api/state", timeout=5)
        assert e.value.code == 403
        e.value.close()
    finally:
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=60)
    assert proc.returncode == 0, err
    assert f"stopped; {tmp_path / 'p'} keeps everything" in out
    assert not (tmp_path / "p" / ".procam-app.lock").exists()  # the project given back


# ---------------------------------------------------------------------------------------------------------------
# in a real browser
# ---------------------------------------------------------------------------------------------------------------
CHROMIUM = os.environ.get("PROCAM_CHROMIUM") or shutil.which("chromium") or "/usr/bin/chromium"


@pytest.fixture
def served(tmp_path):
    """The app on the virtual devices, served by uvicorn on a free port in a thread: (url with token, folder)."""
    from procam import app

    folder = tmp_path / "project"
    s = app.Served(folder, TOKEN)
    yield s.url, folder
    s.stop()


@pytest.fixture
def page():
    """A Playwright page in the system's Chromium, and the console errors and uncaught exceptions it records."""
    sync_api = pytest.importorskip("playwright.sync_api",
                                   reason="Playwright is not installed (pip install \".[test]\")")
    if not Path(CHROMIUM).exists():
        pytest.skip(f"no Chromium at {CHROMIUM} (apt-get install chromium, or set PROCAM_CHROMIUM)")
    with sync_api.sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, headless=True, args=["--no-sandbox"])
        pg = browser.new_page(viewport={"width": 1400, "height": 1000}, accept_downloads=True)
        pg.problems = []
        # errors and uncaught exceptions are the page's; a warning can be the browser's own under load (a slow font,
        # an intervention), which one full run on a busy machine logged
        pg.on("console", lambda m: pg.problems.append(f"console.{m.type}: {m.text}") if m.type == "error" else None)
        pg.on("pageerror", lambda e: pg.problems.append(f"exception: {e}"))
        yield pg
        browser.close()


def _expect(pg, selector, words, seconds):
    """Wait until the element ``selector`` contains ``words`` (a locator: the page's CSP forbids eval)."""
    from playwright.sync_api import expect

    expect(pg.locator(selector)).to_contain_text(words, timeout=seconds * 1000)


def _shot(pg, folder, name):
    """A screenshot of the page, kept with the test's files (and in $PROCAM_APP_SCREENSHOTS when set)."""
    path = folder / f"{name}.png"
    pg.screenshot(path=str(path), full_page=True)
    if os.environ.get("PROCAM_APP_SCREENSHOTS"):
        shutil.copy(path, Path(os.environ["PROCAM_APP_SCREENSHOTS"]) / path.name)


def test_the_page_in_a_browser(served, page, tmp_path):
    """Smoke test: the page loads with its token, shows the live view with the board's corners, takes a board and
    offers it for printing, locks the steps that cannot go on yet; no console errors; without the token, refused."""
    url, folder = served
    page.goto(url.replace(TOKEN, "wrong"))
    assert "refused" in page.content()
    page.goto(url)
    page.fill("#board-cols", "2")
    page.click("#board-save")
    page.wait_for_selector("#error:not([hidden])")
    assert "columns of inner corners" in page.text_content("#error")
    assert [p for p in page.problems if "status of 403" not in p and "status of 400" not in p] == []
    page.problems.clear()  # the refused page and the refused board: the browser logs their status; nothing else
    page.reload()
    _expect(page, "#preview-fps", "frames/s", 20)
    assert page.locator("#calibrate-run").is_disabled() and page.locator("#export-run").is_disabled()
    assert "locked" in page.locator("#step-calibrate").get_attribute("class")
    page.fill("#board-cols", "10")
    page.click("#board-save")
    page.wait_for_selector("#board-svg:not([hidden])")
    assert page.locator("#error").is_hidden() and (folder / "board.svg").is_file()
    assert page.locator("#pose-capture").is_enabled()
    _expect(page, "#advice", re.compile(r"^(adjust|good|ready): "), 20)  # the advice of a frame, drawn
    _shot(page, tmp_path, "smoke")
    assert page.problems == [], page.problems


def test_a_photo_right_after_a_new_pose_is_taken_at_that_pose(served, page):
    """The page sends its changes in order: the board's pose chosen just before a photo applies to that photo, even
    when the pose's request is answered late (held here until the photo's would have run). Sent together, the photo's
    request could be handled first, and the photo taken at the pose before (seen once in the whole flow, under
    load)."""
    url, folder = served
    page.goto(url)
    page.fill("#board-cols", "10")
    page.fill("#board-rows", "6")
    page.fill("#board-square", "24")
    page.click("#board-save")
    page.wait_for_selector("#board-svg:not([hidden])")
    page.select_option("#virtual-pose", "0")
    page.click("#camera-photo")
    _expect(page, "#camera-status", "1 photo(s): f_c", 30)
    held = []

    def hold(route):
        held.append(route)

    page.route("**/api/devices**", hold)
    page.select_option("#virtual-pose", "3")
    page.click("#camera-photo")
    page.wait_for_timeout(1500)  # long enough for a photo request sent beside the held one to have been handled
    assert len(held) == 1 and len(list((folder / "camera").glob("photo*.png"))) == 1
    held[0].continue_()
    page.unroute("**/api/devices**", hold)
    _expect(page, "#camera-status", "2 photo(s): f_c", 30)
    first, second = ((np.min(o, axis=0), np.max(o, axis=0)) for o in
                     json.loads((folder / "procam-app.json").read_text())["photos"]["outlines"])
    assert np.abs(np.subtract(first, second)).max() > 20  # px, the board's extent: two poses, not one twice
    assert page.problems == [], page.problems


@pytest.mark.slow
def test_the_whole_virtual_flow_in_a_browser(served, page, tmp_path):
    """Devices (with the exposure check) -> Board -> Camera (4 photos) -> Projector pose -> Calibrate -> Check in the
    world -> Export -> More projectors, clicked through in Chromium on the virtual devices: the calibration's f_p and
    f_c within the simulator's truth, the world check holds, the exported Blender file is the calibration's, the
    rig's projectors within the truth and its blend masks written; a screenshot of every step; no console errors."""
    from playwright.sync_api import expect

    from procam import export, io

    url, folder = served
    shots = tmp_path / "screenshots"
    shots.mkdir()
    t0 = time.monotonic()
    page.goto(url)
    page.select_option("#devices-projector-size", "1024x576")
    _expect(page, "#devices-list", "1024x576", 10)
    _shot(page, shots, "1-devices")
    page.fill("#board-cols", "10")
    page.fill("#board-rows", "6")
    page.fill("#board-square", "24")
    page.click("#board-save")
    page.wait_for_selector("#board-svg:not([hidden])")
    page.click("#devices-exposure")  # the capture's pre-flight before the capture: levels and advice
    _expect(page, "#devices-exposure-verdict", "the exposure is fine for a capture", 60)
    _expect(page, "#devices-exposure-lines", "of full scale on the board", 5)
    _shot(page, shots, "2-board")
    for i in range(4):
        page.select_option("#virtual-pose", str(i))
        page.click("#camera-photo")
        _expect(page, "#camera-status", f"{i + 1} photo(s): f_c", 30)
    assert "enough" in page.text_content("#camera-status")
    _shot(page, shots, "3-camera")
    page.select_option("#virtual-pose", "0")
    page.click("#pose-capture")
    _expect(page, "#pose-verdict", "pose1: good", 180)
    expect(page.locator("#pose-check")).to_be_visible()
    _shot(page, shots, "4-pose")
    page.click("#calibrate-run")
    _expect(page, "#calibrate-verdict", "verdict: good", 120)
    assert "f (px)" in page.text_content("#calibrate-table") and "projector" in page.text_content("#calibrate-table")
    page.wait_for_selector("#calibrate-residuals:not([hidden])")
    _shot(page, shots, "5-calibrate")
    page.click("#world-run")
    _expect(page, "#world-verdict", "holds:", 120)
    _shot(page, shots, "6-world")
    page.click("#export-run")
    page.wait_for_selector("#export-files a[download='blender.json']", timeout=60000)
    _shot(page, shots, "7-export")
    seconds = time.monotonic() - t0
    # More projectors: the simulator's two-projector rig, one after the other; its calibration; the blend masks
    page.click("#rig-capture")
    _expect(page, "#rig-verdict", re.compile(r"^rig1: left (good|weak), right (good|weak)$"), 240)
    page.click("#rig-calibrate")
    _expect(page, "#rig-calibrate-verdict", re.compile(r"^rig calibration: (good|weak) - "), 120)
    assert "left" in page.text_content("#rig-devices") and "left->right" in page.text_content("#rig-relative")
    page.wait_for_selector("#rig-figure:not([hidden])")
    page.click("#rig-blend")
    _expect(page, "#rig-blend-status", "blend masks in blend/: left overlaps on", 120)
    page.wait_for_selector("#rig-blend-alpha img >> nth=1")
    _shot(page, shots, "8-rig")
    with page.expect_download() as dl:
        page.click("#export-files a[download='blender.json']")
    downloaded = tmp_path / "blender.json"
    dl.value.save_as(downloaded)
    # the calibration against the simulator's truth
    calib = io.load_calibration(folder / "calib.json")
    truth = json.loads((folder / "pose1" / "truth.json").read_text())
    f_p, f_c = calib.projector.K[0, 0], calib.camera.K[0, 0]
    assert abs(f_p - truth["projector"]["f"]) < max(3 * calib.std["f_p"], 0.01 * truth["projector"]["f"])
    assert abs(f_c - truth["camera"]["f"]) < 0.005 * truth["camera"]["f"]
    # the exported Blender file is the calibration's (and the download is the file in the project folder)
    doc = json.loads((folder / "export" / "blender.json").read_text())
    assert downloaded.read_bytes() == (folder / "export" / "blender.json").read_bytes()
    fresh = export.blender_document(calib, unit="mm", near_m=0.1, far_m=10.0)
    assert doc["format"] == "procam-blender" and doc["devices"] == json.loads(json.dumps(fresh["devices"]))
    assert (folder / "export" / "blender.py").is_file() and (folder / "calib.html").is_file()
    assert sorted(p.name for p in shots.iterdir()) == ["1-devices.png", "2-board.png", "3-camera.png", "4-pose.png",
                                                       "5-calibrate.png", "6-world.png", "7-export.png", "8-rig.png"]
    # the rig's calibration against the simulator's truth, and its blend masks in the project folder
    rc = io.load_rig_calibration(folder / "rig-calib.json")
    rig_truth = json.loads((folder / "rig1" / "truth.json").read_text())["devices"]
    for name in ("left", "right"):
        f, sf, f_true = rc.device(name).device.K[0, 0], rc.device(name).std["f"], rig_truth[name]["f"]
        assert abs(f - f_true) < max(3 * sf, 0.02 * f_true), (name, f, sf, f_true)
    assert {p.name for p in (folder / "blend").iterdir()} >= {"alpha_left.png", "alpha_right.png", "blend.npz"}
    assert page.problems == [], page.problems
    print(f"the whole virtual flow in the browser: {seconds:.1f} s")
