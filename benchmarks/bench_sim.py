"""The embedded sim under load: one client subscribed to every topic; the sim's CPU use and actual rates.

Usage: ``python benchmarks/bench_sim.py [--seconds 10] [--rate-scale 1] [--compression none] [--out F.json]``

The sim runs in a child process (``--serve``, internal) that reports its own process time over the
measured window, so the client's decoding work is not counted. CPU is process time / wall time
(1.0 = one core busy).
"""

from __future__ import annotations

import argparse
import asyncio
import json
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import websockets

EXPECTED_HZ = {
    "/odom": 20.0, "/gps/fix": 5.0, "/imu/data": 100.0, "/imu/mag": 25.0, "/camera/front/image_raw": 10.0,
    "/camera/rear/image_raw/compressed": 12.0, "/scan": 10.0, "/battery": 1.0, "/depth": 5.0,
}


def serve(rate_scale: float) -> int:
    """Child: run the sim; on 'start' note the clocks, on 'stop' print process/wall time and exit."""
    from rcon_core.sim import SimServer

    async def main() -> None:
        server = SimServer(port=0, rate_scale=rate_scale)
        await server.start()
        print(server.url, flush=True)
        loop = asyncio.get_running_loop()
        reader = asyncio.StreamReader()
        await loop.connect_read_pipe(lambda: asyncio.StreamReaderProtocol(reader), sys.stdin)
        marks: dict[str, tuple[float, float]] = {}
        while line := (await reader.readline()).decode().strip():
            marks[line] = (time.process_time(), time.monotonic())
            if line == "stop":
                break
        cpu = marks["stop"][0] - marks["start"][0]
        wall = marks["stop"][1] - marks["start"][1]
        renders = {"front": server.robot_node.front.renders, "rear": server.robot_node.rear.renders}
        print(json.dumps({"cpu_s": cpu, "wall_s": wall, "renders": renders}), flush=True)
        await server.stop()

    asyncio.run(main())
    return 0


async def measure(url: str, seconds: float, compression: str, child: subprocess.Popen[str]) -> dict[str, Any]:
    counts: dict[str, int] = {}
    nbytes = 0
    async with websockets.connect(url, max_size=None, max_queue=None) as ws:
        await ws.send(json.dumps({"op": "call_service", "id": "t", "service": "/rosapi/topics", "args": {}}))
        while True:
            reply = json.loads(await ws.recv())
            if reply.get("id") == "t":
                break
        topics = reply["values"]["topics"]
        for topic in topics:
            await ws.send(json.dumps({"op": "subscribe", "topic": topic, "compression": compression}))
        warm_end = time.monotonic() + 1.0
        while time.monotonic() < warm_end:  # let latched frames and the first renders pass
            try:
                await asyncio.wait_for(ws.recv(), 0.2)
            except TimeoutError:
                pass
        assert child.stdin is not None
        child.stdin.write("start\n")
        child.stdin.flush()
        start = time.monotonic()
        end = start + seconds
        while (left := end - time.monotonic()) > 0:
            try:
                raw = await asyncio.wait_for(ws.recv(), left)
            except TimeoutError:
                break
            nbytes += len(raw)
            if isinstance(raw, bytes):
                import cbor2

                topic = cbor2.loads(raw).get("topic")
            else:
                head = raw[:200]
                i = head.find('"topic":"')
                topic = head[i + 9:head.index('"', i + 9)] if i >= 0 else None
            if topic:
                counts[topic] = counts.get(topic, 0) + 1
        child.stdin.write("stop\n")
        child.stdin.flush()
        wall = time.monotonic() - start
    return {"counts": counts, "wall_s": wall, "bytes": nbytes, "topics": topics}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--rate-scale", type=float, default=1.0)
    parser.add_argument("--compression", default="none", choices=["none", "cbor", "cbor-raw", "png"])
    parser.add_argument("--out", type=Path, help="write the figures as JSON here")
    parser.add_argument("--serve", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.serve:
        return serve(args.rate_scale)
    child = subprocess.Popen([sys.executable, __file__, "--serve", "--rate-scale", str(args.rate_scale)],
                             stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    try:
        assert child.stdout is not None
        url = child.stdout.readline().strip()
        result = asyncio.run(measure(url, args.seconds, args.compression, child))
        server = json.loads(child.stdout.readline())
    finally:
        if child.poll() is None:
            child.terminate()
        child.wait(timeout=10)
    wall = result["wall_s"]
    rates = {}
    print(f"sim CPU: {server['cpu_s']:.2f} s process time over {server['wall_s']:.2f} s wall = "
          f"{server['cpu_s'] / server['wall_s'] * 100:.1f}% of one core  (compression {args.compression}, "
          f"rate_scale {args.rate_scale})")
    print(f"received {result['bytes'] / wall / 1e6:.1f} MB/s; camera scene renders {server['renders']}")
    print(f"{'topic':40s} {'expected Hz':>11s} {'actual Hz':>10s}")
    for topic in result["topics"]:
        hz = result["counts"].get(topic, 0) / wall
        expected = EXPECTED_HZ.get(topic)
        rates[topic] = {"actual_hz": round(hz, 2),
                        "expected_hz": expected * args.rate_scale if expected else None}
        exp = f"{expected * args.rate_scale:.1f}" if expected else "-"
        print(f"{topic:40s} {exp:>11s} {hz:10.2f}")
    figures = {"cpu_fraction": server["cpu_s"] / server["wall_s"], "cpu_s": server["cpu_s"],
               "wall_s": server["wall_s"], "mb_per_s": result["bytes"] / wall / 1e6, "rates": rates,
               "compression": args.compression, "rate_scale": args.rate_scale, "renders": server["renders"]}
    if args.out:
        args.out.write_text(json.dumps(figures, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
