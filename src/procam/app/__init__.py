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

#: The ``Host`` header names the app always answers to (this machine).
LOCAL_HOSTS = ("127.0.0.1", "localhost", "[::1]")

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


def host_option(host: str) -> str:
    """``--host HOST`` as a message names it: an IPv6 address quoted (``--host '::'``, not ``--host :::`` before the
    colon that follows it)."""
    return f"--host '{host}'" if ":" in host else f"--host {host}"


def listen(host: str, port: int) -> socket.socket:
    """A TCP socket bound to ``host:port`` (port 0: a free one) for :func:`uvicorn_server` ``.run(sockets=[it])``,
    bound before anything is written, so a port in use or an address of another machine is a one-line
    :class:`ProcamError` naming ``--host`` or ``--port`` (not a server that prints its address and stops)."""
    import errno

    try:
        family, _, _, _, address = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM,
                                                      flags=socket.AI_PASSIVE)[0]
    except (socket.gaierror, UnicodeError) as e:
        raise ProcamError(f"{host_option(host)}: not an address this machine can listen on ({e}); give one of its "
                          "addresses, e.g. 127.0.0.1 (this machine only) or 0.0.0.0 (every network)") from None
    sock = socket.socket(family, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)  # as uvicorn binds: a restart reuses the port
    try:
        sock.bind(address)
    except OSError as e:
        sock.close()
        if e.errno == errno.EADDRINUSE:
            raise ProcamError(f"--port {port}: in use on {host} (another program, or another procam app); choose "
                              "another port, or leave --port out for a free one") from None
        if e.errno == errno.EACCES:
            raise ProcamError(f"--port {port}: not allowed for this user (ports below 1024 need administrator "
                              "rights); choose 1024 to 65535, or leave --port out for a free one") from None
        if e.errno == errno.EADDRNOTAVAIL:
            raise ProcamError(f"{host_option(host)}: not an address of this machine; give one of its addresses, e.g. "
                              "127.0.0.1 (this machine only) or 0.0.0.0 (every network)") from None
        raise ProcamError(f"{host_option(host)} --port {port}: cannot listen there ({e.strerror})") from None
    sock.listen(128)  # a browser that connects as soon as the address is printed waits in the queue, not refused
    return sock


def address(host: str) -> tuple[str, tuple[str, ...], bool]:
    """What ``--host`` means for the page: ``(name in the URL, Host header names the app answers to, reachable
    from other machines)``.  A loopback address (``127.0.0.1``, ``::1``, ``localhost``) is this machine only; a
    wildcard (``0.0.0.0``, ``::``) every network, the URL then names the loopback address of its family."""
    import ipaddress

    try:  # a name or a short form ("0") as the socket reads it
        ip = ipaddress.ip_address(socket.getaddrinfo(host, None, type=socket.SOCK_STREAM, flags=socket.AI_PASSIVE)
                                  [0][4][0].split("%")[0])
    except (OSError, UnicodeError, ValueError, IndexError):
        ip = None
    if ip is not None and ip.is_unspecified:  # the names other machines reach this one by
        return ("127.0.0.1" if ip.version == 4 else "[::1]"), LOCAL_HOSTS + _own_names(), True
    literal = host.strip("[]").split("%")[0] == (ip.compressed if ip is not None else None) or host == "localhost"
    name = host if not literal or ip.version == 4 else f"[{ip.compressed}]"
    local = ip is not None and ip.is_loopback
    return name, tuple(dict.fromkeys(LOCAL_HOSTS + (name.lower(),))), not local


def _own_names() -> tuple[str, ...]:
    """This machine's host name, the addresses it resolves to and the address of its default route of each family
    (IPv6 in brackets, as a ``Host`` header has them)."""
    names = [socket.gethostname().lower()]
    try:
        infos = socket.getaddrinfo(names[0], None, type=socket.SOCK_STREAM)
    except OSError:
        infos = []
    names += [f"[{a[4][0]}]" if a[0] == socket.AF_INET6 else a[4][0] for a in infos]
    for family, probe in ((socket.AF_INET, "192.0.2.1"), (socket.AF_INET6, "2001:db8::1")):
        try:  # the address other machines reach this one at: a UDP "connection" sends nothing, it picks the route
            with socket.socket(family, socket.SOCK_DGRAM) as s:
                s.connect((probe, 9))
                ip = s.getsockname()[0]
            names.append(f"[{ip}]" if family == socket.AF_INET6 else ip)
        except OSError:
            pass  # no route of that family
    return tuple(n for n in dict.fromkeys(names) if n not in LOCAL_HOSTS)


def make(project_dir, *, virtual: bool, token: str, camera: str = "opencv:0", display=None, seed: int = 0,
         hosts=None):
    """The ASGI app of the project folder ``project_dir`` (created if missing) and its devices."""
    need_extra()
    from .devices import Devices
    from .project import Project
    from .server import create_app

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

        sock = listen("127.0.0.1", 0)
        self.port = sock.getsockname()[1]
        self.asgi = make(project_dir, virtual=virtual, token=token)
        self.server = uvicorn_server(self.asgi, "127.0.0.1", self.port)
        self.thread = threading.Thread(target=self.server.run, kwargs={"sockets": [sock]}, daemon=True)
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

