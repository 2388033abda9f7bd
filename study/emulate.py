"""Other hosts emulated on this one: ``make test`` and ``make verify`` under other floating-point code paths.

Last-bit differences between machines come from the code paths their libraries pick for the CPU: the
instructions numba compiles for, the SIMD kernels NumPy dispatches to, the kernels OpenBLAS (under SciPy
and NumPy) selects. Each can be forced down to an older CPU by an environment variable, so a more capable
host can run the suites as a less capable one would. Each configuration gets its own cache
(``STUDY_CACHE_DIR``), so no generated code, compiled function or saved result of another configuration is
reused, and its own copy of the committed snapshot's tables for ``make verify`` (a ``make reproduce`` under
emulation rewrites ``reports/`` of the checkout it runs in).

Emulation reaches only downwards: on a host without AVX-512 the ``avx2`` configuration changes nothing.
``python -m study.emulate --show`` prints what each configuration switches off on this host. Exudyn's
compiled core has no such switch; its cases run as they do natively.

Usage: ``python -m study.emulate [--hosts avx2 sse2] [--targets test verify]`` (``make emulate``).
"""

from __future__ import annotations

import argparse
import io
import os
import shutil
import subprocess
import sys
import tarfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

# NumPy >= 2.4 groups its dispatch targets by x86-64 microarchitecture level: X86_V3 is AVX2 + FMA3,
# X86_V4 (and the ICL/SPR extensions) AVX-512. The OpenBLAS core types name those generations' kernels.
HOSTS: dict[str, dict[str, str]] = {
    "avx2": {  # a host without AVX-512 (e.g. Zen 2/3, Haswell-Skylake client)
        "NUMBA_CPU_NAME": "haswell",
        "NPY_DISABLE_CPU_FEATURES": "X86_V4 AVX512_ICL AVX512_SPR",
        "OPENBLAS_CORETYPE": "Haswell",
    },
    "sse2": {  # the x86-64 baseline: no AVX of any kind in compiled code, NumPy at its x86-64-v2 baseline
        "NUMBA_CPU_NAME": "generic",
        "NPY_DISABLE_CPU_FEATURES": "X86_V3 X86_V4 AVX512_ICL AVX512_SPR",
        "OPENBLAS_CORETYPE": "Nehalem",
    },
}

PROBE = (
    "from numpy._core._multiarray_umath import __cpu_features__ as f, __cpu_dispatch__ as d\n"
    "from numba.core import config\n"
    "import llvmlite.binding as ll\n"
    "print('numpy dispatch on:', ' '.join(x for x in d if f.get(x)) or 'none (baseline only)')\n"
    "print('numba target cpu:', config.CPU_NAME or ll.get_host_cpu_name())\n"
)


def environment(host: str) -> dict[str, str]:
    """The process environment of ``host``: its switches and a cache of its own."""
    if host not in HOSTS:
        raise ValueError(f"--hosts: unknown configuration {host!r} (choices: {', '.join(HOSTS)})")
    env = dict(os.environ)
    env.update(HOSTS[host])
    env["STUDY_CACHE_DIR"] = str(ROOT / ".cache" / "emulate" / host)
    return env


def show(host: str) -> str:
    """What the configuration does on this host, as the child process sees it."""
    out = subprocess.run([sys.executable, "-c", PROBE], env=environment(host), capture_output=True, text=True,
                         check=True)
    return out.stdout.strip()


def committed_snapshot(dest: Path) -> Path:
    """``reports/tables`` as committed at HEAD, written to ``dest/tables`` (replacing what was there)."""
    from study.output_folder import claim_output_folder

    shutil.rmtree(dest, ignore_errors=True)   # emulate's own scratch folder in the cache
    claim_output_folder(dest)   # marked: study verify --out dest reads it as a report folder
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", "HEAD", "reports/tables"], capture_output=True,
                             check=True).stdout
    with tarfile.open(fileobj=io.BytesIO(archive)) as tar:
        tar.extractall(dest, filter="data")
    shutil.move(dest / "reports" / "tables", dest / "tables")
    (dest / "reports").rmdir()
    return dest / "tables"


def run(host: str, targets: list[str]) -> dict[str, tuple[int, float]]:
    """Run each make target under ``host``; exit code and wall seconds per target."""
    env = environment(host)
    scratch = ROOT / ".cache" / "emulate" / host / "reports"
    outcome = {}
    for target in targets:
        cmd = ["make", "--no-print-directory", target]
        if target == "verify":  # compare with the committed snapshot (a reproduce run may have rewritten reports/)
            committed_snapshot(scratch)
            cmd.append(f"OUT={scratch}")
        print(f"== {host}: {' '.join(cmd)}", flush=True)
        t0 = time.perf_counter()
        code = subprocess.run(cmd, cwd=ROOT, env=env).returncode
        outcome[target] = (code, time.perf_counter() - t0)
        print(f"== {host}: make {target} exit {code}, {outcome[target][1]:.0f} s wall", flush=True)
    return outcome


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m study.emulate", description=__doc__.split("\n\n")[0])
    parser.add_argument("--hosts", nargs="+", default=list(HOSTS), help=f"configurations (default: all of {list(HOSTS)})")
    parser.add_argument("--targets", nargs="+", default=["test", "verify"], choices=["test", "verify", "reproduce"],
                        help="make targets to run under each (default: test verify)")
    parser.add_argument("--show", action="store_true", help="only print what each configuration switches")
    args = parser.parse_args(argv)
    try:
        for host in args.hosts:
            environment(host)
    except ValueError as exc:
        parser.error(str(exc))
    results = {}
    for host in args.hosts:
        print(f"== {host}: {' '.join(f'{k}={v}' for k, v in HOSTS[host].items())}\n{show(host)}", flush=True)
        if not args.show:
            results[host] = run(host, args.targets)
    for host, outcome in results.items():
        print(f"{host}: " + ", ".join(f"{t} exit {c} ({s:.0f} s)" for t, (c, s) in outcome.items()))
    return int(any(c for outcome in results.values() for c, _ in outcome.values()))


if __name__ == "__main__":
    sys.exit(main())
