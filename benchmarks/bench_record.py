"""Benchmark of the flight recorder and of replay (issue 27's figures).

Usage: ``python benchmarks/bench_record.py [--only fleet writer ingest pacing seek memory] [--seconds 20]
[--fleet-seconds 120] [--fleet-window 10] [--ingest-rounds 5] [--pacing-seconds 600] [--out FILE.json]``.
Each part prints its figures with the load average of the machine before and after it (a 2-core machine
shared with other work: timing figures taken under load are noisy, and the JSON says what the load was).

- ``fleet``: the 3-vessel fleet benchmark (``bench_app.py --robots 3``: 6 cameras, 60 values at 20 Hz, one
  window) with the app's Record control off and on in turns (``--fleet-window`` seconds each, for
  ``--fleet-seconds``; ``bench_fleet.record_toggle``): the app's CPU share in each state (all threads, and
  by thread), the increase of each (off, on) pair and their median (neighbouring windows see the same
  load and drift: two separate runs differed by more than the recorder costs), the messages the recorder
  wrote and dropped, and every file read back (its message count must equal what was written). Target:
  app CPU +10 % at most, nothing dropped.
- ``writer``: the writer alone (``McapSink``, its thread) taking the fleet's camera frames as fast as it
  can, zstd and lz4: MB/s, and its headroom over the fleet's data rate (target >= 10x).
- ``ingest``: ``rcon record`` (a process) recording a publisher of raw 640x480 rgb8 frames (a bare sim in
  another process, ``--ingest-hz``), in alternating rounds (``--ingest-rounds``) with two subscriber
  processes that only count the frames: a plain one, and one that hands each frame to a second thread
  which reads it (``zlib.crc32``) and drops it -- what any recorder with a writer thread does before it
  compresses or writes anything. Each process's CPU is counted over its steady window only (from 4 s after
  its start to 1.5 s before its end, with the messages it took in that window): the imports of ``rcon
  record`` had been a sixth of the difference at 20 s, and one round each had spread from -8 % to +31 %.
  The recorder's CPU is split into its messages' side (every thread but the writer: receiving, taking the
  bytes, queueing) and its writer (compressing and storing), and each round also measures the **bytes'
  floor** (``bytes_floor``: the same frames, arriving from another thread at the camera's pace, compressed
  the same way and written to the same disk by a bare loop). Printed: MB/s written (target >= 50); the
  whole recorder over plain subscribe (the issue's target, <= 5 %); the hand-off over plain; the
  recorder's messages' side over the hand-off and its writer over the floor (what RCON answers for: each
  within 5 %); and the recorder beyond plain subscribe plus the floor. Why the issue's target cannot be met
  by any recorder that stores the frames: writing a 640x480 rgb8 frame to this disk alone costs about
  0.2 ms of system time, some 45 % of receiving it (0.42-0.46 ms); compressing it with zstd more; and on
  a 2-core machine merely handing it to a second thread costs the receiving thread about a quarter more.
- ``pacing``: a 10-minute recording (odometry 50 Hz, fix 5 Hz, a 320x240 camera 5 Hz) played at 1x with a
  subscriber: each message's release time minus its due time, p50/p99/max (target p99 < 5 ms).
  ``--pacing-seconds`` plays only the first N seconds of it (the default plays all 600).
- ``seek``: a 1 GB recording of 640x480 camera frames served as a robot; 20 seeks to random times, each
  timed from the seek to the first frame at the new time received and decoded by a client (the app's
  paint adds one frame, ~16 ms, not measured here). Target < 300 ms.
- ``memory``: RSS of the process while it records an hour of messages (odometry 20 Hz, a JPEG-sized
  camera 10 Hz: time stamps over an hour, written as fast as the writer takes them, with at most 4 MB
  waiting in its queue as at a live robot's pace), then while it plays that hour-long file at 120x to a
  subscriber (30 s). Target: growth < 20 MB each.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import random
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
MB = 1_000_000
#: the 3-vessel fleet's data rate by its specification: per vessel a 640x480 rgb8 camera at 10 Hz, a JPEG
#: camera at 12 Hz (about 35 kB a frame) and 20 Float64 at 20 Hz
NOMINAL_FLEET = round(3 * (640 * 480 * 3 * 10 + 35_000 * 12 + 20 * 20 * 8) / MB, 1)


def load() -> list[float]:
    return [round(v, 2) for v in os.getloadavg()]


def rss_mb() -> float:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


def pct(values: list[float], q: float) -> float:
    if not values:
        return float("nan")
    values = sorted(values)
    return values[min(len(values) - 1, int(q / 100 * len(values)))]


def proc_cpu_s(pid: int) -> float:
    return sum(proc_cpu_split(pid))


def proc_cpu_split(pid: int) -> tuple[float, float]:
    """(user, system) CPU seconds of a process so far."""
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    tick = os.sysconf("SC_CLK_TCK")
    return int(fields[11]) / tick, int(fields[12]) / tick


def camera_frame(i: int, w: int = 640, h: int = 480, noise: float = 0.0) -> bytes:
    import numpy as np

    img = np.zeros((h, w, 3), dtype=np.uint8)
    img[:, :, 0] = (np.arange(w) + i) % 256
    img[: h // 2, :, 2] = 180
    img[h // 2:, :, 1] = (np.arange(h // 2)[:, None] + i) % 256
    if noise:
        rng = np.random.default_rng(i)
        rows = int(h * noise)
        img[:rows] = rng.integers(0, 256, size=(rows, w, 3), dtype=np.uint8)
    return img.tobytes()


def image_msg(reg: Any, t_ns: int, pixels: bytes, w: int = 640, h: int = 480) -> bytes:
    return reg.serialize_ros1("sensor_msgs/Image", {
        "header": {"seq": 0, "stamp": {"secs": t_ns // 10**9, "nsecs": t_ns % 10**9}, "frame_id": "cam"},
        "height": h, "width": w, "encoding": "rgb8", "is_bigendian": 0, "step": w * 3, "data": pixels})


def schema(reg: Any, name: str) -> tuple[str, str, bytes, str]:
    from rcon_core.record.schema import schema_for

    s = schema_for(name, False, reg)
    return s.name, s.encoding, s.data, s.message_encoding


# ------------------------------------------------------------------------------------------------ fleet

def part_fleet(args: Any) -> dict[str, Any]:
    out: dict[str, Any] = {"load_before": load()}
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "fleet.json"
        env = {"BENCH_RECORD_DIR": str(Path(tmp) / "rec"), "BENCH_RECORD_TOGGLE": str(args.fleet_window),
               "QT_QPA_PLATFORM": "offscreen"}
        subprocess.run([sys.executable, str(HERE / "bench_app.py"), "--robots", "3", "--seconds",
                        str(args.fleet_seconds), "--out", str(path)], env={**os.environ, **env},
                       check=True, stdout=subprocess.DEVNULL)
        run = json.loads(path.read_text())
        tog = run["record_toggle"]
        r = tog["record"]
        in_files, data_bytes, seconds = 0, 0, 0.0
        from mcap.reader import make_reader

        for f in r.get("files", []):
            with open(f, "rb") as fh:
                reader = make_reader(fh)
                st = reader.get_summary().statistics
                in_files += st.message_count
                seconds += (st.message_end_time - st.message_start_time) / 1e9 / 3  # one file per vessel
                for _s, _c, m in reader.iter_messages():
                    data_bytes += len(m.data)
    out.update({
        "windows_s": tog["window_s"], "pairs": tog["pairs"],
        "app_cpu_share_plain": tog["cpu_share"]["off"], "app_cpu_share_recording": tog["cpu_share"]["on"],
        "app_cpu_increase_pct_by_pair": tog["pairs_increase_pct"],
        "app_cpu_increase_pct": tog["increase_pct_median"],
        "app_cpu_increase_pct_pooled": tog["increase_pct_pooled"],
        "app_cpu_by_thread_plain": tog["by_thread"]["off"],
        "app_cpu_by_thread_recording": tog["by_thread"]["on"],
        "messages_written": r.get("messages_written"), "messages_in_files": in_files,
        "dropped": r.get("dropped"), "problem": r.get("problem"), "bytes_on_disk": r.get("bytes_on_disk"),
        "fleet_data_rate_mb_s": round(data_bytes / max(seconds, 1e-9) / MB, 2),
        "camera_frames_shown_per_s": run.get("camera_frames_shown_per_s"),
        "load_during": [run.get("load_average_before"), run.get("load_average_after")],
        "target_cpu_increase_pct": 10.0,
    })
    out["ok_cpu"] = out["app_cpu_increase_pct"] <= 10.0
    out["ok_nothing_dropped"] = r.get("dropped") == 0 and in_files == r.get("messages_written")
    out["load_after"] = load()
    return out


# ------------------------------------------------------------------------------------------------ writer

def part_writer(args: Any, fleet_rate: float | None) -> dict[str, Any]:
    from rcon_core.msgs import TypeRegistry
    from rcon_core.record.writer import McapSink

    reg = TypeRegistry.standard()
    out: dict[str, Any] = {"load_before": load()}
    with tempfile.TemporaryDirectory() as tmp:
        for comp, noise in (("zstd", 0.0), ("lz4", 0.0), ("zstd", 0.5)):
            # the sim's kind of picture (smooth: compresses ~30x), and one half noise (a worse case)
            frames = [image_msg(reg, i, camera_frame(i, noise=noise)) for i in range(30)]
            out["frame_bytes"] = len(frames[0])
            label = comp if not noise else f"{comp}_half_noise"
            sink = McapSink(str(Path(tmp) / f"w-{label}.mcap"), "ros1", compression=comp, max_queue=1 << 40)
            sink.add_channel("/cam", *schema(reg, "sensor_msgs/Image"))
            n = int(args.writer_mb * MB / len(frames[0]))
            t0 = time.perf_counter()
            cpu0 = time.process_time()
            for i in range(n):
                while sink.queued > 64 * MB:
                    time.sleep(0.001)
                sink.write("/cam", i, i, frames[i % len(frames)])
            sink.close()
            wall = time.perf_counter() - t0
            mbps = n * len(frames[0]) / wall / MB
            out[label] = {"mb_s": round(mbps, 1), "cpu_share": round((time.process_time() - cpu0) / wall, 2),
                         "compressed_to_pct": round(sink.size / (n * len(frames[0])) * 100, 1),
                         "dropped": sink.stats.dropped}
            if fleet_rate:
                out[label]["headroom_x"] = round(mbps / fleet_rate, 1)
    out["fleet_data_rate_mb_s"] = fleet_rate
    out["load_after"] = load()
    return out


# ------------------------------------------------------------------------------------------------ ingest

PUBLISHER = """
import asyncio, sys, time
sys.path.insert(0, {root!r})
from rcon_core.sim import SimServer
sys.path.insert(0, {here!r})
from bench_record import camera_frame
async def main():
    s = SimServer(robot=False, port=0)
    await s.start()
    s.advertise_internal("/cam", "sensor_msgs/Image", "/pub")
    print(s.url, flush=True)
    frames = [camera_frame(i) for i in range(8)]
    i = 0
    while True:
        t = time.time()
        if s.topics["/cam"].client_subscribers:
            s.publish("/cam", {{"header": {{"seq": 0, "stamp": {{"secs": int(t), "nsecs": int(t % 1 * 1e9)}},
                       "frame_id": "cam"}}, "height": 480, "width": 640, "encoding": "rgb8", "is_bigendian": 0,
                       "step": 1920, "data": frames[i % 8]}}, "/pub")
            i += 1
        await asyncio.sleep(1 / {hz})
asyncio.run(main())
"""

COUNTER = """
import asyncio, sys, time
sys.path.insert(0, {root!r})
from rcon_core.bridge import BridgeClient
from rcon_core.mallocpolicy import keep_big_blocks
keep_big_blocks()  # as rcon record (and every RCON entry point) does: the same allocator for both
HAND = {hand}  # each frame handed to a second thread that reads it (zlib.crc32) and drops it
if HAND:
    import queue, threading, zlib
    handed = queue.SimpleQueue()
    def reader():
        from rcon_core.priority import name_this_thread
        name_this_thread("bench-handoff")  # its CPU is not the receiving side's (_thread_cpu)
        while True:
            zlib.crc32(handed.get())
    threading.Thread(target=reader, daemon=True).start()
async def main():
    c = BridgeClient({url!r}, max_size=64 << 20)
    await c.connect()
    arrivals = []
    def got(p):
        arrivals.append((time.time_ns(), len(p.data)))
        if HAND:
            handed.put(p.data)
    c.node("count").subscribe("/cam", got, raw=True)
    t0 = time.time()
    while time.time() - t0 < {seconds}:
        await asyncio.sleep(0.5)
    print(" ".join(f"{{t}}:{{n}}" for t, n in arrivals), flush=True)
    await c.close()
asyncio.run(main())
"""

#: a process's CPU is counted from this long after it started (its imports, connecting, subscribing and
#: opening its file are not what a message costs) ...
INGEST_WARM_S = 4.0
#: ... to this long before it ends (nor closing the file)
INGEST_TAIL_S = 1.5


def _thread_cpu(pid: int, name: str = "rcon-record-wr") -> float:
    """CPU seconds so far of the process's threads of OS name ``name`` (Linux): the recorder's writer (its
    name in record/writer.py), or the hand-off counter's reader."""
    total = 0.0
    tick = os.sysconf("SC_CLK_TCK")
    try:
        tids = os.listdir(f"/proc/{pid}/task")
    except OSError:
        return 0.0
    for tid in tids:
        try:
            with open(f"/proc/{pid}/task/{tid}/stat") as f:
                head, tail = f.read().rsplit(")", 1)
        except OSError:
            continue
        if head.split("(", 1)[1] == name:
            fields = tail.split()
            total += (int(fields[11]) + int(fields[12])) / tick
    return total


def _steady_cpu(proc: subprocess.Popen[str], seconds: float,
                thread: str = "rcon-record-wr") -> tuple[int, int, float, float, float]:
    """(window start ns, end ns, user s, system s, of which the threads named ``thread`` s) of ``proc``
    between INGEST_WARM_S after its start and INGEST_TAIL_S before its planned end; then waits for it."""
    time.sleep(INGEST_WARM_S)
    a_ns, (u0, s0), w0 = time.time_ns(), proc_cpu_split(proc.pid), _thread_cpu(proc.pid, thread)
    time.sleep(max(1.0, seconds - INGEST_WARM_S - INGEST_TAIL_S))
    b_ns, (u1, s1), w1 = time.time_ns(), proc_cpu_split(proc.pid), _thread_cpu(proc.pid, thread)
    proc.wait(seconds + 60)
    return a_ns, b_ns, u1 - u0, s1 - s0, w1 - w0


def bytes_floor(compression: str, path: Path, hz: float, frames: int = 240, chunk_frames: int = 4) -> dict[str, float]:
    """The work a frame's bytes cost whatever records them, done bare: the frames arrive fresh from another
    thread at ``hz`` (each a new copy, made there as a receiving thread makes one: compressing frames that
    another thread just wrote, at a camera's pace, costs 0.67 ms a frame here, the same 8 frames over and
    over in a tight loop 0.39 ms), and this thread
    compresses them as ``rcon record`` does (zstd level 3 fed as a stream with the chunk's size pledged,
    lz4's frame, or nothing) in chunks of ``chunk_frames`` (its 4 MB chunk) and writes them to a file on
    the same disk. Milliseconds of this thread's CPU a frame (user, system): what a recorder with a
    writer thread cannot go below."""
    import queue
    import resource

    images = [camera_frame(i) for i in range(8)]
    size = len(images[0]) * chunk_frames
    if compression == "zstd":
        import zstandard

        zc = zstandard.ZstdCompressor(level=3, write_content_size=True)

        def squeeze(chunk: list[Any]) -> Any:
            stream = zc.compressobj(size=size)
            return b"".join([*(stream.compress(c) for c in chunk), stream.flush()])
    elif compression == "lz4":
        import lz4.frame

        def squeeze(chunk: list[Any]) -> Any:
            return lz4.frame.compress(b"".join(chunk), store_size=True)
    else:
        def squeeze(chunk: list[Any]) -> Any:
            return chunk

    handed: queue.Queue[bytearray | None] = queue.Queue(maxsize=chunk_frames)

    def arrive() -> None:
        due = time.monotonic()
        for k in range(frames):
            handed.put(bytearray(images[k % 8]))
            due += 1 / hz
            time.sleep(max(0.0, due - time.monotonic()))
        handed.put(None)

    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
    producer = threading.Thread(target=arrive, daemon=True)
    try:
        r0 = resource.getrusage(resource.RUSAGE_THREAD)
        producer.start()
        chunk: list[bytearray] = []
        while (frame := handed.get()) is not None:
            chunk.append(frame)
            if len(chunk) == chunk_frames:
                out = squeeze(chunk)
                pieces = out if isinstance(out, list) else [out]
                for piece in pieces:
                    data = memoryview(piece)
                    while data:
                        data = data[os.write(fd, data):]
                chunk = []
        r1 = resource.getrusage(resource.RUSAGE_THREAD)
    finally:
        producer.join(10)
        os.close(fd)
        path.unlink()
    user, system = r1.ru_utime - r0.ru_utime, r1.ru_stime - r0.ru_stime
    return {"user_ms": user * 1000 / frames, "sys_ms": system * 1000 / frames, "ms_per_message": (user + system) * 1000 / frames}


def part_ingest(args: Any) -> dict[str, Any]:
    """``rcon record`` against a plain subscriber of the same frames, in alternating rounds (both see the
    same load and drift); each process's CPU counted over its steady window only, and the messages it took
    in that window (the counter's arrival times; the file's log times)."""
    from mcap.reader import make_reader

    out: dict[str, Any] = {"load_before": load(), "offered_hz": args.ingest_hz, "rounds": args.ingest_rounds,
                           "window_s": round(args.seconds - INGEST_WARM_S - INGEST_TAIL_S, 1)}
    pub = subprocess.Popen([sys.executable, "-c", PUBLISHER.format(root=str(HERE.parent), here=str(HERE),
                                                                    hz=args.ingest_hz)],
                           stdout=subprocess.PIPE, text=True)
    frame = 640 * 480 * 3
    plain: list[dict[str, float]] = []
    handoff: list[dict[str, float]] = []  # plain subscribe, each frame handed to a thread that reads it
    recorded: list[dict[str, float]] = []
    floors: list[dict[str, float]] = []
    try:
        url = pub.stdout.readline().strip()  # type: ignore[union-attr]
        seconds = args.seconds
        with tempfile.TemporaryDirectory() as tmp:
            for k in range(args.ingest_rounds):
                for hand, rows in ((False, plain), (True, handoff)):
                    counter = subprocess.Popen([sys.executable, "-c", COUNTER.format(
                        root=str(HERE.parent), url=url, seconds=seconds, hand=hand)], stdout=subprocess.PIPE, text=True)
                    a, b, user, system, reader = _steady_cpu(counter, seconds, "bench-handoff")
                    arrivals = [tuple(map(int, x.split(":"))) for x in counter.stdout.read().split()]  # type: ignore[union-attr]
                    got = [n for t, n in arrivals if a <= t <= b]
                    rows.append({"messages": len(got), "mb_s": sum(got) / ((b - a) / 1e9) / MB,
                                 # the receiving side: every thread but the hand-off's reader
                                 "ms_per_message": (user + system - reader) * 1000 / max(1, len(got)),
                                 "user_ms": user * 1000 / max(1, len(got)), "sys_ms": system * 1000 / max(1, len(got))})
                path = Path(tmp) / f"ingest{k}.mcap"
                rec = subprocess.Popen([sys.executable, "-m", "rcon_core", "record", "-q", "-o", str(path), "/cam",
                                        "--url", url, "--duration", str(seconds), "--compression",
                                        args.ingest_compression],
                                       stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
                a, b, user, system, writer = _steady_cpu(rec, seconds)
                out["said"] = rec.stderr.read().strip()[-300:]  # type: ignore[union-attr]
                with open(path, "rb") as f:
                    reader = make_reader(f)
                    n = sum(1 for _s, c, m in reader.iter_messages(topics=["/cam"]) if a <= m.log_time <= b)
                recorded.append({"messages": n, "mb_s": n * frame / ((b - a) / 1e9) / MB,
                                 "ms_per_message": (user + system) * 1000 / max(1, n),
                                 "user_ms": user * 1000 / max(1, n), "sys_ms": system * 1000 / max(1, n),
                                 "writer_ms": writer * 1000 / max(1, n),
                                 "receive_ms": (user + system - writer) * 1000 / max(1, n),
                                 "file_mb": path.stat().st_size / MB})
                path.unlink()
                floors.append(bytes_floor(args.ingest_compression, Path(tmp) / "floor.bin", args.ingest_hz))
    finally:
        pub.terminate()
        pub.wait()

    def med(rows: list[dict[str, float]], key: str) -> float:
        return round(statistics.median(r[key] for r in rows), 3)

    pairs = [round((r["ms_per_message"] / p["ms_per_message"] - 1) * 100, 1) for p, r in zip(plain, recorded, strict=True)]
    receive = [round((r["receive_ms"] / p["ms_per_message"] - 1) * 100, 1) for p, r in zip(plain, recorded, strict=True)]
    out.update({
        "plain_subscribe": {k: med(plain, k) for k in ("messages", "mb_s", "ms_per_message", "user_ms", "sys_ms")},
        "rcon_record": {**{k: med(recorded, k) for k in ("messages", "mb_s", "ms_per_message", "user_ms", "sys_ms",
                                                          "receive_ms", "writer_ms")},
                        "compression": args.ingest_compression},
        "record_cpu_over_plain_pct_by_round": pairs,
        "record_cpu_over_plain_pct": round(statistics.median(pairs), 1),
        # the recorder's receiving side alone (every thread but the writer: reading, decoding, queueing)
        "record_receive_cpu_over_plain_pct_by_round": receive,
        "record_receive_cpu_over_plain_pct": round(statistics.median(receive), 1),
    })
    over_handoff = [round((r["receive_ms"] / h["ms_per_message"] - 1) * 100, 1) for h, r in zip(handoff, recorded, strict=True)]
    handoff_over_plain = [round((h["ms_per_message"] / p["ms_per_message"] - 1) * 100, 1) for p, h in zip(plain, handoff, strict=True)]
    out.update({
        # the reference that any recorder with a writer thread meets: plain subscribe handing each frame to a
        # second thread that only reads it (on this 2-core machine the receiving thread pays for the frames'
        # memory moving between the cores' caches)
        "plain_with_handoff": {k: med(handoff, k) for k in ("messages", "ms_per_message")},
        "handoff_over_plain_pct_by_round": handoff_over_plain,
        "handoff_over_plain_pct": round(statistics.median(handoff_over_plain), 1),
        "record_receive_over_handoff_pct_by_round": over_handoff,
        "record_receive_over_handoff_pct": round(statistics.median(over_handoff), 1),
    })
    floor = {k: med(floors, k) for k in ("ms_per_message", "user_ms", "sys_ms")}
    writer_over = [round((r["writer_ms"] / f["ms_per_message"] - 1) * 100, 1) for r, f in zip(recorded, floors, strict=True)]
    beyond = [round((r["ms_per_message"] - p["ms_per_message"] - f["ms_per_message"]) / p["ms_per_message"] * 100, 1)
              for p, r, f in zip(plain, recorded, floors, strict=True)]
    out.update({
        # what storing the frames costs whatever records them (bytes_floor), and the writer against it
        "bytes_floor": {**floor, "compression": args.ingest_compression},
        "writer_over_floor_pct_by_round": writer_over,
        "writer_over_floor_pct": round(statistics.median(writer_over), 1),
        # the recorder's whole CPU beyond plain subscribe and the floor, in % of plain subscribe
        "record_beyond_plain_and_floor_pct_by_round": beyond,
        "record_beyond_plain_and_floor_pct": round(statistics.median(beyond), 1),
    })
    out["ok_50_mb_s"] = out["rcon_record"]["mb_s"] >= 50
    # the target "<= 5 % of messages' CPU over plain subscribe", as the issue states it: the whole recorder
    # against plain subscribe (no recorder that stores the frames meets it: the bytes' floor alone is more)
    out["ok_cpu_5_pct"] = out["record_cpu_over_plain_pct"] <= 5
    # what is RCON's to answer for: its messages' side against plain subscribe with a hand-off, its writer
    # against the floor
    out["ok_receive_5_pct_over_handoff"] = out["record_receive_over_handoff_pct"] <= 5
    out["ok_writer_5_pct_over_floor"] = out["writer_over_floor_pct"] <= 5
    out["load_after"] = load()
    return out


# ------------------------------------------------------------------------------------------------ pacing

def make_recording(path: Path, seconds: float, topics: list[tuple[str, str, float, Any]], t0: int = 10**18,
                   max_queued: int = 128 * MB) -> int:
    """Write a recording of ``seconds`` with ``(topic, type, hz, make(i, t_ns) -> bytes)`` channels; the
    messages are made as they are written (never all in memory) and at most ``max_queued`` bytes wait for
    the writer (a live robot's messages come at its pace; the bench makes them as fast as it can)."""
    import heapq

    from rcon_core.msgs import TypeRegistry
    from rcon_core.record.writer import McapSink

    reg = TypeRegistry.standard()
    sink = McapSink(str(path), "ros1", max_queue=1 << 40)
    def stream(topic: str, hz: float, make: Any) -> Any:
        for i in range(int(seconds * hz)):
            yield t0 + int(i / hz * 1e9), topic, i, make

    streams = []
    for topic, type_name, hz, make in topics:
        sink.add_channel(topic, *schema(reg, type_name))
        streams.append(stream(topic, hz, make))
    n = 0
    for t, topic, i, make in heapq.merge(*streams, key=lambda e: e[0]):
        while sink.queued > max_queued:
            time.sleep(0.001)
        sink.write(topic, t, t, make(i, t))
        n += 1
    sink.close()
    return n


def odom(reg: Any) -> Any:
    def make(i: int, t: int) -> bytes:
        return reg.serialize_ros1("nav_msgs/Odometry", {
            "header": {"seq": i, "stamp": {"secs": t // 10**9, "nsecs": t % 10**9}, "frame_id": "odom"},
            "child_frame_id": "base", "pose": {"pose": {"position": {"x": i * 0.01, "y": 0.0, "z": 0.0},
                                                        "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}},
                                               "covariance": [0.0] * 36},
            "twist": {"twist": {"linear": {"x": 1.0, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.0}},
                      "covariance": [0.0] * 36}})
    return make


def fix(reg: Any) -> Any:
    def make(i: int, t: int) -> bytes:
        return reg.serialize_ros1("sensor_msgs/NavSatFix", {
            "header": {"seq": i, "stamp": {"secs": t // 10**9, "nsecs": t % 10**9}, "frame_id": "gps"},
            "status": {"status": 0, "service": 1}, "latitude": 59.9 + i * 1e-6, "longitude": 10.7, "altitude": 0.0,
            "position_covariance": [0.0] * 9, "position_covariance_type": 0})
    return make


async def _play(path: Path, seconds: float, rate: float, topics: list[str], sample: Any = None) -> Any:
    from rcon_core.bridge import BridgeClient
    from rcon_core.sim.playback import serve_recording

    server, player = await serve_recording(str(path), rate=rate, paused=True)
    client = BridgeClient(server.url, max_size=64 << 20)
    await client.connect()
    got = {"n": 0}
    for t in topics:
        client.node(f"s{t}").subscribe(t, lambda _m: got.__setitem__("n", got["n"] + 1), raw=True)
    while not all(server.topic_subscriber_count(t) for t in topics):
        await asyncio.sleep(0.01)
    await asyncio.sleep(0.5)
    player.play()
    t0 = time.monotonic()
    while time.monotonic() - t0 < seconds and not player.ended:
        await asyncio.sleep(0.25)
        if sample is not None:
            sample()
    await client.close()
    await player.stop()
    await server.stop()
    player.recording.close()
    return player, got["n"]


def part_pacing(args: Any) -> dict[str, Any]:
    from rcon_core.msgs import TypeRegistry

    reg = TypeRegistry.standard()
    small = camera_frame(0, 320, 240)
    out: dict[str, Any] = {"load_before": load()}
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "ten-minutes.mcap"
        n = make_recording(path, 600, [("/odom", "nav_msgs/Odometry", 50, odom(reg)),
                                       ("/gps/fix", "sensor_msgs/NavSatFix", 5, fix(reg)),
                                       ("/cam", "sensor_msgs/Image", 5,
                                        lambda i, t: image_msg(reg, t, small, 320, 240))])
        player, received = asyncio.run(_play(path, args.pacing_seconds, 1.0, ["/odom", "/gps/fix", "/cam"]))
    late = [x * 1000 for x in player.lateness]
    out.update({"recording_messages": n, "played_seconds": min(args.pacing_seconds, 600),
                "released": len(late), "received_by_client": received,
                "release_error_p50_ms": round(pct(late, 50), 3), "release_error_p99_ms": round(pct(late, 99), 3),
                "release_error_max_ms": round(max(late), 3) if late else None, "target_p99_ms": 5.0})
    out["ok"] = out["release_error_p99_ms"] < 5.0
    out["load_after"] = load()
    return out


# ------------------------------------------------------------------------------------------------ seek

def part_seek(args: Any) -> dict[str, Any]:
    from rcon_core.msgs import TypeRegistry

    reg = TypeRegistry.standard()
    out: dict[str, Any] = {"load_before": load()}
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "one-gb.mcap"
        frames = [camera_frame(i, noise=1.0) for i in range(16)]
        t = time.perf_counter()
        make_recording(path, args.seek_frames / 10, [("/cam", "sensor_msgs/Image", 10,
                                                     lambda i, tt: image_msg(reg, tt, frames[i % 16]))])
        out["file_gb"] = round(path.stat().st_size / 1e9, 2)
        out["written_in_s"] = round(time.perf_counter() - t, 1)
        out["seeks_ms"] = asyncio.run(_seeks(path, reg))
    s = out["seeks_ms"]
    out.update({"seek_to_frame_p50_ms": round(pct(s, 50), 1), "seek_to_frame_max_ms": round(max(s), 1),
                "target_ms": 300.0})
    out["ok"] = out["seek_to_frame_max_ms"] < 300
    out["load_after"] = load()
    return out


async def _seeks(path: Path, reg: Any) -> list[float]:
    from rcon_core.bridge import BridgeClient
    from rcon_core.sim.playback import serve_recording

    server, player = await serve_recording(str(path), paused=True)
    client = BridgeClient(server.url, max_size=64 << 20)
    await client.connect()
    box: dict[str, Any] = {"t": None, "event": asyncio.Event()}

    def got(msg: Any) -> None:
        stamp = msg["header"]["stamp"]
        t = stamp["secs"] * 10**9 + stamp["nsecs"]
        if box["t"] is not None and abs(t - box["t"]) <= 100_000_000:
            box["event"].set()

    client.node("view").subscribe("/cam", got, compression="cbor-raw", queue_length=1)
    while not server.topic_subscriber_count("/cam"):
        await asyncio.sleep(0.01)
    times = []
    rng = random.Random(27)
    rec = player.recording
    for _ in range(20):
        target = rng.uniform(1.0, rec.duration - 1.0)
        box["t"] = rec.start_ns + int(target * 1e9) - 100_000_000  # the frame before it (10 Hz)
        box["event"] = asyncio.Event()
        t0 = time.perf_counter()
        player.seek(target)
        await asyncio.wait_for(box["event"].wait(), 10)
        times.append((time.perf_counter() - t0) * 1000)
        await asyncio.sleep(0.2)
    await client.close()
    await player.stop()
    await server.stop()
    rec.close()
    return [round(x, 1) for x in times]


# ------------------------------------------------------------------------------------------------ memory

def part_memory(args: Any) -> dict[str, Any]:
    import gc

    from rcon_core.msgs import TypeRegistry

    reg = TypeRegistry.standard()
    jpegs = [bytes(random.Random(k).getrandbits(8) for _ in range(30_000)) for k in range(8)]
    out: dict[str, Any] = {"load_before": load()}
    samples: list[float] = []
    stop = threading.Event()

    def sampler() -> None:
        while not stop.is_set():
            samples.append(rss_mb())
            time.sleep(0.2)

    def jpeg_msg(i: int, t: int) -> bytes:
        return reg.serialize_ros1("sensor_msgs/CompressedImage", {
            "header": {"seq": i, "stamp": {"secs": t // 10**9, "nsecs": t % 10**9}, "frame_id": "cam"},
            "format": "jpeg", "data": jpegs[i % 8]})

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "hour.mcap"
        # warm up the writer and the codecs, then measure
        make_recording(Path(tmp) / "warm.mcap", 10, [("/odom", "nav_msgs/Odometry", 20, odom(reg))])
        gc.collect()
        base = rss_mb()
        th = threading.Thread(target=sampler, daemon=True)
        th.start()
        t = time.perf_counter()
        n = make_recording(path, 3600, [("/odom", "nav_msgs/Odometry", 20, odom(reg)),
                                        ("/camera/compressed", "sensor_msgs/CompressedImage", 10, jpeg_msg)],
                           max_queued=4 * MB)
        stop.set()
        th.join()
        out["record"] = {"messages": n, "file_mb": round(path.stat().st_size / MB, 1),
                         "written_in_s": round(time.perf_counter() - t, 1), "rss_start_mb": round(base, 1),
                         "rss_max_mb": round(max(samples), 1), "rss_growth_mb": round(max(samples) - base, 1)}
        # replay: the first 5 s warm up, then the growth over the rest
        play_samples: list[float] = []
        asyncio.run(_play(path, 3600 / 120 + 10, 120.0, ["/odom", "/camera/compressed"],
                          sample=lambda: play_samples.append(rss_mb())))
        warm = play_samples[min(20, len(play_samples) - 1)]
        out["replay"] = {"rate": 120, "rss_after_warm_up_mb": round(warm, 1), "rss_max_mb": round(max(play_samples), 1),
                         "rss_growth_mb": round(max(play_samples) - warm, 1)}
    out["ok"] = out["record"]["rss_growth_mb"] < 20 and out["replay"]["rss_growth_mb"] < 20
    out["load_after"] = load()
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", nargs="*", default=None)
    parser.add_argument("--seconds", type=float, default=20.0, help="ingest runs (s)")
    parser.add_argument("--fleet-seconds", type=float, default=120.0,
                        help="the fleet run: the Record control off and on in turns for this long (s)")
    parser.add_argument("--fleet-window", type=float, default=10.0,
                        help="each off or on window of the fleet run (s; the first 1.5 s not counted)")
    parser.add_argument("--pacing-seconds", type=float, default=600.0)
    parser.add_argument("--writer-mb", type=float, default=1500.0)
    parser.add_argument("--ingest-hz", type=float, default=120.0)
    parser.add_argument("--ingest-rounds", type=int, default=5,
                        help="plain subscribe and rcon record in turns, this many times each")
    parser.add_argument("--ingest-compression", default="zstd", choices=("zstd", "lz4", "none"))
    parser.add_argument("--seek-frames", type=int, default=1150, help="640x480 frames in the seek file (~1 GB)")
    parser.add_argument("--out", type=Path)
    args = parser.parse_args(argv)
    parts = args.only or ["fleet", "writer", "ingest", "pacing", "seek", "memory"]
    figures: dict[str, Any] = {"cores": os.cpu_count()}
    for part in parts:
        print(f"--- {part} (load {load()})", flush=True)
        if part == "writer":  # the fleet's measured data rate, else its nominal one
            figures[part] = part_writer(args, figures.get("fleet", {}).get("fleet_data_rate_mb_s") or NOMINAL_FLEET)
        else:
            figures[part] = globals()[f"part_{part}"](args)
        print(json.dumps(figures[part], indent=1), flush=True)
    if args.out:
        args.out.write_text(json.dumps(figures, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
