"""The scripts' shared helpers: running `alfe` (under mpirun as root, with a timeout), reading
what a run left (summary.json, history.csv), writing markdown tables, and the machine and
binary notes of the benchmark reports. Used by `study` (and its plans' reports in
`study_reports.py`), `solver-table`, `plot`, `check-baseline`, `compare-binaries`,
`bench-condense`, `dd-scaling`, `amg-scaling`, `dd-peers` and the `bench_*_report.py`."""
import csv
import json
import os
import platform
import subprocess
import tomllib
from datetime import datetime, timezone

# Open MPI refuses to start as root without these (containers and CI run as root).
ROOT_MPI = {"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1"}
# Idle ranks yield the core instead of spinning (timings on an oversubscribed machine).
YIELD = {"OMPI_MCA_mpi_yield_when_idle": "1"}


def env(*extra, **more):
    """os.environ with Open MPI allowed to run as root, plus the dicts in `extra` (such as
    YIELD) and the variables in `more`."""
    e = dict(os.environ, **ROOT_MPI)
    for d in extra:
        e.update(d)
    e.update(more)
    return e


def mpi_command(cmd, ranks=1, oversubscribe=True, mpi_args=(), always=False):
    """`cmd` under `mpirun -n ranks` when ranks > 1 (or `always`), else as it is."""
    if ranks > 1 or always:
        return (["mpirun"] + (["--oversubscribe"] if oversubscribe else []) + ["-n", str(ranks)]
                + list(mpi_args) + list(cmd))
    return list(cmd)


def run_process(cmd, ranks=1, timeout=None, oversubscribe=True, environ=None, mpi_args=(),
                always_mpirun=False):
    """Run `cmd` (on `ranks` ranks): the CompletedProcess (output captured as text), or None
    on a timeout. `environ` defaults to env() (root MPI allowed)."""
    full = mpi_command(cmd, ranks, oversubscribe, mpi_args, always_mpirun)
    try:
        return subprocess.run(full, capture_output=True, text=True, timeout=timeout,
                              env=environ if environ is not None else env())
    except subprocess.TimeoutExpired:
        return None


def last_error(stderr):
    """The last line of alfe's stderr that is its own (`alfe: ...`): under mpirun it is
    followed by Open MPI's banner; else the last line."""
    lines = (stderr or "").strip().splitlines() or [""]
    ours = [line for line in lines if line.startswith("alfe:")]
    return (ours or lines)[-1]


def run(cmd, ranks=1, timeout=None, oversubscribe=True, environ=None, stderr_to=None):
    """Run `cmd` (an `alfe run ...` argument list) on `ranks` ranks: (exit code or None
    on timeout, last stderr line or the timeout). With `stderr_to` (a file path), a run
    that fails leaves its whole stderr there: the last line alone may not say enough, and
    a message must point to a file that is kept."""
    p = run_process(cmd, ranks, timeout, oversubscribe, environ)
    if p is None:
        return None, f"timed out after {timeout:g} s"
    if stderr_to and p.returncode != 0:
        os.makedirs(os.path.dirname(stderr_to), exist_ok=True)
        with open(stderr_to, "w") as f:
            f.write(p.stderr)
    return p.returncode, last_error(p.stderr)


def summary(out):
    """summary.json of the output directory `out` as a dict; {} where it is missing."""
    path = os.path.join(out, "summary.json")
    if not os.path.exists(path):
        return {}
    with open(path) as f:
        return json.load(f)


def results(out):
    """(summary.json as a dict, history.csv as a list of row dicts) of the output directory
    `out`; empty where a file is missing."""
    rows = []
    if os.path.exists(os.path.join(out, "history.csv")):
        with open(os.path.join(out, "history.csv")) as f:
            rows = list(csv.DictReader(f))
    return summary(out), rows


def force_names(head):
    """The names of every force triple (`name.fx/.fy/.fz`) among history.csv's columns
    `head`, in their order: reaction sets, walls, contact entities, pairs, couplings."""
    return [c[:-3] for c in head
            if c.endswith(".fx") and f"{c[:-3]}.fy" in head and f"{c[:-3]}.fz" in head]


# The deck's unit systems (`[scene] units`) as alfe describes them (summary.json's `units`).
UNIT_SYSTEMS = {
    "m-kg-s": "length m, mass kg, time s, force N, stress Pa",
    "mm-t-s": "length mm, mass t, time s, force N, stress MPa",
    "mm-kg-ms": "length mm, mass kg, time ms, force kN, stress GPa",
    "mm-g-ms": "length mm, mass g, time ms, force N, stress MPa",
}


def units(out):
    """The unit of each kind of number of the run in `out`, {"length": "mm", "time": "s",
    "force": "N", ...}, so charts can label their axes: from summary.json's `units` (alfe's
    description, or the deck's short name such as "mm-t-s"), else from the deck.toml alfe
    copied into `out` (a run killed before its summary); {} where neither says."""
    text = summary(out).get("units")
    if not text and os.path.exists(os.path.join(out, "deck.toml")):
        with open(os.path.join(out, "deck.toml"), "rb") as f:
            try:
                text = tomllib.load(f).get("scene", {}).get("units")
            except tomllib.TOMLDecodeError:
                text = None
    return parse_units(text)


def parse_units(text):
    """{"length": "mm", ...} of a unit system's short name ("mm-t-s") or alfe's description
    of it ("length mm, mass t, time s, force N, stress MPa"); {} for None or anything else."""
    text = UNIT_SYSTEMS.get((text or "").strip(), text or "")
    pairs = [p.split() for p in text.split(",")]
    return {p[0]: p[1] for p in pairs if len(p) == 2}


def read_history(path):
    """history.csv at `path` with numbers converted (int, else float, else the text); None
    where the file is missing. A line a killed run left half written is dropped."""
    if not os.path.exists(path):
        return None
    rows = []
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            conv = {}
            for k, v in row.items():
                if k is None or v is None:
                    continue  # a line cut short by a killed run
                try:
                    conv[k] = int(v)
                except ValueError:
                    try:
                        conv[k] = float(v)
                    except ValueError:
                        conv[k] = v
            rows.append(conv)
    if rows and len(rows[-1]) < len(rows[0]):
        rows.pop()
    return rows


def md_table(head, rows, align=None):
    """A markdown table as a list of lines: the header, the rule (`align`, a list of rule
    cells such as "--:", or "---" for every column) and one line per row (cells already
    formatted as text)."""
    rule = align or ["---"] * len(head)
    return (["| " + " | ".join(head) + " |", "|" + "".join(f"{a}|" for a in rule)]
            + ["| " + " | ".join(str(c) for c in r) + " |" for r in rows])


def fmt(v, spec, none=""):
    """format(v, spec), or `none` where v is None."""
    return none if v is None else format(v, spec)


def pyplot():
    """matplotlib.pyplot with the Agg backend, installing Debian's python3-matplotlib
    (apt, as the bench scripts do) if this Python cannot import it; None if that fails."""
    try:
        import matplotlib
    except ImportError:
        print("installing python3-matplotlib (apt) for the charts", flush=True)
        r = subprocess.run("apt-get update -qq && apt-get install -y -qq --no-install-recommends "
                           "python3-matplotlib", shell=True, capture_output=True, text=True)
        if r.returncode != 0:
            print(f"could not install python3-matplotlib: {r.stderr.strip()[-300:]}")
            return None
        try:
            import matplotlib
        except ImportError:
            return None
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


# --- the benchmark reports' notes on the machine and the binary ------------------------------

def read_meta(path):
    """A bench script's meta.env (KEY=value lines) as a dict."""
    meta = {}
    with open(path) as f:
        for line in f:
            line = line.rstrip("\n")
            if "=" in line:
                k, v = line.split("=", 1)
                meta[k] = v
    return meta


def cpu_name():
    cpu = platform.processor() or "?"
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return cpu


def memory_gib():
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemTotal:"):
                    return round(int(line.split()[1]) / 1024**2, 1)
    except OSError:
        pass
    return None


def mpi_version():
    try:
        mpi = subprocess.run(["mpirun", "--version"], capture_output=True, text=True).stdout
        return mpi.splitlines()[0].strip() if mpi else "?"
    except OSError:
        return "?"


def iso(ts, fmt="%Y-%m-%dT%H:%M:%SZ"):
    return datetime.fromtimestamp(ts, tz=timezone.utc).strftime(fmt)


def alfe_info(meta, iso_fmt="%Y-%m-%dT%H:%M:%SZ", head_time=True, dirty_default=None):
    """Which alfe a bench measured (from meta.env): the binary, its digest, the commit it
    was built from, and a note where that is uncertain (a binary older than HEAD, a dirty
    work tree)."""
    head = meta.get("alfe_head") or None
    override = meta.get("alfe_commit_override") or None
    built_from = meta.get("alfe_built_from") or None
    mtime = int(meta["alfe_binary_mtime"]) if meta.get("alfe_binary_mtime") else None
    htime = int(meta["alfe_head_time"]) if meta.get("alfe_head_time") else None
    dirty = int(meta["alfe_dirty_files"]) if meta.get("alfe_dirty_files") else dirty_default
    when = lambda ts: iso(ts, iso_fmt)  # noqa: E731
    info = {
        "binary": meta.get("alfe_path"),
        "binary_sha256_prefix": meta.get("alfe_binary_sha256"),
        "binary_mtime": when(mtime) if mtime else None,
        "repo": meta.get("alfe_repo") or None,
        "repo_head": head,
    }
    if head_time:
        info["repo_head_time"] = when(htime) if htime else None
    info.update({"repo_dirty_source_files": dirty, "commit": override or head, "commit_note": None})
    if override:
        info["commit_note"] = "given with --commit"
    elif head and mtime and htime and mtime < htime:
        # The binary predates the work tree's HEAD: it was built from an earlier commit.
        info["commit"] = built_from or head
        info["commit_note"] = (f"binary written {when(mtime)}, before HEAD {head[:10]} "
                               f"({when(htime)}): taken as the newest commit before the build")
    elif head and dirty:
        info["commit_note"] = f"work tree had {dirty} modified source file(s)"
    return info
