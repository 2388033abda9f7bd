"""Run a command as on a host whose every core is ``--factor`` times slower (Linux cgroup v1 CPU quotas; root).

Usage: python tools/slower_host.py [--factor 1.5] -- make test

Emulating another instruction set (``make emulate``) changes the floating-point paths, not the pace. This tool
changes the pace: every process of the command (the command itself and each descendant, found by polling /proc
every ``--poll`` seconds) is moved into a cgroup of its own whose CFS quota is 1/factor of one CPU per period, so a
single-threaded process runs ``factor`` times slower, and two workers on a 2-core machine are each slowed alike.
A process runs at full speed for at most one poll interval before it is moved; threads share their process's
quota (the study's work is single-threaded per process). Needs write access to /sys/fs/cgroup/cpu (cgroup v1,
root); refuses to run otherwise, rather than running at full speed.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path("/sys/fs/cgroup/cpu")
PERIOD_US = 100_000


def _children(pid: int) -> list[int]:
    """Every descendant of ``pid`` now (from each process's parent in /proc/<pid>/stat)."""
    parent = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            parent[int(entry.name)] = int(fields[1])
    found, frontier = [], [pid]
    while frontier:
        p = frontier.pop()
        kids = [c for c, pp in parent.items() if pp == p]
        found += kids
        frontier += kids
    return found


def _confine(group: Path, pid: int, quota_us: int) -> None:
    """Move ``pid`` into a cgroup of its own under ``group`` with ``quota_us`` per period."""
    cg = group / str(pid)
    cg.mkdir(exist_ok=True)
    (cg / "cpu.cfs_period_us").write_text(str(PERIOD_US))
    (cg / "cpu.cfs_quota_us").write_text(str(quota_us))
    try:
        (cg / "cgroup.procs").write_text(str(pid))
    except OSError:   # it ended meanwhile
        pass


def _sweep(group: Path) -> None:
    """Remove the cgroups whose processes have ended."""
    for cg in group.iterdir():
        if cg.is_dir() and not (cg / "cgroup.procs").read_text().strip():
            try:
                cg.rmdir()
            except OSError:
                pass


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--factor", type=float, default=1.5, help="how many times slower each core is (> 1)")
    parser.add_argument("--poll", type=float, default=0.05, help="seconds between looks for new processes")
    parser.add_argument("command", nargs=argparse.REMAINDER)
    args = parser.parse_args(argv)
    command = args.command[1:] if args.command[:1] == ["--"] else args.command
    if not command or not args.factor > 1:
        parser.error("give a command after '--' and --factor > 1")
    if not os.access(ROOT, os.W_OK):
        print(f"error: {ROOT} is not writable (cgroup v1 CPU controller, root needed): cannot slow the host",
              file=sys.stderr)
        return 2
    group = ROOT / f"slower_host_{os.getpid()}"
    group.mkdir()
    quota = int(PERIOD_US / args.factor)
    placed: set[int] = set()
    start = time.perf_counter()
    process = subprocess.Popen(command)
    try:
        while process.poll() is None:
            for pid in [process.pid, *_children(process.pid)]:
                if pid not in placed:
                    _confine(group, pid, quota)
                    placed.add(pid)
            time.sleep(args.poll)
            _sweep(group)
    finally:
        if process.poll() is None:
            process.kill()
        process.wait()
        _sweep(group)
        for cg in group.iterdir():
            if cg.is_dir():
                for pid in (cg / "cgroup.procs").read_text().split():
                    (ROOT / "cgroup.procs").write_text(pid)
                cg.rmdir()
        group.rmdir()
    print(f"slower_host: {' '.join(command)} took {time.perf_counter() - start:.1f} s wall at factor "
          f"{args.factor} ({len(placed)} processes slowed)", file=sys.stderr)
    return process.returncode


if __name__ == "__main__":
    sys.exit(main())
