"""Runs inside Blender (blender -b --factory-startup --python-exit-code 1 --python THIS --
IMPORTER OUT_DIR): imports an sph-run folder with tools/blender/sph_import.py and checks what
Blender holds against the PLY files, read here independently (struct, no numpy):
  - one object for the whole run (not one per frame), frame range = the run's frame count, and
    the tank as a second object (every boundary particle, the floor below the fluid, normals),
    and moving bodies as a third, animated with their own PLY files;
  - at the first, middle and last frame: one vertex per fluid particle; vertex k is particle k
    (attribute id = k) at the PLY's (x, -z, y) (z-up) to 1e-6 m; velocity a vector attribute,
    density and pressure float attributes; density within 5 % of the rest density (after
    frame 0, which is written before the first density evaluation);
  - up is +Z: the fluid rests on z >= 0 at frame 0 and (dam_break) falls, mean velocity z < 0,
    at the last;
  - the surface, when the run wrote it: "sph_surface" holds at each checked frame that frame's
    mesh PLY (vertex and triangle counts, a vertex at (x, -z, y)); Blender's own bmesh finds every
    edge manifold and an enclosed volume within 1 % of the particles' N (2 r)^3 (the importer and
    the engine's keep_volume together: measured 0.2 % on dam_break); "sph_surface_volume" loads
    that frame's .vdb with its level-set grid "surface".
Exit 1 with the reasons on any failure."""
import importlib.util
import json
import os
import struct
import sys

import bmesh
import bpy

importer, out = sys.argv[sys.argv.index("--") + 1:][:2]
spec = importlib.util.spec_from_file_location("sph_import", importer)
sph_import = importlib.util.module_from_spec(spec)
spec.loader.exec_module(sph_import)
summary = json.load(open(os.path.join(out, "summary.json")))
n_fluid = summary["fluid_particles"]
fail = []


def ply_rows(path, rows):
    """{property: value} of the given vertex rows of an sph PLY frame, by struct."""
    with open(path, "rb") as f:
        props = []
        while True:
            w = f.readline().decode("ascii").split()
            if w and w[0] == "property":
                props.append((w[2], {"float": "f", "double": "d", "uchar": "B", "uint": "I"}[w[1]]))
            if w and w[0] == "end_header":
                break
        fmt = "<" + "".join(t for _, t in props)
        size = struct.calcsize(fmt)
        body = f.read()
    return [dict(zip([p for p, _ in props], struct.unpack_from(fmt, body, r * size))) for r in rows]


for o in list(bpy.data.objects):
    bpy.data.objects.remove(o)
obj = sph_import.import_run(out)
scene = bpy.context.scene
files = sph_import.frames_of(out)
names = sorted(o.name for o in bpy.data.objects)
moving = sph_import.frames_of(out, "moving")
surfaces, volumes = sph_import.frames_of(out, "surface"), sph_import.frames_of(out, "surface", "vdb")
expected = (["sph_boundary"] + (["sph_boundary_moving"] if moving else []) + ["sph_fluid"] +
            (["sph_surface"] if surfaces else []) + (["sph_surface_volume"] if volumes else []))
if names != expected:
    fail.append(f"objects {names}, expected the fluid (one for the whole run) and the boundary")
else:
    b = bpy.data.objects["sph_boundary"].data
    zb = [v.co.z for v in b.vertices]
    n_moving = len(bpy.data.objects["sph_boundary_moving"].data.vertices) if moving else 0
    if len(b.vertices) + n_moving != summary["boundary_particles"] or min(zb) > 0 or "wall_normal" not in b.attributes:
        fail.append(f"the boundary: {len(b.vertices)} + {n_moving} moving points (summary {summary['boundary_particles']}), "
                    f"lowest z {min(zb)} (expected the floor below the fluid), attributes {list(b.attributes.keys())}")
if scene.frame_end - scene.frame_start + 1 != len(files) or len(files) != summary["frames"]:
    fail.append(f"frames {scene.frame_start}..{scene.frame_end} for {len(files)} PLY files, summary {summary['frames']}")
rho0 = summary["physics"].get("rest_density", 1000.0) if isinstance(summary.get("physics"), dict) else 1000.0
for k in sorted({0, len(files) // 2, len(files) - 1}):
    scene.frame_set(scene.frame_start + k)
    mesh = obj.data
    n = len(mesh.vertices)
    if n != n_fluid:
        fail.append(f"frame {k}: {n} vertices, expected {n_fluid}")
        continue
    attrs = {a.name: (a.data_type, a.domain) for a in mesh.attributes}
    for name, kind in [("velocity", "FLOAT_VECTOR"), ("density", "FLOAT"), ("pressure", "FLOAT"), ("id", "INT")]:
        if attrs.get(name) != (kind, "POINT"):
            fail.append(f"frame {k}: attribute {name} is {attrs.get(name)}, expected ({kind}, POINT)")
    if "id" in attrs and any(mesh.attributes["id"].data[i].value != i for i in range(0, n, 97)):
        fail.append(f"frame {k}: vertex i does not hold particle i")
    for i, row in zip((0, n - 1), ply_rows(files[k], (0, n - 1))):
        want = (row["x"], -row["z"], row["y"])
        got = tuple(mesh.vertices[i].co)
        if max(abs(a - b) for a, b in zip(got, want)) > 1e-6:
            fail.append(f"frame {k}: vertex {i} at {got}, the PLY (z-up) says {want}")
    dens = [d.value for d in mesh.attributes["density"].data] if "density" in attrs else [0]
    mean_rho = sum(dens) / len(dens)
    if k > 0 and abs(mean_rho / rho0 - 1) > 0.05:  # frame 0 precedes the first density evaluation
        fail.append(f"frame {k}: mean density {mean_rho:.1f}, expected within 5 % of {rho0}")
    zs = [v.co.z for v in mesh.vertices]
    if k == 0 and min(zs) < 0:
        fail.append(f"frame 0: lowest particle at z = {min(zs)}, expected on or above the floor (z-up)")
    if moving:
        mv = bpy.data.objects["sph_boundary_moving"].data
        row = ply_rows(moving[k], (0,))[0]
        want = (row["x"], -row["z"], row["y"])
        if max(abs(a - b) for a, b in zip(tuple(mv.vertices[0].co), want)) > 1e-6:
            fail.append(f"frame {k}: the moving body's first point at {tuple(mv.vertices[0].co)}, its PLY says {want}")
    if k == len(files) - 1 and k > 0 and summary["scene"] == "dam_break":
        vz = sum(d.vector.z for d in mesh.attributes["velocity"].data) / n
        if not vz < 0:
            fail.append(f"frame {k}: mean velocity z = {vz}, expected the column falling (< 0)")
fluid_volume = n_fluid * (2 * summary["physics"]["particle_radius"]) ** 3
for k in sorted({0, len(surfaces) // 2, len(surfaces) - 1}) if surfaces else []:
    scene.frame_set(scene.frame_start + k)
    mesh = bpy.data.objects["sph_surface"].data
    with open(surfaces[k], "rb") as f:
        data = f.read()
    body_at = data.index(b"end_header\n") + len(b"end_header\n")
    head = data[:body_at].decode("ascii").split("\n")
    nv = int(next(line for line in head if line.startswith("element vertex")).split()[2])
    nf = int(next(line for line in head if line.startswith("element face")).split()[2])
    x, y, z = struct.unpack_from("<3f", data, body_at)
    if (len(mesh.vertices), len(mesh.polygons)) != (nv, nf):
        fail.append(f"surface frame {k}: {len(mesh.vertices)} vertices, {len(mesh.polygons)} faces; the PLY has {nv}, {nf}")
        continue
    if max(abs(a - b) for a, b in zip(tuple(mesh.vertices[0].co), (x, -z, y))) > 1e-6:
        fail.append(f"surface frame {k}: vertex 0 at {tuple(mesh.vertices[0].co)}, the PLY (z-up) says {(x, -z, y)}")
    bm = bmesh.new()
    bm.from_mesh(mesh)
    open_edges = sum(not e.is_manifold for e in bm.edges)
    volume = bm.calc_volume(signed=True)
    bm.free()
    if open_edges or abs(volume / fluid_volume - 1) > 0.01:
        fail.append(f"surface frame {k}: {open_edges} non-manifold edges, volume {volume:.6g} m3 against the "
                    f"particles' {fluid_volume:.6g} (expected closed and within 1 %)")
for k in sorted({0, len(volumes) - 1}) if volumes else []:
    scene.frame_set(scene.frame_start + k)
    vobj = bpy.data.objects["sph_surface_volume"]
    grids = vobj.evaluated_get(bpy.context.evaluated_depsgraph_get()).data.grids
    grids.load()
    if os.path.basename(grids.frame_filepath) != os.path.basename(volumes[k]) or "surface" not in [g.name for g in grids]:
        fail.append(f"volume frame {k}: Blender loaded '{grids.frame_filepath}' with grids "
                    f"{[g.name for g in grids]}, expected {os.path.basename(volumes[k])} with 'surface'")
if surfaces or volumes:
    print(f"Blender imported {len(surfaces)} surface meshes and {len(volumes)} level sets")
print(f"Blender imported {len(files)} frames of {n_fluid} particles as '{obj.name}': " + ("ok" if not fail else "FAILED"))
for f in fail:
    print("FAIL:", f)
sys.exit(1 if fail else 0)
