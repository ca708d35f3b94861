#!/usr/bin/env python3
"""`make cargo-test`: the workspace's tests as `cargo test --release --workspace` runs
them, with the test executables run side by side on every core instead of one after
another.

cargo runs one test executable at a time; many of ours spend most of their time in
one thread (a single long lockstep test, headless Chromium waiting on the page), so on
this project's 2-core machine about half of the machine idled through the tests. Here
cargo builds them (`--no-run`, its JSON messages name each executable and its package),
then each executable runs as cargo would run it (working directory and
CARGO_MANIFEST_DIR of its package, the same arguments), NPROC at a time, the longest of
the last run first (build/cargo-test-times.json). Each one's output is printed whole
when it ends; a failing one is named again at the end and the script exits 1. The doc
tests run last through cargo itself.

  scripts/cargo_test.py [-- TEST-ARGS...]     FINESTEP_TEST_JOBS overrides the count
"""
import concurrent.futures
import json
import os
import subprocess
import sys
import threading
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TIMES = os.path.join(ROOT, "build", "cargo-test-times.json")


def main():
    args = sys.argv[1:]
    if args[:1] == ["--"]:
        args = args[1:]
    cargo = os.environ.get("CARGO", "cargo")
    build = subprocess.run(
        [cargo, "test", "--release", "--workspace", "--no-run", "--message-format=json-render-diagnostics"],
        cwd=ROOT, stdout=subprocess.PIPE, text=True)
    if build.returncode != 0:
        sys.exit(build.returncode)
    runs = []
    for line in build.stdout.splitlines():
        try:
            msg = json.loads(line)
        except json.JSONDecodeError:
            continue
        if msg.get("reason") == "compiler-artifact" and msg.get("profile", {}).get("test") and msg.get("executable"):
            target = msg["target"]
            kind = "unittests" if target["kind"] != ["test"] else "tests"
            runs.append((f"{kind} {target['name']} ({os.path.basename(msg['executable'])})",
                         msg["executable"], os.path.dirname(msg["manifest_path"])))
    try:
        with open(TIMES) as f:
            last = json.load(f)
    except (OSError, ValueError):
        last = {}
    runs.sort(key=lambda r: -last.get(os.path.basename(r[1]).rsplit("-", 1)[0], 0.0))

    jobs = int(os.environ.get("FINESTEP_TEST_JOBS") or os.cpu_count() or 1)
    lock = threading.Lock()
    times = {}
    failed = []

    def run(item):
        name, exe, pkg_dir = item
        env = dict(os.environ, CARGO_MANIFEST_DIR=pkg_dir)
        start = time.monotonic()
        proc = subprocess.run([exe] + args, cwd=pkg_dir, env=env, stdout=subprocess.PIPE,
                              stderr=subprocess.STDOUT, text=True, errors="replace")
        took = time.monotonic() - start
        with lock:
            times[os.path.basename(exe).rsplit("-", 1)[0]] = took
            print(f"     Running {name}: {took:.1f} s", flush=True)
            sys.stdout.write(proc.stdout)
            sys.stdout.flush()
            if proc.returncode != 0:
                failed.append(name)

    start = time.monotonic()
    with concurrent.futures.ThreadPoolExecutor(max_workers=jobs) as pool:
        list(pool.map(run, runs))
    wall = time.monotonic() - start
    os.makedirs(os.path.dirname(TIMES), exist_ok=True)
    with open(TIMES, "w") as f:
        json.dump(times, f, indent=1, sort_keys=True)
    print(f"cargo-test: {len(runs)} test executables, {sum(times.values()):.0f} s of runs in {wall:.0f} s on {jobs} jobs")
    if failed:
        print("cargo-test: FAILED: " + ", ".join(failed))
        sys.exit(1)
    doc = subprocess.run([cargo, "test", "--release", "--workspace", "--doc"] + (["--"] + args if args else []), cwd=ROOT)
    if doc.returncode != 0:
        sys.exit(doc.returncode)


if __name__ == "__main__":
    main()
