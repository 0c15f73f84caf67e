"""The advisor's preview: a window on the operator's screen with the live frame and the advice drawn on it.

:func:`draw_advice` draws one frame and its :class:`procam.advisor.Advice` into any ``pygame.Surface``
(the window's, or an off-screen one -- the same pixels, which is how the tests check the window):

* the camera frame, grey, scaled to the surface (``cv2.resize``, area interpolation);
* the printed board's outline (its outer squares) in the state's colour: green good / ready, amber
  adjust, red no board; the detected corners as dots;
* arrows from the board's centre: a turn points at the edge that should go **away** (labelled with the
  degrees), a tilt likewise at the top or bottom edge, a move points where the board should go;
* a text panel: the headline, the camera's ``psi_c, nu_c`` and predicted ``std(f_c)``, the projector's
  ``psi_p, nu_p`` and ``std(f_p), std(v0p)`` (or that the projector side is unknown), what limits the pose,
  the intrinsics' source; a banner "good — hold still" / "ready" at the bottom.

:class:`PreviewWindow` is a normal (not full-screen) SDL2 window through ``pygame-ce`` (``pip install
'procam[capture]'``); :meth:`~PreviewWindow.show` draws and flips, :meth:`~PreviewWindow.poll` turns keys
into commands: Space / Enter -> ``"capture"``, Esc / Q / closing the window -> ``"quit"``.
"""

from __future__ import annotations

import math

import numpy as np

from ..style import VERDICT_COLOURS, on_dark, rgb
from . import _window
from ._device import Device

#: Colours (RGB) of the states -- the palette's verdict colours (:mod:`procam.style`): a pose ready or good is
#: good, one to adjust weak, no board failed; lightened for the dark panel -- and of the text.
COLOURS = {state: rgb(on_dark(VERDICT_COLOURS[v])) for state, v in
           (("ready", "good"), ("good", "good"), ("adjust", "weak"), ("no-board", "failed"))}
TEXT = (255, 255, 255)
ARROW = (0, 200, 255)
PANEL = (0, 0, 0, 170)


def _pygame():
    """pygame, or a one-line error that says how to install it (or to do without the window)."""
    return _window.import_pygame("the preview window", " (or use --json without a window)")


def fit_size(image_size, max_size) -> tuple[int, int]:
    """The largest size with the image's aspect ratio within ``max_size`` (never larger than the image)."""
    w, h = int(image_size[0]), int(image_size[1])
    s = min(1.0, max_size[0] / w, max_size[1] / h)
    return max(1, int(round(w * s))), max(1, int(round(h * s)))


class _Fonts:
    def __init__(self, pg, height: int):
        pg.font.init()
        base = max(14, int(round(height / 40)))
        self.text = pg.font.Font(None, base + 6)
        self.small = pg.font.Font(None, base + 2)
        self.big = pg.font.Font(None, 2 * base + 12)


def _fmt(v, unit="", nd=1):
    return "?" if v is None or not math.isfinite(v) else f"{v:.{nd}f}{unit}"


def _pct(rel):
    if rel is None or not math.isfinite(rel):
        return "undetermined"
    return f"{100 * rel:.2g} %" if rel < 0.1 else f"{100 * rel:.0f} %"


def advice_lines(advice) -> list[tuple[str, str]]:
    """The text panel's lines ``(style, text)`` for an advice (style ``"head"``, ``"text"``, ``"small"``)."""
    a = advice
    lines = [("head", a.message)]
    for act in a.actions[1:]:
        if act.kind not in ("hold", "capture"):
            lines.append(("text", act.text))
    if a.camera is not None:
        c = a.camera
        lines.append(("text", f"camera:    psi_c {_fmt(c.angles_deg[0], ' deg')}   nu_c {_fmt(c.angles_deg[1], ' deg')}"
                              f"   f_c ± {_pct(c.rel_std_f)} ({_fmt(c.std_f, ' px')})"))
    if a.projector is not None:
        p = a.projector
        lines.append(("text", f"projector: psi_p {_fmt(p.angles_deg[0], ' deg')}   nu_p {_fmt(p.angles_deg[1], ' deg')}"
                              f"   f_p ± {_pct(p.rel_std_f)} ({_fmt(p.std_f, ' px')}), v0p ± {_fmt(p.std_v0, ' px')}"))
        if a.outside_light:
            lines.append(("text", "partly outside the projector's light: " + ", ".join(a.outside_light)))
    elif a.found:
        lines.append(("text", "projector: unknown — capture one pose (even a weak one) to measure R, T"))
    if a.limiting:
        lines.append(("small", f"limited by {a.limiting}; target {a.target_pct:g} % of f"))
    for note in a.notes:
        if note != a.intrinsics and not note.startswith("projector side"):
            lines.append(("small", note))
    lines.append(("small", a.intrinsics))
    return lines


def _arrow(pg, surf, start, end, colour, width=5):
    start, end = np.asarray(start, float), np.asarray(end, float)
    d = end - start
    n = float(np.hypot(*d))
    if n < 1:
        return
    u = d / n
    head = min(22.0, 0.4 * n)
    left = end - head * u + 0.5 * head * np.array([-u[1], u[0]])
    right = end - head * u - 0.5 * head * np.array([-u[1], u[0]])
    pg.draw.line(surf, colour, start, end - 0.6 * head * u, width)
    pg.draw.polygon(surf, colour, [tuple(end), tuple(left), tuple(right)])


def draw_advice(surface, image: np.ndarray, advice, fonts: _Fonts | None = None) -> None:
    """Draw the grey frame ``image`` (H, W) and ``advice`` onto ``surface`` (a ``pygame.Surface``).

    The frame is scaled to the surface's size (its aspect ratio is the caller's business: see
    :func:`fit_size`); every overlay coordinate is scaled the same way.
    """
    import cv2

    pg = _pygame()
    sw, sh = surface.get_size()
    img = np.asarray(image)
    if img.dtype != np.uint8:
        top = float(img.max()) or 1.0
        img = np.clip(img.astype(np.float32) * (255.0 / top), 0, 255).astype(np.uint8)
    h, w = img.shape[:2]
    if (w, h) != (sw, sh):
        img = cv2.resize(img, (sw, sh), interpolation=cv2.INTER_AREA)
    _window.blit_grey(pg, surface, img)  # 8-bit grey palette: no RGB copies
    sx, sy = sw / w, sh / h

    def px(p):
        return (float((p[0] + 0.5) * sx - 0.5), float((p[1] + 0.5) * sy - 0.5))

    fonts = fonts or _Fonts(pg, sh)
    colour = COLOURS.get(advice.state, TEXT)
    if advice.outline is not None:
        pg.draw.polygon(surface, colour, [px(p) for p in advice.outline], 4)
    if advice.corners is not None:
        for p in advice.corners:
            pg.draw.circle(surface, colour, px(p), 3)
    if advice.outline is not None:
        o = np.array([px(p) for p in advice.outline])
        centre = o.mean(axis=0)
        mid = {"left": (o[0] + o[3]) / 2, "right": (o[1] + o[2]) / 2, "top": (o[0] + o[1]) / 2,
               "bottom": (o[2] + o[3]) / 2}
        for act in advice.actions:
            if act.kind in ("turn", "tilt") and act.degrees:
                side = {("turn", True): "right", ("turn", False): "left", ("tilt", True): "top",
                        ("tilt", False): "bottom"}[(act.kind, act.degrees > 0)]
                end = mid[side]
                _arrow(pg, surface, centre, end, ARROW)
                label = fonts.text.render(f"{act.kind} ~{abs(act.degrees):.0f} deg: {side} edge away", True, ARROW)
                x = min(max(0.0, end[0] - label.get_width() / 2), sw - label.get_width())
                y = end[1] + (10 if side != "top" else -label.get_height() - 10)
                box = pg.Surface((label.get_width() + 8, label.get_height() + 4), pg.SRCALPHA)
                box.fill(PANEL)
                surface.blit(box, (x - 4, y - 2))
                surface.blit(label, (x, y))
            elif act.kind == "move" and act.direction:
                step = 0.25 * min(sw, sh)
                v = {"left": (-1, 0), "right": (1, 0), "up": (0, -1), "down": (0, 1)}[act.direction]
                _arrow(pg, surface, centre, centre + step * np.array(v), colour)

    # the text panel
    lines = advice_lines(advice)
    rendered = []
    for style, text in lines:
        font = {"head": fonts.text, "text": fonts.small, "small": fonts.small}[style]
        rendered.append(font.render(text, True, colour if style == "head" else TEXT))
    pad = 8
    width = min(sw, max(r.get_width() for r in rendered) + 2 * pad)
    height = sum(r.get_height() + 2 for r in rendered) + 2 * pad
    panel = pg.Surface((width, height), pg.SRCALPHA)
    panel.fill(PANEL)
    surface.blit(panel, (0, 0))
    y = pad
    for r in rendered:
        surface.blit(r, (pad, y))
        y += r.get_height() + 2
    if advice.good:
        text = "READY — hold still" if advice.ready else "good — hold still"
        banner = fonts.big.render(text, True, colour)
        box = pg.Surface((banner.get_width() + 24, banner.get_height() + 12), pg.SRCALPHA)
        box.fill(PANEL)
        x0 = (sw - box.get_width()) // 2
        y0 = sh - box.get_height() - 12
        surface.blit(box, (x0, y0))
        surface.blit(banner, (x0 + 12, y0 + 6))


class PreviewWindow(Device):
    """A window on the operator's screen showing the live frames with the advice.

    Parameters
    ----------
    image_size : (W, H) of the camera frames.
    max_size : the window's largest size (the frame is scaled down to fit, never up).
    position : the window's top-left corner on the desktop, or None (the system places it).
    title : window title.
    """

    def __init__(self, image_size, max_size=(1280, 800), position=None, title: str = "procam advise"):
        self.image_size = (int(image_size[0]), int(image_size[1]))
        self.size = fit_size(self.image_size, max_size)
        self.position = position
        self.title = title
        self._pg = self._sdl = self._fonts = None

    def open(self):
        if self._sdl is not None:
            return self
        pg = _pygame()
        self._sdl = _window.SdlWindow(pg, self.title, self.size, position=self.position,
                                      refused="cannot open the preview window ({reason}); run procam in a desktop "
                                              "session, or use --json (advice as JSON lines, no window)").open()
        self._pg, self._fonts = pg, _Fonts(pg, self.size[1])
        return self

    def close(self):
        sdl, self._sdl = self._sdl, None
        if sdl is not None:
            sdl.close()

    def show(self, image: np.ndarray, advice) -> None:
        """Draw ``image`` with ``advice`` and flip."""
        if self._sdl is None:
            raise RuntimeError("PreviewWindow.show() before open()")
        draw_advice(self._sdl.surface, image, advice, self._fonts)
        self._sdl.window.flip()

    def poll(self) -> str | None:
        """Handle the window's events: ``"capture"`` (Space, Enter), ``"quit"`` (Esc, Q, closed) or None."""
        if self._sdl is None:
            return None
        pg = self._pg
        out = None
        for ev in pg.event.get():
            if ev.type in (pg.QUIT, pg.WINDOWCLOSE):
                out = "quit"
            elif ev.type == pg.KEYDOWN:
                if ev.key in (pg.K_ESCAPE, pg.K_q):
                    out = "quit"
                elif ev.key in (pg.K_SPACE, pg.K_RETURN, pg.K_KP_ENTER) and out is None:
                    out = "capture"
        return out

    def render_offscreen(self, image: np.ndarray, advice):
        """The same drawing on an off-screen surface of the window's size (a reference for tests)."""
        pg = _pygame()
        surf = pg.Surface(self.size)
        draw_advice(surf, image, advice, self._fonts or _Fonts(pg, self.size[1]))
        return surf
