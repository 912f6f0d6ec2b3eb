"""Imports an sph-run output folder into Blender as one animated point cloud (and surface).

    blender -b --python tools/blender/sph_import.py -- OUT_DIR [--save FILE.blend]
    (or, in Blender: Scripting > Open > Run Script, then File > Import > sph-run folder)

The run's PLY frames (scene key "output": {"format": ["ply"]}, or `sph-run --format ply`) become
one object, "sph_fluid", whose mesh holds one vertex per particle and, per vertex, every
attribute the frames carry (velocity as a vector, density, pressure, dt, ... as floats, id as an
integer), for Geometry Nodes and shaders ("Attribute" node). Blender's own PLY importer drops
those attributes and loads each frame as a separate object.

The fluid surface, when the run wrote it: its meshes (format "mesh", surface/surface_NNNNN.ply)
become one animated, smooth-shaded mesh object "sph_surface"; its level sets (format "vdb",
surface/surface_NNNNN.vdb) one volume object "sph_surface_volume", a native Blender volume
sequence (hidden in renders: the mesh is what renders; unhide it for volume shading).

Axes: sph is y-up, Blender z-up; a point (x, y, z) becomes (x, -z, y), vectors likewise, so the
fluid falls along -Z. Frames: Blender frame `frame_start + k` shows frame k; the scene's frame
rate is set from the frames' times (frames.pvd or the PLY comments). The mesh is replaced on
every frame change by a handler this script registers; the .blend keeps this script as a text
block that registers the handler again when the file is opened (with "Auto Run Python Scripts"
allowed, or run it once by hand).
"""
import math
import os
import re
import sys

import bpy
import numpy as np
from bpy.app.handlers import persistent

# Names Blender keeps for itself (mesh.attributes.new returns None for them).
_RESERVED = {"normal": "wall_normal", "position": "sph_position"}
_PLY_TYPES = {"float": "<f4", "double": "<f8", "uchar": "u1", "uint": "<u4", "int": "<i4"}


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


_FOLDERS = {"frame": "frames", "moving": "boundary", "surface": "surface"}


def frames_of(folder, prefix="frame", ext="ply"):
    """The files of an output folder in frame order: frames/frame_NNNNN.ply (prefix "frame", the
    fluid), boundary/moving_NNNNN.ply ("moving", the moving bodies), surface/surface_NNNNN.ply
    or .vdb ("surface"); [] when the run wrote none."""
    d = os.path.join(folder, _FOLDERS[prefix])
    if not os.path.isdir(d):
        return []
    pattern = re.compile(prefix + r"_(\d{5})\." + ext + "$")
    return [os.path.join(d, f) for f in sorted(f for f in os.listdir(d) if pattern.search(f))]


def read_mesh_ply(path):
    """(vertices (n, 3) float32, triangles (m, 3) int32) of an sph-run surface mesh."""
    with open(path, "rb") as f:
        n = m = 0
        while True:
            line = f.readline()
            if not line:
                raise ValueError(f"{path}: the header has no end_header")
            w = line.decode("ascii", "replace").split()
            if w[:2] == ["element", "vertex"]:
                n = int(w[2])
            if w[:2] == ["element", "face"]:
                m = int(w[2])
            if w and w[0] == "end_header":
                break
        v = np.frombuffer(f.read(12 * n), dtype="<f4").reshape(n, 3)
        faces = np.frombuffer(f.read(13 * m), dtype=np.dtype([("k", "u1"), ("i", "<i4", 3)]))
    if m and (faces["k"] != 3).any():
        raise ValueError(f"{path}: a face that is not a triangle (not an sph-run surface mesh)")
    return v, faces["i"].astype(np.int32)


def load_surface(mesh, path):
    """Replaces the mesh's geometry with the surface mesh at `path` (z-up, smooth shaded)."""
    v, tri = read_mesh_ply(path)
    mesh.clear_geometry()
    mesh.vertices.add(len(v))
    mesh.vertices.foreach_set("co", _z_up(v[:, 0], v[:, 1], v[:, 2]).astype(np.float32).ravel())
    m = len(tri)
    mesh.loops.add(3 * m)
    mesh.loops.foreach_set("vertex_index", tri.ravel())
    mesh.polygons.add(m)
    mesh.polygons.foreach_set("loop_start", np.arange(0, 3 * m, 3, dtype=np.int32))
    mesh.polygons.foreach_set("loop_total", np.full(m, 3, dtype=np.int32))
    mesh.polygons.foreach_set("use_smooth", np.ones(m, dtype=bool))
    mesh.update(calc_edges=True)
    mesh["sph_frame"] = path


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


def _last_frame(folder):
    """(frame count, simulated time of the last frame), from the PLY frames' "t =" comments."""
    files = frames_of(folder) or frames_of(folder, "surface")
    if not files:
        return 0, 0.0
    with open(files[-1], "rb") as h:
        for line in iter(h.readline, b""):
            text = line.decode("ascii", "replace")
            if text.startswith("comment") and "t =" in text:
                return len(files), float(text.split("t =")[1].split()[0])
            if text.startswith("end_header"):
                break
    return len(files), 0.0


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
            (load_surface if obj.get("sph_prefix") == "surface" else load_frame)(obj.data, files[k])


def register_handler():
    for h in list(bpy.app.handlers.frame_change_pre):
        if getattr(h, "__name__", "") == "_on_frame":
            bpy.app.handlers.frame_change_pre.remove(h)
    bpy.app.handlers.frame_change_pre.append(_on_frame)


def _object(name, path, loader=load_frame):
    mesh = bpy.data.meshes.new(name)
    loader(mesh, path)
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def _volume(name, files, scene):
    """A Blender volume sequence of the .vdb files: file k shows at frame frame_start + k."""
    vol = bpy.data.volumes.new(name)
    vol.filepath = files[0]
    vol.is_sequence = len(files) > 1
    vol.frame_start = scene.frame_start
    vol.frame_duration = len(files)
    vol.frame_offset = -1  # Blender numbers the first frame of a sequence 1; ours is 00000
    vol.sequence_mode = "CLIP"
    obj = bpy.data.objects.new(name, vol)
    obj.rotation_euler = (math.pi / 2, 0.0, 0.0)  # y-up grid: (x, y, z) -> (x, -z, y), as the points
    obj.hide_render = True
    scene.collection.objects.link(obj)
    return obj


def import_run(folder, name="sph_fluid"):
    """Creates the animated point-cloud object of an sph-run output folder (and, when the run
    wrote them, "sph_boundary": the walls and obstacles, "sph_boundary_moving": the moving
    bodies, animated, and the surface: "sph_surface" (meshes), "sph_surface_volume" (level
    sets)); returns the fluid's object, or the surface's when the run wrote no particle frames."""
    folder = os.path.abspath(folder)
    if not os.path.isdir(folder):
        raise FileNotFoundError(f"{folder}: no such folder")
    files = frames_of(folder)
    surfaces, volumes = frames_of(folder, "surface"), frames_of(folder, "surface", "vdb")
    if not (files or surfaces or volumes):
        raise FileNotFoundError(f"{folder}: no frames/frame_NNNNN.ply and no surface/ (run sph-run with "
                                "--format ply, and mesh or vdb for the surface)")
    obj = None
    if files:
        obj = _object(name, files[0])
        obj["sph_run"] = folder
    if surfaces:
        s = _object("sph_surface", surfaces[0], load_surface)
        s["sph_run"], s["sph_prefix"] = folder, "surface"
        obj = obj or s
    scene = bpy.context.scene
    if volumes:
        v = _volume("sph_surface_volume", volumes, scene)
        obj = obj or v
    files = files or surfaces or volumes
    static = os.path.join(folder, "boundary", "walls.ply")
    if os.path.exists(static):
        _object("sph_boundary", static)
    moving = frames_of(folder, "moving")
    if moving:
        m = _object("sph_boundary_moving", moving[0])
        m["sph_run"], m["sph_prefix"] = folder, "moving"
    scene.frame_end = scene.frame_start + len(files) - 1
    n, t_last = _last_frame(folder)
    if n > 1 and t_last > 0:
        scene.render.fps = max(1, round((n - 1) / t_last))
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
