"""Check that ParaView reads an alfe result (XDMF3 + HDF5) as alfe wrote it.

    pvpython scripts/paraview_check.py /abs/path/<scene>.xmf [options]
    xvfb-run -a pvpython scripts/paraview_check.py /abs/path/<scene>.xmf --render out.png

Reads the .xmf with Xdmf3ReaderS (falls back to XDMFReader, then OpenDataFile) and
compares what ParaView reports against the HDF5 file as read by h5py under
/usr/bin/python3 (a subprocess: pvpython's environment need not have h5py, and
ParaView's bundled HDF5 is kept out of the h5py process). Checks:

  * time steps: count == number of /steps/* groups, values == their `time` attributes;
  * arrays: point `displacement` (3 comps), cell `stress` (6 or 9), `von_mises` (1),
    `partition`, `material`; points, cells (all hexahedra), coordinates, connectivity;
  * every time step: displacement, stress, von_mises equal the HDF5 step element-wise
    (this pins the time -> dataset mapping);
  * last step: displacement component ranges reported by ParaView == h5py's;
  * WarpByVector(displacement) at the last step: bounds == bounds of x + u from h5py.

Prints one summary block; exits 1 with `FAIL:` lines on any mismatch.
--render PNG only renders the warped mesh coloured by von_mises at the last step
(needs a display, e.g. xvfb-run) and checks the picture is not blank.
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET

import numpy as np

H5_DUMP = r"""
import sys, json, h5py, numpy as np
h5, out = sys.argv[1], sys.argv[2]
with h5py.File(h5, "r") as f:
    names = sorted(f["steps"].keys())
    d = {
        "coordinates": f["mesh/coordinates"][...],
        "connectivity": f["mesh/connectivity"][...],
        "partition": f["mesh/partition"][...],
        "material": f["mesh/material"][...],
        "times": np.array([float(f["steps"][n].attrs["time"]) for n in names]),
        "step_names": np.array(names),
    }
    for i, n in enumerate(names):
        g = f["steps"][n]
        for a in ("displacement", "stress", "von_mises"):
            d["%s_%d" % (a, i)] = g[a][...]
    np.savez(out, **d)
print(h5py.__version__)
"""

RTOL = 1e-12


def h5_path_of(xmf):
    """The HDF5 file the first HDF DataItem of the .xmf points at."""
    for item in ET.parse(xmf).iter("DataItem"):
        if item.get("Format") == "HDF" and item.text and ":" in item.text:
            name = item.text.strip().split(":", 1)[0]
            return name if os.path.isabs(name) else os.path.join(os.path.dirname(xmf), name)
    sys.exit("FAIL: no HDF DataItem in %s" % xmf)


def read_h5(h5):
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "ref.npz")
        p = subprocess.run(["/usr/bin/python3", "-c", H5_DUMP, h5, out],
                           capture_output=True, text=True)
        if p.returncode != 0:
            sys.exit("FAIL: h5py could not read %s (/usr/bin/python3 needs python3-h5py):\n%s"
                     % (h5, p.stderr.strip()))
        with np.load(out) as z:
            ref = {k: z[k] for k in z.files}
    ref["h5py_version"] = p.stdout.strip()
    return ref


def open_reader(xmf):
    import paraview.simple as pv
    errors = []
    for name in ("Xdmf3ReaderS", "XDMFReader"):
        try:
            r = getattr(pv, name)(FileName=[xmf])
            r.UpdatePipelineInformation()
            if list(r.TimestepValues or []):
                return r, name
            errors.append("%s: no time steps" % name)
        except Exception as e:  # reader missing or failed
            errors.append("%s: %s" % (name, e))
    r = pv.OpenDataFile(xmf)
    if r is None:
        sys.exit("FAIL: ParaView cannot open %s (%s)" % (xmf, "; ".join(errors)))
    r.UpdatePipelineInformation()
    return r, "OpenDataFile(%s)" % r.GetXMLName()


def close(a, b, scale=None):
    a, b = np.asarray(a, float), np.asarray(b, float)
    if a.shape != b.shape:
        return False
    s = scale if scale is not None else max(1.0, float(np.abs(b).max(initial=0.0)))
    return float(np.abs(a - b).max(initial=0.0)) <= RTOL * s


def fetch(reader, t):
    import paraview.simple as pv
    from paraview import servermanager
    reader.UpdatePipeline(t)
    d = servermanager.Fetch(reader)
    if d.IsA("vtkMultiBlockDataSet") or d.IsA("vtkPartitionedDataSetCollection"):
        d = pv.servermanager.Fetch(pv.MergeBlocks(Input=reader))
    return d


def arr(data, name):
    from vtkmodules.util.numpy_support import vtk_to_numpy
    a = data.GetArray(name)
    return None if a is None else vtk_to_numpy(a)


def check(args):
    import paraview
    import paraview.simple as pv

    xmf = args.xmf
    fails = []
    info = []

    def need(ok, msg):
        if not ok:
            fails.append(msg)
        return ok

    ref = read_h5(h5_path_of(xmf))
    n_steps = len(ref["times"])
    reader, how = open_reader(xmf)
    info.append("ParaView %s, reader %s, h5py %s" % (
        paraview.servermanager.vtkSMProxyManager.GetParaViewSourceVersion().split()[-1],
        how, ref["h5py_version"]))

    # --- time steps --------------------------------------------------------
    times = [float(t) for t in (reader.TimestepValues or [])]
    need(len(times) == n_steps,
         "ParaView sees %d time steps, the HDF5 file has %d step groups" % (len(times), n_steps))
    if args.expect_steps is not None:
        need(n_steps == args.expect_steps,
             "HDF5 file has %d step groups, expected %d" % (n_steps, args.expect_steps))
    need(len(times) == n_steps and close(times, ref["times"]),
         "time values differ: ParaView %s vs HDF5 %s" % (times, list(ref["times"])))
    info.append("time steps: %d (HDF5 step groups %d), t = %g .. %g, match HDF5 `time` attrs"
                % (len(times), n_steps, times[0] if times else float("nan"),
                   times[-1] if times else float("nan")))
    if fails:
        return info, fails

    # --- arrays, mesh, every step element-wise -----------------------------
    last = fetch(reader, times[-1])
    pd, cd = last.GetPointData(), last.GetCellData()
    want = [("point", pd, "displacement", (3,)), ("cell", cd, "stress", (6, 9)),
            ("cell", cd, "von_mises", (1,)), ("cell", cd, "partition", (1,)),
            ("cell", cd, "material", (1,))]
    for where, data, name, ncomp in want:
        a = data.GetArray(name)
        if need(a is not None, "%s array `%s` missing (have %s)" % (
                where, name, [data.GetArrayName(i) for i in range(data.GetNumberOfArrays())])):
            need(a.GetNumberOfComponents() in ncomp, "%s array `%s` has %d components, expected %s"
                 % (where, name, a.GetNumberOfComponents(), ncomp))
    if fails:
        return info, fails
    n_stress = cd.GetArray("stress").GetNumberOfComponents()
    info.append("arrays: point displacement(3); cell stress(%d, ParaView reports %d components%s), "
                "von_mises(1), partition(1), material(1)"
                % (n_stress, n_stress, ", as written" if n_stress == 6 else ", expanded to 3x3"))

    npts, ncells = last.GetNumberOfPoints(), last.GetNumberOfCells()
    need(npts == len(ref["coordinates"]), "points: ParaView %d, HDF5 %d" % (npts, len(ref["coordinates"])))
    need(ncells == len(ref["connectivity"]), "cells: ParaView %d, HDF5 %d" % (ncells, len(ref["connectivity"])))
    if args.expect_points is not None:
        need(npts == args.expect_points, "points: %d, expected %d" % (npts, args.expect_points))
    if args.expect_cells is not None:
        need(ncells == args.expect_cells, "cells: %d, expected %d" % (ncells, args.expect_cells))
    if fails:
        return info, fails
    from vtkmodules.util.numpy_support import vtk_to_numpy
    types = {last.GetCellType(i) for i in range(ncells)}
    need(types == {12}, "cell types %s, expected only VTK_HEXAHEDRON (12)" % sorted(types))
    need(close(vtk_to_numpy(last.GetPoints().GetData()), ref["coordinates"]),
         "point coordinates differ from /mesh/coordinates")
    conn = vtk_to_numpy(last.GetCells().GetConnectivityArray())
    need(np.array_equal(conn.reshape(ncells, -1), ref["connectivity"]),
         "connectivity differs from /mesh/connectivity")
    part = arr(cd, "partition")
    need(np.array_equal(part, ref["partition"]), "partition differs from /mesh/partition")
    need(np.array_equal(arr(cd, "material"), ref["material"]), "material differs from /mesh/material")
    parts = sorted(int(v) for v in np.unique(part))
    if args.expect_partitions is not None:
        need(parts == list(range(args.expect_partitions)),
             "partition values %s, expected 0..%d" % (parts, args.expect_partitions - 1))
    counts = [int((part == p).sum()) for p in parts]
    info.append("mesh: %d points, %d cells (all hexahedra); coordinates, connectivity equal HDF5"
                % (npts, ncells))
    info.append("partition values %s (cells per part %s); material values %s"
                % (parts, counts, sorted(int(v) for v in np.unique(arr(cd, "material")))))

    bad_steps = []
    for i, t in enumerate(times):
        d = fetch(reader, t)  # Fetch may hand back the live output: refetch every step
        for name, data in (("displacement", d.GetPointData()), ("stress", d.GetCellData()),
                           ("von_mises", d.GetCellData())):
            got, exp = arr(data, name), ref["%s_%d" % (name, i)]
            if name == "stress" and got is not None and got.shape[-1] == 9 and exp.shape[-1] == 6:
                # 3x3 expansion: compare the six distinct entries whatever order ParaView used
                got = np.sort(got, axis=1)
                exp = np.sort(np.concatenate([exp, exp[:, 3:]], axis=1), axis=1)
            if got is None or not close(got.reshape(exp.shape) if got.size == exp.size else got, exp):
                bad_steps.append("%s@t=%g" % (name, t))
    need(not bad_steps, "arrays differ from the HDF5 step datasets: %s" % ", ".join(bad_steps))
    info.append("all %d steps: displacement, stress, von_mises equal HDF5 /steps/* element-wise"
                % n_steps)

    # --- last step: ranges via ParaView's data information --------------------
    reader.UpdatePipeline(times[-1])
    u = ref["displacement_%d" % (n_steps - 1)]
    disp = reader.PointData["displacement"]
    pv_rng = [disp.GetRange(c) for c in range(3)]
    h5_rng = [(float(u[:, c].min()), float(u[:, c].max())) for c in range(3)]
    need(close(pv_rng, h5_rng), "last-step displacement ranges: ParaView %s, h5py %s" % (pv_rng, h5_rng))
    uz_pv = max(abs(pv_rng[2][0]), abs(pv_rng[2][1]))
    info.append("t=%g displacement range x [%.4f, %.4f], y [%.4f, %.4f], z [%.4f, %.4f] (== h5py)"
                % ((times[-1],) + tuple(v for r in pv_rng for v in r)))
    tip = np.isclose(ref["coordinates"][:, 0], ref["coordinates"][:, 0].max())
    info.append("t=%g free end (x = %g, %d nodes): mean u_z %.4f, mean u_x %.4f"
                % (times[-1], ref["coordinates"][:, 0].max(), int(tip.sum()),
                   float(u[tip, 2].mean()), float(u[tip, 0].mean())))
    vm_rng = reader.CellData["von_mises"].GetRange(0)
    info.append("t=%g max |u_z| = %.4f (h5py %.4f); von_mises range [%.2f, %.2f]"
                % (times[-1], uz_pv, float(np.abs(u[:, 2]).max()), vm_rng[0], vm_rng[1]))

    # --- WarpByVector -------------------------------------------------------
    x = ref["coordinates"]
    undeformed = reader.GetDataInformation().GetBounds()
    warp = pv.WarpByVector(Input=reader, Vectors=["POINTS", "displacement"], ScaleFactor=1.0)
    warp.UpdatePipeline(times[-1])
    b = warp.GetDataInformation().GetBounds()
    w = x + u
    h5_b = [v for c in range(3) for v in (float(w[:, c].min()), float(w[:, c].max()))]
    x_b = [v for c in range(3) for v in (float(x[:, c].min()), float(x[:, c].max()))]
    need(close(undeformed, x_b), "undeformed bounds %s != HDF5 %s" % (list(undeformed), x_b))
    need(close(b, h5_b), "warped bounds %s != h5py x+u %s" % (list(b), h5_b))
    info.append("WarpByVector(displacement) at t=%g: bounds x [%.4f, %.4f] y [%.4f, %.4f] "
                "z [%.4f, %.4f] (== h5py x+u; undeformed z-min %.4f)"
                % ((times[-1],) + tuple(b) + (undeformed[4],)))
    return info, fails


def render(args):
    import paraview.simple as pv
    reader, _ = open_reader(args.xmf)
    t = list(reader.TimestepValues)[-1]
    scene = pv.GetAnimationScene()
    scene.UpdateAnimationUsingDataTimeSteps()
    scene.AnimationTime = t
    warp = pv.WarpByVector(Input=reader, Vectors=["POINTS", "displacement"], ScaleFactor=1.0)
    view = pv.CreateView("RenderView")
    view.ViewSize = [1200, 700]
    view.ViewTime = t
    view.OrientationAxesVisibility = 1
    view.Background = [1, 1, 1]
    try:
        view.UseColorPaletteForBackground = 0
    except AttributeError:
        pass
    # ghost of the undeformed beam
    ghost = pv.Show(reader, view)
    ghost.Representation = "Wireframe"
    ghost.AmbientColor = ghost.DiffuseColor = [0.6, 0.6, 0.6]
    ghost.Opacity = 0.4
    pv.ColorBy(ghost, None)
    disp = pv.Show(warp, view)
    disp.Representation = "Surface With Edges"
    pv.ColorBy(disp, ("CELLS", "von_mises"))
    lut = pv.GetColorTransferFunction("von_mises")
    lut.RescaleTransferFunction(*warp.CellData["von_mises"].GetRange(0))
    disp.SetScalarBarVisibility(view, True)
    bar = pv.GetScalarBar(lut, view)
    bar.Title = "von Mises [MPa]"
    bar.ComponentTitle = ""
    bar.TitleColor = bar.LabelColor = [0, 0, 0]
    text = pv.Text(Text="alfe cantilever, t = %g (displacement x1)" % t)
    td = pv.Show(text, view)
    td.Color = [0, 0, 0]
    td.FontSize = 14
    view.CameraPosition = [5, -40, -2.5]
    view.CameraFocalPoint = [5, 0.5, -2.5]
    view.CameraViewUp = [0, 0, 1]
    view.ResetCamera()
    pv.Render(view)
    os.makedirs(os.path.dirname(os.path.abspath(args.render)), exist_ok=True)
    pv.SaveScreenshot(args.render, view, ImageResolution=[1200, 700])
    # not blank: read it back and count distinct colours
    from vtkmodules.vtkIOImage import vtkPNGReader
    from vtkmodules.util.numpy_support import vtk_to_numpy
    png = vtkPNGReader()
    png.SetFileName(args.render)
    png.Update()
    px = vtk_to_numpy(png.GetOutput().GetPointData().GetScalars())
    ncol = len(np.unique(px[:, :3].astype(np.uint32) @ np.array([65536, 256, 1], np.uint32)))
    if ncol < 20:
        sys.exit("FAIL: %s looks blank (%d distinct colours)" % (args.render, ncol))
    print("rendered %s (%dx%d, %d colours)" % (args.render, 1200, 700, ncol))


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("xmf", help="absolute path to <scene>.xmf")
    p.add_argument("--expect-steps", type=int)
    p.add_argument("--expect-points", type=int)
    p.add_argument("--expect-cells", type=int)
    p.add_argument("--expect-partitions", type=int)
    p.add_argument("--render", metavar="PNG", help="only render the warped last step to PNG")
    args = p.parse_args()
    if not os.path.isabs(args.xmf):
        args.xmf = os.path.abspath(args.xmf)  # ParaView's XDMF readers resolve HDF paths from it
    if not os.path.isfile(args.xmf):
        sys.exit("FAIL: no such file %s" % args.xmf)
    if args.render:
        render(args)
        return
    info, fails = check(args)
    print("paraview check: %s" % args.xmf)
    for line in info:
        print("  " + line)
    if fails:
        for f in fails:
            print("FAIL: " + f)
        sys.exit(1)
    print("paraview check: OK")


if __name__ == "__main__":
    main()
