"""The fleet mode of ``bench_app.py`` (``--robots N``): N vessels, each a sim in its own process, one window.

Each vessel (``benchmarks/fleet_sim.py``, named ``boat1``..) streams its two cameras (``front``: rgb8
640x480 at 10 Hz; ``rear``: JPEG at 12 Hz) and 20 Float64 values at 20 Hz, each carrying its publish
time; the window has one robot per vessel and one canvas with, per vessel, both cameras and 20 value
widgets, plus a teleop pad on the first vessel that is held down (20 Hz) for the whole measurement.

Figures (``robots`` in the JSON): publish-to-painted p50/p95/p99 of the values (``paint_latency_*``) and of
the camera frames (``camera_publish_to_painted_*``: from the moment the sim published the frame, drawn and
encoded; ``camera_paint_latency_*``: from its header stamp, taken before the sim drew it), GUI frame time
p50/p95, per camera
the frames the sim published, the app received, painted (``shown``) and dropped in the window (latest
wins: ``dropped`` = published - shown) with the latency of the frames shown in the first and the last
second (a growing backlog would show as a growing latency), the stale camera frames the bridge skipped
before decoding (``stale_skipped_by_the_bridge``: a newer frame of the topic was already waiting), idle RSS, CPU of the app and of each sim,
the teleop pad's publish intervals as the sim received them (jitter = |interval - period|, p99), and the
load average of the machine.
"""

from __future__ import annotations

import contextlib
import gc
import json
import os
import re
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import bench_app as ba
from wake_probes import WakeProbes

TARGETS = {"frame_p95_ms": 16.0, "paint_latency_p99_ms": 33.0, "camera_publish_to_painted_p99_ms": 33.0,
           "idle_rss_mb": 250.0, "teleop_jitter_p99_ms": 5.0}
VALUES = 20
CAMERAS = (("front", "/camera/front/image_raw", "sensor_msgs/Image"),
           ("rear", "/camera/rear/image_raw/compressed", "sensor_msgs/CompressedImage"))
TELEOP_HZ = 20.0
ROW_H = 400


@contextlib.contextmanager
def fleet_processes(n: int, hz: float, latency_policy: bool = True, malloc_policy: bool = True):
    """N ``fleet_sim.py`` processes (boat1..); yields [(name, url, pid)]."""
    here = Path(__file__).resolve().parent
    procs: list[subprocess.Popen] = []
    try:
        out = []
        for k in range(1, n + 1):
            name = f"boat{k}"
            proc = subprocess.Popen([sys.executable, str(here / "fleet_sim.py"), "--name", name, "--values",
                                     str(VALUES), "--hz", str(hz), *([] if latency_policy else ["--no-latency-policy"]),
                                     *([] if malloc_policy else ["--no-malloc-policy"])],
                                    stdout=subprocess.PIPE,
                                    stderr=subprocess.STDOUT, text=True)
            procs.append(proc)
            line = proc.stdout.readline() if proc.stdout else ""
            match = re.search(r"ws://\S+", line)
            if not match:
                raise RuntimeError(f"the simulator {name} did not start: {line!r}")
            out.append((name, match.group(0), proc.pid))
        yield out
    finally:
        for proc in procs:
            proc.terminate()
        for proc in procs:
            try:
                proc.wait(10)
            except subprocess.TimeoutExpired:  # a vessel starved of CPU: never left running
                proc.kill()
                proc.wait(5)


def fleet_plugins() -> Any:
    pm = ba.make_plugins("label")  # bench.value
    pm.load_entry_points()  # sensors.image, sensors.teleop
    return pm


def workspace(n: int, plugins: Any) -> Any:
    from rcon_core.app.fleet_demo import robot_id, vessel_name
    from rcon_core.canvas import Canvas, Geometry, WidgetInstance, Workspace
    from rcon_core.canvas.robots import Robot
    from rcon_core.plugins import Binding, Role

    idle = Canvas("c-idle", "Idle")
    bench = Canvas("c-fleet", "Fleet bench")
    for k in range(1, n + 1):
        rid, ns, y0 = robot_id(k), f"/{vessel_name(k)}", 16 + (k - 1) * ROW_H
        for j, (cam, topic, type_name) in enumerate(CAMERAS):
            bench.widgets.append(WidgetInstance(
                f"cam-{k}-{cam}", "sensors.image", Binding(ns + topic, type_name, Role.SUBSCRIBE, (), robot=rid),
                Geometry(16 + j * 336, y0, 320, 260), {"max_fps": 0.0}, f"{vessel_name(k)} {cam}"))
        for i in range(VALUES):
            x, y = 688 + (i % 7) * 168, y0 + (i // 7) * 128
            bench.widgets.append(WidgetInstance(
                f"v-{k}-{i}", "bench.value", Binding(f"{ns}/bench/v{i}", "std_msgs/Float64", Role.SUBSCRIBE,
                                                     ("data",), robot=rid), Geometry(x, y, 160, 112), {}, f"v{i}"))
    spec = plugins.widget("sensors.teleop")
    settings = spec.settings_to_dict(spec.make_settings({"rate_hz": TELEOP_HZ, "max_linear": 1.0}))
    bench.widgets.append(WidgetInstance(
        "teleop-1", "sensors.teleop", Binding("/boat1/cmd_vel", "geometry_msgs/Twist", Role.PUBLISH, (),
                                              robot=robot_id(1)),
        Geometry(16, 16 + n * ROW_H, 288, 240), settings, "Drive boat1"))
    ws = Workspace([idle, bench], idle.id)
    ws.robots = [Robot(robot_id(k), vessel_name(k)) for k in range(1, n + 1)]
    return ws


def thread_cpu_s() -> dict[str, float]:
    """CPU seconds of each of this process's threads so far, summed by thread name (Linux)."""
    out: dict[str, float] = {}
    names = {t.native_id: t.name for t in __import__("threading").enumerate()}
    tick = os.sysconf("SC_CLK_TCK")
    for tid in os.listdir("/proc/self/task"):
        try:
            with open(f"/proc/self/task/{tid}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
        except OSError:
            continue
        name = names.get(int(tid)) or "(not a Python thread)"
        name = re.sub(r"[-_]?\d+$", "", name)  # workers of one kind together
        out[name] = out.get(name, 0.0) + (int(fields[11]) + int(fields[12])) / tick
    return out


def proc_cpu_s(pid: int) -> float:
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


#: after the Record control is switched on or off, CPU is not counted for this long (s): the recorder's
#: subscriptions change and its files open or close
TOGGLE_SETTLE_S = 1.5


def record_toggle(app: Any, window: Any, seconds: float, window_s: float) -> dict[str, Any]:
    """The Record control off and on in turns (``window_s`` each, off first) for ``seconds``: the app's CPU
    share (all threads, and by thread) in each state, counted from :data:`TOGGLE_SETTLE_S` after each switch
    to the next. Both states see the same sims, load and drift, so the recorder's cost is the difference of
    neighbours: ``pairs`` gives each (off, on) pair's increase, the figure is their median.

    Returns ``{"pairs_increase_pct": [...], "increase_pct_median": x, "cpu_share": {"off": a, "on": b},
    "by_thread": {"off": {...}, "on": {...}}, "record": {messages, dropped, ...}}``."""
    control = window.record_control
    spent: dict[str, list[tuple[float, float, dict[str, float]]]] = {"off": [], "on": []}
    written = dropped = size = events = 0
    files: list[str] = []
    problems: list[str] = []
    n = max(2, int(seconds // window_s) // 2 * 2)
    for k in range(n):
        state = "on" if k % 2 else "off"
        if state == "on":
            control.start()
        ba.spin(app, TOGGLE_SETTLE_S)
        w0, c0, t0 = time.perf_counter(), time.process_time(), thread_cpu_s()
        ba.spin(app, max(0.5, window_s - TOGGLE_SETTLE_S))
        w1, c1, t1 = time.perf_counter(), time.process_time(), thread_cpu_s()
        spent[state].append((w1 - w0, c1 - c0, {name: t - t0.get(name, 0.0) for name, t in t1.items()}))
        if state == "on" and control.recording is not None:
            rec = control.recording
            control.stop()
            status = rec.status()
            written += status.messages
            dropped += status.dropped
            size += status.size
            events += status.events
            files.extend(status.files)
            if status.problem:
                problems.append(status.problem)

    def share(rows: list[tuple[float, float, dict[str, float]]]) -> float:
        return sum(cpu for _w, cpu, _t in rows) / sum(w for w, _c, _t in rows)

    def by_thread(rows: list[tuple[float, float, dict[str, float]]]) -> dict[str, float]:
        wall = sum(w for w, _c, _t in rows)
        names = {name for _w, _c, t in rows for name in t}
        out = {name: round(sum(t.get(name, 0.0) for _w, _c, t in rows) / wall, 3) for name in names}
        return dict(sorted(((k, v) for k, v in out.items() if v >= 0.002), key=lambda kv: -kv[1]))

    pairs = [round((on[1] / on[0]) / (off[1] / off[0]) * 100 - 100, 1)
             for off, on in zip(spent["off"], spent["on"], strict=True)]
    off, on = share(spent["off"]), share(spent["on"])
    return {"window_s": window_s, "pairs": len(pairs), "pairs_increase_pct": pairs,
            "increase_pct_median": round(statistics.median(pairs), 1),
            "cpu_share": {"off": round(off, 3), "on": round(on, 3)},
            "increase_pct_pooled": round((on / off - 1) * 100, 1),
            "by_thread": {"off": by_thread(spent["off"]), "on": by_thread(spent["on"])},
            "record": {"messages_written": written, "dropped": dropped, "bytes_on_disk": size,
                       "operator_events": events, "files": files, "problem": "; ".join(problems) or None}}


def run(args: Any) -> dict:
    """Run the fleet benchmark; returns the figures."""
    os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
    from qtpy import QtCore, QtWidgets
    from qtpy.QtTest import QTest

    from rcon_core.app.config import AppConfig
    from rcon_core.app.fleet_demo import connect_fleet, robot_id
    from rcon_core.app.main_window import MainWindow
    from rcon_core.bridge import BridgeClient, ConnectionState
    from rcon_core.gcpolicy import CollectorPolicy

    n = args.robots
    app = QtWidgets.QApplication.instance() or QtWidgets.QApplication([])
    figures: dict[str, Any] = {"robots": n, "values_per_robot": VALUES, "hz": args.hz,
                               "cameras_per_robot": {c: t for c, t, _ in CAMERAS}, "seconds": args.seconds,
                               "teleop_hz": TELEOP_HZ,
                               "background_load": getattr(args, "background_load", 0),
                               "load_average_before": [round(v, 2) for v in os.getloadavg()]}
    plugins = fleet_plugins()
    figures["latency_policy"] = not getattr(args, "no_latency_policy", False)
    with tempfile.TemporaryDirectory() as tmp, fleet_processes(n, args.hz, figures["latency_policy"],
                                                                not getattr(args, "no_malloc_policy", False)) as sims:
        # the collector policy the app's entry point gives its window (rcon_core/app/main.py)
        collector = None if args.no_gc_policy else CollectorPolicy()
        window = MainWindow(AppConfig(Path(tmp) / "cfg"), plugins, collector=collector)
        window.resize(1900, min(2000, 120 + n * ROW_H + 260))
        window.show()
        window.activateWindow()
        window.open_workspace(workspace(n, plugins))
        connect_fleet(window, [url for _, url, _ in sims])

        def all_connected() -> bool:
            links = [window.fleet_ui.links.link(robot_id(k)) for k in range(1, n + 1)]
            return all(lk.client is not None and lk.client.state == ConnectionState.CONNECTED for lk in links)

        if not ba.spin(app, 20, all_connected):
            raise RuntimeError("the app did not connect to every vessel")
        ba.spin(app, 1.0)
        figures["idle_rss_mb"] = round(ba.rss_mb(), 1)

        window.switch_canvas(1)
        probe = ba.make_paint_probe(window)
        cams: dict[str, Any] = {}  # widget id -> the newest frame handed to its view, not yet painted
        shown: dict[str, list[tuple[int, int, float, float]]] = {}  # id -> (index, dropped, stamp, painted)
        # (stamp, received, decoded, painted) of each frame shown, for where a camera frame's time goes
        stages: dict[str, list[tuple[float, float, float, float]]] = {}

        def on_paint(hosted: Any, state: Any) -> None:
            # (the value widgets' views note their own stamps in ba.PENDING)
            if hosted.widget.kind == "sensors.image" and state.value is not None:
                cams[hosted.widget.id] = state.value

        window.host.paint_hooks.append(on_paint)
        painted_at = [0]

        def camera_paints() -> None:  # after each paint pass: the frames it painted
            if ba.PASSES[0] == painted_at[0]:
                return
            painted_at[0] = ba.PASSES[0]
            now = time.time()
            for wid, frame in list(cams.items()):
                shown.setdefault(wid, []).append((frame.index, frame.dropped, frame.stamp or now, now))
                stages.setdefault(wid, []).append((frame.stamp or now, frame.received, frame.decoded, now))
            cams.clear()

        hosted = window.host.hosted
        ba.spin(app, 20, lambda: all(h.painted_seq > 2 for h in hosted.values() if h.widget.kind != "sensors.teleop"))
        # the teleop pad: held at 60% forward for the whole window
        pad = hosted["teleop-1"].view
        centre, radius = pad.pad()
        c = centre.toPoint()
        QTest.mousePress(pad, QtCore.Qt.MouseButton.LeftButton, pos=c)
        QTest.mouseMove(pad, c - QtCore.QPoint(0, int(radius * 0.6)))
        ba.spin(app, 0.5)

        stats_client = BridgeClient(sims[0][1], reconnect=False)
        bt = window.link.thread

        def sim_stats() -> list[dict]:
            async def get() -> list[dict]:
                out = []
                for name, url, _pid in sims:
                    c2 = stats_client if url == sims[0][1] else BridgeClient(url, reconnect=False)
                    if c2.state != ConnectionState.CONNECTED:
                        await c2.connect(timeout=5)
                    r = await c2.call_service(f"/{name}/bench/stats", {}, timeout=5)
                    out.append(json.loads(r["message"]))
                    if c2 is not stats_client:
                        await c2.close()
                return out

            return bt.run(get()).result(15)

        # how late a thread of the app wakes for something due (wake_probes.py): BENCH_PROBES=all adds the
        # raised thread and the hand-off to the loop beside the loop timer and the plain thread
        kinds = ("loop_timer", "thread") + (("thread_raised", "raised_to_loop")
                                           if os.environ.get("BENCH_PROBES") == "all" else ())
        probes = WakeProbes(bt.loop, kinds)
        probes.start()
        if os.environ.get("BENCH_SLOW_CALLBACKS"):  # diagnosis: log what holds the bridge loop over 4 ms
            import logging

            logging.basicConfig(level=logging.WARNING)
            bt.loop.call_soon_threadsafe(bt.loop.set_debug, True)
            bt.loop.slow_callback_duration = float(os.environ.get("BENCH_SLOW_CALLBACKS_S", "0.004"))
        gc_pauses: list[tuple[int, float]] = []  # (generation, ms) of each collection in the window
        gc_started = [0.0]

        def gc_watch(phase: str, info: dict) -> None:
            if phase == "start":
                gc_started[0] = time.perf_counter()
            else:
                gc_pauses.append((info["generation"], (time.perf_counter() - gc_started[0]) * 1000))

        gc.callbacks.append(gc_watch)
        # the measurement window
        ba.PAINTED.clear()
        ba.PASS_TIMES.clear()
        shown.clear()
        window.clock.work_times.clear()
        frame_busy: list[float] = []
        works = window.clock.work_times

        def measure_tick(_now: float) -> None:
            camera_paints()
            if works:
                frame_busy.append(works[-1] + ba.BUSY[0])
            ba.BUSY[0] = 0.0

        window.clock._consumers.insert(0, measure_tick)
        recording = os.environ.get("BENCH_RECORD_DIR")  # bench_record.py: the Record control on meanwhile
        toggle = float(os.environ.get("BENCH_RECORD_TOGGLE", "0") or 0)  # bench_record.py: on and off in turns
        if recording:
            window.record_control.directory = Path(recording)
            if not toggle:
                window.record_control.start()
        before = sim_stats()
        sim_cpu0 = [proc_cpu_s(pid) for _, _, pid in sims]
        threads0 = thread_cpu_s()
        t_start, cpu0, wall0 = time.time(), time.process_time(), time.perf_counter()
        check = QtCore.QTimer()
        check.timeout.connect(camera_paints)
        check.start(2)
        profiler = None
        if os.environ.get("BENCH_PROFILE"):  # diagnosis: cProfile of the GUI thread over the window
            import cProfile

            profiler = cProfile.Profile()
            profiler.enable()
        loop_profiler = None
        if os.environ.get("BENCH_PROFILE_BRIDGE"):  # diagnosis: cProfile of the bridge loop thread
            import cProfile

            loop_profiler = cProfile.Profile()
            bt.loop.call_soon_threadsafe(loop_profiler.enable)
        if recording and toggle:
            figures["record_toggle"] = record_toggle(app, window, args.seconds, toggle)
        else:
            ba.spin(app, args.seconds)
        if profiler is not None:
            profiler.disable()
            profiler.dump_stats(os.environ["BENCH_PROFILE"])
        if loop_profiler is not None:
            done = __import__("threading").Event()

            def stop_profile() -> None:
                loop_profiler.disable()
                done.set()

            bt.loop.call_soon_threadsafe(stop_profile)
            done.wait(5)
            loop_profiler.dump_stats(os.environ["BENCH_PROFILE_BRIDGE"])
        check.stop()
        probes.stop()
        gc.callbacks.remove(gc_watch)
        wall = time.perf_counter() - wall0
        cpu = (time.process_time() - cpu0) / wall
        sim_cpu = [(proc_cpu_s(pid) - c0) / wall for (_, _, pid), c0 in zip(sims, sim_cpu0, strict=True)]
        threads1 = thread_cpu_s()
        thread_share = {name: round((t - threads0.get(name, 0.0)) / wall, 3) for name, t in threads1.items()
                        if t - threads0.get(name, 0.0) > 0.005 * wall}
        after = sim_stats()
        t_end = time.time()
        QTest.mouseRelease(pad, QtCore.Qt.MouseButton.LeftButton, pos=c)
        window.removeEventFilter(probe)
        figures["load_average_after"] = [round(v, 2) for v in os.getloadavg()]
        if recording and not toggle and window.record_control.recording is not None:
            rec = window.record_control.recording
            status = rec.status()
            window.record_control.stop()
            figures["record"] = {"messages_written": rec.status().messages, "dropped": rec.status().dropped,
                                 "bytes_on_disk": rec.status().size, "operator_events": status.events,
                                 "files": list(rec.status().files), "problem": status.problem}

        # ---- cameras
        cameras: dict[str, dict] = {}
        cam_latencies: list[float] = []  # header stamp (the sim's capture: before drawing) to painted
        cam_pub_latencies: list[float] = []  # the sim's publish (drawn and encoded) to painted
        cam_stages: dict[str, list[float]] = {"publish_to_received": [], "received_to_decoded": [],
                                              "decoded_to_painted": []}
        for k in range(1, n + 1):
            for cam, topic, _type in CAMERAS:
                wid = f"cam-{k}-{cam}"
                rows = [r for r in shown.get(wid, []) if t_start <= r[3] <= t_end]
                published = after[k - 1]["published"].get(topic, 0) - before[k - 1]["published"].get(topic, 0)
                lat_ms = [(p - s) * 1000 for _i, _d, s, p in rows]
                cam_latencies.extend(lat_ms)
                published_at = {round(st, 4): wall for st, wall in after[k - 1]["camera_published"].get(topic, [])}
                pub_ms = [(p - published_at[round(s, 4)]) * 1000 for _i, _d, s, p in rows if round(s, 4) in published_at]
                cam_pub_latencies.extend(pub_ms)
                for st, rec, dec, painted in stages.get(wid, []):
                    pub = published_at.get(round(st, 4))
                    if pub is not None and t_start <= painted <= t_end:
                        cam_stages["publish_to_received"].append((rec - pub) * 1000)
                        cam_stages["received_to_decoded"].append((dec - rec) * 1000)
                        cam_stages["decoded_to_painted"].append((painted - dec) * 1000)
                first = [(p - s) * 1000 for _i, _d, s, p in rows if p - t_start <= 1.0]
                last = [(p - s) * 1000 for _i, _d, s, p in rows if t_end - p <= 1.0]
                # frames that reached the model (decoded or replaced in its latest-wins slot) in the window
                received = (rows[-1][0] + rows[-1][1]) - (rows[0][0] + rows[0][1]) + 1 if rows else 0
                count = len({r[0] for r in rows})
                cameras[f"boat{k}.{cam}"] = {
                    "published": published, "received": received, "shown": count,
                    "dropped_before_the_app": max(0, published - received),
                    "dropped_in_the_app": max(0, received - count),
                    "in_order": all(a[0] < b[0] for a, b in zip(rows, rows[1:], strict=False)),
                    # the newest frame shown at the end is fresh: latest wins, nothing queued behind it
                    "last_shown_age_ms": round((t_end - rows[-1][2]) * 1000, 1) if rows else float("nan"),
                    "latency_first_s_p50_ms": round(ba.pct(first, 50), 1),
                    "latency_last_s_p50_ms": round(ba.pct(last, 50), 1),
                    "latency_p99_ms": round(ba.pct(lat_ms, 99), 1),
                }
        figures["cameras"] = cameras
        # stale camera frames the bridge skipped before decoding (latest-only topics, rcon_core/bridge/latest.py)
        clients = [window.fleet_ui.links.link(robot_id(k)).client for k in range(1, n + 1)]
        figures["stale_skipped_by_the_bridge"] = sum(c.stats.get("stale_skipped", 0) for c in clients if c)
        # ---- teleop at the sim
        arrivals = [t for t in after[0]["cmd_vel_arrivals"] if t >= wall0 and t <= wall0 + wall]
        intervals = [(b - a) * 1000 for a, b in zip(arrivals, arrivals[1:], strict=False)]
        period_ms = 1000.0 / TELEOP_HZ
        jitter = [abs(i - period_ms) for i in intervals]
        # the same at the app: the model's clock when it handed each command to the link (what the sim's
        # figure adds to this is the way there: the app's socket write, loopback and the sim's loop)
        model = hosted["teleop-1"].model
        sent = [t for t in model.send_times if wall0 <= t <= wall0 + wall]
        app_jitter = [abs((b - a) * 1000 - period_ms) for a, b in zip(sent, sent[1:], strict=False)]
        sim_lags = [ms for t, ms in after[0]["loop_lag"] if wall0 <= t <= wall0 + wall]
        frames = [b * 1000 for b in frame_busy[1:]]
        wake = probes.figures()

        def lat(name: str, values: list[float]) -> dict:
            return {f"{name}_p{q}_ms": round(ba.pct(values, q), 2) for q in (50, 95, 99)}

        figures.update({
            "frame_p50_ms": round(ba.pct(frames, 50), 2),
            "frame_p95_ms": round(ba.pct(frames, 95), 2),
            **lat("paint_latency", [v * 1000 for v in ba.PAINTED]),
            **lat("camera_paint_latency", cam_latencies),
            **lat("camera_publish_to_painted", cam_pub_latencies),
            "camera_frames_matched_to_their_publish": len(cam_pub_latencies),
            # where a camera frame's time goes: the link and the bridge loop / the decode worker / the GUI
            "camera_stages_p50_p99_ms": {k: [round(ba.pct(v, 50), 1), round(ba.pct(v, 99), 1)]
                                         for k, v in cam_stages.items()},
            "paint_pass_p50_ms": round(ba.pct([v * 1000 for v in ba.PASS_TIMES], 50), 2),
            "paint_pass_p95_ms": round(ba.pct([v * 1000 for v in ba.PASS_TIMES], 95), 2),
            "paints": len(ba.PAINTED),
            "values_expected": int(n * VALUES * args.hz * args.seconds),
            "teleop_messages": len(arrivals),
            "teleop_interval_p50_ms": round(ba.pct(intervals, 50), 2),
            "teleop_interval_max_ms": round(max(intervals), 2) if intervals else float("nan"),
            "teleop_jitter_p99_ms": round(ba.pct(jitter, 99), 2),
            "teleop_jitter_p95_ms": round(ba.pct(jitter, 95), 2),
            "teleop_jitter_at_the_app_p99_ms": round(ba.pct(app_jitter, 99), 2),
            "teleop_jitter_at_the_app_max_ms": round(max(app_jitter), 2) if app_jitter else float("nan"),
            # what delays a command: the app's bridge loop (where the pad's ticker runs) and boat1's sim loop
            "app_bridge_loop_lag_p99_ms": wake["loop_timer"]["p99_ms"],
            "wake_lateness": wake,
            "sim1_loop_lag_p99_ms": round(ba.pct(sim_lags, 99), 2),
            "app_cpu_share": round(cpu, 3),
            # the garbage collector stops every thread of the app while it runs
            "gc_collections": len(gc_pauses),
            "gc_pause_max_ms": round(max((ms for _g, ms in gc_pauses), default=0.0), 2),
            "gc_pause_total_ms": round(sum(ms for _g, ms in gc_pauses), 1),
            "gc_gen2_pauses_ms": [round(ms, 1) for g, ms in gc_pauses if g == 2],
            "gc_policy": collector is not None,
            "gc_settle_pauses_ms": [round(ms, 1) for ms in collector.pauses_ms] if collector else [],
            "sim_cpu_share": [round(v, 3) for v in sim_cpu],
            # the app's CPU by thread (name; workers of a kind summed): MainThread = the GUI
            "app_cpu_share_by_thread": dict(sorted(thread_share.items(), key=lambda kv: -kv[1])),
            "camera_frames_shown_per_s": round(sum(c["shown"] for c in cameras.values()) / wall, 1),
            "app_cpu_ms_per_camera_frame_shown": round(
                cpu * wall * 1000 / max(1, sum(c["shown"] for c in cameras.values())), 2),
            "peak_rss_mb": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1),
        })
        with contextlib.suppress(Exception):
            bt.run(stats_client.close()).result(5)
        window.shutdown()
    for key, target in TARGETS.items():
        figures[f"{key}_target"] = target
        figures[f"{key}_ok"] = bool(figures.get(key, float("inf")) < target)
    figures["cameras_latest_shown"] = all(
        c["in_order"] and c["last_shown_age_ms"] < 500 for c in figures["cameras"].values())
    figures["cameras_no_backlog"] = all(
        not c["latency_last_s_p50_ms"] > 2 * c["latency_first_s_p50_ms"] + 20 for c in figures["cameras"].values())
    return figures


if __name__ == "__main__":  # run_all.py runs every bench_*.py: the fleet of 3 unless --robots says otherwise
    argv = sys.argv[1:]
    raise SystemExit(ba.main(argv if "--robots" in argv else [*argv, "--robots", "3"]))
