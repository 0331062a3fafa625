#!/usr/bin/env python3
"""Runs the workspace's test binaries two at a time (scripts/test.sh, "host tests").

`cargo test` runs its test binaries one after another and holds the build directory's lock
while they run, so two `cargo test` commands cannot overlap either. A binary whose last test
runs alone (a 10 kHz diagnosis, a QEMU run) leaves the second core idle. This script takes
the binaries `cargo test --no-run` built (cargo's JSON messages, read from stdin), and runs
them as cargo would (working directory and CARGO_MANIFEST_DIR the package's, the given test
arguments), `--jobs` at a time, the slowest first (their order in SLOW_FIRST, measured in CI),
each one's output kept and printed whole when it ends. Exit status 1 when any binary fails,
after all have run; every failing binary's name is printed last.

usage: cargo test ... --no-run --message-format=json | run-test-binaries.py [--jobs 2] -- ARGS
"""

import argparse
import json
import os
import subprocess
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor

# Test targets by their CI run time, slowest first (CI log of 2026-11-27: hidden 173 s,
# messy_logs 149 s, qemu_cross 59 s, real_transforms 55 s, real_combinations 53 s,
# monitor_strangers 43 s, strangers 18 s, cli_robust 16 s, stm32_board 14 s, trust 12 s).
# The others follow in cargo's order.
SLOW_FIRST = ["hidden", "messy_logs", "qemu_cross", "real_transforms", "real_combinations",
              "monitor_strangers", "strangers", "cli_robust", "stm32_board", "trust"]


def binaries(lines):
    """(label, executable, package directory) of every test binary in cargo's JSON messages."""
    out = []
    for line in lines:
        line = line.strip()
        if not line.startswith("{"):
            continue
        m = json.loads(line)
        if m.get("reason") != "compiler-artifact" or not m.get("profile", {}).get("test"):
            continue
        exe = m.get("executable")
        if not exe:
            continue
        target = m["target"]
        pkg_dir = os.path.dirname(m["manifest_path"])
        kind = "tests" if target["kind"] == ["test"] else "unittests"
        out.append((f"{kind} {target['name']} ({os.path.basename(pkg_dir)})", exe, pkg_dir,
                    target["name"]))
    return out


def order(bins):
    """The SLOW_FIRST targets first, in that order, then the rest as cargo listed them."""
    rank = {n: i for i, n in enumerate(SLOW_FIRST)}
    return sorted(bins, key=lambda b: rank.get(b[3], len(SLOW_FIRST)))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--jobs", type=int, default=2, help="binaries run at once (default 2)")
    ap.add_argument("args", nargs="*", help="arguments for every test binary (after --)")
    a = ap.parse_args()
    if not 1 <= a.jobs <= 64:
        sys.exit(f"run-test-binaries.py: --jobs {a.jobs} is outside 1..64")
    bins = order(binaries(sys.stdin))
    if not bins:
        sys.exit("run-test-binaries.py: no test binary in cargo's messages on stdin")
    lock = threading.Lock()
    failed = []
    t_start = time.time()

    def run(b):
        label, exe, pkg_dir, _ = b
        env = dict(os.environ, CARGO_MANIFEST_DIR=pkg_dir)
        t0 = time.time()
        p = subprocess.run([exe, *a.args], cwd=pkg_dir, env=env, stdout=subprocess.PIPE,
                           stderr=subprocess.STDOUT, text=True, errors="replace")
        dt = time.time() - t0
        with lock:
            print(f"\n     Running {label} [{exe}] (rc {p.returncode}, {dt:.1f} s, "
                  f"at {time.time() - t_start:.0f} s)", flush=True)
            sys.stdout.write(p.stdout)
            sys.stdout.flush()
            if p.returncode != 0:
                failed.append(label)

    with ThreadPoolExecutor(max_workers=a.jobs) as pool:
        list(pool.map(run, bins))
    print(f"\n{len(bins)} test binaries in {time.time() - t_start:.0f} s, {a.jobs} at a time")
    if failed:
        print("FAILED: " + ", ".join(failed), file=sys.stderr)
        sys.exit(1)


if __name__ == "__main__":
    main()
