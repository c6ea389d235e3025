"""Bridge benchmark: RCON's client vs roslibpy vs a bare websockets+orjson loop, against ONE loopback server.

Usage: ``python benchmarks/bench_bridge.py [--out PATH] [--quick]``.

The flood server lives in this module (websockets, in a thread of the parent process).  Each client runs in
its own subprocess so peak RSS is per client.  Figures:

* small-message ingest: std_msgs/Float64 publish frames sent back to back, messages/s;
* round trip: publish on /bench/ping, the server echoes it on /bench/pong; p50/p99 in ms;
* 640x480 rgb8 sensor_msgs/Image ingest, frames/s, as JSON (base64 data) and as CBOR (byte string);
  roslibpy has no CBOR decoding, so it only runs the JSON case;
* peak RSS of the client process (resource.getrusage).
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import resource
import statistics
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

import cbor2
import orjson

HERE = Path(__file__).resolve().parent
WIDTH, HEIGHT = 640, 480


def sizes(quick: bool) -> dict[str, int]:
    return {"small": 20000 if quick else 60000, "rtt": 200 if quick else 1000,
            "image_json": 30 if quick else 120, "image_cbor": 30 if quick else 120}


# =============================================================================================== server


def _image_msg() -> dict[str, Any]:
    data = bytes((i * 7) & 0xFF for i in range(256)) * (WIDTH * HEIGHT * 3 // 256)
    return {"header": {"seq": 1, "stamp": {"secs": 1, "nsecs": 2}, "frame_id": "cam"}, "height": HEIGHT,
            "width": WIDTH, "encoding": "rgb8", "is_bigendian": 0, "step": WIDTH * 3, "data": data}


class FloodServer:
    """Sends pre-encoded frames as fast as websockets allows; echoes /bench/ping to /bench/pong."""

    def __init__(self, n: dict[str, int]) -> None:
        import base64

        self.n = n
        self.small = [orjson.dumps({"op": "publish", "topic": "/bench/f64", "msg": {"data": i * 0.5}}).decode()
                      for i in range(1000)]
        img = _image_msg()
        self.image_cbor = cbor2.dumps({"op": "publish", "topic": "/bench/image", "msg": img})
        img_json = dict(img, data=base64.b64encode(img["data"]).decode())
        self.image_json = orjson.dumps({"op": "publish", "topic": "/bench/image", "msg": img_json}).decode()
        self.loop = asyncio.new_event_loop()
        self.port = 0
        self._thread = threading.Thread(target=self.loop.run_forever, daemon=True)

    def start(self) -> FloodServer:
        from websockets.asyncio.server import serve

        self._thread.start()

        async def go() -> Any:
            return await serve(self._handle, "127.0.0.1", 0, compression=None, max_size=None)

        self._server = asyncio.run_coroutine_threadsafe(go(), self.loop).result(10)
        self.port = self._server.sockets[0].getsockname()[1]
        return self

    def stop(self) -> None:
        async def close() -> None:
            self._server.close()
            await self._server.wait_closed()

        asyncio.run_coroutine_threadsafe(close(), self.loop).result(10)
        self.loop.call_soon_threadsafe(self.loop.stop)
        self._thread.join(5)

    async def _handle(self, ws: Any) -> None:
        from websockets.exceptions import ConnectionClosed

        try:
            await self._serve(ws)
        except ConnectionClosed:  # roslibpy drops the socket without a close handshake
            pass

    async def _serve(self, ws: Any) -> None:
        pong_subscribed = False
        async for raw in ws:
            frame = orjson.loads(raw)
            op = frame.get("op")
            if op == "subscribe":
                topic = frame["topic"]
                if topic == "/bench/f64":
                    small = self.small
                    for i in range(self.n["small"]):
                        await ws.send(small[i % 1000])
                elif topic == "/bench/image":
                    cbor = frame.get("compression") == "cbor"
                    f = self.image_cbor if cbor else self.image_json
                    for _ in range(self.n["image_cbor" if cbor else "image_json"]):
                        await ws.send(f)
                elif topic == "/bench/pong":
                    pong_subscribed = True
            elif op == "publish" and frame.get("topic") == "/bench/ping" and pong_subscribed:
                await ws.send(orjson.dumps({"op": "publish", "topic": "/bench/pong", "msg": frame["msg"]}).decode())
            elif op == "call_service":  # a rosapi stand-in: message_details from the standard registry
                values: Any = {}
                if frame.get("service") == "/rosapi/message_details":
                    values = {"typedefs": self._typedefs(frame["args"]["type"])}
                await ws.send(orjson.dumps({"op": "service_response", "id": frame.get("id"),
                                            "service": frame.get("service"), "values": values,
                                            "result": True}).decode())

    def _typedefs(self, name: str) -> list[dict[str, Any]]:
        sys.path.insert(0, str(HERE.parent))
        from rcon_core.msgs import TypeRegistry

        return TypeRegistry.standard().typedefs(name)


# =============================================================================================== clients


def _rss_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _pct(values: list[float], p: float) -> float:
    values = sorted(values)
    return values[min(len(values) - 1, int(round(p / 100 * (len(values) - 1))))]


async def client_rcon(url: str, n: dict[str, int]) -> dict[str, Any]:
    sys.path.insert(0, str(HERE.parent))
    from rcon_core.bridge import BridgeClient

    out: dict[str, Any] = {}
    c = BridgeClient(url, latency_interval=3600)
    await c.connect(timeout=10)
    loop = asyncio.get_running_loop()

    async def ingest(topic: str, count: int, compression: str = "none") -> float:
        done = loop.create_future()
        state = {"k": 0, "t0": 0.0}

        def cb(msg: dict[str, Any]) -> None:
            k = state["k"] = state["k"] + 1
            if k == 1:
                state["t0"] = time.perf_counter()
            if k == count:
                done.set_result(time.perf_counter())

        node = c.node(f"bench-{topic}-{compression}")
        node.subscribe(topic, cb, type="std_msgs/Float64" if "f64" in topic else "sensor_msgs/Image",
                       compression=compression)
        t1 = await asyncio.wait_for(done, 120)
        node.close()
        return (count - 1) / (t1 - state["t0"])

    out["small_msgs_per_s"] = await ingest("/bench/f64", n["small"])
    # round trip
    node = c.node("rtt")
    pub = node.advertise("/bench/ping", "std_msgs/Float64")
    waiters: dict[float, asyncio.Future[float]] = {}

    def on_pong(msg: dict[str, Any]) -> None:
        f = waiters.pop(msg["data"], None)
        if f is not None:
            f.set_result(time.perf_counter())

    node.subscribe("/bench/pong", on_pong, type="std_msgs/Float64")
    await asyncio.sleep(0.3)
    rtts = []
    for i in range(n["rtt"]):
        f = waiters[float(i)] = loop.create_future()
        t0 = time.perf_counter()
        pub.publish({"data": float(i)})
        rtts.append((await asyncio.wait_for(f, 10)) - t0)
    out["rtt_p50_ms"] = statistics.median(rtts) * 1000
    out["rtt_p99_ms"] = _pct(rtts, 99) * 1000
    node.close()
    out["image_json_fps"] = await ingest("/bench/image", n["image_json"])
    out["image_cbor_fps"] = await ingest("/bench/image", n["image_cbor"], "cbor")
    await c.close()
    return out


async def client_bare(url: str, n: dict[str, int]) -> dict[str, Any]:
    """The floor: websockets recv + one orjson.loads (or cbor2.loads) per frame, a topic check, nothing else."""
    from websockets.asyncio.client import connect

    out: dict[str, Any] = {}
    async with connect(url, compression=None, max_size=None, ping_interval=None) as ws:

        async def ingest(topic: str, count: int, compression: str = "none") -> float:
            await ws.send(orjson.dumps({"op": "subscribe", "topic": topic, "compression": compression}).decode())
            k = 0
            t0 = 0.0
            while k < count:
                raw = await ws.recv()
                m = orjson.loads(raw) if isinstance(raw, str) else cbor2.loads(raw)
                if m["op"] == "publish" and m["topic"] == topic:
                    k += 1
                    if k == 1:
                        t0 = time.perf_counter()
            return (count - 1) / (time.perf_counter() - t0)

        out["small_msgs_per_s"] = await ingest("/bench/f64", n["small"])
        await ws.send(orjson.dumps({"op": "advertise", "topic": "/bench/ping", "type": "std_msgs/Float64"}).decode())
        await ws.send(orjson.dumps({"op": "subscribe", "topic": "/bench/pong"}).decode())
        await asyncio.sleep(0.3)
        rtts = []
        for i in range(n["rtt"]):
            t0 = time.perf_counter()
            await ws.send(orjson.dumps({"op": "publish", "topic": "/bench/ping", "msg": {"data": float(i)}}).decode())
            while orjson.loads(await ws.recv())["msg"]["data"] != float(i):
                pass
            rtts.append(time.perf_counter() - t0)
        out["rtt_p50_ms"] = statistics.median(rtts) * 1000
        out["rtt_p99_ms"] = _pct(rtts, 99) * 1000
        out["image_json_fps"] = await ingest("/bench/image", n["image_json"])
        out["image_cbor_fps"] = await ingest("/bench/image", n["image_cbor"], "cbor")
    return out


def client_roslibpy(url: str, n: dict[str, int]) -> dict[str, Any]:
    import logging

    import roslibpy

    logging.getLogger("roslibpy").setLevel(logging.ERROR)
    port = int(url.rsplit(":", 1)[1])
    ros = roslibpy.Ros("127.0.0.1", port)
    ros.run(timeout=10)
    out: dict[str, Any] = {}

    def ingest(topic: str, typ: str, count: int) -> float:
        done = threading.Event()
        state = {"k": 0, "t0": 0.0, "t1": 0.0}

        def cb(msg: dict[str, Any]) -> None:
            state["k"] += 1
            if state["k"] == 1:
                state["t0"] = time.perf_counter()
            if state["k"] == count:
                state["t1"] = time.perf_counter()
                done.set()

        t = roslibpy.Topic(ros, topic, typ)
        t.subscribe(cb)
        if not done.wait(120):
            raise RuntimeError(f"roslibpy got {state['k']} of {count} on {topic}")
        t.unsubscribe()
        return (count - 1) / (state["t1"] - state["t0"])

    out["small_msgs_per_s"] = ingest("/bench/f64", "std_msgs/Float64", n["small"])
    ping = roslibpy.Topic(ros, "/bench/ping", "std_msgs/Float64")
    ping.advertise()
    got: dict[str, Any] = {"event": threading.Event(), "want": -1.0}

    def on_pong(msg: dict[str, Any]) -> None:
        if msg["data"] == got["want"]:
            got["t"] = time.perf_counter()
            got["event"].set()

    pong = roslibpy.Topic(ros, "/bench/pong", "std_msgs/Float64")
    pong.subscribe(on_pong)
    time.sleep(0.3)
    rtts = []
    for i in range(n["rtt"]):
        got["event"].clear()
        got["want"] = float(i)
        t0 = time.perf_counter()
        ping.publish(roslibpy.Message({"data": float(i)}))
        if not got["event"].wait(10):
            raise RuntimeError("roslibpy round trip timed out")
        rtts.append(got["t"] - t0)
    out["rtt_p50_ms"] = statistics.median(rtts) * 1000
    out["rtt_p99_ms"] = _pct(rtts, 99) * 1000
    out["image_json_fps"] = ingest("/bench/image", "sensor_msgs/Image", n["image_json"])
    ros.terminate() if hasattr(ros, "terminate") else ros.close()
    return out


def run_client(kind: str, url: str, quick: bool) -> dict[str, Any]:
    n = sizes(quick)
    if kind == "rcon":
        result = asyncio.run(client_rcon(url, n))
    elif kind == "bare":
        result = asyncio.run(client_bare(url, n))
    else:
        result = client_roslibpy(url, n)
    result["peak_rss_mb"] = _rss_mb()
    return result


# =============================================================================================== driver


def _ratio(a: float | None, b: float | None) -> str:
    return f"{a / b:.2f}x" if a and b else "-"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, help="write the figures as JSON here")
    parser.add_argument("--quick", action="store_true", help="smaller counts (a smoke run)")
    parser.add_argument("--clients", nargs="*", default=["bare", "rcon", "roslibpy"])
    parser.add_argument("--rounds", type=int, default=3, help="interleaved rounds; the best figure is kept")
    parser.add_argument("--client", help=argparse.SUPPRESS)  # internal: run one client in this process
    parser.add_argument("--url", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.client:
        print(json.dumps(run_client(args.client, args.url, args.quick)))
        return 0
    server = FloodServer(sizes(args.quick)).start()
    url = f"ws://127.0.0.1:{server.port}"
    results: dict[str, Any] = {}
    runs: dict[str, list[dict[str, Any]]] = {k: [] for k in args.clients}
    started = time.perf_counter()
    try:
        for _round in range(1 if args.quick else args.rounds):  # interleaved rounds: fair under shared-CPU noise
            for kind in args.clients:
                cmd = [sys.executable, str(Path(__file__).resolve()), "--client", kind, "--url", url]
                if args.quick:
                    cmd.append("--quick")
                env = dict(os.environ, PYTHONWARNINGS="ignore")
                proc = subprocess.run(cmd, capture_output=True, text=True, timeout=300, env=env)
                if proc.returncode != 0:
                    print(f"{kind}: FAILED\n{proc.stderr[-2000:]}", file=sys.stderr)
                    results[kind] = {"error": proc.stderr[-500:]}
                    continue
                runs[kind].append(json.loads(proc.stdout.strip().splitlines()[-1]))
    finally:
        server.stop()
    for kind, rs in runs.items():  # best of the rounds per figure (lowest for times and RSS)
        if rs and kind not in results:
            results[kind] = {key: (min if key.startswith(("rtt", "peak")) else max)(r[key] for r in rs)
                             for key in rs[0]}
    rows = [("small ingest (msg/s)", "small_msgs_per_s", "{:,.0f}"), ("round trip p50 (ms)", "rtt_p50_ms", "{:.3f}"),
            ("round trip p99 (ms)", "rtt_p99_ms", "{:.3f}"), ("image JSON (frames/s)", "image_json_fps", "{:.1f}"),
            ("image CBOR (frames/s)", "image_cbor_fps", "{:.1f}"), ("peak RSS (MB)", "peak_rss_mb", "{:.0f}")]
    kinds = [k for k in args.clients if "error" not in results.get(k, {"error": 1})]
    print(f"{'':24}" + "".join(f"{k:>12}" for k in kinds) + f"{'rcon/bare':>12}{'rcon/roslibpy':>15}")
    for label, key, fmt in rows:
        cells = "".join(f"{(fmt.format(results[k][key]) if key in results[k] else '-'):>12}" for k in kinds)
        rc, bare, rl = (results.get(k, {}).get(key) for k in ("rcon", "bare", "roslibpy"))
        print(f"{label:24}{cells}{_ratio(rc, bare):>12}{_ratio(rc, rl):>15}")
    rc, rl = results.get("rcon", {}), results.get("roslibpy", {})
    summary = {
        "ingest_vs_bare": (rc.get("small_msgs_per_s") or 0) / (results.get("bare", {}).get("small_msgs_per_s") or 1),
        "ingest_vs_roslibpy": (rc.get("small_msgs_per_s") or 0) / (rl.get("small_msgs_per_s") or 1),
        "rtt_p99_vs_roslibpy": (rc.get("rtt_p99_ms") or 0) / (rl.get("rtt_p99_ms") or 1),
        "image_json_vs_roslibpy": (rc.get("image_json_fps") or 0) / (rl.get("image_json_fps") or 1),
        "image_cbor_vs_roslibpy_json": (rc.get("image_cbor_fps") or 0) / (rl.get("image_json_fps") or 1),
    }
    print("summary: " + ", ".join(f"{k}={v:.2f}" for k, v in summary.items()))
    print(f"total {time.perf_counter() - started:.1f} s")
    if args.out:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps({"clients": results, "summary": summary, "sizes": sizes(args.quick),
                                        "runs": runs}, indent=2))
    return 0 if all("error" not in results.get(k, {}) for k in args.clients) else 1


if __name__ == "__main__":
    raise SystemExit(main())
