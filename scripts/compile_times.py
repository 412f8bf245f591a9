#!/usr/bin/env python3
"""Seconds to compile translation units, from a build's compile_commands.json (CMake writes one in every build).

Which sources make the build slow, measured: each selected compile command is run again as the build runs it (the
compiler cache bypassed, the object written to a temporary file), JOBS at a time, and its wall time printed, the
slowest first, with the total.

  scripts/compile_times.py build                       # every translation unit
  scripts/compile_times.py build estimators/graph      # those whose path contains a pattern
  scripts/compile_times.py build --tree ../other FILE  # the same commands on another checkout's sources

--tree compiles another checkout's copy of each file with this build's flags (say, an older commit in a worktree):
the two trees' figures then differ by the sources alone.  Times on a busy machine are not comparable: run it alone.
"""
import argparse
import json
import os
import shlex
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor


def commands(build, patterns):
    with open(os.path.join(build, "compile_commands.json")) as f:
        entries = json.load(f)
    return [e for e in entries if not patterns or any(p in e["file"] for p in patterns)]


def compile_once(entry, source_root, build, tree, scratch, index):
    args = shlex.split(entry["command"])
    if os.path.basename(args[0]) == "ccache":
        args = args[1:]
    args[args.index("-o") + 1] = os.path.join(scratch, f"{index}.o")
    if tree:
        here, there, built = os.path.abspath(source_root), os.path.abspath(tree), os.path.abspath(build)

        def moved(a):  # a source path or include folder of this checkout, not a generated one of the build
            path = a[2:] if a.startswith("-I") else a
            if not path.startswith(here) or path.startswith(built):
                return a
            return a.replace(here, there, 1)

        args = [moved(a) for a in args]
    start = time.monotonic()
    result = subprocess.run(args, cwd=entry["directory"], capture_output=True, text=True)
    seconds = time.monotonic() - start
    if result.returncode != 0:
        sys.exit(f"{entry['file']}: the compiler failed:\n{result.stderr[-2000:]}")
    return seconds, os.path.relpath(entry["file"], source_root)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("build", help="a configured CMake build folder")
    parser.add_argument("patterns", nargs="*", help="only sources whose path contains one of these")
    parser.add_argument("--jobs", type=int, default=2, help="compilations at once (default 2)")
    parser.add_argument("--tree", help="compile this checkout's copies of the sources instead")
    parser.add_argument("--source-root", default=os.path.dirname(os.path.dirname(os.path.abspath(__file__))),
                        help="the checkout the build was configured from (default: this script's)")
    opts = parser.parse_args()
    selected = commands(opts.build, opts.patterns)
    if not selected:
        sys.exit("no compile command matches")
    with tempfile.TemporaryDirectory() as scratch, ThreadPoolExecutor(opts.jobs) as pool:
        runs = list(pool.map(lambda ie: compile_once(ie[1], opts.source_root, opts.build, opts.tree, scratch, ie[0]),
                             enumerate(selected)))
    for seconds, name in sorted(runs, reverse=True):
        print(f"{seconds:7.1f} s  {name}")
    print(f"{sum(s for s, _ in runs):7.1f} s  total, {len(runs)} translation units, {opts.jobs} at a time")


if __name__ == "__main__":
    main()
