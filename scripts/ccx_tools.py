"""Reading CalculiX's files for the comparisons (`ccx-compare`, `ccx-export-compare`):
node coordinates from an `.inp`, the last displacement block of a `.dat`, and the
largest difference from an alfe run's HDF5 displacements (nodes matched by position)."""
import os
import re

import h5py


def inp_nodes(text):
    """Node number → coordinates from the *NODE blocks."""
    nodes, on = {}, False
    for line in text.splitlines():
        t = line.strip()
        if t.startswith("**") or not t:
            continue
        if t.startswith("*"):
            on = re.match(r"\*node\s*(,|$)", t, re.I) is not None
            continue
        if on:
            f = [x.strip() for x in t.split(",")]
            nodes[int(f[0])] = [float(x) if x else 0.0 for x in (f[1:] + ["", "", ""])[:3]]
    return nodes


def dat_displacements(text):
    """Node number → displacement from the last `displacements` block of a .dat."""
    blocks, cur = [], None
    for line in text.splitlines():
        if "displacements" in line:
            cur = {}
            blocks.append(cur)
            continue
        f = line.split()
        if cur is not None and len(f) == 4 and re.fullmatch(r"\d+", f[0]):
            cur[int(f[0])] = [float(x) for x in f[1:]]
        elif cur is not None and f and not re.fullmatch(r"\d+", f[0]):
            cur = None
    return blocks[-1] if blocks else None


def compare(out_dir, nodes, ref):
    """(nodes compared, unmatched, max |u_ref|, max |u_alfe − u_ref| / max |u_ref|)."""
    h5 = [f for f in os.listdir(out_dir) if f.endswith(".h5")][0]
    with h5py.File(os.path.join(out_dir, h5)) as f:
        xyz = f["mesh/coordinates"][()]
        last = sorted(f["steps"].keys())[-1]
        u = f["steps"][last]["displacement"][()]
    scale = max(max(abs(c) for c in x) for x in nodes.values()) or 1.0

    def key(x):
        return tuple(round(c / scale, 6) for c in x)

    at = {key(x): u[i] for i, x in enumerate(xyz)}
    umax = max(max(abs(c) for c in v) for v in ref.values()) or 1.0
    worst, missing = 0.0, 0
    for n, v in ref.items():
        a = at.get(key(nodes[n]))
        if a is None:
            missing += 1
            continue
        worst = max(worst, max(abs(a[k] - v[k]) for k in range(3)))
    return len(ref) - missing, missing, umax, worst / umax
