"""Publish hot path: ``Publisher.publish`` through the session to the link, with a transport that accepts every
frame at once (no socket), so only RCON's own Python is timed.

Usage: ``python benchmarks/bench_publish.py [--reps N] [--runs N] [--out PATH]``; to compare with another source tree (a
checkout of before a change), run it again with ``PYTHONPATH=<tree>`` (the first line printed says which
``rcon_core`` was timed).  Two publishers: a command (``geometry_msgs/Twist``, the default ``max_age`` of
0.25 s: the safety envelope, the deadline, the link's freshness check) and a plain one (``max_age=None``:
encode and write).  Prints the median and the best of ``runs`` runs of ``reps`` publishes, in microseconds
per publish.  Figures taken on a shared machine are noisy: give ``cat /proc/loadavg`` beside them.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import statistics
import time
from pathlib import Path
from typing import Any

import rcon_core
from rcon_core.bridge.client import BridgeClient
from rcon_core.bridge.linkbase import Link


class AcceptingLink(Link):
    """A link whose transport takes every frame at once."""

    name = "accepting"

    def __init__(self, on_stale: Any) -> None:
        super().__init__(on_stale)
        self.frames = 0

    def write_now(self, data: bytes) -> bool:
        self.frames += 1
        return True


async def run(reps: int, runs: int) -> dict[str, tuple[float, float]]:
    client = BridgeClient("ws://bench.invalid:9090", stall_timeout=None)
    link = AcceptingLink(client.session.stale_in_queue)
    client.link = link
    shell = getattr(client, "shell", None)
    if shell is not None:
        shell.attached(link)
    else:  # a tree from before the session's shell (issue 24.7)
        client.session.attached(link)
    node = client.node("bench")
    cases = [
        ("command (Twist, max_age 0.25)", node.advertise("/cmd_vel", "geometry_msgs/Twist"),
         {"linear": {"x": 0.5, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.1}}),
        ("plain (String, max_age None)", node.advertise("/state", "std_msgs/String", max_age=None),
         {"data": "hello"}),
    ]
    out = {}
    before = link.frames  # the advertisements
    for name, pub, msg in cases:
        per: list[float] = []
        publish = pub.publish
        for _ in range(runs):
            t0 = time.perf_counter()
            for _ in range(reps):
                publish(msg)
            per.append((time.perf_counter() - t0) / reps * 1e6)
        out[name] = (statistics.median(per), min(per))
    assert link.frames - before == 2 * reps * runs, "every publish reached the link"
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--reps", type=int, default=50_000, help="publishes per run (default 50000)")
    parser.add_argument("--runs", type=int, default=15, help="runs per publisher (default 15)")
    parser.add_argument("--out", type=Path, help="write the figures as JSON here")
    args = parser.parse_args()
    figures = asyncio.run(run(args.reps, args.runs))
    print(f"rcon_core: {rcon_core.__file__}")
    for name, (median, best) in figures.items():
        print(f"{name:32s} median {median:.3f} us  best {best:.3f} us per publish")
    if args.out is not None:
        args.out.write_text(json.dumps({"rcon_core": rcon_core.__file__, "us_per_publish": {
            name: {"median": median, "best": best} for name, (median, best) in figures.items()}}, indent=1))


if __name__ == "__main__":
    main()
