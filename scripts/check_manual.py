"""Checks the user manual (docs/) so that it cannot rot; run by scripts/test.

  bash scripts/check-manual [ALFE]   (default: the repository's target/release/alfe)

1. The deck reference (docs/src/deck/) is what scripts/deck-reference generates from
   `ALFE schema` and docs/deck/, and every example in it passes the schema and
   `ALFE check` without a warning.
2. Every other ```toml block of the manual and of README.md is a valid deck, or a valid
   fragment of one: a block with a [scene] table must pass `ALFE check` without a
   warning, any other must pass the deck's JSON Schema (its tables, without the
   required ones).
3. `mdbook build docs` succeeds without a warning or an error, and every link between
   the manual's pages points at a page, an image or a heading that exists.
4. The tutorial (docs/src/tutorial.md) runs as written, in a fresh temporary directory
   with `alfe` on the PATH being ALFE, ALFE_REPO the repository and mpirun allowed as
   root. Its conventions:
   * a ```console block holds commands: each line that starts with `$ ` is run, in
     order, with `bash -o pipefail -c` in that directory (a line ending in `\\` goes on
     on the next one); the other lines are sample output and are not compared;
   * a line `<!-- file: NAME -->` just before a fenced block writes the block's text to
     NAME there, before the commands after it;
   * a line `<!-- requires: CMD ... -->` just before a ```console block runs it only if
     every CMD is on the PATH, else prints "skipped" (for ParaView's pvpython and
     xvfb-run);
   * ```sh blocks (set-up, ParaView's GUI) are shown, not run.
   A command that fails stops the check with the command, its exit code and its output.

Prints what it checked and how long each part took; exits 1 on the first part that
fails.
"""

import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import tomllib

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DOCS = os.path.join(ROOT, "docs")
SRC = os.path.join(DOCS, "src")
TIMEOUT = 300  # seconds per tutorial command; each takes a few


def die(msg):
    print(f"check-manual: {msg}", file=sys.stderr)
    sys.exit(1)


def step(name, t0):
    print(f"check-manual: {name} ok ({time.time() - t0:.1f} s)")


def mdbook():
    found = shutil.which("mdbook")
    if found:
        return found
    cargo_home = os.environ.get("CARGO_HOME", os.path.expanduser("~/.cargo"))
    p = os.path.join(cargo_home, "bin", "mdbook")
    if os.path.exists(p):
        return p
    die("mdbook not found: scripts/install-deps installs it")


def pages():
    for d, _, files in os.walk(SRC):
        for f in sorted(files):
            if f.endswith(".md"):
                yield os.path.join(d, f)


def fences(text):
    """[(language, body, line of the opening fence, the line before it)]"""
    out, lines, i = [], text.splitlines(), 0
    while i < len(lines):
        m = re.match(r"^(\s*)```(\S*)\s*$", lines[i])
        if m and m[2]:
            indent, j = m[1], i + 1
            while j < len(lines) and not re.match(r"^\s*```\s*$", lines[j]):
                j += 1
            body = "\n".join(l[len(indent):] for l in lines[i + 1 : j]) + "\n"
            out.append((m[2], body, i + 1, lines[i - 1].strip() if i else ""))
            i = j
        i += 1
    return out


def check_reference(alfe):
    r = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "deck-reference"), "--check", "--alfe", alfe])
    if r.returncode != 0:
        die("the deck reference is out of date or an example is wrong (above)")


def check_snippets(alfe):
    import jsonschema

    schema = json.loads(subprocess.run([alfe, "schema"], capture_output=True, text=True, check=True).stdout)
    fragment = dict(schema, required=[])
    validator = jsonschema.Draft202012Validator(fragment)
    files = [p for p in pages() if not p.startswith(os.path.join(SRC, "deck") + os.sep)]
    files.append(os.path.join(ROOT, "README.md"))
    tmp = tempfile.mkdtemp(prefix="check-manual-decks-")
    n = 0
    for path in files:
        rel = os.path.relpath(path, ROOT)
        for lang, body, line, _ in fences(open(path).read()):
            if lang != "toml":
                continue
            n += 1
            where = f"{rel}:{line}"
            try:
                deck = tomllib.loads(body)
            except tomllib.TOMLDecodeError as e:
                die(f"{where}: not TOML: {e}")
            errs = sorted(validator.iter_errors(deck), key=lambda e: list(e.path))
            if errs:
                die(f"{where}: the deck schema refuses it: {list(errs[0].path)}: {errs[0].message}")
            if "scene" in deck:
                p = os.path.join(tmp, f"deck{n}.toml")
                with open(p, "w") as fh:
                    fh.write(body)
                r = subprocess.run([alfe, "check", p], capture_output=True, text=True)
                warn = [l.strip() for l in r.stdout.splitlines() if l.strip().startswith("warning:")]
                if r.returncode != 0 or warn:
                    die(f"{where}: `alfe check` refuses it:\n{r.stderr.strip() or chr(10).join(warn)}")
    shutil.rmtree(tmp)
    return n


def check_links():
    """Every relative link of a page names a file that exists and, for a page, a heading
    or anchor that the built HTML has (mdBook's own ids)."""
    ids = {}
    bad = []
    for path in pages():
        text = open(path).read()
        text = re.sub(r"```.*?```", "", text, flags=re.S)
        text = re.sub(r"`[^`\n]*`", "", text)
        rel = os.path.relpath(path, SRC)
        for target in re.findall(r"\]\(([^)\s]+)\)", text):
            if re.match(r"[a-z]+:", target):
                continue
            file, _, anchor = target.partition("#")
            dest = os.path.normpath(os.path.join(os.path.dirname(path), file)) if file else path
            if not os.path.exists(dest):
                bad.append(f"{rel}: link to {target}: no such file")
                continue
            if anchor and dest.endswith(".md"):
                html = os.path.join(DOCS, "book", os.path.relpath(dest, SRC)[:-3] + ".html")
                if html not in ids:
                    ids[html] = set(re.findall(r'id="([^"]+)"', open(html).read()))
                if anchor not in ids[html]:
                    bad.append(f"{rel}: link to {target}: no such heading or anchor")
    if bad:
        die("broken links:\n  " + "\n  ".join(bad))


def build_book():
    r = subprocess.run([mdbook(), "build", DOCS], capture_output=True, text=True)
    out = (r.stdout + r.stderr).strip()
    noisy = [l for l in out.splitlines() if re.search(r"\b(WARN|ERROR|warning|error)\b", l)]
    if r.returncode != 0 or noisy:
        die(f"`mdbook build docs` failed or warned:\n{out}")


def tutorial_commands():
    """[(kind, payload, line)]: ("file", (name, text)), ("run", command), ("skip", why)."""
    path = os.path.join(SRC, "tutorial.md")
    out = []
    for lang, body, line, before in fences(open(path).read()):
        m = re.match(r"<!--\s*file:\s*(\S+)\s*-->", before)
        if m:
            out.append(("file", (m[1], body), line))
            continue
        if lang != "console":
            continue
        m = re.match(r"<!--\s*requires:\s*(.*?)\s*-->", before)
        missing = [c for c in (m[1].split() if m else []) if not shutil.which(c)]
        cmds, cur = [], None
        for l in body.splitlines():
            if cur is not None:
                cur += "\n" + l
            elif l.startswith("$ "):
                cur = l[2:]
            else:
                continue
            if cur.endswith("\\"):
                continue
            cmds.append(cur)
            cur = None
        if missing:
            out.append(("skip", f"{len(cmds)} command(s): {' '.join(missing)} not found", line))
        else:
            out.extend(("run", c, line) for c in cmds)
    if not any(k == "run" for k, _, _ in out):
        die("docs/src/tutorial.md has no commands to run")
    return out


def run_tutorial(alfe):
    work = tempfile.mkdtemp(prefix="alfe-tutorial-")
    bindir = os.path.join(work, ".bin")
    os.makedirs(bindir)
    os.symlink(alfe, os.path.join(bindir, "alfe"))
    cwd = os.path.join(work, "tutorial")
    os.makedirs(cwd)
    env = dict(os.environ)
    env.update(PATH=bindir + os.pathsep + env["PATH"], ALFE_REPO=ROOT, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    for kind, payload, line in tutorial_commands():
        where = f"docs/src/tutorial.md:{line}"
        if kind == "file":
            name, text = payload
            with open(os.path.join(cwd, name), "w") as fh:
                fh.write(text)
            print(f"  wrote {name}")
            continue
        if kind == "skip":
            print(f"  skipped ({where}): {payload}")
            continue
        t0 = time.time()
        try:
            r = subprocess.run(["bash", "-o", "pipefail", "-c", payload], cwd=cwd, env=env, capture_output=True, text=True, timeout=TIMEOUT)
        except subprocess.TimeoutExpired:
            die(f"{where}: `{payload}` did not finish in {TIMEOUT} s (in {cwd})")
        if r.returncode != 0:
            die(f"{where}: `{payload}` failed with exit code {r.returncode} (in {cwd}):\n{(r.stdout + r.stderr).strip()}")
        print(f"  $ {payload}  ({time.time() - t0:.1f} s)")
    shutil.rmtree(work)


def main():
    alfe = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "target", "release", "alfe"))
    if not os.access(alfe, os.X_OK):
        die(f"no alfe binary at {alfe}")
    t_all = t0 = time.time()
    check_reference(alfe)
    step("deck reference", t0)
    t0 = time.time()
    n = check_snippets(alfe)
    step(f"{n} other TOML blocks", t0)
    t0 = time.time()
    build_book()
    check_links()
    step("mdbook build and links", t0)
    t0 = time.time()
    run_tutorial(alfe)
    step("tutorial", t0)
    print(f"check-manual: all ok ({time.time() - t_all:.1f} s)")


if __name__ == "__main__":
    main()
