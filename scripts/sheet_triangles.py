"""Driver of `scripts/sheet-triangles` (run with a Python that has the gmsh wheel)."""
import argparse
import json
import math
import os
import shutil
import sys
import tempfile

import gmsh

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)
import alfe_run  # noqa: E402

R = 25.0
REFERENCE = 0.3024
BEAM = 14.0 * 60.0**3 / (3 * 210000.0 * 20.0 / 12.0)


def roof_mesh(size, mode, path):
    """The Scordelis–Lo quarter roof's middle surface (axis x, z up, θ 50°–90°, x 0–25),
    physical curves diaphragm, midspan, crown, free, point midside, surface roof; `mode`
    quad (Blossom), mixed (simple recombination: some triangles stay), tri."""
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    g = gmsh.model.geo
    c = g.addPoint(0, 0, 0, size)
    th = math.radians(50)
    p1 = g.addPoint(0, R * math.cos(th), R * math.sin(th), size)
    p2 = g.addPoint(0, 0, R, size)
    arc = g.addCircleArc(p1, c, p2)
    ex = g.extrude([(1, arc)], 25, 0, 0)
    g.synchronize()
    surf = [e for e in ex if e[0] == 2][0][1]
    phys = {}
    for _, cv in gmsh.model.getBoundary([(2, surf)], oriented=False):
        x0, y0, z0, x1, y1, z1 = gmsh.model.getBoundingBox(1, cv)
        if x1 < 1e-6:
            phys["diaphragm"] = cv
        elif x0 > 25 - 1e-6:
            phys["midspan"] = cv
        elif z0 > R - 1e-6:
            phys["crown"] = cv
        else:
            phys["free"] = cv
    for name, cv in phys.items():
        gmsh.model.addPhysicalGroup(1, [cv], name=name)
    gmsh.model.addPhysicalGroup(2, [surf], name="roof")
    for _, t in gmsh.model.getBoundary([(1, phys["midspan"])], oriented=False):
        if gmsh.model.getValue(0, t, [])[2] < R - 1e-6:
            gmsh.model.addPhysicalGroup(0, [t], name="midside")
    gmsh.option.setNumber("Mesh.Algorithm", 6 if mode == "tri" else 8)
    if mode != "tri":
        gmsh.option.setNumber("Mesh.RecombineAll", 1)
        gmsh.option.setNumber("Mesh.RecombinationAlgorithm", 0 if mode == "mixed" else 1)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.model.mesh.generate(2)
    counts = element_counts()
    gmsh.write(path)
    gmsh.finalize()
    return counts


def plate_mesh(nx, ny, mode, path):
    """The 60 x 20 plate's surface, nx x ny cells: quads, triangles (each cell cut on an
    alternating diagonal) or mixed (the tip half in triangles); curves root, tip."""
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    g = gmsh.model.geo
    pts = [g.addPoint(x, y, 0) for x, y in ((0, 0), (60, 0), (60, 20), (0, 20))]
    lines = [g.addLine(pts[i], pts[(i + 1) % 4]) for i in range(4)]
    loop = g.addCurveLoop(lines)
    s = g.addPlaneSurface([loop])
    for ln, n in zip(lines, (nx, ny, nx, ny)):
        g.mesh.setTransfiniteCurve(ln, n + 1)
    g.mesh.setTransfiniteSurface(s, "Alternate")
    if mode == "quad":
        g.mesh.setRecombine(2, s)
    g.synchronize()
    gmsh.model.addPhysicalGroup(1, [lines[3]], name="root")
    gmsh.model.addPhysicalGroup(1, [lines[1]], name="tip")
    gmsh.model.addPhysicalGroup(2, [s], name="plate")
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.model.mesh.generate(2)
    counts = element_counts()
    gmsh.write(path)
    gmsh.finalize()
    return counts


def element_counts():
    out = {"quads": 0, "triangles": 0}
    types, tags, _ = gmsh.model.mesh.getElements(2)
    for t, e in zip(types, tags):
        out["quads" if t == 3 else "triangles"] += len(e)
    return out


def roof_deck(base, msh, form):
    deck = base.replace(
        'mesh = { kind = "ring", inner_radius = 24.875, outer_radius = 25.125, thickness = 25.0, angles = [50, 90], cells = [1, 16, 16] }\nrotate = { axis = [1, 1, 1], angle = 120 }',
        f'mesh = {{ kind = "sheet", file = "{msh}", thickness = 0.25 }}')
    deck = deck.replace('formulation = "eas"', f'formulation = "{form}"')
    for a, b in (('group = "zmin"', 'group = "diaphragm"'), ('group = "zmax"', 'group = "midspan"'),
                 ('group = "end"', 'group = "crown"'), ('group = "outer"', 'group = "top"'),
                 ('box = { min = [25.0, 15.9, 19.0], max = [25.0, 16.2, 19.3] }', 'group = "midside"')):
        assert a in deck, a
        deck = deck.replace(a, b)
    return deck


def plate_deck(msh, form):
    return f"""[scene]
name = "plate"
units = "mm-t-s"
[[materials]]
name = "steel"
model = "linear-elastic"
E = 210000.0
nu = 0.0
[[parts]]
name = "plate"
material = "steel"
formulation = "{form}"
mesh = {{ kind = "sheet", file = "{msh}", thickness = 1.0 }}
[[node_sets]]
name = "root"
group = "root"
[[surfaces]]
name = "tip"
group = "tip"
[[boundary]]
type = "fixed"
set = "root"
[[loads]]
type = "traction"
surface = "tip"
traction = [0, 0, 0.7]
[analysis]
type = "static"
end_time = 1.0
step = 1.0
[output]
displacements = ["tip"]
"""


def run(binary, deck, work, name, column):
    path = os.path.join(work, name + ".toml")
    open(path, "w").write(deck)
    out = os.path.join(work, name)
    code, err = alfe_run.run([binary, "run", path, "--out", out, "--quiet",
                              "--partitions", os.path.join(work, "parts")], timeout=1800)
    if code != 0:
        return {"ok": False, "error_message": err}
    hist = alfe_run.read_history(os.path.join(out, "history.csv"))
    s = alfe_run.summary(out)
    return {"ok": True, "value": abs(hist[-1][column]), "unknowns": s["unknowns"],
            "wall_s": s["wall_time_s"]}


def main():
    ap = argparse.ArgumentParser(description="sheets of triangles: Scordelis–Lo and a plate")
    ap.add_argument("--bin", default=os.path.join(ROOT, "target/release/alfe"))
    ap.add_argument("--out", default=os.path.join(HERE, "results/elements"))
    ap.add_argument("--fixture", action="store_true")
    ap.add_argument("--from-json", action="store_true", help="redraw the table from DIR's json")
    a = ap.parse_args()
    if a.from_json:
        report(json.load(open(os.path.join(a.out, "sheet-triangles.json"))), a.out)
        return
    work = tempfile.mkdtemp(prefix="sheet-triangles-")
    base = alfe_run.run_process([a.bin, "scene", "show", "scordelis-lo"]).stdout
    rows = []
    for size in (1.5625, 0.78125, 0.390625):
        for mode in ("quad", "mixed", "tri"):
            msh = os.path.join(work, f"roof-{mode}-{size}.msh")
            counts = roof_mesh(size, mode, msh)
            if a.fixture and mode == "mixed" and size == 0.78125:
                shutil.copy(msh, os.path.join(ROOT, "tests/meshes/scordelis-lo-mixed.msh"))
            for form in ("eas", "standard"):
                r = run(a.bin, roof_deck(base, msh, form), work, f"roof-{mode}-{size}-{form}",
                        "midside.uz")
                r.update(case="scordelis-lo", size=size, mode=mode, formulation=form, **counts)
                if r["ok"]:
                    r["ratio"] = r["value"] / REFERENCE
                rows.append(r)
                print(json.dumps(r), flush=True)
    for n in (1, 2):
        for mode in ("quad", "mixed", "tri"):
            msh = os.path.join(work, f"plate-{mode}-{n}.msh")
            if mode == "mixed":
                counts = mixed_plate(24 * n, 8 * n, msh)
            else:
                counts = plate_mesh(24 * n, 8 * n, mode, msh)
            for form in ("eas", "standard"):
                r = run(a.bin, plate_deck(msh, form), work, f"plate-{mode}-{n}-{form}", "tip.uz")
                r.update(case="plate", size=60 / (24 * n), mode=mode, formulation=form, **counts)
                if r["ok"]:
                    r["ratio"] = r["value"] / BEAM
                rows.append(r)
                print(json.dumps(r), flush=True)
    os.makedirs(a.out, exist_ok=True)
    json.dump(rows, open(os.path.join(a.out, "sheet-triangles.json"), "w"), indent=1)
    report(rows, a.out)
    shutil.rmtree(work, ignore_errors=True)


def report(rows, out):
    table = [[r["case"], f'{r["size"]:.3g}', r["mode"], str(r["quads"]), str(r["triangles"]),
              "auto (EAS)" if r["formulation"] == "eas" else "standard",
              alfe_run.fmt(r.get("value"), ".4f", "failed"),
              alfe_run.fmt(r.get("ratio"), ".3f", "")] for r in rows]
    md = ("# Sheets of triangles (`scripts/sheet-triangles`)\n\n"
          f"Scordelis–Lo (reference {REFERENCE}: `midside.uz`) from Gmsh meshes of its middle "
          "surface, element size h (t = 0.25); the 60 x 20 x 1 plate under a 14 N tip load "
          f"(beam theory {BEAM:.4f} mm), cells 60/h x 20/h, mixed = the tip half in "
          "triangles. Quads become EAS hex8 and triangles solid-shell wedges under `auto`; "
          "`standard` is the standard hex8 and wedge6. One layer, 1 rank.\n\n"
          + "\n".join(alfe_run.md_table(["case", "h", "mesh", "quads", "triangles",
                                         "formulation", "deflection", "/ reference"], table))
          + "\n")
    open(os.path.join(out, "sheet-triangles.md"), "w").write(md)
    print(md)


def mixed_plate(nx, ny, path):
    """The plate with its root half in quads and its tip half in triangles: two surfaces."""
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    g = gmsh.model.geo
    xy = ((0, 0), (30, 0), (60, 0), (60, 20), (30, 20), (0, 20))
    p = [g.addPoint(x, y, 0) for x, y in xy]
    ln = [g.addLine(p[i], p[(i + 1) % 6]) for i in range(6)]
    mid = g.addLine(p[1], p[4])
    s1 = g.addPlaneSurface([g.addCurveLoop([ln[0], mid, ln[4], ln[5]])])
    s2 = g.addPlaneSurface([g.addCurveLoop([ln[1], ln[2], ln[3], -mid])])
    for c, n in ((ln[0], nx // 2), (ln[1], nx // 2), (ln[3], nx // 2), (ln[4], nx // 2),
                 (ln[2], ny), (ln[5], ny), (mid, ny)):
        g.mesh.setTransfiniteCurve(c, n + 1)
    g.mesh.setTransfiniteSurface(s1)
    g.mesh.setTransfiniteSurface(s2, "Alternate")
    g.mesh.setRecombine(2, s1)
    g.synchronize()
    gmsh.model.addPhysicalGroup(1, [ln[5]], name="root")
    gmsh.model.addPhysicalGroup(1, [ln[2]], name="tip")
    gmsh.model.addPhysicalGroup(2, [s1, s2], name="plate")
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.model.mesh.generate(2)
    counts = element_counts()
    gmsh.write(path)
    gmsh.finalize()
    return counts


if __name__ == "__main__":
    main()
