"""Benchmark of the sim's lenient frame reader on hostile 1 MB frames (``rcon_core.sim.frames``).

Each shape is a frame that is not one valid JSON value, so the lenient path runs: ``{`` repeated, ``{"``
repeated, ``{"a":`` repeated, one ``{`` followed by ``{}`` pairs (the most work per byte), escaped
quotes, broken objects, and 1000+ empty objects. Figure: seconds per frame (the event loop is blocked
that long). Target: every shape under 1 s (the old scanner took minutes for some: it retried at every
``{`` and each failure built an error message counting the lines before it).

Usage: ``python benchmarks/bench_sim_frames.py [--size 1000000] [--out FILE.json]``.
"""

from __future__ import annotations

import argparse
import json
import logging
import sys
import time
from pathlib import Path

TARGET_S = 1.0


def shapes(n: int) -> dict[str, str]:
    return {
        "open_braces": "{" * n,
        "brace_quote": '{"' * (n // 2),
        "open_keys": '{"a":' * (n // 5),
        "nested_pairs": "{" + "{}" * (n // 2),
        "escaped_quotes": '{"' + '\\"' * (n // 2),
        "broken_objects": '{"a": tru}' * (n // 10),
        "empty_objects": "{}" * (n // 2),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--size", type=int, default=1_000_000, help="frame size in characters")
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args(argv)
    logging.disable(logging.WARNING)  # the reader logs one line per dropped frame

    from rcon_core.sim.frames import parse_frame

    figures: dict[str, float] = {}
    for name, text in shapes(args.size).items():
        start = time.perf_counter()
        values = parse_frame(text, "bench")
        figures[f"{name}_s"] = round(time.perf_counter() - start, 4)
        print(f"{name:>15}: {len(text) / 1e6:4.2f} MB  {figures[f'{name}_s']:7.4f} s  ({len(values)} values)")
    worst = max(figures.values())
    print(f"target every shape < {TARGET_S} s: {'ok' if worst < TARGET_S else 'MISSED'} (worst {worst} s)")
    if args.out is not None:
        args.out.write_text(json.dumps({"figures": figures, "target_s": TARGET_S}, indent=2) + "\n")
    return 0 if worst < TARGET_S else 1


if __name__ == "__main__":
    sys.exit(main())
