"""The engine exports' files (``procam export --format opengl|blender|unity|projector-view``): the JSON documents of
:mod:`procam.export`, the Blender script beside its JSON, the distortion maps an engine camera cannot hold, and
the projector's view as PNG.

Every file is written atomically and carries procam's mark (:mod:`procam.io.formats`), so a later export may
overwrite it and nothing else.  Files beside an output are named after it: ``rig.json`` gets ``rig.py`` (the
Blender script, which reads ``rig.json`` from its own folder), ``rig_projector_predistort.npz`` /
``rig_projector_predistort_st.png`` and ``rig_camera_undistort.npz`` / ``rig_camera_undistort_st.png`` (for the
devices that have lens distortion); ``view.png`` gets ``view_mask.png``.  Documents name their neighbours by file
name only, never by an absolute path.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from .files import to_jsonable, write_image, write_text
from .formats import script_mark
from .maps import save_maps

#: The distortion map each device gets beside an engine export: what it does, in the file name.
DISTORTION_MAPS = {"camera": "undistort", "projector": "predistort"}


def save_document(doc: dict, path) -> Path:
    """Write an export document (:mod:`procam.export`) as JSON, atomically."""
    return write_text(path, json.dumps(to_jsonable(doc), indent=1))


def blender_script_path(path) -> Path:
    """The Blender script beside the Blender export ``path`` (``rig.json`` -> ``rig.py``)."""
    return Path(path).with_suffix(".py")


def save_blender(doc: dict, path, script: str) -> list[Path]:
    """Write the Blender export ``doc`` as ``path`` (JSON) and ``script`` (the text of
    :mod:`procam.export.blender_cameras`, which creates its cameras) beside it (:func:`blender_script_path`), under
    procam's mark (a first line with the digest of the rest: :func:`procam.io.formats.script_mark`); returns both
    paths."""
    script_path = blender_script_path(path)
    write_text(script_path, script_mark(script) + script)
    return [save_document(doc, path), script_path]


def distortion_map_paths(path, devices) -> dict:
    """``{device: (npz path, ST-map png path)}`` beside ``path`` for each of ``devices`` (the devices with lens
    distortion)."""
    path = Path(path)
    out = {}
    for name in devices:
        base = path.with_name(f"{path.stem}_{name}_{DISTORTION_MAPS[name]}")
        out[name] = (base.with_suffix(".npz"), base.parent / (base.name + "_st.png"))
    return out


def save_distortion_maps(path, maps: dict) -> dict:
    """Write each device's distortion maps beside ``path`` (:func:`distortion_map_paths`): ``maps`` is
    ``{device: {"map_x", "map_y", "st_map", "K", "size"}}`` (:func:`procam.export.maps.distortion_maps`); the remap
    table as ``.npz``, the ST map (RGB, uint16) as a 16-bit PNG.  Returns ``{device: {"what", "remap", "st_map"}}``
    with file names only (for the export document)."""
    out = {}
    for name, (npz, png) in distortion_map_paths(path, maps).items():
        m = maps[name]
        save_maps(npz, m["map_x"], m["map_y"], K=m["K"], size=np.array(m["size"]))
        write_image(png, np.asarray(m["st_map"])[..., ::-1])
        out[name] = {"what": DISTORTION_MAPS[name], "remap": npz.name, "st_map": png.name}
    return out


def projector_view_paths(path) -> tuple[Path, Path]:
    """The projector's view ``path`` and its mask beside it (``view.png`` -> ``view_mask.png``)."""
    path = Path(path)
    return path, path.with_name(f"{path.stem}_mask{path.suffix}")


def save_projector_view(view, path) -> list[Path]:
    """Write a :class:`procam.export.projector_view.ProjectorView` as ``path`` (the image) and its decoded-valid
    mask beside it (255 decoded, 0 not), both PNG; returns both paths."""
    img_path, mask_path = projector_view_paths(path)
    write_image(mask_path, np.where(view.mask, 255, 0).astype(np.uint8))
    write_image(img_path, view.image)
    return [img_path, mask_path]
