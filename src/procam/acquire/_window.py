"""One SDL window start-up, for the projector's full-screen window and the advisor's preview.

Both windows are SDL2 windows through ``pygame-ce`` (``pip install 'procam[capture]'``), started the same way:

1. :func:`import_pygame` imports pygame without its banner on stdout (it would break JSON lines there), or
   says in one line how to install it (:func:`need` does that for any optional package);
2. :class:`SdlWindow` sets SDL's hints in the environment for the window's lifetime (a user's own setting
   wins), starts SDL's video when nobody has (and quits it on close only then: the preview may open while
   the projector window is up), refuses SDL's ``offscreen``/``dummy`` drivers unless ``SDL_VIDEODRIVER``
   asks for them (no desktop session: nothing would be seen), opens the window (placed, borderless,
   full screen, without the mouse pointer, as asked) and takes its surface.  Whatever fails is undone and
   reported as the caller's one-line :class:`~procam.errors.ProcamError` with SDL's reason in it;
3. :func:`blit_grey` draws a (H, W) uint8 image as an 8-bit grey palette surface: SDL expands each value
   ``v`` to ``(v, v, v)`` exactly while blitting, with no RGB copy of the frame.
"""

from __future__ import annotations

import importlib
import os

import numpy as np

from ..errors import ProcamError

INSTALL_HINT = "pip install 'procam[capture]'"

#: An 8-bit grey palette: index v -> (v, v, v).
GREY_PALETTE = [(v, v, v) for v in range(256)]


def need(name: str, what: str, alternative: str = ""):
    """Import the optional package ``name``, or raise a one-line :class:`ProcamError`: ``what`` needs it,
    how to install it, and ``alternative`` (e.g. ``" (or use --json without a window)"``)."""
    try:
        return importlib.import_module(name)
    except ImportError:
        raise ProcamError(f"{what} needs the '{name}' package, which is not installed; install it with: "
                          f"{INSTALL_HINT}{alternative}") from None


def import_pygame(what: str, alternative: str = ""):
    """pygame, imported without its banner on stdout (see :func:`need` for ``what`` and ``alternative``)."""
    hide = "PYGAME_HIDE_SUPPORT_PROMPT" not in os.environ
    if hide:
        os.environ["PYGAME_HIDE_SUPPORT_PROMPT"] = "1"
    try:
        return need("pygame", what, alternative)
    finally:
        if hide:
            os.environ.pop("PYGAME_HIDE_SUPPORT_PROMPT", None)


def blit_grey(pg, surface, image: np.ndarray, position=(0, 0)) -> None:
    """Blit the (H, W) uint8 ``image`` 1:1 onto ``surface`` at ``position`` through an 8-bit grey palette."""
    image = np.ascontiguousarray(image)
    grey = pg.image.frombuffer(image, (image.shape[1], image.shape[0]), "P")
    grey.set_palette(GREY_PALETTE)
    surface.blit(grey, position)


class SdlWindow:
    """An SDL2 window and its surface, started as the module docstring says.

    Parameters
    ----------
    pg : the pygame module (:func:`import_pygame`).
    title : window title.
    size : (width, height) of the window in pixels.
    position : the window's top-left corner on the desktop, or None (the system places it).
    borderless, fullscreen, hide_mouse : no frame; full screen in desktop mode (no video-mode change);
        no mouse pointer over it.
    hints : ``{environment variable: value}`` SDL reads while the window is up (a variable already set is
        left as it is).
    refused : the error when the window cannot be opened, ``{reason}`` standing for SDL's reason.

    :meth:`open` returns the window or raises :class:`~procam.errors.ProcamError`; :meth:`close` destroys the
    window and undoes the rest.  ``window`` and ``surface`` are pygame's (None while closed).
    """

    def __init__(self, pg, title: str, size, *, position=None, borderless: bool = False, fullscreen: bool = False,
                 hide_mouse: bool = False, hints: dict | None = None,
                 refused: str = "cannot open a window ({reason})"):
        self.pg = pg
        self.title = title
        self.size = (int(size[0]), int(size[1]))
        self.position = None if position is None else (int(position[0]), int(position[1]))
        self.borderless, self.fullscreen, self.hide_mouse = borderless, fullscreen, hide_mouse
        self.hints = dict(hints or {})
        self.refused = refused
        self.window = self.surface = None
        self._owns_video = False
        self._env_set: list[str] = []

    def open(self) -> SdlWindow:
        if self.window is not None:
            return self
        pg = self.pg
        for key, value in self.hints.items():
            if key not in os.environ:
                os.environ[key] = value
                self._env_set.append(key)
        self._owns_video = not pg.display.get_init()
        win = None
        try:
            pg.display.init()
            driver = pg.display.get_driver()
            if driver in ("offscreen", "dummy") and os.environ.get("SDL_VIDEODRIVER") != driver:
                raise pg.error(f"no desktop session (SDL found only its '{driver}' video driver)")
            kw = {} if self.position is None else {"position": self.position}
            win = pg.Window(self.title, size=self.size, borderless=self.borderless, **kw)
            if self.fullscreen:
                win.set_fullscreen(desktop=True)
            if self.hide_mouse:
                pg.mouse.set_visible(False)
            surface = win.get_surface()
        except Exception as e:  # pygame.error: no video device, no X server, X server refused ...
            if win is not None:
                win.destroy()
            self._undo()
            raise ProcamError(self.refused.replace("{reason}", str(e))) from None
        self.window, self.surface = win, surface
        return self

    def close(self) -> None:
        if self.window is not None:
            try:
                self.window.destroy()
            finally:
                self.window = self.surface = None
                self._undo()

    def _undo(self) -> None:
        """Quit SDL's video if this window started it; restore the environment."""
        if self._owns_video:
            self.pg.display.quit()
            self._owns_video = False
        for key in self._env_set:
            os.environ.pop(key, None)
        self._env_set = []
