"""``procam app``: the guided calibration in a browser (docs/app.md).

A local web server (starlette on uvicorn, the ``app`` extra: ``pip install "procam[app]"``) serves one page whose
sections are the steps -- Devices, Board, Camera, Projector pose, Calibrate, Check in the world, Export, More
projectors -- over the same library calls the command line makes (:mod:`procam.app.work`; the rig's in
:mod:`procam.app.rig`).  The project folder is the state (:mod:`procam.app.project`); long work runs in a thread
with progress and cancel (:mod:`procam.app.jobs`); the devices are the simulator's with ``virtual``
(:mod:`procam.app.devices`); the routes and their guards are :mod:`procam.app.server`.

Nothing here is imported by the rest of procam; starlette and uvicorn are imported only here.
"""

from __future__ import annotations

import secrets
import socket

from ..errors import ProcamError

#: What ``procam app`` says when the extra is missing.
INSTALL_HINT = 'the app needs its extra: pip install "procam[app]" (starlette and uvicorn)'


def need_extra() -> None:
    """Raise a one-line :class:`ProcamError` when starlette or uvicorn is missing."""
    import importlib.util

    missing = [m for m in ("starlette", "uvicorn") if importlib.util.find_spec(m) is None]
    if missing:
        raise ProcamError(f"{INSTALL_HINT}; missing: {', '.join(missing)}")


def new_token() -> str:
    """A random token for the session's URL (192 bits)."""
    return secrets.token_urlsafe(24)


def free_port(host: str) -> int:
    """A TCP port free on ``host`` now."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind((host, 0))
        return s.getsockname()[1]


def make(project_dir, *, virtual: bool, token: str, camera: str = "opencv:0", display=None, seed: int = 0,
         hosts=None):
    """The ASGI app of the project folder ``project_dir`` (created if missing) and its devices."""
    need_extra()
    from .devices import Devices
    from .project import Project
    from .server import LOCAL_HOSTS, create_app

    project = Project(project_dir)
    devices = Devices(virtual, camera=camera, display=display, seed=seed,
                      projector_size=project.state["projector_size"] if virtual else (1920, 1080))
    return create_app(project, devices, token, hosts=tuple(hosts or LOCAL_HOSTS))


def uvicorn_server(app, host: str, port: int):
    """A uvicorn server of ``app`` on ``host:port`` (not started: ``.run()``, or in a thread)."""
    import uvicorn

    return uvicorn.Server(uvicorn.Config(app, host=host, port=port, log_level="warning", access_log=False,
                                         lifespan="off"))


def shutdown(asgi, timeout: float = 60.0) -> None:
    """After the server stopped: cancel the running job and wait for it (a capture removes its partial folder),
    wait for the live view's advisor, close the camera."""
    st = asgi.state.procam
    job = st.jobs.running()
    if job is not None:
        job.cancel()
        st.jobs.wait(timeout)
    st.live.wait(timeout)
    st.devices.release()


class Served:
    """The app served by uvicorn on a free port of ``127.0.0.1`` in a background thread, on the virtual devices
    (tests, benchmarks, a notebook): ``url`` opens the page; :meth:`stop` ends it (then :func:`shutdown`)."""

    def __init__(self, project_dir, token: str, *, virtual: bool = True, timeout: float = 30.0):
        import threading
        import time

        self.port = free_port("127.0.0.1")
        self.asgi = make(project_dir, virtual=virtual, token=token)
        self.server = uvicorn_server(self.asgi, "127.0.0.1", self.port)
        self.thread = threading.Thread(target=self.server.run, daemon=True)
        self.thread.start()
        t0 = time.monotonic()
        while not self.server.started:
            if time.monotonic() - t0 > timeout or not self.thread.is_alive():
                self.stop()
                raise ProcamError(f"the app did not start within {timeout:g} s on 127.0.0.1:{self.port}")
            time.sleep(0.05)
        self.url = f"http://127.0.0.1:{self.port}/?token={token}"

    def stop(self, timeout: float = 120.0) -> None:
        self.server.should_exit = True
        self.thread.join(20)
        shutdown(self.asgi, timeout)

