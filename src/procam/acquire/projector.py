"""Projector output: a full-screen window on one display that shows each pattern pixel for pixel.

:class:`ProjectorWindow` opens a borderless, full-screen (desktop mode: no video-mode change)
window on a chosen display through SDL2 (``pygame-ce``), placed by the display's position in the
desktop layout (``screeninfo``).  Each :meth:`~ProjectorWindow.show` blits a (H, W) grey image 1:1
into the window surface and flips: no scaling, no colour conversion beyond grey -> RGB.  The
window refuses to open when the display's size differs from the pattern size (the projector would
resample every pattern).  :class:`VirtualProjector` records what it is asked to show (the virtual
camera renders it).

Both projectors have the same small interface: ``size`` (W, H), ``show(image)``, ``wait(seconds)``
(sleeps while keeping the window responsive), ``describe()`` and a context manager.  ``shown``
counts the images shown, ``current`` is the last one.

``pygame`` and ``screeninfo`` are imported when a window is opened or displays are listed; they
come with ``pip install 'procam[capture]'``.
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass

import numpy as np

from ..errors import ProcamError
from . import _window
from ._device import Device


class CaptureAborted(ProcamError):
    """The user closed the projector window or pressed Esc in it."""


@dataclass(frozen=True)
class Display:
    """One monitor of the desktop: ``index`` (procam's ``--display N``), position ``x, y`` and size
    ``width, height`` in desktop pixels, ``name`` and ``primary`` (None when the system does not say)."""

    index: int
    x: int
    y: int
    width: int
    height: int
    name: str = ""
    primary: bool | None = None

    @property
    def size(self) -> tuple[int, int]:
        return self.width, self.height

    def label(self) -> str:
        role = {True: ", primary", False: "", None: ""}[self.primary]
        name = f" {self.name}" if self.name else ""
        return f"display {self.index}:{name} {self.width}x{self.height} at ({self.x}, {self.y}){role}"


def list_displays() -> list[Display]:
    """The desktop's monitors in ``screeninfo``'s order (``index`` is procam's ``--display``).

    Raises :class:`ProcamError` when ``screeninfo`` is missing or finds no display (no desktop
    session: ``DISPLAY`` unset, a remote shell).
    """
    screeninfo = _window.need("screeninfo", "the projector window")
    try:
        monitors = screeninfo.get_monitors()
    except Exception as e:  # screeninfo raises its own ScreenInfoError, or ctypes errors
        raise ProcamError(f"cannot list the displays ({e}); run procam in the desktop session the projector "
                          "is connected to (on Linux: is DISPLAY set?)") from None
    if not monitors:
        raise ProcamError("no display found; run procam in the desktop session the projector is connected to")
    return [Display(i, int(m.x), int(m.y), int(m.width), int(m.height), m.name or "",
                    None if getattr(m, "is_primary", None) is None else bool(m.is_primary))
            for i, m in enumerate(monitors)]


def choose_display(displays: list[Display], index: int | None = None) -> Display:
    """Display ``index``, or by default the one display that is not the primary.

    Raises :class:`ProcamError` (one line, listing the displays) when ``index`` is out of range or
    the default is ambiguous (one display only, or several that are not the primary).
    """
    listing = "; ".join(d.label() for d in displays)
    if index is not None:
        if not 0 <= index < len(displays):
            raise ProcamError(f"--display {index}: there are {len(displays)} displays ({listing}); "
                              "choose one with --display N")
        return displays[index]
    if len(displays) == 1:
        raise ProcamError(f"only one display is connected ({listing}); connect the projector as a second display, "
                          "or pass --display 0 to show the patterns on this one")
    others = [d for d in displays if d.primary is not True]
    if len(others) == 1:
        return others[0]
    raise ProcamError(f"cannot tell which display is the projector ({listing}); pass --display N")


def _checked(image: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """``image`` as a contiguous (H, W) uint8 array, after checking its shape and type."""
    image = np.asarray(image)
    w, h = size
    if image.shape != (h, w) or image.dtype != np.uint8:
        raise ValueError(f"the projector shows ({h}, {w}) uint8 images, got {image.shape} {image.dtype}")
    return np.ascontiguousarray(image)


class _Projector(Device):
    """Shared bookkeeping: the last image shown and how many were shown."""

    size: tuple[int, int]

    def __init__(self, size):
        self.size = (int(size[0]), int(size[1]))
        self.current: np.ndarray | None = None
        self.shown = 0
        self.last_show_time: float | None = None

    def _record(self, image):
        self.current = image
        self.shown += 1
        self.last_show_time = time.monotonic()

    def wait(self, seconds: float) -> None:
        """Sleep ``seconds`` (the window keeps handling its events meanwhile)."""
        if seconds > 0:
            time.sleep(seconds)


class VirtualProjector(_Projector):
    """A projector that only records what it is asked to show (for the virtual camera and tests).

    Parameters
    ----------
    size : (width, height) in pixels.
    """

    def show(self, image: np.ndarray) -> None:
        """Record ``image`` (H, W) uint8 as the one now shown."""
        self._record(np.array(_checked(image, self.size), copy=True))

    def describe(self) -> dict:
        return {"backend": "virtual", "size": list(self.size)}


class ProjectorWindow(_Projector):
    """A borderless full-screen window on one display that shows patterns pixel for pixel.

    Parameters
    ----------
    size : (width, height) of the patterns, the projector's native size.  Must equal the
        display's size: the window refuses to open otherwise.
    display : index into :func:`list_displays` (``--display``); None = the one that is not the
        primary (:func:`choose_display`).
    title : window title (shown by task bars).

    Use as a context manager; :meth:`show` returns once the image has been handed to the display
    (after the flip), the capture loop then waits its settle time for the projector to show it.
    Esc or closing the window raises :class:`CaptureAborted`.
    """

    def __init__(self, size, display: int | None = None, title: str = "procam capture"):
        super().__init__(size)
        self.display_index = display
        self.title = title
        self.display: Display | None = None
        self._sdl = None
        self._pg = None

    def open(self):
        if self._sdl is not None:
            return self
        self.display = choose_display(list_displays(), self.display_index)
        d = self.display
        if d.size != self.size:
            raise ProcamError(
                f"display {d.index} is {d.width}x{d.height} but the patterns are {self.size[0]}x{self.size[1]}: "
                f"set that display to the projector's native resolution, or pass --projector {d.width}x{d.height} "
                "if that is the projector's native size (a scaled pattern cannot be decoded pixel-exact)")
        pg = _window.import_pygame("the projector window")
        # the hint keeps the full-screen window up when the terminal on the other display takes the focus
        self._sdl = _window.SdlWindow(pg, self.title, d.size, position=(d.x, d.y), borderless=True, fullscreen=True,
                                      hide_mouse=True, hints={"SDL_VIDEO_MINIMIZE_ON_FOCUS_LOSS": "0"},
                                      refused=f"cannot open a window on {d.label()} ({{reason}}); run procam in the "
                                              "desktop session the projector is connected to").open()
        self._pg = pg
        got = tuple(self._sdl.surface.get_size())
        if got != self.size or tuple(self._sdl.window.size) != self.size:
            self.close()
            raise ProcamError(
                f"the full-screen window on {d.label()} is {got[0]}x{got[1]} pixels, not {self.size[0]}x{self.size[1]}: "
                "the system scales this display (HiDPI / display scaling); set its scaling to 100 %")
        self.show(np.zeros((self.size[1], self.size[0]), np.uint8))
        return self

    def close(self):
        sdl, self._sdl = self._sdl, None
        if sdl is not None:
            sdl.close()

    def _pump(self):
        pg = self._pg
        for ev in pg.event.get():
            if ev.type in (pg.QUIT, pg.WINDOWCLOSE) or (ev.type == pg.KEYDOWN and ev.key == pg.K_ESCAPE):
                raise CaptureAborted("capture stopped: the projector window was closed or Esc was pressed in it")

    def show(self, image: np.ndarray) -> None:
        """Show ``image`` (H, W) uint8 full screen, pixel for pixel; returns after the flip."""
        if self._sdl is None:
            raise RuntimeError("ProjectorWindow.show() before open()")
        grey = _checked(image, self.size)
        self._pump()
        _window.blit_grey(self._pg, self._sdl.surface, grey)  # SDL expands it exactly, v -> (v, v, v)
        self._sdl.window.flip()
        self._record(grey.copy())

    def wait(self, seconds: float) -> None:
        """Sleep ``seconds`` while handling the window's events (Esc aborts)."""
        end = time.monotonic() + max(0.0, seconds)
        while True:
            if self._sdl is not None:
                self._pump()
            left = end - time.monotonic()
            if left <= 0:
                return
            time.sleep(min(left, 0.02))

    def describe(self) -> dict:
        d = {"backend": "pygame-window", "size": list(self.size)}
        if self.display is not None:
            d["display"] = asdict(self.display)
        if self._pg is not None:
            d["sdl_driver"] = self._pg.display.get_driver() if self._pg.display.get_init() else None
            d["pygame"] = self._pg.version.ver
        return d
