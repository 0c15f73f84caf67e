"""The renderer: physically plausible captures of a :class:`~procam.simulate.Scene`, in every pattern family
(Gray codes, and the phase families' fringes through the projector's response ``proj_gamma``).

Per camera pixel a ray (supersampled, :mod:`~procam.simulate.geometry`): board / background albedo,
projector illumination through the projector's lens with defocus, black level and the projector's
response (``proj_gamma``), cast shadows (the board's, the background solids'), occlusion, ambient
light, gain, vignetting, optical blur, shot and read noise, the camera's gamma, 8/16-bit output.
The geometry is computed once per scene (:class:`Renderer`); each pattern image is then a cheap 1-D
profile lookup, because Gray-code stripes, fringes (and any other 1-D pattern,
:meth:`Renderer.linear_stripes`) depend on one projector coordinate only.

* :func:`render` - the whole sequence at once, with its ground truth.
* :class:`Renderer` - one pattern image at a time (:meth:`Renderer.frame`), e.g. for a simulated
  camera that is triggered per projected pattern.
* :func:`write_capture` - a rendered capture in procam's capture-folder layout (thin over
  :func:`procam.capture.write_sequence`).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Callable

import cv2
import numpy as np

from .. import capture as _capture
from .. import patterns as _patterns
from ..io.files import to_jsonable
from .geometry import GEOMETRY_BAND, _geometry_bands
from .scene import Scene
from .truth import truth

__all__ = ["Renderer", "render", "write_capture"]


#: Samples per projector pixel of the 1-D stripe profiles looked up by ``cv2.remap``.
PROFILE_UPSAMPLE = 8


# --------------------------------------------------------------------------------------------
# rendering: the image sequence
# --------------------------------------------------------------------------------------------

def _profile(values: np.ndarray, sigma: float, pad: int):
    """Upsampled, defocused 1-D light profile of a projector line ``values`` (n,) in [0, 1].

    Sample ``q`` of the result is at projector coordinate ``(q - pad + 0.5) / U - 0.5`` with
    ``U = PROFILE_UPSAMPLE`` (projector pixel i covers [i - .5, i + .5]); zero outside the panel.
    """
    U = PROFILE_UPSAMPLE
    line = np.zeros(len(values) * U + 2 * pad, dtype=np.float32)
    line[pad:pad + len(values) * U] = np.repeat(values.astype(np.float32), U)
    if sigma > 0:
        line = cv2.GaussianBlur(line[None, :], (0, 0), sigmaX=sigma * U, sigmaY=1e-6,
                                borderType=cv2.BORDER_CONSTANT)[0]
    return line[None, :]


def _to_profile_map(p: np.ndarray, pad: int) -> np.ndarray:
    """Projector coordinates -> sample index of :func:`_profile` (float32; far outside where NaN)."""
    q = (p.astype(np.float64) + 0.5) * PROFILE_UPSAMPLE - 0.5 + pad
    return np.where(np.isfinite(q), q, -1e6).astype(np.float32)


class Renderer:
    """One scene's Gray-code capture, one pattern image at a time.

    The geometry (camera rays, surfaces, shading, projector coordinates per supersample) is computed
    here, once: it is most of the cost of a capture.  Each :meth:`frame` is then a 1-D profile
    lookup, the camera's blur and noise, gamma and quantisation.  A pattern value becomes light through
    the projector's response (:meth:`emitted`); Gray-code patterns are binary, so ``proj_gamma`` does
    not change them.

    Parameters
    ----------
    scene : the set-up (board pose, photometry, bit depth, supersampling).
    order : the sequence: a Gray-code order, ``"opencv"`` or ``"moreno"`` (see :mod:`procam.patterns`), or a pattern
        set of the scene's projector (a :class:`~procam.patterns.PhaseSet` renders a phase family).

    Attributes
    ----------
    scene : Scene
    pattern_set : procam.patterns.PatternSet
        The sequence: ``pattern_set.count`` images (46 for a 1920x1080 projector), the white and
        black frames at ``pattern_set.white`` / ``pattern_set.black``.

    Examples
    --------
    Frames ``0, 1, ...`` drawn in order with one generator are :func:`render`'s images, bit for bit::

        r = Renderer(scene, "opencv")
        rng = np.random.default_rng(seed)
        images = [r.frame(k, rng) for k in range(r.pattern_set.count)]  # == render(scene, seed=seed)[0]
    """

    def __init__(self, scene: Scene, order="opencv"):
        self.scene = scene
        self.pattern_set = _sequence(scene, order)
        Wp, Hp = scene.proj_size
        self.pad = int(np.ceil(4 * max(scene.proj_defocus, 0.25) * PROFILE_UPSAMPLE)) + PROFILE_UPSAMPLE
        s = scene.supersample
        W, H = scene.cam_size
        shape = (H * s, W * s)
        self.sigma = scene.proj_defocus
        # float32 maps (faster than fixed-point ones for a one-row source image); the y map of the one-row profile
        # is all zeros: one band of it serves every band
        self.mapx, self.mapy, self.coef_cols, self.coef_rows, self.full, self.amb = (
            np.empty(shape, np.float32) for _ in range(6))
        self._zeros = np.zeros((max(self.BAND * s, GEOMETRY_BAND), W * s), np.float32)
        ones_x = _profile(np.ones(Wp), self.sigma, self.pad)
        ones_y = _profile(np.ones(Hp), self.sigma, self.pad)

        def work(r0, r1, g):  # the geometry of rows r0:r1, as stored by _geometry, into the lookup tables
            b = slice(r0, r1)
            self.mapx[b] = _to_profile_map(g["xp"].astype(np.float32), self.pad)
            self.mapy[b] = _to_profile_map(g["yp"].astype(np.float32), self.pad)
            mask_x = self._lookup(ones_x, "x", b)
            mask_y = self._lookup(ones_y, "y", b)
            coef = g["coef"].astype(np.float32)
            self.coef_cols[b] = coef * mask_y          # column patterns vary with x only
            self.coef_rows[b] = coef * mask_x          # row patterns vary with y only
            self.full[b] = coef * mask_x * mask_y      # a white panel
            self.amb[b] = g["amb"]

        # band by band: no full-size intermediates (the float64 maps, the masks, the products)
        _geometry_bands(scene, s, work, GEOMETRY_BAND)
        self._index_sequence()

    def _index_sequence(self) -> None:
        """The Gray-code bit planes and frame index of :attr:`pattern_set` (a phase family draws its lines)."""
        self.index = {}
        if _patterns.is_phase(self.pattern_set):
            return
        Wp, Hp = self.scene.proj_size
        self.col_planes = _patterns.bit_planes(Wp, self.pattern_set.col_bits, self.pattern_set.col_offset)
        self.row_planes = _patterns.bit_planes(Hp, self.pattern_set.row_bits, self.pattern_set.row_offset)
        for j, (a, b) in enumerate(self.pattern_set.pair_indices("col")):
            self.index[int(a)], self.index[int(b)] = ("col", j, False), ("col", j, True)
        for j, (a, b) in enumerate(self.pattern_set.pair_indices("row")):
            self.index[int(a)], self.index[int(b)] = ("row", j, False), ("row", j, True)

    def with_patterns(self, order) -> "Renderer":
        """This renderer for another sequence of the same projector (a Gray-code order or any pattern set,
        :func:`procam.patterns.pattern_set`); the geometry, most of the cost, is shared."""
        import copy

        other = copy.copy(self)
        other.pattern_set = _sequence(self.scene, order)
        other._index_sequence()
        return other

    #: Scene fields :meth:`photometry` may change: they act after the geometry (the projector's response and
    #: black level, the camera's blur, noise, gamma and bit depth).
    PHOTOMETRY = ("proj_gamma", "proj_black", "cam_blur", "read_noise", "full_well", "gamma", "bits")

    def photometry(self, **changes) -> "Renderer":
        """This renderer for the scene with other :data:`PHOTOMETRY` (the geometry, most of the cost, is shared):
        ``r.photometry(proj_gamma=2.2, read_noise=1.5)`` renders what ``Renderer(scene.replace(...))`` would."""
        bad = sorted(set(changes) - set(self.PHOTOMETRY))
        if bad:
            raise ValueError(f"photometry() changes only {', '.join(self.PHOTOMETRY)}; {', '.join(bad)} change the "
                             "geometry: make a new Renderer")
        import copy

        other = copy.copy(self)
        other.scene = self.scene.replace(**changes)
        return other

    #: camera rows per band of :meth:`linear` (its buffer is then over 4 MB: huge pages, few page faults)
    BAND = 96

    def _lookup(self, profile, axis, rows: slice, out=None):
        m = (self.mapx if axis == "x" else self.mapy)[rows]
        return cv2.remap(profile, m, self._zeros[:m.shape[0]], cv2.INTER_LINEAR, dst=out,
                         borderMode=cv2.BORDER_CONSTANT, borderValue=0)

    def frame(self, k: int, rng: np.random.Generator) -> np.ndarray:
        """Image ``k`` of the sequence as the camera records it.

        Parameters
        ----------
        k : index in the sequence, ``0 <= k < pattern_set.count``.
        rng : the noise source; one generator used for frames ``0, 1, ...`` in order gives
            :func:`render`'s images.

        Returns
        -------
        (H, W) uint8 (``scene.bits == 8``) or uint16 (full scale 65535).
        """
        return self.finish(self.linear(k), rng)

    def emitted(self, values) -> np.ndarray:
        """Light (fraction of the projector's white) of a line of pattern values: a bool line is a binary pattern
        (True = white), any other is 0-255 levels; ``proj_black + (1 - proj_black) * (v / 255) ** proj_gamma``."""
        sc = self.scene
        values = np.asarray(values)
        level = values if values.dtype == bool else (values.astype(np.float64) / 255.0) ** sc.proj_gamma
        return sc.proj_black + (1.0 - sc.proj_black) * level

    def linear(self, k: int) -> np.ndarray:
        """Noise-free linear camera image k (H, W) float32 (fraction of full scale), before blur."""
        if not 0 <= k < self.pattern_set.count:
            raise IndexError(f"frame {k} is outside the sequence of {self.pattern_set.count} images")
        if k == self.pattern_set.white:
            return self._linear("white")
        if k == self.pattern_set.black:
            return self._linear("black")
        if _patterns.is_phase(self.pattern_set):  # a fringe or a Gray stripe of a phase family: its 1-D line
            axis, line = self.pattern_set.line(k)
            return self.linear_stripes(line, axis)
        axis, j, inv = self.index[k]
        plane = self.col_planes[j] if axis == "col" else self.row_planes[j]
        if inv:
            plane = ~plane
        return self._linear(axis, _profile(self.emitted(plane), self.sigma, self.pad))

    def linear_stripes(self, values, axis: str) -> np.ndarray:
        """Noise-free linear camera image (H, W) float32 of any 1-D pattern: ``values`` (projector width,) for
        ``axis="col"`` (the pattern varies along the panel's x) or (projector height,) for ``"row"``; 0-255 levels
        (through ``proj_gamma``, :meth:`emitted`) or bool.  :meth:`finish` adds the camera's blur and noise."""
        if axis not in ("col", "row"):
            raise ValueError(f"axis must be 'col' or 'row', got {axis!r}")
        n = self.scene.proj_size[0 if axis == "col" else 1]
        values = np.asarray(values)
        if values.shape != (n,):
            raise ValueError(f"a {axis} pattern of this projector has {n} values, got shape {values.shape}")
        return self._linear(axis, _profile(self.emitted(values), self.sigma, self.pad))

    def linear_image(self, image) -> np.ndarray:
        """Noise-free linear camera image (H, W) float32 of ANY projector image: ``image`` (projector height,
        projector width), 0-255 levels through ``proj_gamma`` (:meth:`emitted`) or bool.  :meth:`finish` adds the
        camera's blur and noise.

        The panel image is defocused (Gaussian, ``proj_defocus`` projector px, black beyond the panel) and looked
        up bilinearly at native resolution (the 1-D patterns' profiles are 8x finer): right for images smooth on
        the scale of a projector pixel (blobs, the white panel up to its outermost pixel); a binary stripe pattern
        renders best through :meth:`linear_stripes`.
        """
        sc = self.scene
        Wp, Hp = sc.proj_size
        image = np.asarray(image)
        if image.shape != (Hp, Wp):
            raise ValueError(f"a projector image of this scene is ({Hp}, {Wp}) (height, width), got {image.shape}")
        U, pad = PROFILE_UPSAMPLE, self.pad // PROFILE_UPSAMPLE + 1
        light = np.zeros((Hp + 2 * pad, Wp + 2 * pad), np.float32)
        light[pad:pad + Hp, pad:pad + Wp] = self.emitted(image)
        if self.sigma > 0:
            light = cv2.GaussianBlur(light, (0, 0), sigmaX=self.sigma, sigmaY=self.sigma,
                                     borderType=cv2.BORDER_CONSTANT)
        W, H = sc.cam_size
        s = self.mapx.shape[0] // H
        out = np.empty((H, W), np.float32)
        shift = np.float32(pad - self.pad / U + 0.5 / U - 0.5)  # profile sample index -> padded panel pixel
        for y0 in range(0, H, self.BAND):
            y1 = min(H, y0 + self.BAND)
            b = slice(y0 * s, y1 * s)
            # the surfaces' shading: the white panel's light over the panel's own (defocused) extent
            with np.errstate(divide="ignore", invalid="ignore"):
                coef = np.where(self.full[b] > 1e-12, self.coef_cols[b] * self.coef_rows[b] / self.full[b], 0.0)
            x = self.mapx[b] / np.float32(U) + shift
            y = self.mapy[b] / np.float32(U) + shift
            hi = cv2.remap(light, x, y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=0)
            hi = hi * coef.astype(np.float32) + self.amb[b]
            cv2.resize(hi, (W, y1 - y0), dst=out[y0:y1], interpolation=cv2.INTER_AREA)
        return out

    def _linear(self, what: str, prof=None) -> np.ndarray:
        """The linear image of the white or black panel, or of a column or row profile (:func:`_profile`)."""
        sc = self.scene
        black = sc.proj_black
        W, H = sc.cam_size
        s = self.mapx.shape[0] // H  # supersamples per pixel and axis
        out = np.empty((H, W), np.float32)
        buf = np.empty((self.BAND * s, W * s), np.float32)
        # in bands of camera rows, in one buffer: no supersampled temporaries of the whole image (37 MB each for a
        # 1280x800 camera at 3x3); every step is per pixel (the area average per block of s x s samples), so the
        # bands and the in-place operations give the same numbers as whole-image ones
        for y0 in range(0, H, self.BAND):
            y1 = min(H, y0 + self.BAND)
            b = slice(y0 * s, y1 * s)
            hi = buf[:(y1 - y0) * s]
            if what == "white":
                np.add(self.full[b], self.amb[b], out=hi)
            elif what == "black":
                np.multiply(self.full[b], black, out=hi)
                hi += self.amb[b]
            else:
                self._lookup(prof, "x" if what == "col" else "y", b, out=hi)
                hi *= self.coef_cols[b] if what == "col" else self.coef_rows[b]
                hi += self.amb[b]
            cv2.resize(hi, (W, y1 - y0), dst=out[y0:y1], interpolation=cv2.INTER_AREA)
        return out

    def finish(self, lin: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Optics, noise, gamma and quantisation of a linear image."""
        sc = self.scene
        if sc.cam_blur > 0:
            lin = cv2.GaussianBlur(lin, (0, 0), sigmaX=sc.cam_blur, sigmaY=sc.cam_blur,
                                   borderType=cv2.BORDER_REFLECT)
        var = np.full_like(lin, (sc.read_noise / 255.0) ** 2)
        if sc.full_well > 0:
            var += np.maximum(lin, 0) / sc.full_well
        noisy = lin + np.sqrt(var) * rng.standard_normal(lin.shape, dtype=np.float32)
        np.clip(noisy, 0.0, 1.0, out=noisy)
        if sc.gamma != 1.0:
            noisy = noisy ** (1.0 / sc.gamma)
        top = 255 if sc.bits == 8 else 65535
        return np.rint(noisy * top).astype(np.uint8 if sc.bits == 8 else np.uint16)


def _sequence(scene: Scene, order):
    """The pattern set of ``order``: a Gray-code order (str) for the scene's projector, or a pattern set itself
    (:class:`procam.patterns.PatternSet` or :class:`~procam.patterns.PhaseSet`) of its size."""
    if isinstance(order, str):
        return _patterns.pattern_set(*scene.proj_size, order)
    if (order.width, order.height) != tuple(scene.proj_size):
        raise ValueError(f"the pattern set is for a {order.width}x{order.height} projector, the scene's is "
                         f"{scene.proj_size[0]}x{scene.proj_size[1]}")
    return order


def render(scene: Scene, order="opencv", seed: int = 0,
           progress: Callable[[int, int], None] | None = None):
    """Render the full Gray-code capture of ``scene``.

    Parameters
    ----------
    scene : the set-up (board pose, photometry, bit depth, supersampling).
    order : the sequence: ``"opencv"`` (default) or ``"moreno"`` (Gray codes, see :mod:`procam.patterns`), or a
        pattern set (:class:`~procam.patterns.PhaseSet` for the phase families).
    seed : noise seed; the same seed gives bit-identical images.
    progress : optional ``callable(done, total)`` called after the geometry and after each image.

    Returns
    -------
    stack : (K, H, W) uint8 (``bits=8``) or uint16 (``bits=16``, full scale 65535), K = 46 for a
        1920x1080 projector, in the sequence order.
    truth : dict, :func:`truth` plus ``"render"`` (order, seed, pattern set).
    """
    r = Renderer(scene, order)
    ps = r.pattern_set
    total = ps.count + 1
    if progress is not None:
        progress(1, total)
    rng = np.random.default_rng(seed)
    W, H = scene.cam_size
    stack = np.empty((ps.count, H, W), dtype=np.uint8 if scene.bits == 8 else np.uint16)
    for k in range(ps.count):
        stack[k] = r.frame(k, rng)
        if progress is not None:
            progress(k + 2, total)
    t = truth(scene)
    t["render"] = {"order": ps.order, "seed": int(seed), "count": int(ps.count),
                   "white": None if ps.white is None else int(ps.white),
                   "black": None if ps.black is None else int(ps.black),
                   "pattern_set": ps.to_dict()}
    return stack, to_jsonable(t)


# --------------------------------------------------------------------------------------------
# output
# --------------------------------------------------------------------------------------------

def write_capture(out_dir, stack: np.ndarray, truth: dict, order="opencv", *, force: bool = False) -> list[Path]:
    """Write a rendered capture in procam's default capture-folder layout.

    Files: ``00.png`` ... ``45.png`` (zero-padded index, sequence order), ``truth.json`` (``truth``),
    ``patterns.json`` (:meth:`procam.patterns.PatternSet.to_dict` plus ``"files"``) and the manifest
    ``.procam-manifest.json``.  Every file is written under a hidden temporary name and renamed
    (:func:`procam.capture.write_sequence`), so an interrupted run leaves no half-written image that a
    loader would pick up.  ``out_dir`` must be new, empty or an earlier simulator output; ``force`` writes
    into another folder, but never over (or deletes) a file procam did not write.  Numbered PNGs of an
    earlier, longer simulated sequence are deleted, so they are not read as part of this one.

    Parameters
    ----------
    out_dir : folder (created if missing).
    stack : (K, H, W) uint8 or uint16 images from :func:`render`.
    truth : the truth dict from :func:`render` (its projector size names the pattern set).
    order : the sequence the stack was rendered in (a Gray-code order or the pattern set).
    force : write into a folder that holds other files.

    Returns
    -------
    list of the image paths, in sequence order.  Raises :class:`procam.errors.OutputError` when the
    folder is refused.
    """
    wp, hp = truth["projector"]["size"]
    ps = _patterns.pattern_set(int(wp), int(hp), order) if isinstance(order, str) else order
    stack = np.asarray(stack)
    if stack.ndim != 3 or stack.shape[0] != ps.count:
        raise ValueError(f"stack must be ({ps.count}, H, W) for a {wp}x{hp} projector, got {stack.shape}")
    if stack.dtype not in (np.uint8, np.uint16):
        raise ValueError(f"stack must be uint8 or uint16, got {stack.dtype}")
    return _capture.write_sequence(out_dir, stack, ps, writer="simulate", force=force,
                                   extra_files={"truth.json": json.dumps(to_jsonable(truth), indent=1)})
