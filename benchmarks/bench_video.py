"""Benchmark of video in the Image widget: H.264 from a robot to the screen, bytes per frame against raw and
JPEG, and how long a viewer joining mid-stream waits.

1. ``stream``: 1280x720 and 1920x1080 H.264 at 30 fps (libx264 ultrafast/zerolatency, no B-frames, a keyframe
   every second) published as ``foxglove_msgs/CompressedVideo`` by a SimServer in a CHILD process (the frames
   are the sim's camera renderer turning, encoded before the clock starts, so the publisher costs that
   process little), shown by the real Image widget (model + view, offscreen Qt) in this process, driven like
   the app drives it (a 60 Hz tick that refreshes the view when ``state.seq`` moved). Figures: frames
   published and painted per second; the worker's decode time per packet and convert time per shown
   picture (wall ms, the decode thread: ``decode_ms``, ``convert_ms``, and ``decode_convert_ms`` for the
   packets whose picture was shown; convert is the whole making of the frame: YUV to RGB at the view's size,
   the RGB32 layout, the Frame); publish-to-painted latency p50/p99 (header stamp -> the view finished
   painting it) and its trend (first second vs last second); the video queue's largest depth and overflows
   (``backlog``: a growing one shows as a latency trend and overflows); this process's CPU per painted
   frame (``app_cpu_ms_per_frame``: bridge loop, decode worker and GUI; the publisher is another process).
   Targets (issue 28): 720p decode + convert p95 < 10 ms, publish-to-painted p99 < 50 ms, no growing
   backlog; 1080p p99 < 66 ms.
2. ``bytes``: 300 frames of the sim's front camera at 640x360 while the vessel turns, as raw rgb8, JPEG q80
   and H.264 at the sim's settings (15 fps, 600 kbit/s, keyframe every 1 s): bytes per frame on the wire
   (the CBOR publish frame the sim sends: payload plus message) and picture quality (PSNR in dB of the
   decoded frame against the raw one, averaged over frames).
3. ``join``: the real sim (``rcon sim`` in a child process) streams its front camera as H.264 while one client
   watches; a second Image widget subscribes at a random moment, again and again: time from subscribing to
   its first picture, against the target of one keyframe interval + 100 ms.

The load average is printed beside each figure: on a shared machine the timing figures are noisy.

Usage: ``QT_QPA_PLATFORM=offscreen python benchmarks/bench_video.py [--seconds 8] [--only stream|bytes|join]
[--sizes 1280x720,1920x1080] [--joins 12] [--out FILE.json]``
"""

from __future__ import annotations

import argparse
import asyncio
import json
import math
import os
import random
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
TOPIC = "/bench/video"


def pct(values: list[float], q: float) -> float:
    if not values:
        return float("nan")
    values = sorted(values)
    return values[min(len(values) - 1, int(q / 100 * len(values)))]


def load() -> str:
    return Path("/proc/loadavg").read_text().split(" ", 3)[0] if Path("/proc/loadavg").exists() else "?"


def camera_frames(width: int, height: int, n: int) -> list[np.ndarray]:
    """``n`` frames of the sim's front camera while the vessel turns and rolls (RGB)."""
    from rcon_core.sim.camera import CameraRenderer
    from rcon_core.sim.vessel import Vessel

    cam = CameraRenderer("front", width=width, height=height)
    v = Vessel()
    out = []
    for i in range(n):
        t = 1_000.0 + i / 15
        v.command(1.5, 0.25, t)  # under way and turning: the scene moves and rolls like the sim's
        list(v.step(1 / 15, t))
        out.append(cam.frame(v, 1_700_000_000 + i / 15))
    return out


# -- the publisher (child process) --------------------------------------------------------------------

def serve(width: int, height: int, fps: float, frames: int) -> None:
    """Child process: encode ``frames`` frames, then publish them in a loop at ``fps`` on TOPIC; prints the
    URL when ready, stops when stdin closes."""
    from rcon_core.sim import SimServer
    from rcon_core.sim.video import H264Encoder, VideoSettings

    enc = H264Encoder(VideoSettings(width=width, height=height, fps=fps, keyframe_interval=1.0,
                                    bitrate=int(width * height * fps * 0.1)))
    packets = []
    for img in camera_frames(width, height, frames):
        out = enc.encode(img)
        assert out is not None
        packets.append(out[0])

    async def run() -> None:
        server = SimServer(robot=False)
        await server.start()
        server.advertise_internal(TOPIC, "foxglove_msgs/CompressedVideo", "/bench_camera")
        print(server.url, flush=True)
        loop = asyncio.get_running_loop()
        stop = asyncio.Event()
        threading.Thread(target=lambda: (sys.stdin.read(), loop.call_soon_threadsafe(stop.set)), daemon=True).start()
        period, due, i = 1.0 / fps, loop.time(), 0
        while not stop.is_set():
            if server.has_subscribers(TOPIC):
                ns = time.time_ns()
                server.publish(TOPIC, {"timestamp": {"secs": ns // 10**9, "nsecs": ns % 10**9},
                                       "frame_id": "bench", "data": packets[i % len(packets)],
                                       "format": "h264"}, "/bench_camera")
                i += 1
            else:
                i = 0  # a new viewer starts at a keyframe
            due += period
            now = loop.time()
            if due < now:
                due = now + period
            try:
                await asyncio.wait_for(stop.wait(), due - now)
            except TimeoutError:
                pass
        await server.stop()

    asyncio.run(run())


class Child:
    """A child process printing its URL on its first line; ended by closing its stdin (or killed)."""

    def __init__(self, args: list[str]) -> None:
        self.proc = subprocess.Popen([sys.executable, *args], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     text=True)
        assert self.proc.stdout is not None
        line = self.proc.stdout.readline()
        while line and "ws://" not in line:
            line = self.proc.stdout.readline()
        if "ws://" not in line:
            self.close()
            raise RuntimeError(f"the child process printed no URL: {line!r}")
        self.url = "ws://" + line.split("ws://", 1)[1].split()[0]

    def close(self) -> None:
        try:
            if self.proc.stdin:
                self.proc.stdin.close()
            self.proc.terminate()
            self.proc.wait(10)
        except Exception:  # noqa: BLE001 - best effort
            self.proc.kill()


# -- the viewer (this process) ------------------------------------------------------------------------

def watch(url: str, topic: str, type_name: str, seconds: float, warmup: float,
          view_size: tuple[int, int]) -> dict[str, Any]:
    from qtpy import QtCore, QtWidgets
    from rcon_widgets_sensors.image import ImageModel, ImageSettings
    from rcon_widgets_sensors.image_view import ImageView
    from rcon_widgets_sensors.video import VideoStream

    from rcon_core.bridge import BridgeClient
    from rcon_core.bridge.threaded import BridgeThread
    from rcon_core.plugins import Binding

    app = QtWidgets.QApplication.instance() or QtWidgets.QApplication(sys.argv[:1])  # noqa: F841 - kept alive
    feed_ms: list[float] = []
    convert_ms: list[float] = []
    shown_feed: list[float] = []
    real_feed = VideoStream.feed

    def timed_feed(self: Any, pkt: Any) -> Any:
        t0 = time.perf_counter()
        out = real_feed(self, pkt)
        feed_ms.append((time.perf_counter() - t0) * 1000)
        return out

    VideoStream.feed = timed_feed  # type: ignore[method-assign]
    bt = BridgeThread().start()
    client = BridgeClient(url, reconnect=False)
    bt.run(client.connect()).result(10)
    model = ImageModel(ImageSettings(), Binding(topic, type_name, "subscribe"), client.node("bench-video"),
                       dispatch=bt.call)
    real_show = model._show_video

    def timed_show(picture: Any, pkt: Any) -> None:
        # the whole conversion: YUV -> RGB at the view's size, the RGB32 layout, the Frame and set_value
        t0 = time.perf_counter()
        real_show(picture, pkt)
        convert_ms.append((time.perf_counter() - t0) * 1000)
        shown_feed.append(feed_ms[-1] if feed_ms else 0.0)

    model._show_video = timed_show  # type: ignore[method-assign]  # read when the first packet comes
    view = ImageView(model)
    view.resize(*view_size)
    view.show()
    painted: list[tuple[float, float]] = []
    view.on_painted = lambda frame, t: painted.append((t, t - (frame.stamp or frame.received)))
    bt.call(model.start).result(5)
    last_seq = [-1]
    depth = [0]

    def tick() -> None:
        st = model.state
        worker = model.video_worker
        if worker is not None:
            depth[0] = max(depth[0], worker.queued)
        if st.seq != last_seq[0]:
            last_seq[0] = st.seq
            view.refresh(st)

    timer = QtCore.QTimer()
    timer.setTimerType(QtCore.Qt.TimerType.PreciseTimer)
    timer.setInterval(16)
    timer.timeout.connect(tick)
    timer.start()
    marks: dict[str, Any] = {}

    def start_measuring() -> None:
        marks.update(t0=time.time(), cpu0=time.process_time(), feeds=len(feed_ms), converts=len(convert_ms),
                     packets=model.meter.total_count, load0=load())
        depth[0] = 0

    loop = QtCore.QEventLoop()
    QtCore.QTimer.singleShot(int(warmup * 1000), start_measuring)
    QtCore.QTimer.singleShot(int((warmup + seconds) * 1000), loop.quit)
    loop.exec()
    end_wall, end_cpu, packets = time.time(), time.process_time(), model.meter.total_count
    timer.stop()
    worker = model.video_worker
    overflows = worker.overflows if worker is not None else 0
    info = model.video.info if model.video is not None else None
    bt.call(model.stop).result(5)
    bt.run(client.close()).result(5)
    bt.stop()
    view.close()
    VideoStream.feed = real_feed  # type: ignore[method-assign]
    t0 = marks["t0"]
    measured = [p for p in painted if p[0] >= t0]
    lat = [p[1] * 1000 for p in measured]
    first = [p[1] * 1000 for p in measured if p[0] < t0 + 1.0]
    last = [p[1] * 1000 for p in measured if measured and p[0] > measured[-1][0] - 1.0]
    feeds = feed_ms[marks["feeds"]:]
    conv = convert_ms[marks["converts"]:]
    both = [f + c for f, c in zip(shown_feed[marks["converts"]:], conv, strict=False)]
    span = max(1e-6, end_wall - t0)
    return {
        "packets_per_s": round((packets - marks["packets"]) / span, 1),
        "painted_fps": round(len(measured) / span, 1),
        "decode_ms_p50": round(pct(feeds, 50), 2), "decode_ms_p95": round(pct(feeds, 95), 2),
        "convert_ms_p50": round(pct(conv, 50), 2), "convert_ms_p95": round(pct(conv, 95), 2),
        "decode_convert_ms_p50": round(pct(both, 50), 2), "decode_convert_ms_p95": round(pct(both, 95), 2),
        "latency_p50_ms": round(pct(lat, 50), 1), "latency_p99_ms": round(pct(lat, 99), 1),
        "latency_first_s_p50_ms": round(pct(first, 50), 1), "latency_last_s_p50_ms": round(pct(last, 50), 1),
        "backlog_max_queued": depth[0], "backlog_overflows": overflows,
        "losses": info.losses if info else None, "decoder_errors": info.errors if info else None,
        "app_cpu_ms_per_frame": round(1000 * (end_cpu - marks["cpu0"]) / max(1, len(measured)), 2),
        "app_cpu_percent": round(100 * (end_cpu - marks["cpu0"]) / span, 1),
        "view": f"{view_size[0]}x{view_size[1]}",
        "load_start": marks["load0"], "load_end": load(),
    }


def bench_stream(size: str, seconds: float, view_size: tuple[int, int]) -> dict[str, Any]:
    w, h = (int(v) for v in size.split("x"))
    child = Child([str(Path(__file__).resolve()), "--serve", size])
    try:
        out = watch(child.url, TOPIC, "foxglove_msgs/CompressedVideo", seconds, 1.5, view_size)
    finally:
        child.close()
    out["stream"] = f"h264_{size}_30fps"
    target = 50.0 if h <= 720 else 66.0
    out["targets"] = {"decode_convert_ms_p95 < 10": out["decode_convert_ms_p95"] < 10,
                      f"latency_p99_ms < {target:g}": out["latency_p99_ms"] < target,
                      "no growing backlog": out["backlog_overflows"] == 0
                      and out["latency_last_s_p50_ms"] < out["latency_first_s_p50_ms"] + 20}
    return out


# -- bytes per frame and quality ----------------------------------------------------------------------

def psnr(a: np.ndarray, b: np.ndarray) -> float:
    mse = float(np.mean((a.astype(np.float64) - b.astype(np.float64)) ** 2))
    return 99.0 if mse == 0 else 10 * math.log10(255.0 ** 2 / mse)


def bench_bytes(n: int = 300) -> dict[str, Any]:
    import av
    import cv2

    from rcon_core.sim.encoding import cbor_dumps, publish_frame
    from rcon_core.sim.video import H264Encoder, VideoSettings

    settings = VideoSettings()
    frames = camera_frames(settings.width, settings.height, n)
    header = {"header": {"seq": 0, "stamp": {"secs": 1, "nsecs": 2}, "frame_id": "camera_front_optical"}}
    raw_b, jpg_b, h264_b, jpg_q, h264_q = [], [], [], [], []
    for img in frames:
        h, w = img.shape[:2]
        msg = {**header, "height": h, "width": w, "encoding": "rgb8", "is_bigendian": 0, "step": w * 3,
               "data": img.tobytes()}
        raw_b.append(len(cbor_dumps(publish_frame("/camera/front/image_raw", msg))))
        ok, buf = cv2.imencode(".jpg", cv2.cvtColor(img, cv2.COLOR_RGB2BGR), [cv2.IMWRITE_JPEG_QUALITY, 80])
        data = buf.tobytes()
        jpg_b.append(len(cbor_dumps(publish_frame("/camera/front/image_raw/compressed",
                                                  {**header, "format": "jpeg", "data": data}))))
        jpg_q.append(psnr(cv2.cvtColor(cv2.imdecode(buf, cv2.IMREAD_COLOR), cv2.COLOR_BGR2RGB), img))
    enc = H264Encoder(settings)
    dec = av.CodecContext.create("h264", "r")
    keys = 0
    for img in frames:
        out = enc.encode(img)
        assert out is not None
        data, key, _pts = out
        keys += key
        msg = {"timestamp": {"secs": 1, "nsecs": 2}, "frame_id": "camera_front_optical", "data": data,
               "format": "h264"}
        h264_b.append(len(cbor_dumps(publish_frame("/camera/front/image_raw/foxglove", msg))))
        pics = dec.decode(av.Packet(data))
        h264_q.append(psnr(pics[-1].to_ndarray(format="rgb24"), img))
    mean = lambda v: sum(v) / len(v)  # noqa: E731
    return {
        "frames": n, "size": f"{settings.width}x{settings.height}", "fps": settings.fps,
        "h264_settings": f"ultrafast/zerolatency, no B-frames, {settings.bitrate // 1000} kbit/s, "
                         f"keyframe every {settings.keyframe_interval:g} s ({keys} keyframes)",
        "raw_bytes_per_frame": round(mean(raw_b)), "jpeg_q80_bytes_per_frame": round(mean(jpg_b)),
        "h264_bytes_per_frame": round(mean(h264_b)), "h264_keyframe_bytes_max": max(h264_b),
        "jpeg_q80_psnr_db": round(mean(jpg_q), 1), "h264_psnr_db": round(mean(h264_q), 1),
        "raw_bytes_per_s": round(mean(raw_b) * settings.fps), "jpeg_bytes_per_s": round(mean(jpg_b) * settings.fps),
        "h264_bytes_per_s": round(mean(h264_b) * settings.fps),
    }


# -- join mid-stream ------------------------------------------------------------------------------------

def bench_join(joins: int) -> dict[str, Any]:
    from rcon_widgets_sensors.image import ImageModel, ImageSettings

    from rcon_core.bridge import BridgeClient
    from rcon_core.bridge.threaded import BridgeThread
    from rcon_core.plugins import Binding
    from rcon_core.sim.video import FOXGLOVE_TOPIC, VideoSettings

    child = Child(["-m", "rcon_core.cli.main", "sim", "--port", "0"])
    load0 = load()
    waits: list[float] = []
    try:
        bt = BridgeThread().start()
        keeper = BridgeClient(child.url, reconnect=False)
        bt.run(keeper.connect()).result(10)
        seen = [0]
        bt.call(lambda: keeper.node("keeper").subscribe(FOXGLOVE_TOPIC, lambda m: seen.__setitem__(0, seen[0] + 1),
                                                        compression="cbor")).result(5)
        deadline = time.monotonic() + 20
        while seen[0] < 20 and time.monotonic() < deadline:
            time.sleep(0.05)
        client = BridgeClient(child.url, reconnect=False)
        bt.run(client.connect()).result(10)
        rng = random.Random(3)
        for i in range(joins):
            time.sleep(rng.uniform(0.05, 1.2))  # a random phase of the GOP
            model = ImageModel(ImageSettings(), Binding(FOXGLOVE_TOPIC, "foxglove_msgs/CompressedVideo", "subscribe"),
                               client.node(f"join{i}"), dispatch=bt.call)
            t0 = time.monotonic()
            bt.call(model.start).result(5)
            model.wait_frame(0, 10)
            waits.append(time.monotonic() - t0)
            bt.call(model.stop).result(5)
        bt.run(client.close()).result(5)
        bt.run(keeper.close()).result(5)
        bt.stop()
    finally:
        child.close()
    interval = VideoSettings().keyframe_interval
    return {"joins": joins, "keyframe_interval_s": interval, "first_picture_s_p50": round(pct(waits, 50), 3),
            "first_picture_s_max": round(max(waits), 3), "target_s": interval + 0.1,
            "within_target": sum(w <= interval + 0.1 for w in waits), "load_start": load0, "load_end": load()}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=8.0)
    parser.add_argument("--only", choices=("stream", "bytes", "join"))
    parser.add_argument("--sizes", default="1280x720,1920x1080")
    parser.add_argument("--view", default="1280x720", help="the view's size WxH (default 1280x720)")
    parser.add_argument("--joins", type=int, default=12)
    parser.add_argument("--serve", metavar="WxH", help=argparse.SUPPRESS)  # the child publisher
    parser.add_argument("--out", type=Path)
    args = parser.parse_args(argv)
    if args.serve:
        w, h = (int(v) for v in args.serve.split("x"))
        serve(w, h, 30.0, 60)
        return 0
    os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
    vw, vh = (int(v) for v in args.view.split("x"))
    figures: dict[str, Any] = {"benchmark": "video", "cpus": os.cpu_count()}
    ok = True
    if args.only in (None, "bytes"):
        b = figures["bytes"] = bench_bytes()
        print(f"bytes per frame at {b['size']} ({b['frames']} frames of the sim's camera; H.264 {b['h264_settings']}):",
              flush=True)
        for name, key in (("raw rgb8", "raw"), ("JPEG q80", "jpeg_q80"), ("H.264", "h264")):
            per_s = b[f"{key.split('_')[0]}_bytes_per_s"]
            quality = "the reference" if key == "raw" else f"PSNR {b[f'{key}_psnr_db']:5.1f} dB"
            print(f"  {name:>9}: {b[f'{key}_bytes_per_frame']:>8} B/frame  ({per_s / 1000:8.1f} kB/s at "
                  f"{b['fps']:g} fps)  {quality}", flush=True)
    if args.only in (None, "stream"):
        figures["streams"] = []
        for size in args.sizes.split(","):
            r = bench_stream(size, args.seconds, (vw, vh))
            figures["streams"].append(r)
            ok = ok and all(r["targets"].values())
            print(f"{r['stream']}: {r['packets_per_s']}/s in, painted {r['painted_fps']}/s; decode p50 "
                  f"{r['decode_ms_p50']} p95 {r['decode_ms_p95']} ms, convert p50 {r['convert_ms_p50']} p95 "
                  f"{r['convert_ms_p95']} ms, decode+convert p95 {r['decode_convert_ms_p95']} ms; publish-to-painted "
                  f"p50 {r['latency_p50_ms']} p99 {r['latency_p99_ms']} ms (first s {r['latency_first_s_p50_ms']}, "
                  f"last s {r['latency_last_s_p50_ms']}); queue max {r['backlog_max_queued']}, overflows "
                  f"{r['backlog_overflows']}; app CPU {r['app_cpu_ms_per_frame']} ms/frame ({r['app_cpu_percent']}%); "
                  f"view {r['view']}; load {r['load_start']} -> {r['load_end']}", flush=True)
            print(f"  targets: {r['targets']}", flush=True)
    if args.only in (None, "join"):
        j = figures["join"] = bench_join(args.joins)
        print(f"join mid-stream (the sim, keyframe every {j['keyframe_interval_s']:g} s): first picture p50 "
              f"{j['first_picture_s_p50']} s, max {j['first_picture_s_max']} s; {j['within_target']}/{j['joins']} "
              f"within {j['target_s']:g} s; load {j['load_start']} -> {j['load_end']}", flush=True)
    if args.out:
        args.out.write_text(json.dumps(figures, indent=2))
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
