# procam: creates the cameras of a procam Blender export (procam export --format blender) in a Blender scene
"""Create the camera and the projector of a procam Blender export (``procam export --format blender -o rig.json``)
as camera objects in a Blender scene.

In Blender (``procam export`` writes this file beside the JSON)::

    blender --python rig.py                          # reads rig.json beside the script
    blender --python rig.py -- rig.json projector    # the JSON, and the device that becomes the scene camera

or run it from Blender's text editor, or in Python with the ``bpy`` module::

    import rig; rig.create_cameras("rig.json")

Each device becomes a camera object named ``procam camera`` / ``procam projector`` with the document's camera
properties and ``matrix_world``; the scene's render resolution and pixel aspect are set for the device that
becomes ``scene.camera`` (:func:`use_device` switches).  Blender cameras are pinholes: the export's distortion
maps carry the lens distortion.  The conventions are in the JSON and in procam's docs/exports.md.
"""

import json
import os
import sys

#: The object name of a device.
NAME = "procam {}"


def _load(doc):
    if isinstance(doc, (str, os.PathLike)):
        with open(doc, encoding="utf-8") as f:
            doc = json.load(f)
    if not isinstance(doc, dict) or doc.get("format") != "procam-blender":
        raise ValueError("not a procam Blender export (format procam-blender)")
    return doc


def use_device(doc, name, scene=None):
    """Make device ``name``'s camera the scene's camera and set the scene's render settings for it."""
    import bpy

    doc = _load(doc)
    scene = scene or bpy.context.scene
    for key, value in doc["devices"][name]["render"].items():
        setattr(scene.render, key, value)
    scene.camera = bpy.data.objects[NAME.format(name)]
    return scene.camera


def create_cameras(doc, scene=None, active=None):
    """Create (or update) both devices' camera objects in ``scene`` (default: the current one) from the export
    ``doc`` (its dict or the path of its JSON); ``active`` (default: the document's ``scene_camera``) becomes the
    scene camera.  Returns ``{device: object}``."""
    import bpy
    from mathutils import Matrix

    doc = _load(doc)
    scene = scene or bpy.context.scene
    made = {}
    for name, dev in doc["devices"].items():
        oname = NAME.format(name)
        obj = bpy.data.objects.get(oname)
        if obj is None:
            obj = bpy.data.objects.new(oname, bpy.data.cameras.new(oname))
        if obj.name not in scene.collection.objects:
            scene.collection.objects.link(obj)
        for key, value in dev["data"].items():
            setattr(obj.data, key, value)
        obj.matrix_world = Matrix(dev["matrix_world"])
        made[name] = obj
    use_device(doc, active or doc.get("scene_camera", "projector"), scene)
    return made


def main(argv=None):
    """``blender --python THIS.py [-- rig.json [camera|projector]]``."""
    argv = list(sys.argv if argv is None else argv)
    args = argv[argv.index("--") + 1:] if "--" in argv else []
    path = args[0] if args else os.path.splitext(os.path.abspath(__file__))[0] + ".json"
    create_cameras(path, active=args[1] if len(args) > 1 else None)


if __name__ == "__main__":
    main()
