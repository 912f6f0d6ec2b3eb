#!/usr/bin/python3
"""Writes the inner surface of a drinking glass as a Wavefront OBJ: a surface of revolution
about the y axis (radius 0.08 m at the bottom widening to 0.11 m at the rim, 0.22 m tall) and
its circular bottom. Triangles face the axis and up, i.e. the fluid side (the engine samples
boundary particles one radius behind the front face).

usage: tools/make_glass_obj.py [OUT.obj] [--segments 48] [--rings 12]
"""
import argparse
import math
from sph_python import errors_as_exit_2, require  # noqa: E402 (tools/ is the script's folder)

errors_as_exit_2()

ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
ap.add_argument("out", nargs="?", default="scenes/meshes/glass.obj")
ap.add_argument("--segments", type=int, default=48)
ap.add_argument("--rings", type=int, default=12)
args = ap.parse_args()
require(args.segments >= 3, f"--segments {args.segments}: expected at least 3 (a closed ring)")
require(args.rings >= 1, f"--rings {args.rings}: expected at least 1")

r_bottom, r_top, height = 0.08, 0.11, 0.22
n, m = args.segments, args.rings
verts = []
for k in range(m + 1):  # side rings, bottom (k = 0) to rim
    y = height * k / m
    r = r_bottom + (r_top - r_bottom) * k / m
    for i in range(n):
        a = 2 * math.pi * i / n
        verts.append((r * math.cos(a), y, r * math.sin(a)))
centre = len(verts)
verts.append((0.0, 0.0, 0.0))
faces = []
ring = lambda k, i: k * n + (i % n)
for k in range(m):
    for i in range(n):
        # Front side towards the axis: counter-clockwise seen from inside.
        a, b, c, d = ring(k, i), ring(k, i + 1), ring(k + 1, i + 1), ring(k + 1, i)
        faces.append((a, c, d))
        faces.append((a, b, c))
for i in range(n):  # bottom disc, facing up
    faces.append((centre, ring(0, i + 1), ring(0, i)))
with open(args.out, "w") as fh:
    fh.write(f"# inner surface of a glass: {len(verts)} vertices, {len(faces)} triangles (tools/make_glass_obj.py)\n")
    for v in verts:
        fh.write(f"v {v[0]:.6f} {v[1]:.6f} {v[2]:.6f}\n")
    for f in faces:
        fh.write(f"f {f[0] + 1} {f[1] + 1} {f[2] + 1}\n")
print(f"{args.out}: {len(verts)} vertices, {len(faces)} triangles")
