"""Load an alfe run in ParaView as a user would, check what it shows, draw its last step.

    xvfb-run -a pvpython scripts/paraview_shots.py RUN_DIR SCENE OUT.png

Opens RUN_DIR/SCENE.xmf with ParaView's "XDMF Reader" (the reader the manual names) and
compares what ParaView shows with the HDF5 file as h5py reads it (a /usr/bin/python3
subprocess: pvpython's own Python need not have h5py):

  * the time steps: the state at t = 0, then every output step's time;
  * the blocks, at the first and at the last step: the parts by name (HDF5
    /mesh attribute `part_names`), then every wall, entity, coupling and traced point
    (the groups with a `block` or `path_block` attribute); the same names at both steps;
  * the bounds, at the last step: each part's deformed surface (WarpByVector of
    `displacement`, then its surface: points no cell of the part uses are not drawn)
    against x + u of the nodes of the part's cells from HDF5; every other block's points
    against /steps/<last>/<its group>/points (a path's: .../path/points);
  * closed surfaces: a wall or entity whose shape encloses a solid (not a plane) has no
    boundary edge (ParaView's FeatureEdges);

then renders the last step (parts coloured by von Mises, walls and entities grey) to
OUT.png and checks that the picture is not blank. Prints one summary line; exits 1 with
`FAIL:` lines on any mismatch.
"""

import json
import os
import subprocess
import sys

from paraview import servermanager as sm
from paraview.simple import (
    ColorBy,
    ExtractBlock,
    ExtractSurface,
    FeatureEdges,
    GetActiveViewOrCreate,
    GetColorTransferFunction,
    GetScalarBar,
    MergeBlocks,
    Render,
    ResetCamera,
    SaveScreenshot,
    Show,
    WarpByVector,
    XDMFReader,
)

H5 = r"""
import sys, json, h5py, numpy as np
f = h5py.File(sys.argv[1], "r")
steps = sorted(f["steps"].keys())
last = f["steps"][steps[-1]]
x = f["mesh/coordinates"][...] + last["displacement"][...]
conn = f["mesh/connectivity"][...]
part = f["mesh/part"][...]
names = json.loads(f["mesh"].attrs["part_names"])
mixed = conn.ndim == 1
if mixed:  # [type, nodes...] per cell; node counts by XDMF type id
    per = {9: 8, 6: 4, 38: 10, 8: 6}
    cells, i = [], 0
    while i < len(conn):
        n = per[int(conn[i])]
        cells.append(conn[i + 1:i + 1 + n]); i += 1 + n
else:
    cells = list(conn)
parts = {}
for p, name in enumerate(names):
    used = sorted({int(v) for c, q in zip(cells, part) if q == p for v in c})
    if used:
        parts[name] = [x[used].min(0).tolist(), x[used].max(0).tolist()]
grids = {}
def grid(name, g):
    attr = lambda k: (lambda v: v.decode() if isinstance(v, bytes) else str(v))(g.attrs.get(k, b""))
    if "block" in g.attrs:
        pts = last[name]["points"][...]
        grids[attr("block")] = [pts.min(0).tolist(), pts.max(0).tolist(), attr("shape")]
    if "path_block" in g.attrs:
        pts = last[name]["path"]["points"][...]
        grids[attr("path_block")] = [pts.min(0).tolist(), pts.max(0).tolist(), ""]
f.visititems(lambda name, g: grid(name, g) if isinstance(g, h5py.Group)
             and not name.startswith(("steps", "mesh")) else None)
print(json.dumps({"times": [float(f["steps"][s].attrs["time"]) for s in steps],
                  "parts": parts, "part_order": [n for n in names if n in parts],
                  "grids": grids}))
"""

OPEN_SHAPES = {"plane", "finite-plane"}


def block_names(data):
    return [data.GetMetaData(i).Get(data.NAME()) for i in range(data.GetNumberOfBlocks())]


def bounds_close(a, b, scale):
    return all(abs(p - q) <= 1e-6 * scale for p, q in zip(a, b))


def main():
    run_dir, scene, png = sys.argv[1], sys.argv[2], sys.argv[3]
    fails = []
    h5 = json.loads(subprocess.run(
        ["/usr/bin/python3", "-c", H5, os.path.join(run_dir, scene + ".h5")],
        check=True, capture_output=True, text=True,
        env=dict(os.environ, HDF5_USE_FILE_LOCKING="FALSE")).stdout)
    reader = XDMFReader(FileNames=[os.path.join(run_dir, scene + ".xmf")])
    times = list(reader.TimestepValues)
    if times[0] != 0.0 or len(times) != len(h5["times"]) or any(
            abs(a - b) > 1e-12 * max(1.0, abs(b)) for a, b in zip(times, h5["times"])):
        fails.append(f"times {times} != HDF5 {h5['times']} (t = 0 first)")
    want = h5["part_order"] + sorted(h5["grids"])
    for t in (times[0], times[-1]):
        reader.UpdatePipeline(t)
        got = block_names(sm.Fetch(reader))
        if sorted(got[len(h5["part_order"]):]) != sorted(h5["grids"]) or \
                got[:len(h5["part_order"])] != h5["part_order"]:
            fails.append(f"blocks at t = {t}: {got}, expected {want}")
    t_end = times[-1]
    lo = [min(b[0][c] for b in h5["parts"].values()) for c in range(3)]
    hi = [max(b[1][c] for b in h5["parts"].values()) for c in range(3)]
    scale = max(h - l for l, h in zip(lo, hi))
    # Each part's drawn (surface) bounds, deformed, against HDF5.
    for i, name in enumerate(h5["part_order"]):
        one = ExtractBlock(Input=reader, Selectors=[f"/Root/{name}"])
        surf = ExtractSurface(Input=MergeBlocks(Input=WarpByVector(Input=one, Vectors=["POINTS", "displacement"])))
        surf.UpdatePipeline(t_end)
        b = sm.Fetch(surf).GetBounds()
        got = [b[0], b[2], b[4], b[1], b[3], b[5]]
        exp = h5["parts"][name][0] + h5["parts"][name][1]
        if not bounds_close(got, exp, scale):
            fails.append(f"part {name}: drawn bounds {got}, HDF5 {exp}")
    for name, (blo, bhi, shape) in h5["grids"].items():
        one = ExtractBlock(Input=reader, Selectors=[f"/Root/{name}"])
        merged = MergeBlocks(Input=one)
        merged.UpdatePipeline(t_end)
        d = sm.Fetch(merged)
        b = d.GetBounds()
        if not bounds_close([b[0], b[2], b[4], b[1], b[3], b[5]], blo + bhi, scale):
            fails.append(f"{name}: bounds {b}, HDF5 {blo + bhi}")
        if shape and shape not in OPEN_SHAPES and d.GetNumberOfCells() > 0 and "trace" not in name:
            edges = FeatureEdges(Input=ExtractSurface(Input=merged), BoundaryEdges=1,
                                 FeatureEdges=0, NonManifoldEdges=1, ManifoldEdges=0)
            edges.UpdatePipeline(t_end)
            n = sm.Fetch(edges).GetNumberOfCells()
            if n:
                fails.append(f"{name} ({shape}): {n} open or non-manifold edges")
    # The picture: the deformed parts by von Mises, walls and entities grey.
    view = GetActiveViewOrCreate("RenderView")
    view.ViewSize = [1200, 800]
    view.ViewTime = t_end
    view.OrientationAxesVisibility = 1
    view.Background = [1.0, 1.0, 1.0]
    try:
        view.UseColorPaletteForBackground = 0
    except AttributeError:
        pass
    parts = ExtractBlock(Input=reader, Selectors=[f"/Root/{n}" for n in h5["part_order"]])
    warped = WarpByVector(Input=parts, Vectors=["POINTS", "displacement"])
    d = Show(warped, view)
    d.Representation = "Surface With Edges"
    ColorBy(d, ("CELLS", "von_mises"))
    d.RescaleTransferFunctionToDataRange(True, False)
    d.SetScalarBarVisibility(view, True)
    bar = GetScalarBar(GetColorTransferFunction("von_mises"), view)
    bar.Title = "von Mises stress"
    bar.ComponentTitle = ""
    bar.TitleColor = bar.LabelColor = [0.1, 0.1, 0.1]
    if h5["grids"]:
        rigid = ExtractBlock(Input=reader, Selectors=[f"/Root/{n}" for n in h5["grids"]])
        r = Show(rigid, view)
        r.ColorArrayName = [None, ""]
        r.DiffuseColor = [0.6, 0.6, 0.65]
        r.Opacity = 0.6
    view.CameraPosition = [1.0, -1.6, 1.0]
    view.CameraFocalPoint = [0.0, 0.0, 0.0]
    view.CameraViewUp = [0.0, 0.0, 1.0]
    ResetCamera(view)
    Render(view)
    SaveScreenshot(png, view, ImageResolution=[1200, 800])
    # Not blank: enough pixels differ from the white background.
    from vtkmodules.vtkIOImage import vtkPNGReader
    img = vtkPNGReader()
    img.SetFileName(png)
    img.Update()
    arr = img.GetOutput().GetPointData().GetScalars()
    n = arr.GetNumberOfTuples()
    drawn = sum(1 for i in range(0, n, 7)
                if sum(arr.GetTuple(i)[:3]) < 3 * 250)
    if drawn < 0.02 * n / 7:
        fails.append(f"{png}: only {drawn} of {n // 7} sampled pixels drawn")
    for f in fails:
        print("FAIL: " + scene + ": " + f)
    print(f"{scene}: {len(times)} steps (t = 0 .. {t_end:g}); blocks {want}; "
          f"{'ok' if not fails else 'FAILED'}; picture {png}")
    sys.stdout.flush()
    # Leave without ParaView's teardown: under xvfb-run it ends in a GLX error that
    # would turn a passed check into exit status 1.
    os._exit(1 if fails else 0)


main()
