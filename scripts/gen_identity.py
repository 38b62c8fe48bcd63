#!/usr/bin/env python3
"""Is the generated C unchanged by a refactoring?  Generates every examples/
project (default and --selective all) and every tests/execution case (each
wrapped in a one-task configuration, as tests/execution/runner.py does) into
OUT, in one process; with --compare REF, compares OUT with an earlier OUT
file by file (logs with the output directory normalised) and exits 1 on a
difference.

    mkdir /tmp/base; git archive HEAD iec2kmod kmod_templates | tar -x -C /tmp/base
    python3 scripts/gen_identity.py /tmp/before --code /tmp/base
    python3 scripts/gen_identity.py /tmp/after --compare /tmp/before

--code DIR imports iec2kmod from another tree (the one before the change)
while the sources stay this tree's, so that both runs name the same paths.

The wrapper configurations are written to OUT/../gen_identity_src so that
both runs name the same source paths.  About a minute on an idle machine."""

from __future__ import annotations

import argparse
import contextlib
import filecmp
import io
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


_CASES = """
import json, sys
import runner
src = sys.argv[1]
out = []
for c in runner.discover():
    n = c.name.replace("/", "__").rsplit(".", 1)[0]
    paths = [str(c.path)]
    if not c.standalone:
        cfg = f"{src}/{n}_config.st"
        open(cfg, "w").write(runner.wrapper_config(n, [c]))
        paths.append(cfg)
    out.append((n, paths))
print(json.dumps(out))
"""


def jobs(out: Path, src: Path):
    for ex in sorted(p.name for p in (ROOT / "examples").iterdir() if p.is_dir()):
        yield ex, ["gen", "-o", str(out / ex), str(ROOT / "examples" / ex)]
        yield ex + ".sel", ["gen", "--selective", "all", "-o", str(out / (ex + ".sel")),
                            str(ROOT / "examples" / ex)]
    # the cases and their wrappers, by this tree's runner (in its own process:
    # the tree imported here may be another one)
    src.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(ROOT), str(ROOT / "tests" / "execution"), os.environ.get("PYTHONPATH", "")]))
    listed = subprocess.run([sys.executable, "-c", _CASES, str(src)], env=env, check=True,
                            capture_output=True, text=True).stdout
    for n, paths in json.loads(listed):
        yield "cases/" + n, ["gen", "-o", str(out / "cases" / n)] + paths


def generate(out: Path) -> int:
    from iec2kmod.cli import main
    shutil.rmtree(out, ignore_errors=True)
    (out / "cases").mkdir(parents=True)
    n = 0
    with open(out / "rc.txt", "w") as rcf:
        for name, argv in jobs(out, out.parent / "gen_identity_src"):
            buf = io.StringIO()
            try:
                with contextlib.redirect_stdout(buf), contextlib.redirect_stderr(buf):
                    rc = main(argv)
            except SystemExit as exc:
                rc = exc.code
            (out / f"{name}.log").write_text(buf.getvalue().replace(str(out), "OUT"))
            rcf.write(f"{name} rc={rc}\n")
            n += 1
    return n


def compare(a: Path, b: Path) -> list[str]:
    diffs = []

    def walk(cmp: filecmp.dircmp, rel: str):
        for f in cmp.left_only + cmp.right_only:
            diffs.append(f"only in one tree: {rel}{f}")
        _, mismatch, errors = filecmp.cmpfiles(cmp.left, cmp.right, cmp.common_files,
                                               shallow=False)
        diffs.extend(f"differs: {rel}{f}" for f in mismatch + errors)
        for d, sub in cmp.subdirs.items():
            walk(sub, f"{rel}{d}/")

    walk(filecmp.dircmp(a, b), "")
    return diffs


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", type=Path)
    ap.add_argument("--compare", type=Path, metavar="REF")
    ap.add_argument("--code", type=Path, metavar="DIR", default=ROOT,
                    help="the tree iec2kmod is imported from (default: this one)")
    args = ap.parse_args()
    sys.path.insert(0, str(args.code.resolve()))
    os.chdir(ROOT)
    n = generate(args.out.resolve())
    files = sum(1 for p in args.out.rglob("*") if p.is_file())
    print(f"{n} generations, {files} files in {args.out}")
    if args.compare is None:
        return 0
    diffs = compare(args.compare, args.out)
    for d in diffs[:50]:
        print(d)
    print(f"{len(diffs)} difference(s) against {args.compare}")
    return 1 if diffs else 0


if __name__ == "__main__":
    sys.exit(main())
