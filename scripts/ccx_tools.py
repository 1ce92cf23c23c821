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


def dat_totals(text, nset):
    """[(time, (fx, fy, fz))] of the `*NODE PRINT, TOTALS=ONLY` blocks of a node set."""
    out, lines = [], text.splitlines()
    head = re.compile(r"total force \(fx,fy,fz\) for set (\S+) and time\s+(\S+)")
    for i, line in enumerate(lines):
        m = head.search(line)
        if not m or m.group(1).upper() != nset.upper():
            continue
        for row in lines[i + 1:i + 4]:
            f = row.split()
            if len(f) == 3:
                out.append((float(m.group(2)), tuple(float(x) for x in f)))
                break
    return out


def at_time(series, t):
    """Linear interpolation of [(time, value)] at t; None outside the times reached."""
    for (t0, v0), (t1, v1) in zip(series, series[1:]):
        if t0 - 1e-9 <= t <= t1 + 1e-9:
            s = 0.0 if t1 == t0 else (t - t0) / (t1 - t0)
            return v0 + s * (v1 - v0)
    return None
