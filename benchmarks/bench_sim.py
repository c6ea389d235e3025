"""The embedded sim under load: one client subscribed to every topic; the sim's CPU use and actual rates.

Usage: ``python benchmarks/bench_sim.py [--seconds 10] [--rate-scale 1] [--compression none] [--topics T,T]
[--teleop HZ] [--out F.json]``

The sim runs in a child process (``--serve``, internal) that reports its own process time over the
measured window, so the client's decoding work is not counted. CPU is process time / wall time
(1.0 = one core busy). ``--topics`` subscribes only to those topics (e.g. the two cameras), ``--teleop HZ``
holds the teleop pad (a ``/cmd_vel`` of 1 m/s and 0.3 rad/s at HZ) so the vessel moves and every camera frame
is a new scene. The child also reports the CPU per camera frame (process time / camera frames published)
and its event loop's lag: a probe sleeping 5 ms at a time, how late each wake-up was.
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


LAG_PERIOD = 0.005
CAMERAS = ("/camera/front/image_raw", "/camera/rear/image_raw/compressed")


def _percentile(values: list[float], q: float) -> float:
    if not values:
        return float("nan")
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(q / 100 * len(ordered)))]


async def _lag_probe(lags: list[float], recording: list[bool]) -> None:
    """Sleep LAG_PERIOD at a time; note how late each wake-up was (while ``recording[0]``)."""
    while True:
        asked = time.monotonic() + LAG_PERIOD
        await asyncio.sleep(LAG_PERIOD)
        if recording[0]:
            lags.append(time.monotonic() - asked)


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
        marks: dict[str, tuple[float, float, float]] = {}
        node = server.robot_node
        lags: list[float] = []
        recording = [False]
        probe = asyncio.create_task(_lag_probe(lags, recording))
        frames: dict[str, int] = {}
        while line := (await reader.readline()).decode().strip():
            marks[line] = (time.process_time(), time.monotonic(), time.thread_time())
            recording[0] = line == "start"
            if line == "start":
                frames = {t: node.published_counts.get(t, 0) for t in CAMERAS}
            if line == "stop":
                break
        probe.cancel()
        cpu = marks["stop"][0] - marks["start"][0]
        wall = marks["stop"][1] - marks["start"][1]
        loop_cpu = marks["stop"][2] - marks["start"][2]  # the event loop's own thread
        frames = {t: node.published_counts.get(t, 0) - frames.get(t, 0) for t in CAMERAS}
        renders = {"front": node.front.renders, "rear": node.rear.renders}
        lag_ms = {"p50": _percentile(lags, 50) * 1e3, "p99": _percentile(lags, 99) * 1e3,
                  "max": max(lags, default=float("nan")) * 1e3, "samples": len(lags)}
        print(json.dumps({"cpu_s": cpu, "loop_cpu_s": loop_cpu, "wall_s": wall, "renders": renders, "camera_frames": frames,
                          "loop_lag_ms": lag_ms}), flush=True)
        await server.stop()

    asyncio.run(main())
    return 0


async def _teleop(ws: Any, hz: float) -> None:
    """Hold the pad: a /cmd_vel at ``hz`` so the vessel moves (and turns) the whole time."""
    twist = {"linear": {"x": 1.0, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.3}}
    frame = json.dumps({"op": "publish", "topic": "/cmd_vel", "msg": twist})
    while True:
        await ws.send(frame)
        await asyncio.sleep(1.0 / hz)


async def measure(url: str, seconds: float, compression: str, child: subprocess.Popen[str],
                  only: list[str] | None = None, teleop_hz: float = 0.0) -> dict[str, Any]:
    counts: dict[str, int] = {}
    nbytes = 0
    async with websockets.connect(url, max_size=None, max_queue=None) as ws:
        await ws.send(json.dumps({"op": "call_service", "id": "t", "service": "/rosapi/topics", "args": {}}))
        while True:
            reply = json.loads(await ws.recv())
            if reply.get("id") == "t":
                break
        topics = reply["values"]["topics"]
        if only:
            missing = sorted(set(only) - set(topics))
            if missing:
                raise SystemExit(f"no such topic on the sim: {', '.join(missing)}")
            topics = only
        for topic in topics:
            await ws.send(json.dumps({"op": "subscribe", "topic": topic, "compression": compression}))
        pad = asyncio.create_task(_teleop(ws, teleop_hz)) if teleop_hz > 0 else None
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
        if pad is not None:
            pad.cancel()
    return {"counts": counts, "wall_s": wall, "bytes": nbytes, "topics": topics}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--rate-scale", type=float, default=1.0)
    parser.add_argument("--compression", default="none", choices=["none", "cbor", "cbor-raw", "png"])
    parser.add_argument("--topics", help="comma-separated topics to subscribe to (default: every topic); "
                        "'cameras' for the two camera topics")
    parser.add_argument("--teleop", type=float, default=0.0, metavar="HZ",
                        help="hold the teleop pad: /cmd_vel at HZ so the vessel moves (default: off)")
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
        only = None
        if args.topics:
            only = list(CAMERAS) if args.topics == "cameras" else [t for t in args.topics.split(",") if t]
        result = asyncio.run(measure(url, args.seconds, args.compression, child, only, args.teleop))
        server = json.loads(child.stdout.readline())
    finally:
        if child.poll() is None:
            child.terminate()
        child.wait(timeout=10)
    wall = result["wall_s"]
    rates = {}
    print(f"sim CPU: {server['cpu_s']:.2f} s process time over {server['wall_s']:.2f} s wall = "
          f"{server['cpu_s'] / server['wall_s'] * 100:.1f}% of one core  (compression {args.compression}, "
          f"rate_scale {args.rate_scale}); the event loop's thread {server['loop_cpu_s']:.2f} s, "
          f"other threads (camera drawing) {server['cpu_s'] - server['loop_cpu_s']:.2f} s")
    print(f"received {result['bytes'] / wall / 1e6:.1f} MB/s; camera scene renders {server['renders']}")
    camera_frames = sum(server["camera_frames"].values())
    per_frame_ms = server["cpu_s"] / camera_frames * 1e3 if camera_frames else float("nan")
    lag = server["loop_lag_ms"]
    print(f"camera frames published {server['camera_frames']}: {per_frame_ms:.1f} ms sim CPU per camera frame "
          f"(all of the sim's process time / camera frames)")
    print(f"sim loop lag ({LAG_PERIOD * 1e3:.0f} ms probe, {lag['samples']} wake-ups): p50 {lag['p50']:.2f} ms, "
          f"p99 {lag['p99']:.2f} ms, max {lag['max']:.2f} ms")
    print(f"{'topic':40s} {'expected Hz':>11s} {'actual Hz':>10s}")
    for topic in result["topics"]:
        hz = result["counts"].get(topic, 0) / wall
        expected = EXPECTED_HZ.get(topic)
        rates[topic] = {"actual_hz": round(hz, 2),
                        "expected_hz": expected * args.rate_scale if expected else None}
        exp = f"{expected * args.rate_scale:.1f}" if expected else "-"
        print(f"{topic:40s} {exp:>11s} {hz:10.2f}")
    figures = {"cpu_fraction": server["cpu_s"] / server["wall_s"], "cpu_s": server["cpu_s"],
               "loop_cpu_s": server["loop_cpu_s"],
               "wall_s": server["wall_s"], "mb_per_s": result["bytes"] / wall / 1e6, "rates": rates,
               "compression": args.compression, "rate_scale": args.rate_scale, "renders": server["renders"],
               "camera_frames": server["camera_frames"], "cpu_ms_per_camera_frame": per_frame_ms,
               "loop_lag_ms": lag, "teleop_hz": args.teleop, "topics": result["topics"]}
    if args.out:
        args.out.write_text(json.dumps(figures, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
