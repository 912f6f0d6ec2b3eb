"""Opens an sph-run output folder in ParaView (pvbatch) the way a user does, through
frames.pvd, and checks what ParaView sees against the run's own records:
  - the time steps are the .pvd's, the first 0, each the end (t + dt) of a stats.csv step (9 digits);
  - every frame has summary.json's fluid particle count, the arrays asked for, and ids
    0..N-1 in order (frames are written in id order, so point k is particle k in every frame);
  - each frame's TimeValue is its time step;
  - boundary/walls.vtu holds every boundary particle (scenes without moving bodies) with normals;
  - the surface meshes (surface/surface_NNNNN.ply, format "mesh"), opened as one file series:
    one time step per frame, and each step's points and triangles are its file's.
Usage: pvbatch paraview_check.py OUT_DIR ARRAY[,ARRAY...]   (exit 1 with the reason on failure)"""
import csv
import json
import sys

from paraview import servermanager
from paraview.simple import PVDReader
from vtk.util.numpy_support import vtk_to_numpy

out, arrays = sys.argv[1], sys.argv[2].split(",")
summary = json.load(open(f"{out}/summary.json"))
# the end of each step (stats.csv's t is the step's start), to the file's 9 digits
rows = [0.0] + [float(r["t"]) + float(r["dt"]) for r in csv.DictReader(open(f"{out}/stats.csv"))]
reader = PVDReader(FileName=f"{out}/frames.pvd")
times = list(reader.TimestepValues)
fail = []
if len(times) != summary["frames"]:
    fail.append(f"{len(times)} time steps in ParaView, summary.json says {summary['frames']} frames")
if not times or times[0] != 0.0:
    fail.append(f"the first time is {times[:1]}, expected 0")
for t in times:
    if min(abs(t - r) for r in rows) > 1e-8 * max(1.0, t):
        fail.append(f"time {t!r} is the end of no step in stats.csv")
    reader.UpdatePipeline(t)
    data = servermanager.Fetch(reader)
    n = data.GetNumberOfPoints()
    if n != summary["fluid_particles"]:
        fail.append(f"t = {t}: {n} points, expected {summary['fluid_particles']}")
    pd = data.GetPointData()
    names = [pd.GetArrayName(i) for i in range(pd.GetNumberOfArrays())]
    for a in arrays + ["id"]:
        if a not in names:
            fail.append(f"t = {t}: no array '{a}' (has {names})")
    if "id" in names:
        ids = vtk_to_numpy(pd.GetArray("id"))
        if not (ids == range(n)).all():
            fail.append(f"t = {t}: ids are not 0..{n - 1} in order")
    tv = data.GetFieldData().GetArray("TimeValue")
    if tv is None or abs(tv.GetValue(0) - t) > 1e-12:
        fail.append(f"t = {t}: the frame's TimeValue is {None if tv is None else tv.GetValue(0)}")
# The walls, written once (a scene without moving bodies: all of its boundary particles).
import os
from paraview.simple import XMLUnstructuredGridReader
bfile = f"{out}/boundary/walls.vtu"
if not os.path.exists(bfile):
    fail.append("no boundary/walls.vtu")
else:
    b = servermanager.Fetch(XMLUnstructuredGridReader(FileName=[bfile]))
    bnames = [b.GetPointData().GetArrayName(i) for i in range(b.GetPointData().GetNumberOfArrays())]
    if b.GetNumberOfPoints() != summary["boundary_particles"] or "normal" not in bnames:
        fail.append(f"walls.vtu: {b.GetNumberOfPoints()} points (summary {summary['boundary_particles']}), "
                    f"arrays {bnames}")
import glob
from paraview.simple import PLYReader
surfaces = sorted(glob.glob(f"{out}/surface/surface_*.ply"))
if surfaces:
    series = PLYReader(FileNames=surfaces)
    steps = list(series.TimestepValues)
    if len(steps) != len(surfaces) or len(surfaces) != summary["frames"]:
        fail.append(f"the surface series: {len(steps)} time steps for {len(surfaces)} files, {summary['frames']} frames")
    for k in sorted({0, len(surfaces) - 1}):
        series.UpdatePipeline(steps[k] if steps else 0)
        d = servermanager.Fetch(series)
        with open(surfaces[k], "rb") as f:
            head = f.read(1024).split(b"end_header")[0].decode("ascii").split("\n")
        nv = int(next(line for line in head if line.startswith("element vertex")).split()[2])
        nf = int(next(line for line in head if line.startswith("element face")).split()[2])
        if (d.GetNumberOfPoints(), d.GetNumberOfCells()) != (nv, nf) or nf == 0:
            fail.append(f"surface frame {k}: ParaView has {d.GetNumberOfPoints()} points, {d.GetNumberOfCells()} "
                        f"cells; the file {nv}, {nf}")
    print(f"ParaView read {len(surfaces)} surface meshes")
print(f"ParaView read {len(times)} time steps of {summary['fluid_particles']} points: "
      + ("ok" if not fail else "FAILED"))
for f in fail:
    print("FAIL:", f)
sys.exit(1 if fail else 0)
