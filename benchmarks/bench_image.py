"""Benchmark of the Image widget: can it keep up with camera streams without growing latency?

Three streams are served by a loopback SimServer (robot off; frames published with the sim's own
encoding, CBOR as the widget asks): 1280x720 JPEG, 640x480 JPEG and 640x480 rgb8 (raw), at 30 fps, one
after the other (``--only NAME`` for one). Each is shown
by the real Image widget (model + view, offscreen Qt) driven like the app drives it (a 60 Hz frame tick
that refreshes the view when ``state.seq`` moved). Figures per stream: frames published and shown per
second, frames dropped (latest-wins), and publish-to-painted latency p50/p99 (header stamp -> the view
finished painting that frame), plus the latency trend (last second vs first second: growing latency
means a queue builds up), the decode worker's CPU per frame (``decode_cpu_ms_*``: thread CPU time of
``ImageModel.decode``, which makes the frame at the view's size and its RGB32 copy), the view's
``paintEvent`` time (``paint_ms_*``, GUI thread) and the size of the pixel array painted.

``--view WxH`` sets the view's size (default 640x400; the fleet console's camera views are about 320x260).

Usage: ``QT_QPA_PLATFORM=offscreen python benchmarks/bench_image.py [--seconds 6] [--fps 30] [--view WxH]
[--out FILE.json]``
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import sys
import time
from pathlib import Path
from typing import Any

import cv2
import numpy as np

STREAMS = {
    "jpeg_1280x720": ("sensor_msgs/CompressedImage", 1280, 720),
    "jpeg_640x480": ("sensor_msgs/CompressedImage", 640, 480),  # the fleet benchmark's rear cameras
    "rgb8_640x480": ("sensor_msgs/Image", 640, 480),
}


def pct(values: list[float], q: float) -> float:
    if not values:
        return float("nan")
    values = sorted(values)
    return values[min(len(values) - 1, int(q / 100 * len(values)))]


def make_frames(width: int, height: int, n: int = 30) -> list[np.ndarray]:
    """A moving test pattern (gradient, a sweeping bar and a circle) as RGB frames."""
    yy, xx = np.mgrid[0:height, 0:width]
    base = np.stack([(xx * 255 // width), (yy * 255 // height), np.full_like(xx, 120)], axis=2).astype(np.uint8)
    frames = []
    for i in range(n):
        img = base.copy()
        x = int(i / n * width)
        img[:, max(0, x - 20):x + 20] = (255, 255, 255)
        cv2.circle(img, (width // 2, height // 2), height // 4 + 5 * (i % 6), (240, 60, 40), -1)
        cv2.putText(img, f"frame {i}", (20, 60), cv2.FONT_HERSHEY_SIMPLEX, 2, (0, 0, 0), 4)
        frames.append(img)
    return frames


def stamp_now() -> dict[str, int]:
    ns = time.time_ns()
    return {"secs": ns // 1_000_000_000, "nsecs": ns % 1_000_000_000}


async def publish_stream(server: Any, topic: str, type_name: str, payloads: list[Any], fps: float,
                         seconds: float, published: list[int]) -> None:
    """Publish on the server's loop at a steady rate (skips, never bursts, when behind)."""
    loop = asyncio.get_running_loop()
    period = 1.0 / fps
    due = loop.time()
    end = due + seconds
    i = 0
    while loop.time() < end:
        header = {"seq": i, "stamp": stamp_now(), "frame_id": "bench"}
        body = payloads[i % len(payloads)]
        server.publish(topic, {"header": header, **body}, "/bench_camera")
        published[0] += 1
        i += 1
        due += period
        now = loop.time()
        if due < now:
            due = now + period
        await asyncio.sleep(due - now)


def run_stream(name: str, seconds: float, fps: float, warmup: float = 1.0,
               view_size: tuple[int, int] = (640, 400)) -> dict[str, Any]:
    from qtpy import QtCore, QtWidgets
    from rcon_widgets_sensors.image import ImageModel, ImageSettings
    from rcon_widgets_sensors.image_view import ImageView

    from rcon_core.bridge import BridgeClient
    from rcon_core.bridge.threaded import BridgeThread
    from rcon_core.plugins import Binding
    from rcon_core.sim import SimServer

    type_name, w, h = STREAMS[name]
    frames = make_frames(w, h)
    if type_name.endswith("CompressedImage"):
        payloads = []
        for f in frames:
            ok, buf = cv2.imencode(".jpg", cv2.cvtColor(f, cv2.COLOR_RGB2BGR), [cv2.IMWRITE_JPEG_QUALITY, 80])
            payloads.append({"format": "jpeg", "data": buf.tobytes()})
    else:
        payloads = [{"height": h, "width": w, "encoding": "rgb8", "is_bigendian": 0, "step": w * 3,
                     "data": f.tobytes()} for f in frames]
    topic = f"/bench/{name}"
    app = QtWidgets.QApplication.instance() or QtWidgets.QApplication(sys.argv[:1])  # noqa: F841 - kept alive
    with SimServer.in_thread(robot=False) as server:
        server.run_sync(lambda: server.advertise_internal(topic, type_name.replace("/msg/", "/"), "/bench_camera"))
        bt = BridgeThread().start()
        client = BridgeClient(server.url, reconnect=False)
        bt.run(client.connect()).result(10)
        model = ImageModel(ImageSettings(max_fps=fps), Binding(topic, type_name, "subscribe"),
                           client.node("bench-image"), dispatch=bt.call)
        decode_cpu: list[float] = []  # thread CPU seconds per decode (worker thread)
        real_decode = model.decode

        def timed_decode(msg: dict[str, Any], received: float | None = None) -> Any:
            c0 = time.thread_time()
            frame = real_decode(msg, received)
            decode_cpu.append(time.thread_time() - c0)
            return frame

        model.decode = timed_decode
        view = ImageView(model)
        paint_s: list[float] = []  # wall seconds per paintEvent (GUI thread)
        real_paint = view.paintEvent

        def timed_paint(event: Any) -> None:
            p0 = time.perf_counter()
            real_paint(event)
            paint_s.append(time.perf_counter() - p0)

        view.paintEvent = timed_paint
        view.resize(*view_size)
        view.show()
        painted: list[tuple[float, float, int]] = []  # (painted wall time, latency s, frame index)
        view.on_painted = lambda frame, t: painted.append((t, t - (frame.stamp or frame.received), frame.index))
        bt.call(model.start).result(5)
        last_seq = [-1]

        def tick() -> None:  # what the app's frame clock does for each visible widget
            st = model.state
            if st.seq != last_seq[0]:
                last_seq[0] = st.seq
                view.refresh(st)

        timer = QtCore.QTimer()
        timer.setTimerType(QtCore.Qt.TimerType.PreciseTimer)
        timer.setInterval(16)
        timer.timeout.connect(tick)
        timer.start()
        published = [0]
        total = warmup + seconds
        fut = asyncio.run_coroutine_threadsafe(
            publish_stream(server, topic, type_name, payloads, fps, total, published), server.loop)
        cpu0 = time.process_time()
        loop = QtCore.QEventLoop()
        QtCore.QTimer.singleShot(int(warmup * 1000), lambda: marks.append((time.time(), published[0],
                                                                            time.process_time())))
        marks: list[tuple[float, int, float]] = []
        QtCore.QTimer.singleShot(int((total + 0.3) * 1000), loop.quit)
        loop.exec()
        fut.result(5)
        timer.stop()
        shown = view.frame
        pixels = f"{shown.rgb.shape[1]}x{shown.rgb.shape[0]}" if shown is not None else "-"
        end_wall, end_cpu = time.time(), time.process_time()
        bt.call(model.stop).result(5)
        bt.run(client.close()).result(5)
        bt.stop()
        view.close()
    t0, pub0, cpu_start = marks[0] if marks else (painted[0][0], 0, cpu0)
    measured = [p for p in painted if p[0] >= t0]
    span = max(1e-6, (measured[-1][0] - t0) if measured else seconds)
    n_skip = max(0, int(len(decode_cpu) * warmup / (warmup + seconds)))  # roughly the warm-up's decodes
    dec = [d * 1000 for d in decode_cpu[n_skip:]]
    pnt = [d * 1000 for d in paint_s[len(paint_s) // 10:]]
    lat = [p[1] * 1000 for p in measured]
    first = [p[1] * 1000 for p in measured if p[0] < t0 + 1.0]
    last = [p[1] * 1000 for p in measured if p[0] > measured[-1][0] - 1.0] if measured else []
    return {
        "stream": name,
        "size": f"{w}x{h}",
        "published_fps": round((published[0] - pub0) / seconds, 1),
        "shown_fps": round(len(measured) / span, 1),
        "dropped_latest_wins": model.dropped,
        "latency_p50_ms": round(pct(lat, 50), 1),
        "latency_p99_ms": round(pct(lat, 99), 1),
        "latency_first_s_p50_ms": round(pct(first, 50), 1),
        "latency_last_s_p50_ms": round(pct(last, 50), 1),
        "process_cpu_percent_incl_server": round(100 * (end_cpu - cpu_start) / max(1e-6, end_wall - t0), 1),
        "frames_painted": len(measured),
        "view": f"{view_size[0]}x{view_size[1]}",
        "pixels_painted": pixels,
        "decode_cpu_ms_p50": round(pct(dec, 50), 2),
        "decode_cpu_ms_p95": round(pct(dec, 95), 2),
        "paint_ms_p50": round(pct(pnt, 50), 2),
        "paint_ms_p95": round(pct(pnt, 95), 2),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=6.0)
    parser.add_argument("--fps", type=float, default=30.0)
    parser.add_argument("--only", choices=sorted(STREAMS), default=None)
    parser.add_argument("--view", default="640x400", help="the view's size WxH (default 640x400)")
    parser.add_argument("--out", type=Path)
    args = parser.parse_args(argv)
    try:
        w, h = (int(v) for v in args.view.lower().split("x"))
        view_size = (w, h)
        assert min(view_size) > 0
    except (ValueError, AssertionError):
        parser.error(f"--view wants WxH in pixels, e.g. 320x260, not {args.view!r}")
    os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
    results = []
    for name in STREAMS:
        if args.only and name != args.only:
            continue
        r = run_stream(name, args.seconds, args.fps, view_size=view_size)
        results.append(r)
        print(f"{name:>15}: published {r['published_fps']:5.1f}/s  shown {r['shown_fps']:5.1f}/s  "
              f"latency p50 {r['latency_p50_ms']:6.1f} ms  p99 {r['latency_p99_ms']:6.1f} ms  "
              f"(first s {r['latency_first_s_p50_ms']:.1f}, last s {r['latency_last_s_p50_ms']:.1f})  "
              f"dropped {r['dropped_latest_wins']}  process cpu {r['process_cpu_percent_incl_server']:.0f}%", flush=True)
        print(f"{'':>15}  view {r['view']} painting {r['pixels_painted']} px: decode cpu p50 "
              f"{r['decode_cpu_ms_p50']:.2f} ms p95 {r['decode_cpu_ms_p95']:.2f} ms; paintEvent p50 "
              f"{r['paint_ms_p50']:.2f} ms p95 {r['paint_ms_p95']:.2f} ms", flush=True)
    figures = {"benchmark": "image", "seconds": args.seconds, "fps": args.fps, "view": args.view,
               "streams": results}
    if args.out:
        args.out.write_text(json.dumps(figures, indent=2))
    ok = all(r["shown_fps"] >= 0.8 * r["published_fps"] for r in results)
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
