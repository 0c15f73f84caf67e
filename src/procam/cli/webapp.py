"""``procam app``: the guided calibration in a browser (:mod:`procam.app`, docs/app.md).  (Named ``webapp``: a
module ``procam.cli.app`` would shadow the package's typer object :data:`procam.cli.app`.)

Importing this module registers the command on :data:`procam.cli._app.app`.
"""

from __future__ import annotations

from pathlib import Path

import typer

from ._app import app, fail, refuse, say, user_errors, warn
from ._options import SIMULATED_PROJECTOR, DisplayOpt, SeedOpt, camera_settings, real_camera, seed_applies


@app.command("app")
@user_errors
def app_cmd(
    project: Path = typer.Argument(Path("procam-project"), metavar="PROJECT_DIR", help="The project folder: "
                                   "captures, camera file, calibration, report and exports land here; reopening it "
                                   "resumes."),
    virtual: bool = typer.Option(False, "--virtual", help="The simulator as the projector and camera (the demo)."),
    camera: str = typer.Option("opencv:0", "--camera", help="opencv:INDEX | genicam:PRODUCER.cti[#DEVICE] | "
                               "folder:PATH (procam capture --list-devices)."),
    display: DisplayOpt = None,
    host: str = typer.Option("127.0.0.1", "--host", help="The address to listen on (this machine only by default)."),
    port: int = typer.Option(0, "--port", help="The TCP port (0: a free one)."),
    no_browser: bool = typer.Option(False, "--no-browser", help="Print the address instead of opening the browser."),
    seed: SeedOpt = 0,
):
    """Start the app's local server and open the browser on it: Devices, Board, Camera, Projector pose, Calibrate,
    Check in the world, Export, More projectors (docs/app.md). Ctrl+C stops it; the project folder keeps everything."""
    from .. import app as procam_app

    if not 0 <= port <= 65535:
        fail(f"--port must be from 0 to 65535, got {port}")
    camera_settings(None, None, None, seed, display)
    if virtual:
        refuse(("camera",), "chooses the real camera; --virtual uses the simulator as the camera")
        refuse(("display",), SIMULATED_PROJECTOR)
    else:
        refuse(("seed",), seed_applies("--virtual"))
        real_camera(camera)
    procam_app.need_extra()
    name, hosts, reachable = procam_app.address(host)
    sock = procam_app.listen(host, port)  # a port in use or another machine's address: before the folder is made
    try:
        token = procam_app.new_token()
        asgi = procam_app.make(project, virtual=virtual, token=token, camera=camera, display=display, seed=seed,
                               hosts=hosts)
        asgi.state.procam.project.hold()  # one app per project folder: a second one would write the same state
    except BaseException:
        sock.close()
        raise
    if reachable:
        warn(f"{procam_app.host_option(host)}: the app is reachable from other machines (the token still guards it)")
    url = f"http://{name}:{sock.getsockname()[1]}/?token={token}"
    say(f"procam app on {project.resolve()}: {url}")
    say("Ctrl+C stops it")
    if not no_browser:
        import threading
        import webbrowser

        threading.Timer(0.8, webbrowser.open, args=(url,)).start()
    try:
        procam_app.uvicorn_server(asgi, host, port).run(sockets=[sock])
    except KeyboardInterrupt:  # Ctrl+C is how the app is stopped (uvicorn raises it again after its shutdown)
        pass
    finally:
        procam_app.shutdown(asgi)  # a running capture is cancelled, and removes its partial folder
        asgi.state.procam.project.release()
    say(f"stopped; {project} keeps everything (procam app {project} resumes)")
