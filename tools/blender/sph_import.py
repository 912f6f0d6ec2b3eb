"""Imports an sph-run output folder into Blender as one animated point cloud.

    blender -b --python tools/blender/sph_import.py -- OUT_DIR [--save FILE.blend]
    (or, in Blender: Scripting > Open > Run Script, then File > Import > sph-run folder)

The run's PLY frames (scene key "output": {"format": ["ply"]}, or `sph-run --format ply`) become
one object, "sph_fluid", whose mesh holds one vertex per particle and, per vertex, every
attribute the frames carry (velocity as a vector, density, pressure, dt, ... as floats, id as an
integer), for Geometry Nodes and shaders ("Attribute" node). Blender's own PLY importer drops
those attributes and loads each frame as a separate object.

Axes: sph is y-up, Blender z-up; a point (x, y, z) becomes (x, -z, y), vectors likewise, so the
fluid falls along -Z. Frames: Blender frame `frame_start + k` shows frame k; the scene's frame
rate is set from the frames' times (frames.pvd or the PLY comments). The mesh is replaced on
every frame change by a handler this script registers; the .blend keeps this script as a text
block that registers the handler again when the file is opened (with "Auto Run Python Scripts"
allowed, or run it once by hand).
"""
import os
import re
import sys

import bpy
import numpy as np
from bpy.app.handlers import persistent

# Names Blender keeps for itself (mesh.attributes.new returns None for them).
_RESERVED = {"normal": "wall_normal", "position": "sph_position"}
_PLY_TYPES = {"float": "<f4", "double": "<f8", "uchar": "u1", "uint": "<u4", "int": "<i4"}
def _numbered(prefix):
    return re.compile(prefix + r"_(\d{5})\.ply$")


def read_ply(path):
    """(columns by property name as numpy arrays, t) of one binary little-endian sph PLY frame."""
    with open(path, "rb") as f:
        if f.readline().strip() != b"ply":
            raise ValueError(f"{path}: not a PLY file")
        props, n, t = [], 0, None
        while True:
            line = f.readline()
            if not line:
                raise ValueError(f"{path}: the header has no end_header")
            words = line.decode("ascii", "replace").split()
            if not words:
                continue
            if words[0] == "format" and words[1] != "binary_little_endian":
                raise ValueError(f"{path}: format {words[1]}, expected binary_little_endian (an sph-run frame)")
            if words[0] == "comment" and "t =" in line.decode("ascii", "replace"):
                t = float(line.decode("ascii").split("t =")[1].split()[0])
            if words[0] == "element" and words[1] == "vertex":
                n = int(words[2])
            if words[0] == "property":
                if words[1] not in _PLY_TYPES:
                    raise ValueError(f"{path}: property type {words[1]} is not one sph-run writes")
                props.append((words[2], _PLY_TYPES[words[1]]))
            if words[0] == "end_header":
                break
        data = np.frombuffer(f.read(), dtype=np.dtype(props), count=n)
    return {name: data[name] for name, _ in props}, t


def frames_of(folder, prefix="frame"):
    """The PLY files of an output folder in frame order: frames/frame_NNNNN.ply (prefix "frame",
    the fluid) or boundary/moving_NNNNN.ply (prefix "moving", the moving bodies)."""
    d = os.path.join(folder, "frames" if prefix == "frame" else "boundary")
    if not os.path.isdir(d):
        if prefix != "frame":
            return []
        raise FileNotFoundError(f"{folder}: no frames/ folder (is this an sph-run output folder?)")
    pattern = _numbered(prefix)
    files = sorted(f for f in os.listdir(d) if pattern.search(f))
    if not files and prefix == "frame":
        raise FileNotFoundError(f"{d}: no frame_NNNNN.ply (run sph-run with --format ply)")
    return [os.path.join(d, f) for f in files]


def _z_up(x, y, z):
    return np.stack([x, -z, y], axis=1)


def _attributes(cols):
    """Blender attributes of one frame: name -> (type, values)."""
    out = {}
    names = [k for k in cols if k not in ("x", "y", "z")]
    vectors = {k[:-2] for k in names if k.endswith("_x") and k[:-2] + "_y" in cols and k[:-2] + "_z" in cols}
    for v in sorted(vectors):
        out[v] = ("FLOAT_VECTOR", _z_up(cols[v + "_x"], cols[v + "_y"], cols[v + "_z"]).astype(np.float32))
    for k in names:
        if k[:-2] in vectors:
            continue
        if k == "id" or cols[k].dtype.kind in "ui":
            out[k] = ("INT", cols[k].astype(np.int32))
        else:
            out[k] = ("FLOAT", cols[k].astype(np.float32))
    return out


def load_frame(mesh, path):
    """Replaces the mesh's vertices and attributes with the PLY frame at `path`."""
    cols, _ = read_ply(path)
    n = len(cols["x"])
    co = _z_up(cols["x"], cols["y"], cols["z"]).astype(np.float32)
    if len(mesh.vertices) != n:  # emitters add particles: rebuild
        mesh.clear_geometry()
        mesh.vertices.add(n)
    mesh.vertices.foreach_set("co", co.ravel())
    for name, (kind, values) in _attributes(cols).items():
        name = _RESERVED.get(name, name)
        a = mesh.attributes.get(name)
        if a is None or a.data_type != kind or a.domain != "POINT":
            if a is not None:
                mesh.attributes.remove(a)
            a = mesh.attributes.new(name, kind, "POINT")
            if a is None:
                raise ValueError(f"{path}: Blender refuses an attribute named '{name}'")
        a.data.foreach_set("vector" if kind == "FLOAT_VECTOR" else "value", values.ravel())
    mesh["sph_frame"] = path
    mesh.update()


@persistent
def _on_frame(scene, *_):
    for obj in scene.objects:
        folder = obj.get("sph_run")
        if not folder or obj.type != "MESH":
            continue
        files = frames_of(folder, obj.get("sph_prefix", "frame"))
        if not files:
            continue
        k = min(max(scene.frame_current - scene.frame_start, 0), len(files) - 1)
        if obj.data.get("sph_frame") != files[k]:
            load_frame(obj.data, files[k])


def register_handler():
    for h in list(bpy.app.handlers.frame_change_pre):
        if getattr(h, "__name__", "") == "_on_frame":
            bpy.app.handlers.frame_change_pre.remove(h)
    bpy.app.handlers.frame_change_pre.append(_on_frame)


def _object(name, path):
    mesh = bpy.data.meshes.new(name)
    load_frame(mesh, path)
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def import_run(folder, name="sph_fluid"):
    """Creates the animated point-cloud object of an sph-run output folder (and, when the run
    wrote them, "sph_boundary": the walls and obstacles, and "sph_boundary_moving": the moving
    bodies, animated); returns the fluid's object."""
    folder = os.path.abspath(folder)
    files = frames_of(folder)
    obj = _object(name, files[0])
    obj["sph_run"] = folder
    static = os.path.join(folder, "boundary", "walls.ply")
    if os.path.exists(static):
        _object("sph_boundary", static)
    moving = frames_of(folder, "moving")
    if moving:
        m = _object("sph_boundary_moving", moving[0])
        m["sph_run"], m["sph_prefix"] = folder, "moving"
    scene = bpy.context.scene
    scene.frame_end = scene.frame_start + len(files) - 1
    if len(files) > 1:
        _, t_last = read_ply(files[-1])
        if t_last:
            scene.render.fps = max(1, round((len(files) - 1) / t_last))
    # Keep this script in the .blend, registering the handler when the file is opened.
    text = bpy.data.texts.get("sph_import.py") or bpy.data.texts.new("sph_import.py")
    text.from_string(open(__file__).read())
    text.use_module = True
    register_handler()
    return obj


class ImportSphRun(bpy.types.Operator):
    """Import an sph-run output folder (PLY frames) as an animated point cloud"""
    bl_idname = "import_scene.sph_run"
    bl_label = "sph-run folder"
    directory: bpy.props.StringProperty(subtype="DIR_PATH")

    def execute(self, context):
        folder = self.directory.rstrip("/")
        if os.path.basename(folder) == "frames":
            folder = os.path.dirname(folder)
        import_run(folder)
        return {"FINISHED"}

    def invoke(self, context, event):
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}


def _menu(self, context):
    self.layout.operator(ImportSphRun.bl_idname, text="sph-run folder (PLY frames)")


def register():
    if not hasattr(bpy.types, "IMPORT_SCENE_OT_sph_run"):
        bpy.utils.register_class(ImportSphRun)
        bpy.types.TOPBAR_MT_file_import.append(_menu)
    register_handler()


if __name__ == "__main__" or __name__ == "sph_import.py":
    register()
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    if argv:
        import_run(argv[0])
        if "--save" in argv:
            bpy.ops.wm.save_as_mainfile(filepath=os.path.abspath(argv[argv.index("--save") + 1]))
