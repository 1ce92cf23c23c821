"""Check that ParaView reads an alfe result (XDMF3 + HDF5) as alfe wrote it.

    pvpython scripts/paraview_check.py /abs/path/<scene>.xmf [options]
    xvfb-run -a pvpython scripts/paraview_check.py /abs/path/<scene>.xmf --render out.png

Reads the .xmf with Xdmf3ReaderS (falls back to XDMFReader, then OpenDataFile; --reader
picks another, e.g. XDMFReader for a scene with walls: it names the blocks) and compares what ParaView
reports against the HDF5 file as read by h5py under /usr/bin/python3 (a subprocess:
pvpython's environment need not have h5py, and ParaView's bundled HDF5 is kept out of
the h5py process). Checks:

  * time steps: count == number of /steps/* groups, values == their `time` attributes;
  * arrays: point `displacement` (3 comps), cell `stress` (6 or 9), `von_mises` (1),
    `partition`, `material`, and every other dataset of the step groups; points, cells
    (all hexahedra), coordinates, connectivity;
  * every time step: every field of the mesh equals the HDF5 step element-wise
    (this pins the time -> dataset mapping; a 9-component stress must be alfe's tensor);
  * `stress` component names as ParaView reports them (colour-by menu, Calculator
    variables, spreadsheet columns), and that the names land on alfe's columns: a
    Calculator's von Mises from stress_XX .. stress_XZ == `von_mises`, stress_XY,
    stress_YZ, stress_XZ == HDF5 columns 3, 4, 5 (with --wall-force WALL also: the volume
    integral of stress_XZ and stress_ZZ over the height == the wall's fx, fz in history.csv);
  * how the other XDMF readers show `stress` (declared a six-column `Matrix`: all three
    readers give the six columns, named; a 3x3 expansion in XDMF's Tensor6 order, as
    the legacy XDMFReader made of alfe's old `Tensor6` declaration, is reported as WRONG);
    --no-other-readers skips this;
  * last step: displacement component ranges reported by ParaView == h5py's;
  * WarpByVector(displacement) at the last step: bounds == bounds of x + u from h5py.

With walls (HDF5 /walls/*; the .xmf's blocks, each a temporal collection) also:

  * block names: the part (`/mesh` attribute `part_names`) and `wall_<name>` at every
    step as the reader shows them (the XDMF Reader names blocks after the .xmf, the same
    at every step); --expect-blocks pins them;
  * every step: the wall block exists, is triangles equal /walls/<name>/triangles, and its
    points equal /steps/NNNNNN/walls/<name>/points; the walls that move are reported;
  * a `plane` wall: its drawn square lies under the model (the undeformed mesh on the
    side its normal points to, its footprint inside the square) with a side 1 to 1.5
    times the model's extent in the plane;
  * WarpByVector leaves the wall blocks where they are;
  * how the other readers show the blocks (Xdmf3ReaderS: one block of unnamed pieces;
    Xdmf3ReaderT: the blocks in order, unnamed).

Prints one summary block; exits 1 with `FAIL:` lines on any mismatch.
--render PNG only renders the warped mesh coloured by von_mises at the last step (with
walls: the walls too, displacement scaled by --render-scale) (needs a display, e.g.
xvfb-run) and checks the picture is not blank.
"""

import argparse
import csv
import os
import re
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
        "part_names": np.array(json.loads(f["mesh"].attrs["part_names"])),
        "times": np.array([float(f["steps"][n].attrs["time"]) for n in names]),
        "step_names": np.array(names),
    }
    fields = sorted(k for k in f["steps"][names[0]].keys()
                    if isinstance(f["steps"][names[0]][k], h5py.Dataset)) if names else []
    d["fields"] = np.array(fields)
    for i, n in enumerate(names):
        g = f["steps"][n]
        for a in fields:
            d["field_%s_%d" % (a, i)] = g[a][...]
    walls = sorted(f["walls"].keys()) if "walls" in f else []
    d["walls"] = np.array(walls)
    for w in walls:
        g = f["walls"][w]
        cells = [k for k in g.keys() if isinstance(g[k], h5py.Dataset)]
        d["wall_cells_%s" % w] = g[cells[0]][...]
        d["wall_cells_path_%s" % w] = np.array("/walls/%s/%s" % (w, cells[0]))
        for a in ("name", "shape"):
            v = g.attrs.get(a, b"")
            d["wall_%s_%s" % (a, w)] = np.array(v.decode() if isinstance(v, bytes) else str(v))
        for i, n in enumerate(names):
            p = "walls/%s/points" % w
            if p in f["steps"][n]:
                d["wall_points_%s_%d" % (w, i)] = f["steps"][n][p][...]
    np.savez(out, **d)
print(h5py.__version__)
"""

RTOL = 1e-12
STRESS_NAMES = ["XX", "YY", "ZZ", "XY", "YZ", "XZ"]  # alfe's columns: xx, yy, zz, xy, yz, xz
# alfe's tensor as a row-major 3x3 from its columns xx, yy, zz, xy, yz, xz
FULL_FROM_VOIGT = [0, 3, 5, 3, 1, 4, 5, 4, 2]
# the 3x3 that XDMF's own Tensor6 order (xx, xy, xz, yy, yz, zz) gives from the same columns
FULL_FROM_XDMF_TENSOR6 = [0, 1, 2, 1, 3, 4, 2, 4, 5]
RIGID = ("wall_", "entity_", "coupling_")  # blocks that are not parts of the mesh


def is_part(name):
    """A part's block (the mesh), not a wall's, entity's or coupling's."""
    return bool(name) and not name.startswith(RIGID)


def mesh_selector(ref):
    """The (first) part's block at every step (alfe names it after the part)."""
    return "/Root/%s" % ref["part_names"][0]


def h5_path_of(xmf):
    """The HDF5 file the first HDF DataItem of the .xmf points at."""
    for item in ET.parse(xmf).iter("DataItem"):
        if item.get("Format") == "HDF" and item.text and ":" in item.text:
            name = item.text.strip().split(":", 1)[0]
            return name if os.path.isabs(name) else os.path.join(os.path.dirname(xmf), name)
    sys.exit("FAIL: no HDF DataItem in %s" % xmf)


def xmf_grid_names(xmf):
    """The block names at each step: alfe's .xmf is one spatial collection of blocks,
    each a temporal collection of its grid per step, named as the block."""
    top = ET.parse(xmf).getroot().find("Domain/Grid")
    blocks = top.findall("Grid")
    steps = [[g.get("Name") for g in b.findall("Grid")] for b in blocks]
    n = len(steps[0]) if steps else 0
    if any(len(s) != n for s in steps) or any(g != b.get("Name") for b, s in zip(blocks, steps) for g in s):
        return [[]]
    return [[b.get("Name") for b in blocks] for _ in range(n)]


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


def open_reader(xmf, name=None):
    import paraview.simple as pv
    errors = []
    for n in ([name] if name else ["Xdmf3ReaderS", "XDMFReader"]):
        try:
            prop = "FileNames" if n == "XDMFReader" else "FileName"
            r = getattr(pv, n)(**{prop: [xmf]})
            r.UpdatePipelineInformation()
            if list(r.TimestepValues or []):
                return r, n
            errors.append("%s: no time steps" % n)
        except Exception as e:  # reader missing or failed
            errors.append("%s: %s" % (n, e))
    if name:
        sys.exit("FAIL: ParaView's %s cannot open %s (%s)" % (name, xmf, "; ".join(errors)))
    r = pv.OpenDataFile(xmf)
    if r is None:
        sys.exit("FAIL: ParaView cannot open %s (%s)" % (xmf, "; ".join(errors)))
    r.UpdatePipelineInformation()
    return r, "OpenDataFile(%s)" % r.GetXMLName()


def close(a, b, scale=None):
    """Equal to RTOL relative to max|b| (or scale); NaN only where the other is NaN."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    if a.shape != b.shape:
        return False
    nan = np.isnan(b)
    if not np.array_equal(np.isnan(a), nan):
        return False
    a, b = a[~nan], b[~nan]
    s = scale if scale is not None else max(1.0, float(np.abs(b).max(initial=0.0)))
    return float(np.abs(a - b).max(initial=0.0)) <= RTOL * s


def leaves(d):
    """[(block name or None, dataset)] of a composite dataset's leaves, in order."""
    if not d.IsA("vtkCompositeDataSet"):
        return [(None, d)]
    out = []
    it = d.NewIterator()
    it.SetSkipEmptyNodes(False)
    it.InitTraversal()
    while not it.IsDoneWithTraversal():
        md = it.GetCurrentMetaData()
        out.append((md.Get(d.NAME()) if md.Has(d.NAME()) else None, it.GetCurrentDataObject()))
        it.GoToNextItem()
    return out


def base(name):
    """A block name without the reader's `[k]` suffix."""
    return re.sub(r"\[\d+\]$", "", name or "")


def fetch_all(src, t):
    from paraview import servermanager
    src.UpdatePipeline(t)
    return servermanager.Fetch(src)


def fetch(src, t, walls):
    """The mesh dataset at time t: the part's block with walls, else the merged output."""
    import paraview.simple as pv
    from paraview import servermanager
    src.UpdatePipeline(t)
    d = servermanager.Fetch(src)
    if walls:
        for name, b in leaves(d):
            if is_part(base(name)):
                return b
        return None
    if d.IsA("vtkMultiBlockDataSet") or d.IsA("vtkPartitionedDataSetCollection"):
        d = pv.servermanager.Fetch(pv.MergeBlocks(Input=src))
    return d


def arr(data, name):
    from vtkmodules.util.numpy_support import vtk_to_numpy
    a = data.GetArray(name)
    return None if a is None else vtk_to_numpy(a)


def bounds_of(x):
    return [v for c in range(3) for v in (float(x[:, c].min()), float(x[:, c].max()))]


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
    walls = [str(w) for w in ref["walls"]]
    reader, how = open_reader(xmf, args.reader)
    pv_version = paraview.servermanager.vtkSMProxyManager.GetParaViewSourceVersion().split()[-1]
    info.append("ParaView %s, reader %s, h5py %s" % (pv_version, how, ref["h5py_version"]))

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

    # --- blocks (walls) ----------------------------------------------------
    if walls:
        block_checks(args, reader, how, ref, times, walls, need, info)
        if fails:
            return info, fails

    # --- arrays, mesh, every step element-wise -----------------------------
    last = fetch(reader, times[-1], walls)
    if not need(last is not None, "no part block at t=%g" % times[-1]):
        return info, fails
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
    fields = [str(f) for f in ref["fields"]]
    extra = [f for f in fields if f not in ("displacement", "stress", "von_mises")]
    for f in extra:
        need(pd.GetArray(f) is not None or cd.GetArray(f) is not None,
             "HDF5 step field `%s` is not an array in ParaView" % f)
    info.append("arrays: point displacement(3); cell stress(%d, ParaView reports %d components%s), "
                "von_mises(1), partition(1), material(1)%s"
                % (n_stress, n_stress, ", as written" if n_stress == 6 else ", expanded to 3x3",
                   "; also %s" % ", ".join("%s(%d)" % (f, (pd.GetArray(f) or cd.GetArray(f))
                                                          .GetNumberOfComponents())
                                           for f in extra if pd.GetArray(f) or cd.GetArray(f))
                   if extra else ""))

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
        d = fetch(reader, t, walls)  # Fetch may hand back the live output: refetch every step
        if d is None:
            bad_steps.append("no mesh block@t=%g" % t)
            continue
        for name in fields:
            data = d.GetPointData() if d.GetPointData().GetArray(name) is not None else d.GetCellData()
            got, exp = arr(data, name), ref["field_%s_%d" % (name, i)]
            if name == "stress" and got is not None and got.shape[-1] == 9 and exp.shape[-1] == 6:
                # a 3x3 expansion must be the tensor alfe wrote, row-major
                exp = exp[:, FULL_FROM_VOIGT]
            if got is None or not close(got.reshape(exp.shape) if got.size == exp.size else got, exp):
                bad_steps.append("%s@t=%g" % (name, t))
    need(not bad_steps, "arrays differ from the HDF5 step datasets: %s" % ", ".join(bad_steps))
    info.append("all %d steps: %s equal HDF5 /steps/* element-wise"
                % (n_steps, ", ".join(fields) if extra else "displacement, stress, von_mises"))
    if fails:
        return info, fails

    # --- stress component names ----------------------------------------------
    if n_stress == 6:
        stress_names(args, reader, walls, ref, times, need, info)

    # --- the other readers -----------------------------------------------------
    if not args.no_other_readers:
        other_readers(args, how, ref, times, xmf_grid_names(xmf)[0] if walls else [],
                      need, info)

    # --- last step: ranges via ParaView's data information --------------------
    reader.UpdatePipeline(times[-1])
    u = ref["field_displacement_%d" % (n_steps - 1)]
    disp = reader.PointData["displacement"]
    pv_rng = [disp.GetRange(c) for c in range(3)]
    h5_rng = [(float(u[:, c].min()), float(u[:, c].max())) for c in range(3)]
    need(close(pv_rng, h5_rng), "last-step displacement ranges: ParaView %s, h5py %s" % (pv_rng, h5_rng))
    uz_pv = max(abs(pv_rng[2][0]), abs(pv_rng[2][1]))
    info.append("t=%g displacement range x [%.4f, %.4f], y [%.4f, %.4f], z [%.4f, %.4f] (== h5py)"
                % ((times[-1],) + tuple(v for r in pv_rng for v in r)))
    if not walls:
        tip = np.isclose(ref["coordinates"][:, 0], ref["coordinates"][:, 0].max())
        info.append("t=%g free end (x = %g, %d nodes): mean u_z %.4f, mean u_x %.4f"
                    % (times[-1], ref["coordinates"][:, 0].max(), int(tip.sum()),
                       float(u[tip, 2].mean()), float(u[tip, 0].mean())))
    vm_rng = reader.CellData["von_mises"].GetRange(0)
    line = "t=%g max |u_z| = %.4f (h5py %.4f); von_mises range [%.2f, %.2f]" % (
        times[-1], uz_pv, float(np.abs(u[:, 2]).max()), vm_rng[0], vm_rng[1])
    if "contact_pressure" in fields:
        cp = reader.PointData["contact_pressure"].GetRange(0)
        line += "; contact_pressure range [%.4f, %.4f]" % cp
    info.append(line)

    # --- WarpByVector -------------------------------------------------------
    x = ref["coordinates"]
    warp = pv.WarpByVector(Input=reader, Vectors=["POINTS", "displacement"], ScaleFactor=1.0)
    h5_b = bounds_of(x + u)
    x_b = bounds_of(x)
    if walls:
        undeformed = list(fetch(reader, times[-1], walls).GetBounds())
        wd = fetch_all(warp, times[-1])
        b, moved = None, []
        for name, blk in leaves(wd):
            if is_part(base(name)):
                b = list(blk.GetBounds())
            elif base(name).startswith("wall_") and base(name)[5:] in walls:
                w = base(name)[5:]
                pts = vtk_to_numpy(blk.GetPoints().GetData())
                if not close(pts, ref["wall_points_%s_%d" % (w, n_steps - 1)]):
                    moved.append(name)
        need(b is not None, "WarpByVector output has no mesh block")
        need(not moved, "WarpByVector moved the wall blocks %s" % moved)
        b = b or [float("nan")] * 6
    else:
        undeformed = reader.GetDataInformation().GetBounds()
        warp.UpdatePipeline(times[-1])
        b = warp.GetDataInformation().GetBounds()
    need(close(undeformed, x_b), "undeformed bounds %s != HDF5 %s" % (list(undeformed), x_b))
    need(close(b, h5_b), "warped bounds %s != h5py x+u %s" % (list(b), h5_b))
    info.append("WarpByVector(displacement) at t=%g: %sbounds x [%.4f, %.4f] y [%.4f, %.4f] "
                "z [%.4f, %.4f] (== h5py x+u; undeformed z-min %.4f)%s"
                % ((times[-1], "mesh block " if walls else "") + tuple(b) + (undeformed[4],)
                   + ("; wall blocks left where they are" if walls else "",)))
    return info, fails


def block_checks(args, reader, how, ref, times, walls, need, info):
    """Block names per step, the wall blocks against HDF5 and a plane wall's size."""
    from vtkmodules.util.numpy_support import vtk_to_numpy
    xnames = xmf_grid_names(args.xmf)
    odd = [(i, n) for i, n in enumerate(xnames) if n != xnames[0] or not n]
    need(len(xnames) == len(times) and not odd,
         "the .xmf's steps are not spatial collections with the same grids: step 0 %s, %s"
         % (xnames[0] if xnames else None, ", ".join("step %d %s" % o for o in odd[:3])))
    expected = list(xnames[0]) if xnames else []
    want = [str(p) for p in ref["part_names"]] + ["wall_%s" % w for w in walls]
    need(all(w in expected for w in want),
         "the .xmf's grids %s lack some of %s (HDF5 /walls: %s)" % (expected, want, walls))
    if args.expect_blocks:
        need(expected == args.expect_blocks.split(","),
             "the .xmf's grids are %s, expected %s" % (expected, args.expect_blocks))
    shown = []  # block names ParaView shows, per step
    bad, moved_walls, first_pts = [], {}, {}
    for i, t in enumerate(times):
        d = fetch_all(reader, t)
        blocks = leaves(d)
        names = [n for n, _ in blocks]
        shown.append(names)
        # The XDMF Reader names blocks as the .xmf does; the Xdmf3 readers leave them
        # unnamed (see the manual's ParaView chapter).
        if names != expected:
            bad.append("t=%g: %s" % (t, names))
            continue
        for name, blk in blocks:
            if not base(name).startswith("wall_") or base(name)[5:] not in walls:
                continue
            w = base(name)[5:]
            pts = vtk_to_numpy(blk.GetPoints().GetData())
            exp = ref.get("wall_points_%s_%d" % (w, i))
            if exp is None or not close(pts, exp):
                bad.append("%s points at t=%g differ from HDF5 /steps/%s/walls/%s/points"
                           % (name, t, ref["step_names"][i], w))
            cells = ref["wall_cells_%s" % w]
            conn = vtk_to_numpy(blk.GetCells().GetConnectivityArray())
            types = {blk.GetCellType(c) for c in range(blk.GetNumberOfCells())}
            if types != {5} or not np.array_equal(conn.reshape(len(cells), -1) if conn.size == cells.size
                                                  else conn, cells):
                bad.append("%s cells at t=%g differ from HDF5 %s (types %s)"
                           % (name, t, ref["wall_cells_path_%s" % w], sorted(types)))
            if i == 0:
                first_pts[w] = pts.copy()
            elif not close(pts, first_pts[w]):
                moved_walls[w] = pts - first_pts[w]
    need(not bad, "block names or wall blocks wrong (reader %s): %s" % (how, "; ".join(bad)))
    info.append("blocks (%s): %s at t=%g, %s at t=%g"
                % (how, shown[0], times[0], shown[-1], times[-1]))
    for w in walls:
        pts = ref["wall_points_%s_%d" % (w, len(times) - 1)]
        line = "wall_%s (%s): %d points, %d triangles at every step == HDF5 /steps/*/walls/%s/points, %s" % (
            w, ref["wall_shape_%s" % w], len(pts), len(ref["wall_cells_%s" % w]), w,
            ref["wall_cells_path_%s" % w])
        if w in moved_walls:
            dv = moved_walls[w].mean(axis=0)
            line += "; moves by (%.4g, %.4g, %.4g) from t=%g to t=%g" % (tuple(dv) + (times[0], times[-1]))
        else:
            line += "; does not move"
        info.append(line)
    if bad:
        return
    for w in walls:
        if str(ref["wall_shape_%s" % w]) == "plane":
            plane_size(w, reader, ref, times, need, info)
    if args.expect_moving:
        for w in args.expect_moving.split(","):
            need(w in moved_walls, "wall %s does not move, expected it to" % w)


def plane_size(w, reader, ref, times, need, info):
    """A plane wall is drawn as a square under the model, about the model's size."""
    from vtkmodules.util.numpy_support import vtk_to_numpy
    x = None
    for i, t in enumerate(times):
        mesh = fetch(reader, t, True)
        x = vtk_to_numpy(mesh.GetPoints().GetData())  # undeformed coordinates (ParaView's)
        p = ref["wall_points_%s_%d" % (w, i)]
        e1, e2 = p[1] - p[0], p[3] - p[0]
        l1, l2 = np.linalg.norm(e1), np.linalg.norm(e2)
        if not need(len(p) == 4 and l1 > 0 and l2 > 0 and abs(l1 - l2) <= 1e-9 * l1
                    and abs(np.dot(e1, e2)) <= 1e-9 * l1 * l2
                    and close(p[2], p[1] + e2, scale=l1),
                    "wall_%s at t=%g is not drawn as a square: %s" % (w, t, p.tolist())):
            return
        u1, u2 = e1 / l1, e2 / l2
        n = np.cross(u1, u2)
        h = (x - p[0]) @ n  # height of the model's nodes over the plane
        a, b = (x - p[0]) @ u1, (x - p[0]) @ u2  # footprint in the square's axes
        extent = max(np.ptp(a), np.ptp(b))
        ratio = l1 / extent
        tol = 1e-9 * l1
        ok = need(h.min() >= -tol, "wall_%s at t=%g: model nodes below the plane (height %g)"
                  % (w, t, h.min()))
        ok &= need(a.min() >= -tol and a.max() <= l1 + tol and b.min() >= -tol and b.max() <= l2 + tol,
                   "wall_%s at t=%g: the model's footprint [%g, %g] x [%g, %g] is not inside the "
                   "%g x %g square" % (w, t, a.min(), a.max(), b.min(), b.max(), l1, l2))
        ok &= need(1.0 < ratio <= 1.5, "wall_%s at t=%g: square side %g is %.3g times the model's "
                   "extent %g in the plane (expected about 1.2)" % (w, t, l1, ratio, extent))
        if not ok:
            return  # the first step that fails is enough
        if i == 0:
            c_sq = p[0] + 0.5 * (e1 + e2)
            c_model = p[0] + 0.5 * (a.min() + a.max()) * u1 + 0.5 * (b.min() + b.max()) * u2
            info.append("wall_%s drawn as a %g x %g square (%.3g x the model's extent %g in the plane), "
                        "normal (%g, %g, %g), model on its normal side (min height %.3g), footprint "
                        "inside it at every step; at t=%g centre (%g, %g, %g), under the model's "
                        "(%g, %g, %g)"
                        % ((w, l1, l2, ratio, extent) + tuple(n) + (h.min(), t) + tuple(c_sq)
                           + tuple(c_model)))


def other_readers(args, how, ref, times, expected, need, info):
    """How the other XDMF readers of ParaView (Xdmf3ReaderS, Xdmf3ReaderT, XDMFReader) show
    the file: time steps, the blocks of the first two steps (with walls) and the stress
    array at the last step, so that the README can say which reader to pick."""
    from vtkmodules.util.numpy_support import vtk_to_numpy
    seen = []
    s_ref = ref["field_stress_%d" % (len(times) - 1)]
    n_nodes = len(ref["coordinates"])
    for name in ("Xdmf3ReaderS", "Xdmf3ReaderT", "XDMFReader"):
        if name == how:
            continue
        r, _ = open_reader(args.xmf, name)
        rt = [float(t) for t in r.TimestepValues]
        need(close(rt, ref["times"]), "%s: time values %s differ from HDF5" % (name, rt))
        what = []
        if expected:
            shapes = []
            for i in range(min(2, len(times))):
                d = fetch_all(r, times[i])
                top = [d.GetBlock(k).GetClassName() for k in range(d.GetNumberOfBlocks())] \
                    if d.IsA("vtkMultiBlockDataSet") else [d.GetClassName()]
                shapes.append((top, [(n, b.GetNumberOfPoints()) for n, b in leaves(d)]))
            names0 = [n for n, _ in shapes[0][1]]
            npts = [k for _, k in shapes[0][1]]
            if name == "Xdmf3ReaderS":
                # Top Level Partition: the step's grids become pieces of one unnamed block
                need(shapes[0][0] == ["vtkMultiPieceDataSet"] and names0 == [None] * len(expected),
                     "Xdmf3ReaderS: expected one vtkMultiPieceDataSet of %d unnamed pieces, got %s"
                     % (len(expected), shapes[0]))
                what.append("one block (vtkMultiPieceDataSet) of %d unnamed pieces (%s points), "
                            "no block names" % (len(npts), ", ".join(map(str, npts))))
            elif name == "Xdmf3ReaderT":
                # The blocks in order, unnamed: VTK's Xdmf3 reader names no collection.
                names1 = [n for n, _ in shapes[1][1]] if len(shapes) > 1 else []
                ok = names0 == [None] * len(expected) and names1 in ([], names0)
                need(ok, "%s: blocks %s, %s, expected %d unnamed ones" % (name, names0, names1,
                                                                           len(expected)))
                what.append("blocks %s, then %s (unnamed: the XDMF Reader names them)"
                            % (names0, names1))
            else:
                names1 = [n for n, _ in shapes[1][1]] if len(shapes) > 1 else []
                ok = names0 == expected and (len(times) < 2 or names1 == expected)
                need(ok, "%s: block names %s, %s, expected %s at both" % (name, names0, names1,
                                                                          expected))
                what.append("blocks %s, then %s" % (names0, names1))
        # stress at the last step, on the leaf that is the mesh
        mesh = [b for _, b in leaves(fetch_all(r, times[-1]))
                if b is not None and b.GetNumberOfPoints() == n_nodes
                and b.GetCellData().GetArray("stress") is not None]
        if not need(len(mesh) == 1, "%s: no single mesh leaf with `stress`" % name):
            continue
        a = mesh[0].GetCellData().GetArray("stress")
        got = vtk_to_numpy(a)
        tensors = mesh[0].GetCellData().GetTensors()
        flag = " (the tensors attribute)" if tensors is not None and tensors.GetName() == "stress" else ""
        comp = [r.CellData["stress"].GetComponentName(c) for c in range(a.GetNumberOfComponents())]
        if a.GetNumberOfComponents() == 6:
            need(close(got, s_ref) and comp == STRESS_NAMES,
                 "%s: stress (6) differs from HDF5 or is named %s" % (name, comp))
            what.append("stress 6 components as written, named %s" % " ".join(comp))
        elif a.GetNumberOfComponents() == 9 and close(got, s_ref[:, FULL_FROM_VOIGT]):
            what.append("stress expanded to the 3x3 tensor alfe wrote%s" % flag)
        elif a.GetNumberOfComponents() == 9 and close(got, s_ref[:, FULL_FROM_XDMF_TENSOR6]):
            # Tensor6 read in XDMF's order xx, xy, xz, yy, yz, zz: wrong for alfe's columns
            what.append("stress expanded to 9 components%s named %s, built from alfe's columns "
                        "as [[xx, yy, zz], [yy, xy, yz], [zz, yz, xz]] (XDMF's Tensor6 order "
                        "xx, xy, xz, yy, yz, zz): WRONG for alfe's order, use an Xdmf3 reader"
                        % (flag, " ".join(comp)))
        else:
            need(False, "%s: stress with %d components matching neither alfe's nor XDMF's order"
                 % (name, a.GetNumberOfComponents()))
        seen.append("%s: %s" % (name, "; ".join(what)))
    for line in seen:
        info.append("other reader " + line)


def stress_names(args, reader, walls, ref, times, need, info):
    """The names ParaView gives the six stress components, and where they land."""
    import paraview.simple as pv
    t = times[-1]
    reader.UpdatePipeline(t)
    ai = reader.CellData["stress"]
    names = [ai.GetComponentName(c) for c in range(6)]
    need(names == STRESS_NAMES, "stress component names in ParaView: %s, expected %s"
         % (names, STRESS_NAMES))
    mesh_src = pv.ExtractBlock(Input=reader, Selectors=[mesh_selector(ref)]) if walls else reader
    s = ref["field_stress_%d" % (len(times) - 1)]
    vm = ref["field_von_mises_%d" % (len(times) - 1)]
    f = ("sqrt(0.5*((stress_XX-stress_YY)^2+(stress_YY-stress_ZZ)^2+(stress_ZZ-stress_XX)^2)"
         "+3*(stress_XY^2+stress_YZ^2+stress_XZ^2))")
    calc = pv.Calculator(Input=mesh_src, AttributeType="Cell Data", ResultArrayName="vm_named",
                         Function=f)
    d = fetch(calc, t, walls)
    got = None if d is None else arr(d.GetCellData(), "vm_named")
    need(got is not None and close(got, vm),
         "von Mises from stress_XX .. stress_XZ (ParaView Calculator) differs from von_mises")
    landed = []
    for c, n in enumerate(STRESS_NAMES):
        one = pv.Calculator(Input=mesh_src, AttributeType="Cell Data", ResultArrayName="c",
                            Function="stress_" + n)
        d = fetch(one, t, walls)
        got = None if d is None else arr(d.GetCellData(), "c")
        cols = [] if got is None else [k for k in range(6) if np.array_equal(got, s[:, k])]
        landed.append(cols)
        need(cols == [c], "Calculator's stress_%s is HDF5 stress column(s) %s, expected %d"
             % (n, cols, c))
    # The spreadsheet (and File > Export / CSV) names the columns differently.
    view = pv.CreateView("SpreadSheetView")
    view.FieldAssociation = "Cell Data"
    view.ViewTime = t
    pv.Show(mesh_src, view)
    with tempfile.TemporaryDirectory() as tmp:
        csv_path = os.path.join(tmp, "sheet.csv")
        pv.ExportView(csv_path, view=view)
        with open(csv_path) as fh:
            header = next(csv.reader(fh))
    pv.Delete(view)
    cols = [h for h in header if h.startswith("stress_")]
    want_cols = ["stress_%d" % k for k in range(6)] + ["stress_Magnitude"]
    need(cols == want_cols, "spreadsheet stress columns %s, expected %s" % (cols, want_cols))
    line = ("stress components in ParaView (colour-by menu, Calculator variables stress_XX ..): "
            "%s = HDF5 columns 0..5 (xx, yy, zz, xy, yz, xz); Calculator von Mises of them == "
            "von_mises; spreadsheet/CSV columns %s" % (" ".join(names), " ".join(cols)))
    info.append(line)
    if args.wall_force:
        wall_force(args, mesh_src, walls, times, need, info)


def wall_force(args, mesh_src, walls, times, need, info):
    """With a wall normal to z pressing and dragging the model's bottom: the volume
    integral of stress_XZ (stress_ZZ) over the model's height is the x (z) force the
    body exerts on the wall, history.csv's <wall>.fx (.fz): pins XZ as the xz shear."""
    import paraview.simple as pv
    from paraview import servermanager
    from vtkmodules.util.numpy_support import vtk_to_numpy
    w, t = args.wall_force, times[-1]
    hist = os.path.join(os.path.dirname(args.xmf), "history.csv")
    with open(hist) as fh:
        rows = [r for r in csv.DictReader(fh) if abs(float(r["time"]) - t) <= 1e-9 * max(1.0, abs(t))]
    if not need(rows and ("%s.fx" % w) in rows[-1], "history.csv: no row at t=%g with %s.fx" % (t, w)):
        return
    fx, fz = float(rows[-1]["%s.fx" % w]), float(rows[-1]["%s.fz" % w])
    calc = pv.Calculator(Input=mesh_src, AttributeType="Cell Data", ResultArrayName="sxz",
                         Function="stress_XZ")
    calc2 = pv.Calculator(Input=calc, AttributeType="Cell Data", ResultArrayName="szz",
                          Function="stress_ZZ")
    integ = pv.IntegrateVariables(Input=calc2)
    integ.UpdatePipeline(t)
    d = servermanager.Fetch(integ)
    cd = d.GetCellData()
    mesh = fetch(mesh_src, t, True) if walls else servermanager.Fetch(mesh_src)
    zb = mesh.GetBounds()[4:6]
    height = zb[1] - zb[0]
    gx = float(vtk_to_numpy(cd.GetArray("sxz"))[0]) / height
    gz = float(vtk_to_numpy(cd.GetArray("szz"))[0]) / height
    need(abs(gx - fx) <= 1e-6 * max(abs(fx), abs(fz)) and abs(gz - fz) <= 1e-6 * max(abs(fx), abs(fz)),
         "t=%g: integral of stress_XZ, stress_ZZ over the height (%g, %g) != %s.fx, %s.fz "
         "(%g, %g) of history.csv" % (t, gx, gz, w, w, fx, fz))
    info.append("t=%g: integral of stress_XZ dV / height = %.4f == %s.fx %.4f, of stress_ZZ = %.4f == "
                "%s.fz %.4f (history.csv): XZ is the shear the friction carries"
                % (t, gx, w, fx, gz, w, fz))


def render(args):
    import paraview.simple as pv
    reader, _ = open_reader(args.xmf, args.reader)
    t = list(reader.TimestepValues)[-1]
    names = (xmf_grid_names(args.xmf) or [[]])[0]
    walls = any(not is_part(n) for n in names)
    scene = pv.GetAnimationScene()
    scene.UpdateAnimationUsingDataTimeSteps()
    scene.AnimationTime = t
    parts = ["/Root/%s" % n for n in names if is_part(n)]
    mesh = pv.ExtractBlock(Input=reader, Selectors=parts) if walls else reader
    scale = args.render_scale
    warp = pv.WarpByVector(Input=mesh, Vectors=["POINTS", "displacement"], ScaleFactor=scale)
    view = pv.CreateView("RenderView")
    view.ViewSize = [1200, 700]
    view.ViewTime = t
    view.OrientationAxesVisibility = 1
    view.Background = [1, 1, 1]
    try:
        view.UseColorPaletteForBackground = 0
    except AttributeError:
        pass
    # ghost of the undeformed body
    ghost = pv.Show(mesh, view)
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
    name = os.path.splitext(os.path.basename(args.xmf))[0]
    if walls:
        wall = pv.ExtractBlock(Input=reader, Selectors=["/Root/*[starts-with(@label,'wall_')]"])
        wd = pv.Show(wall, view)
        wd.Representation = "Surface With Edges"
        wd.ColorArrayName = ["POINTS", ""]  # solid colour (ColorBy(wd, None) fails: no arrays)
        wd.AmbientColor = wd.DiffuseColor = [0.55, 0.6, 0.7]
        text = pv.Text(Text="alfe %s, t = %g (displacement x%g; walls at their position)"
                       % (name, t, scale))
    else:
        text = pv.Text(Text="alfe %s, t = %g (displacement x%g)" % (name, t, scale))
    td = pv.Show(text, view)
    td.Color = [0, 0, 0]
    td.FontSize = 14
    if walls:
        reader.UpdatePipeline(t)
        b = reader.GetDataInformation().GetBounds()
        c = [0.5 * (b[0] + b[1]), 0.5 * (b[2] + b[3]), 0.5 * (b[4] + b[5])]
        view.CameraFocalPoint = c
        view.CameraPosition = [c[0] + 25, c[1] - 55, c[2] + 30]
        disp.Ambient, disp.Diffuse = 0.35, 0.65  # the side faces are dim under the light kit
    else:
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
    p.add_argument("--reader", choices=["Xdmf3ReaderS", "Xdmf3ReaderT", "XDMFReader"],
                   help="ParaView reader (default: Xdmf3ReaderS, then XDMFReader, then OpenDataFile)")
    p.add_argument("--expect-steps", type=int)
    p.add_argument("--expect-points", type=int)
    p.add_argument("--expect-cells", type=int)
    p.add_argument("--expect-partitions", type=int)
    p.add_argument("--expect-blocks", metavar="A,B", help="the grids of every step, e.g. mesh,wall_floor")
    p.add_argument("--expect-moving", metavar="W,..", help="walls that must move, e.g. floor")
    p.add_argument("--wall-force", metavar="WALL",
                   help="check stress_XZ, stress_ZZ against WALL.fx, .fz of history.csv (a wall normal to z)")
    p.add_argument("--no-other-readers", action="store_true",
                   help="skip how the other XDMF readers show the file")
    p.add_argument("--render", metavar="PNG", help="only render the warped last step to PNG")
    p.add_argument("--render-scale", type=float, default=1.0, help="displacement scale of --render")
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
