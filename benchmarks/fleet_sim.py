"""One vessel of the fleet benchmark, in its own process: a named sim plus what the benchmark measures.

``python benchmarks/fleet_sim.py --name boat2 [--values 20] [--hz 20]`` prints the sim's URL, then serves:

- the vessel (``/boat2/...``: both cameras at their own rates, 10 Hz rgb8 and 12 Hz JPEG);
- ``/boat2/bench/v0`` .. ``v19`` (std_msgs/Float64) at ``--hz``, each value the publish time
  (``time.perf_counter()``, CLOCK_MONOTONIC: comparable between processes on Linux);
- ``/boat2/bench/stats`` (std_srvs/Trigger): ``message`` is JSON: messages published per topic so far,
  the arrival time of every ``/boat2/cmd_vel`` message (perf_counter, as the sim received it), the
  sim loop's lateness (how late a 5 ms sleep wakes up, ms; what delays the arrival of a command), the
  process's CPU seconds, and per camera topic the (header stamp, wall clock) of each frame as it was
  published (drawn and encoded, handed to the subscribers).
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import signal
import time

from background_load import die_with_parent

from rcon_core.gcpolicy import keep_settled
from rcon_core.sim import SimServer


async def serve(name: str, values: int, hz: float) -> None:
    server = SimServer(port=0, name=name)
    await server.start()
    settler = asyncio.get_running_loop().create_task(keep_settled())  # as `rcon sim` does
    node = server.topic("/bench")
    topics = [server.topic(f"/bench/v{i}") for i in range(values)]
    for t in topics:
        server.advertise_internal(t, "std_msgs/Float64", node)
    arrivals: list[float] = []
    server.subscribe_internal(server.topic("/cmd_vel"), "geometry_msgs/Twist", node,
                              lambda _msg: arrivals.append(time.perf_counter()))
    sent = {"values": 0}
    # camera frames as they are published (after drawing and encoding): (header stamp, wall clock), so the
    # benchmark can tell publish-to-painted apart from capture-to-painted
    camera_published: dict[str, list[tuple[float, float]]] = {}

    def camera_publish(topic: str, msg: dict) -> None:
        stamp = msg["header"]["stamp"]
        secs = stamp.get("secs", stamp.get("sec", 0)) + stamp.get("nsecs", stamp.get("nanosec", 0)) * 1e-9
        rows = camera_published.setdefault(topic, [])
        rows.append((secs, time.time()))
        del rows[:-600]

    for cam, type_name in (("/camera/front/image_raw", "sensor_msgs/Image"),
                           ("/camera/rear/image_raw/compressed", "sensor_msgs/CompressedImage")):
        server.subscribe_internal(server.topic(cam), type_name, node,
                                  lambda msg, cam=cam: camera_publish(cam, msg))
    lags: list[tuple[float, float]] = []  # (perf_counter, ms late) of the loop's 5 ms sleeps

    async def lag_probe() -> None:
        while True:
            t = time.perf_counter()
            await asyncio.sleep(0.005)
            now = time.perf_counter()
            lags.append((now, (now - t - 0.005) * 1000))
            del lags[:-20_000]

    probe = asyncio.get_running_loop().create_task(lag_probe())

    def stats(_req: dict) -> dict:
        body = {"published": {**server.robot_published(), **sent}, "cmd_vel_arrivals": list(arrivals),
                "loop_lag": list(lags), "cpu_s": time.process_time(), "camera_published": camera_published}
        return {"success": True, "message": json.dumps(body)}

    server.add_service(server.topic("/bench/stats"), "std_srvs/Trigger", node, stats)
    print(f"fleet_sim {name} on {server.url}", flush=True)
    stop = asyncio.Event()
    loop = asyncio.get_running_loop()
    for sig in (signal.SIGINT, signal.SIGTERM):
        with contextlib.suppress(NotImplementedError, RuntimeError):
            loop.add_signal_handler(sig, stop.set)
    period = 1.0 / hz
    nxt = time.perf_counter()
    try:
        while not stop.is_set():
            for t in topics:
                if server.has_subscribers(t):
                    server.publish(t, {"data": time.perf_counter()}, node)
                    sent["values"] += 1
            nxt += period
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(stop.wait(), max(0.0, nxt - time.perf_counter()))
    finally:
        probe.cancel()
        settler.cancel()
        await server.stop()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--name", required=True)
    parser.add_argument("--values", type=int, default=20)
    parser.add_argument("--hz", type=float, default=20.0)
    parser.add_argument("--no-latency-policy", action="store_true", help="as before favour_latency (priority.py)")
    parser.add_argument("--no-malloc-policy", action="store_true", help="glibc's allocator as it is (mallocpolicy.py)")
    args = parser.parse_args()
    from rcon_core import priority

    if args.no_latency_policy:
        priority.raise_this_thread = lambda: False
    else:
        priority.favour_latency()  # as `rcon sim` does: its loop thread raised, a short GIL switch interval
    if not args.no_malloc_policy:
        from rcon_core.mallocpolicy import keep_big_blocks

        keep_big_blocks()  # as `rcon sim` does (rcon_core/mallocpolicy.py)
    die_with_parent()  # a benchmark killed outright leaves no vessel running
    asyncio.run(serve(args.name, args.values, args.hz))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
