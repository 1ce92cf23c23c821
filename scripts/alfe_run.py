"""One `alfe run` and what it left, shared by the study scripts (cylinder-study,
indent-study, solver-table): the command under mpirun when ranks > 1, its exit code and
last stderr line (or a timeout), then summary.json and history.csv of its output
directory."""
import csv
import json
import os
import subprocess


def run(cmd, ranks=1, timeout=None, oversubscribe=True):
    """Run `cmd` (an `alfe run ...` argument list) on `ranks` ranks: (exit code or None
    on timeout, last stderr line or the timeout)."""
    if ranks > 1:
        cmd = ["mpirun"] + (["--oversubscribe"] if oversubscribe else []) + ["-n", str(ranks)] + cmd
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
        lines = p.stderr.strip().splitlines() or [""]
        # Under mpirun alfe's own error line is followed by Open MPI's banner.
        ours = [l for l in lines if l.startswith("alfe:")]
        return p.returncode, (ours or lines)[-1]
    except subprocess.TimeoutExpired:
        return None, f"timed out after {timeout:g} s"


def results(out):
    """(summary.json as a dict, history.csv as a list of row dicts) of the output directory
    `out`; empty where a file is missing."""
    summ, rows = {}, []
    if os.path.exists(os.path.join(out, "summary.json")):
        with open(os.path.join(out, "summary.json")) as f:
            summ = json.load(f)
    if os.path.exists(os.path.join(out, "history.csv")):
        with open(os.path.join(out, "history.csv")) as f:
            rows = list(csv.DictReader(f))
    return summ, rows


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
