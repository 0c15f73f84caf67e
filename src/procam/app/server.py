"""The app's HTTP side: starlette routes over :mod:`procam.app.work`, and the guards every request passes.

Guards (in this order): the ``Host`` header must name this machine (:class:`TrustedHostMiddleware`: no DNS
rebinding); a request that says where it comes from (``Origin``, ``Sec-Fetch-Site``) must come from the app's own
page; and it must carry the session's token (``X-Procam-Token`` header, or ``token`` in the query for what the
page loads by URL: images, downloads).  A refused request gets 403 and one line.  Inputs are checked as the command
line checks them; a mistake is a 400 with the library's one line, a running job a 409.
"""

from __future__ import annotations

import base64
import secrets
from pathlib import Path

from starlette.applications import Starlette
from starlette.concurrency import run_in_threadpool
from starlette.middleware import Middleware
from starlette.middleware.trustedhost import TrustedHostMiddleware
from starlette.requests import Request
from starlette.responses import FileResponse, HTMLResponse, JSONResponse, PlainTextResponse
from starlette.routing import Route

from ..errors import ProcamError
from . import LOCAL_HOSTS, rig, work
from .devices import Devices
from .jobs import Busy, Jobs, error_line, results_carry_warnings
from .project import Project

STATIC = Path(__file__).with_name("static")
#: A project file shown in the browser (the report, a picture, an SVG) is a sandbox of its own: its scripts run (the
#: report's 3-D view) in an opaque origin, which can neither read the app's pages nor pass its guards.
FILES_POLICY = ("default-src 'none'; img-src 'self' data: blob:; style-src 'unsafe-inline'; "
                "script-src 'unsafe-inline'; sandbox allow-scripts")


class Guard:
    """ASGI middleware: the token, and the origin of a request that names one (see the module docstring)."""

    def __init__(self, app, token: str):
        self.app, self.token = app, token

    async def __call__(self, scope, receive, send):
        if scope["type"] != "http":
            return await self.app(scope, receive, send)
        request = Request(scope)
        why = self.refused(request)
        if why:
            return await PlainTextResponse(f"refused: {why}", status_code=403)(scope, receive, send)
        return await self.app(scope, receive, send)

    def refused(self, request: Request) -> str:
        """Why ``request`` is refused, or ""."""
        host = request.headers.get("host", "")
        origin = request.headers.get("origin")
        if origin is not None and origin != f"{request.url.scheme}://{host}":
            return f"a request from another site ({origin}); use the app's own page"
        if request.headers.get("sec-fetch-site") == "cross-site":
            return "a request from another site; use the app's own page"
        given = request.headers.get("x-procam-token") or request.query_params.get("token") or ""
        if not secrets.compare_digest(given.encode(), self.token.encode()):
            return "no valid token; open the address procam app printed (it carries the token)"
        return ""


class AppState:
    """What the routes share: the project, the devices, the jobs, the live view's advisor."""

    def __init__(self, project: Project, devices: Devices):
        self.project, self.devices = project, devices
        self.jobs = Jobs()
        self.live = work.LiveView()


def _error(e: Exception) -> JSONResponse:
    """One line for the page: 409 while another job runs, 400 for the user's input (a ProcamError, an OS error
    naming the path), 500 for a bug (which the line asks to report)."""
    status = 409 if isinstance(e, Busy) else 400 if isinstance(e, (ProcamError, OSError)) else 500
    return JSONResponse({"error": error_line(e)}, status_code=status)


async def _body(request: Request) -> dict:
    try:
        body = await request.json()
    except ValueError:
        raise ProcamError("the request's body is not JSON") from None
    if not isinstance(body, dict):
        raise ProcamError("the request's body must be a JSON object")
    return body


def create_app(project: Project, devices: Devices, token: str, hosts=None) -> Starlette:
    """The ASGI app of ``project`` on ``devices``; every request must carry ``token``; ``hosts`` the names the app
    answers to (the `Host` header without its port; default: :data:`procam.app.LOCAL_HOSTS`)."""
    st = AppState(project, devices)

    def guarded(handler):
        async def route(request: Request):
            try:
                with results_carry_warnings():
                    return await handler(request)
            except Exception as e:  # noqa: BLE001 - every error is one line for the page
                return _error(e)
        return route

    async def index(request: Request):
        page = (STATIC / "index.html").read_text(encoding="utf-8")
        return HTMLResponse(page.replace("{{TOKEN}}", token),
                            headers={"Content-Security-Policy": "default-src 'self'; img-src 'self' data: blob:; "
                                     "style-src 'self'; script-src 'self'; frame-ancestors 'none'",
                                     "Referrer-Policy": "no-referrer", "Cache-Control": "no-store"})

    async def static(request: Request):
        name = request.path_params["name"]
        if name not in ("app.js", "app.css"):
            return PlainTextResponse("not found", status_code=404)
        return FileResponse(STATIC / name, headers={"Cache-Control": "no-store"})

    async def state(request: Request):
        s = project.summary()
        calib = work.saved_calibration(project) if project.file("calibration").is_file() else None
        running = st.jobs.running()
        return JSONResponse({**s, "devices": devices.describe(), "photos": [str(p.name) for p in work.photos(project)],
                             "calibration": work.describe_calibration(calib) if calib is not None else None,
                             "job": running.to_dict() if running else None, "rig": rig.summary(project)})

    def idle(what: str) -> None:
        """Refuse to change ``what`` while a job uses it (the board, the devices, the camera)."""
        running = st.jobs.running()
        if running is not None:
            raise Busy(f"the {running.kind} is running; change the {what} when it is done, or cancel it")

    async def set_board(request: Request):
        b = await _body(request)
        idle("board")
        project.set_board(b.get("cols"), b.get("rows"), b.get("square"))
        return JSONResponse({"board": project.state["board"], **work.board_svg(project)})

    async def set_devices(request: Request):
        b = await _body(request)
        idle("devices")
        if "projector_size" in b:
            size = b["projector_size"]
            if not (isinstance(size, list) and len(size) == 2 and all(isinstance(v, int) for v in size)):
                raise ProcamError(f"projector_size: give [width, height] in pixels, got {size!r}")
            devices.set_projector_size(size)
            project.state["projector_size"] = list(devices.projector_size)
            project.save()
        if "pose" in b:
            devices.set_pose(b["pose"])
        if "turn" in b or "tilt" in b:
            devices.move(b.get("turn", 0.0), b.get("tilt", 0.0))
        return JSONResponse(devices.describe())

    async def preview(request: Request):
        if st.jobs.running() is not None:
            return JSONResponse({"busy": True})
        jpeg, frame, advice = await run_in_threadpool(st.live.preview, project, devices)
        return JSONResponse({"image": "data:image/jpeg;base64," + base64.b64encode(jpeg).decode(), "frame": frame,
                             "advice": advice})

    async def camera(request: Request):
        b = await _body(request)
        idle("camera")
        action = b.get("action")
        if action == "photo":  # a grab and the camera's calibration from every photo so far: a job
            project.board()
            job = st.jobs.start("photo", lambda job: work.take_photo(project, devices, job))
            return JSONResponse(job.to_dict(), status_code=202)
        if action == "file":
            return JSONResponse(work.use_camera_file(project, b.get("name")))
        if action == "none":
            return JSONResponse(work.use_camera_file(project, None))
        raise ProcamError(f"camera action: give photo, file or none, got {action!r}")

    def start(kind, fn, ready):
        async def route(request: Request):
            ready()  # a step procam knows cannot go on is refused now, with its reason
            job = st.jobs.start(kind, lambda job: fn(job))
            return JSONResponse(job.to_dict(), status_code=202)
        return route

    capture = start("capture", lambda job: work.capture(job, project, devices, st.live.advising), project.board)
    world = start("world check", lambda job: work.check_world(job, project, devices),
                  lambda: work.need_calibration(project))

    def after_calibrate(job):
        result = work.calibrate(job, project)
        calib = work.saved_calibration(project) if result["written"] else None
        if calib is not None:
            st.live.advising.learn(calib, work.FILES["calibration"])
        return result

    calibrate = start("calibrate", after_calibrate, lambda: work.usable_pose(project))
    exposure = start("exposure check", lambda job: work.exposure_check(job, project, devices), project.board)
    rig_calibrate = start("rig calibration", lambda job: rig.calibrate(job, project), lambda: rig.usable_rig(project))
    rig_blend = start("blend", lambda job: rig.blend(job, project), lambda: rig.usable_rig(project, judged=False))

    async def rig_capture(request: Request):
        b = await _body(request)
        project.board()
        spec = b.get("projectors") or None
        rig.projectors(devices, spec)  # a wrong list is answered now, not by a failed job
        job = st.jobs.start("rig capture", lambda job: rig.capture(job, project, devices, spec))
        return JSONResponse(job.to_dict(), status_code=202)

    def job_of(request: Request):
        try:
            return st.jobs.get(int(request.path_params["job_id"]))
        except ValueError:
            raise ProcamError(f"job {request.path_params['job_id']!r}: give its number") from None

    async def job(request: Request):
        return JSONResponse(job_of(request).to_dict())

    async def cancel(request: Request):
        j = job_of(request)
        j.cancel()
        return JSONResponse(j.to_dict())

    async def export(request: Request):
        b = await _body(request)
        formats, near, far = b.get("formats"), b.get("near", 100.0), b.get("far", 10000.0)
        work.export_checked(project, formats, near, far)  # a mistake is answered now, not by a failed job
        job = st.jobs.start("export", lambda job: work.export(project, formats, near, far, job=job))
        return JSONResponse(job.to_dict(), status_code=202)

    async def files(request: Request):
        name = request.path_params["path"]
        if not work.safe_name(name):
            raise ProcamError(f"{name}: not a file name the app serves")
        path = project.path(name)
        if not path.is_file():
            return JSONResponse({"error": f"{name}: no such file in the project"}, status_code=404)
        download = request.query_params.get("download") == "1"
        return FileResponse(path, filename=path.name if download else None,
                            content_disposition_type="attachment" if download else "inline",
                            headers={"Cache-Control": "no-store", "X-Content-Type-Options": "nosniff",
                                     "Content-Security-Policy": FILES_POLICY})

    routes = [Route("/", index), Route("/static/{name}", static),
              Route("/api/state", guarded(state)), Route("/api/board", guarded(set_board), methods=["POST"]),
              Route("/api/devices", guarded(set_devices), methods=["POST"]),
              Route("/api/preview", guarded(preview)), Route("/api/camera", guarded(camera), methods=["POST"]),
              Route("/api/capture", guarded(capture), methods=["POST"]),
              Route("/api/calibrate", guarded(calibrate), methods=["POST"]),
              Route("/api/world", guarded(world), methods=["POST"]),
              Route("/api/export", guarded(export), methods=["POST"]),
              Route("/api/exposure", guarded(exposure), methods=["POST"]),
              Route("/api/rig/capture", guarded(rig_capture), methods=["POST"]),
              Route("/api/rig/calibrate", guarded(rig_calibrate), methods=["POST"]),
              Route("/api/rig/blend", guarded(rig_blend), methods=["POST"]),
              Route("/api/jobs/{job_id}", guarded(job)),
              Route("/api/jobs/{job_id}/cancel", guarded(cancel), methods=["POST"]),
              Route("/files/{path:path}", guarded(files))]
    middleware = [Middleware(TrustedHostMiddleware, allowed_hosts=list(hosts or LOCAL_HOSTS)), Middleware(Guard, token=token)]
    app = Starlette(routes=routes, middleware=middleware)
    app.state.procam = st
    return app

