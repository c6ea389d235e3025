"""What the operator PIN costs to verify, and to guess offline from a copied ``app.json``.

For each scrypt cost (``n``; r=8, p=1 as ``rcon_core.app.pin`` uses) it times one PIN check (best and
median of ``--rounds``) and prints how long one core needs to try every PIN of 4, 6 and 8 digits (half of
that on average to find one). The row marked ``*`` is the cost ``make_record`` uses now. Timings on a
shared machine are noisy: the load is printed with them.

Usage: ``python benchmarks/bench_pin.py [--rounds 5]``
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

from rcon_core.app.pin import SCRYPT_N, SCRYPT_P, SCRYPT_R, check_pin, make_record


def span(seconds: float) -> str:
    for unit, size in (("years", 365 * 86400), ("days", 86400), ("h", 3600), ("min", 60)):
        if seconds >= size:
            return f"{seconds / size:.1f} {unit}"
    return f"{seconds:.0f} s"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args()
    try:
        load = open("/proc/loadavg").read().split()[:3]
    except OSError:
        load = ["?"]
    print(f"load average: {' '.join(load)}; cores: {os.cpu_count()}")
    print(f"{'n':>8} {'MiB':>4} {'best s':>7} {'median s':>8}   every 4-digit   every 6-digit   every 8-digit")
    record = make_record("2468")
    for exp in (14, 15, 16, 17):
        n = 2**exp
        trial = {**record, "n": n}
        times = []
        for _ in range(args.rounds):
            start = time.perf_counter()
            check_pin(trial, "1357")
            times.append(time.perf_counter() - start)
        per = statistics.median(times)
        mark = "*" if (n, SCRYPT_R, SCRYPT_P) == (SCRYPT_N, 8, 1) else " "
        mib = 128 * SCRYPT_R * n // (1024 * 1024)
        print(f"{mark}2**{exp:<4} {mib:>4} {min(times):7.3f} {per:8.3f}   "
              f"{span(per * 1e4):>13}   {span(per * 1e6):>13}   {span(per * 1e8):>13}")


if __name__ == "__main__":
    main()
