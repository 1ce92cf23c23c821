#!/usr/bin/python3
"""A run's results in a small JSON digest, and the comparison of two digests.

  scene_digest.py digest OUT_DIR            print the digest of a finished run (history.csv,
                                            summary.json and the last step of the HDF5 file)
  scene_digest.py compare BASE.json NEW.json [--rtol R]
                                            exit 1 with one line per difference

The digest keeps what must not move when the code is restructured: every history column
but timings and linear-solver internals, the per-step nonlinear iteration and retry counts,
and the last step's displacement at up to 400 nodes (by the user's node number) with norms
of the displacement and von Mises fields. Floats compare to `rtol` times the largest
magnitude of their column (or field); counts compare exactly. Needs h5py (Debian's
`python3-h5py`, hence /usr/bin/python3).
"""

import csv
import json
import math
import os
import sys

# Timings and linear-solver internals: allowed to change with the code.
SKIP = {"wall_time_s", "assembly_s", "linear_s", "linear_iterations", "residual_evaluations",
        "factorizations", "final_relative_residual"}
# Compared exactly.
COUNTS = {"step", "nonlinear_iterations", "retries", "contact_active", "contact_sticking"}
SAMPLE = 400


def digest(out):
    with open(os.path.join(out, "summary.json")) as f:
        s = json.load(f)
    with open(os.path.join(out, "history.csv")) as f:
        rows = list(csv.reader(f))
    head, body = rows[0], rows[1:]
    cols = {}
    for i, name in enumerate(head):
        if name in SKIP:
            continue
        vals = []
        for r in body:
            v = float(r[i])
            vals.append(int(v) if name in COUNTS and math.isfinite(v) else v)
        cols[name] = vals
    d = {
        "scene": s["scene"],
        "ranks": s["ranks"],
        "solver": s["solver"],
        "converged": s["converged"],
        "steps": s["steps"],
        "nonlinear_iterations": s["nonlinear_iterations"],
        "retries": s["retries"],
        "history": cols,
    }
    import h5py  # noqa: E402  (only the digest needs it)
    import numpy as np

    h5 = os.path.join(out, s["scene"] + ".h5")
    with h5py.File(h5, "r") as f:
        steps = sorted(f["steps"].keys())
        if steps:
            last = f["steps"][steps[-1]]
            ids = f["mesh/original_node_id"][:, 0] if f["mesh/original_node_id"].ndim == 2 else f["mesh/original_node_id"][:]
            u = last["displacement"][:]
            order = np.argsort(ids)
            u = u[order]
            n = u.shape[0]
            pick = sorted(set(int(round(x)) for x in np.linspace(0, n - 1, min(SAMPLE, n))))
            d["field_step"] = steps[-1]
            d["field_time"] = float(last.attrs["time"])
            d["u_nodes"] = pick
            d["u"] = [[float(x) for x in u[i]] for i in pick]
            d["u_max"] = float(np.abs(u).max())
            d["u_l2"] = float(np.sqrt((u * u).sum()))
            vm = last["von_mises"][:]
            d["von_mises_max"] = float(np.nanmax(vm)) if vm.size else 0.0
            d["von_mises_l2"] = float(np.sqrt(np.nansum(vm * vm)))
    return d


def group(name):
    """Columns that share a scale: the components of one vector, and the energies."""
    if name in ("kinetic_energy", "internal_energy", "external_work"):
        return "energy"
    head, _, tail = name.rpartition(".")
    if head and tail in ("fx", "fy", "fz", "mx", "my", "mz", "ux", "uy", "uz", "rx", "ry", "rz"):
        return head + "." + tail[0]
    return name


# The smallest scale of a column group: a group whose values are all round-off or
# solver tolerance (ALM penetration, the moments of a symmetric load) is compared with an
# absolute rtol × 1e-2 (1e-10), so another pivot order's round-off is not a change.
SCALE_FLOOR = 1e-2


def close(a, b, scale, rtol):
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    return abs(a - b) <= rtol * max(scale, SCALE_FLOOR)


def compare(base, new, rtol):
    bad = []
    for k in ("converged", "steps", "nonlinear_iterations", "retries"):
        if base[k] != new[k]:
            bad.append(f"{k}: {base[k]} -> {new[k]}")
    bh, nh = base["history"], new["history"]
    scales = {}
    for name, bv in bh.items():
        g = group(name)
        m = max((abs(x) for x in bv if math.isfinite(x)), default=0.0)
        scales[g] = max(scales.get(g, 0.0), m)
    for name, bv in bh.items():
        if name not in nh:
            bad.append(f"history column {name} is missing")
            continue
        nv = nh[name]
        if len(bv) != len(nv):
            bad.append(f"history {name}: {len(bv)} rows -> {len(nv)}")
            continue
        if name in COUNTS:
            for i, (x, y) in enumerate(zip(bv, nv)):
                if x != y:
                    bad.append(f"history {name} row {i + 1}: {x} -> {y}")
            continue
        scale = scales[group(name)]
        worst = (0.0, None)
        for i, (x, y) in enumerate(zip(bv, nv)):
            if not close(x, y, scale, rtol):
                e = abs(x - y) / max(scale, SCALE_FLOOR)
                if not math.isfinite(e) or e > worst[0]:
                    worst = (e, i)
        if worst[1] is not None:
            i = worst[1]
            bad.append(f"history {name} row {i + 1}: {bv[i]!r} -> {nv[i]!r} (relative to its scale {worst[0]:.2e})")
    for name in nh:
        if name not in bh:
            bad.append(f"history column {name} is new")
    if "u" in base:
        if base.get("u_nodes") != new.get("u_nodes"):
            bad.append("the sampled nodes differ (another mesh?)")
        else:
            scale = base["u_max"]
            worst = max((abs(x - y) for a, b in zip(base["u"], new["u"]) for x, y in zip(a, b)), default=0.0)
            if worst > rtol * max(scale, 1e-300):
                bad.append(f"displacement: max difference {worst:.3e} at scale {scale:.3e}")
        for k in ("u_max", "u_l2", "von_mises_max", "von_mises_l2"):
            if not close(base[k], new[k], abs(base[k]), rtol):
                bad.append(f"{k}: {base[k]!r} -> {new[k]!r}")
        if base.get("field_step") != new.get("field_step"):
            bad.append(f"last field step: {base.get('field_step')} -> {new.get('field_step')}")
    return bad


def main(argv):
    if len(argv) >= 2 and argv[0] == "digest":
        json.dump(digest(argv[1]), sys.stdout, separators=(",", ":"))
        sys.stdout.write("\n")
        return 0
    if len(argv) >= 3 and argv[0] == "compare":
        rtol = 1e-8
        if "--rtol" in argv:
            rtol = float(argv[argv.index("--rtol") + 1])
        with open(argv[1]) as f:
            base = json.load(f)
        with open(argv[2]) as f:
            new = json.load(f)
        bad = compare(base, new, rtol)
        for b in bad:
            print(b)
        if not bad:
            print(f"same within {rtol:g}: {base['scene']} on {base['ranks']} rank(s), "
                  f"{base['steps']} steps, {base['nonlinear_iterations']} nonlinear iterations")
        return 1 if bad else 0
    print(__doc__, file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
