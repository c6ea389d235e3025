"""Run every benchmark in this folder, one after the other, and print their figures.

Usage: ``python benchmarks/run_all.py [--out DIR] [--only NAME ...]``.  Each ``bench_*.py`` runs as a
script in its own process (so one benchmark's imports, threads and children never count in another's
memory or CPU figures) and accepts ``--out PATH`` (a JSON file with the same figures it prints).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--out", type=Path, default=Path("."), help="folder for bench-NAME.json files")
    parser.add_argument("--only", nargs="*", default=None, help="names such as bridge, sim, app")
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    failed = []
    for path in sorted(HERE.glob("bench_*.py")):
        name = path.stem.removeprefix("bench_")
        if args.only and name not in args.only:
            continue
        print(f"\n=== {name} ({path.name}) ===", flush=True)
        started = time.perf_counter()
        rc = subprocess.call([sys.executable, str(path), "--out", str(args.out / f"bench-{name}.json")])
        print(f"=== {name}: exit {rc}, {time.perf_counter() - started:.1f} s", flush=True)
        if rc:
            failed.append(name)
    if failed:
        print("failed:", ", ".join(failed))
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
