"""Benchmark of the app on the embedded robot: 50 live widgets at 20 Hz each.

Figures (latencies p50/p95/p99, from the publish time stamp carried in the message):

- ``paint_latency_*`` (the figure the target is set on): publish to *painted*: until the end of the Qt
  paint pass that painted the widget (the window's UpdateRequest: layout, every paintEvent of the batch,
  and the flush of the backing store);
- ``view_paint_latency_*`` (``--view label`` only): publish to the end of the view's own paintEvent;
- ``latency_*``: publish to the host handing the new state to the view (``view.refresh(state)``);
- frame time per display frame p50/p95: the frame clock's work, the wake-up passes the bridge thread
  triggered and Qt's paint passes (whole, not only the views' paint events);
- CPU share, peak memory, start-up time to the first painted canvas, idle memory.

``--view label`` (default) shows each value in a plain QLabel subclass under the app's theme;
``--view std.label`` uses the real Label widget of ``rcon_widgets_std`` (value + age caption).
Usage: ``QT_QPA_PLATFORM=offscreen python benchmarks/bench_app.py [--widgets 50] [--hz 20] [--seconds 8]
[--view label|std.label] [--operator] [--no-gc-policy] [--no-latency-policy] [--background-load N]
[--out FILE.json]``.

``--background-load N`` runs N busy processes (one core each, ``background_load.py``) for the whole run,
as other work on the machine would; they are ended when the benchmark ends, however it ends.

``--robots N`` runs the fleet benchmark instead (``bench_fleet.py``: N vessels, each a sim in its own
process with two cameras and 20 values at 20 Hz, one window, a held teleop pad; the JSON has ``robots``).
"""

from __future__ import annotations

import argparse
import contextlib
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

TARGETS = {"frame_p95_ms": 16.0, "paint_latency_p99_ms": 20.0, "startup_s": 1.5, "idle_rss_mb": 150.0}


def rss_mb() -> float:
    with open("/proc/self/statm") as f:
        pages = int(f.read().split()[1])
    return pages * os.sysconf("SC_PAGE_SIZE") / 2**20


def pct(values: list[float], q: float) -> float:
    if not values:
        return float("nan")
    values = sorted(values)
    return values[min(len(values) - 1, int(q / 100 * len(values)))]


BUSY = [0.0]  # seconds spent in Qt paint passes and wake-up passes since the last frame tick
PAINTED: list[float] = []  # publish to the end of the paint pass that painted the value (s)
VIEW_PAINTED: list[float] = []  # publish to the end of the view's own paintEvent (s), --view label
PENDING: dict[int, float] = {}  # view id -> publish stamp of the oldest value refreshed but not yet painted
PASSES = [0]
PASS_TIMES: list[float] = []  # duration of each paint pass (s)


def value_stamp(state) -> float | None:
    """The publish time stamp (perf_counter) carried by the message behind ``state``."""
    msg = state.message
    data = msg.get("data") if isinstance(msg, dict) else None
    if isinstance(data, float) and data > 0:
        return data
    return None


def make_paint_probe(window):
    """An event filter on the top-level window that runs Qt's paint pass itself (the window's
    UpdateRequest: deferred layout, every dirty widget's paintEvent, flush) and times it: the end of the
    pass is when every value refreshed before it is painted."""
    from qtpy import QtCore

    class PaintProbe(QtCore.QObject):
        def eventFilter(self, obj, event) -> bool:  # noqa: N802 - Qt's name
            if obj is window and event.type() == QtCore.QEvent.Type.UpdateRequest:
                t = time.perf_counter()
                window.event(event)
                end = time.perf_counter()
                BUSY[0] += end - t
                PASSES[0] += 1
                PASS_TIMES.append(end - t)
                PAINTED.extend(end - stamp for stamp in PENDING.values())
                PENDING.clear()
                return True
            return False

    probe = PaintProbe()
    window.installEventFilter(probe)
    return probe


def spin(app, seconds: float, until=None) -> bool:
    """Run the Qt event loop for up to ``seconds`` (or until ``until()``), the way the app runs it.

    (``QApplication.processEvents()`` is avoided: in PySide6 6.12 each call drops a reference to None.)
    """
    from qtpy import QtCore

    loop = QtCore.QEventLoop()
    end = time.monotonic() + seconds
    check = QtCore.QTimer()
    check.setInterval(5)

    def poll() -> None:
        if time.monotonic() >= end or (until is not None and until()):
            loop.quit()

    check.timeout.connect(poll)
    check.start()
    loop.exec()
    check.stop()
    return until() if until is not None else True


@contextlib.contextmanager
def sim_url(in_process: bool):
    """The embedded robot's URL: in its own process by default (so the figures are the app's own
    memory and CPU, as on a real robot), or in this process with ``in_process``."""
    if in_process:
        from rcon_core.sim.server import SimServer

        with SimServer.in_thread(port=0) as server:
            yield server.url
        return
    proc = subprocess.Popen([sys.executable, "-m", "rcon_core", "sim", "--port", "0"], stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True)
    try:
        line = proc.stdout.readline() if proc.stdout else ""
        match = re.search(r"ws://\S+", line)
        if not match:
            raise RuntimeError(f"the simulator did not start: {line!r}")
        yield match.group(0)
    finally:
        proc.terminate()
        proc.wait(10)


def make_plugins(view: str = "label"):
    import attrs
    from qtpy import QtWidgets

    from rcon_core.plugins import Accepts, PluginManager, Role, WidgetModel, WidgetSpec, hookimpl

    @attrs.define
    class BenchSettings:
        def problems(self) -> list[str]:
            return []

    class BenchView(QtWidgets.QLabel):
        def __init__(self, model) -> None:
            super().__init__("—")
            self.stamp = 0.0  # publish time of the value shown, until its paintEvent ends

        def paintEvent(self, event) -> None:  # noqa: N802 - Qt's name
            super().paintEvent(event)
            if self.stamp:
                VIEW_PAINTED.append(time.perf_counter() - self.stamp)
                self.stamp = 0.0

        def refresh(self, state) -> None:
            stamp = value_stamp(state)
            if stamp is not None:
                self.setText(f"{state.value:.4f}")
                self.stamp = self.stamp or stamp
                PENDING.setdefault(id(self), stamp)
            else:
                self.setText("—")

    mod = sys.modules[__name__]
    mod.BenchView = BenchView  # the spec names it lazily as module:attr
    if view == "std.label":
        from rcon_widgets_std.label import LabelModel, LabelSettings
        from rcon_widgets_std.label_view import LabelView

        class BenchLabelView(LabelView):
            """The real Label view; only notes the stamp of each value it is given."""

            def refresh(self, state) -> None:
                super().refresh(state)
                stamp = value_stamp(state)
                if stamp is not None:
                    PENDING.setdefault(id(self), stamp)

        mod.BenchLabelView = BenchLabelView
        spec = WidgetSpec(kind="bench.value", title="Value", model=LabelModel, view=f"{__name__}:BenchLabelView",
                          roles={Role.SUBSCRIBE}, accepts=Accepts(fields=["float"]), settings=LabelSettings,
                          default_size=(160, 80))
    else:
        spec = WidgetSpec(kind="bench.value", title="Value", model=WidgetModel, view=f"{__name__}:BenchView",
                          roles={Role.SUBSCRIBE}, accepts=Accepts(fields=["float"]), settings=BenchSettings,
                          default_size=(160, 80))

    class Plugin:
        @hookimpl
        def rcon_register_widgets(self, registry) -> None:
            registry.add(spec)

    pm = PluginManager(environ={})
    pm.register(Plugin(), name="bench")
    return pm


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--widgets", type=int, default=50)
    parser.add_argument("--hz", type=float, default=20.0)
    parser.add_argument("--seconds", type=float, default=8.0)
    parser.add_argument("--out", type=Path)
    parser.add_argument("--view", choices=["label", "std.label"], default="label",
                        help="the widget shown: a plain themed QLabel, or the real std Label widget")
    parser.add_argument("--operator", action="store_true", help="operator (locked) mode instead of edit mode")
    parser.add_argument("--in-process-sim", action="store_true",
                        help="run the simulated robot in this process (its memory and CPU then count too)")
    parser.add_argument("--no-gc-policy", action="store_true",
                        help="leave the garbage collector at Python's defaults (rcon_core/gcpolicy.py)")
    parser.add_argument("--no-latency-policy", action="store_true",
                        help="leave thread priorities and the GIL's switch interval as they were before "
                             "rcon_core/priority.py's favour_latency (the GUI, bridge and sim loop threads not "
                             "raised); bulk threads are still lowered")
    parser.add_argument("--robots", type=int, metavar="N",
                        help="the fleet benchmark: N vessels in their own processes (see bench_fleet.py)")
    parser.add_argument("--no-malloc-policy", action="store_true",
                        help="leave glibc's allocator at its defaults (rcon_core/mallocpolicy.py), app and sims")
    parser.add_argument("--background-load", type=int, default=0, metavar="N",
                        help="N busy processes (0-8) beside the benchmark for the whole run, ended with it")
    args = parser.parse_args(argv)
    os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from background_load import MAX_PROCESSES, busy_processes

    if not 0 <= args.background_load <= MAX_PROCESSES:
        parser.error(f"--background-load must be from 0 to {MAX_PROCESSES}")
    if args.robots is not None and not 1 <= args.robots <= 6:
        parser.error("--robots must be from 1 to 6")
    with busy_processes(args.background_load, max_seconds=3 * args.seconds + 180):
        return run(args)


def latency_policy(off: bool) -> None:
    """What the app's entry point does (rcon_core/priority.py), or with ``off`` what it did before."""
    from rcon_core import priority

    if off:
        priority.raise_this_thread = lambda: False  # the bridge thread and the sim's loop thread too
    else:
        priority.favour_latency()


def run(args: argparse.Namespace) -> int:
    latency_policy(args.no_latency_policy)
    if not args.no_malloc_policy:
        from rcon_core.mallocpolicy import keep_big_blocks

        keep_big_blocks()  # as the app's entry point does (rcon_core/mallocpolicy.py)
    if args.robots is not None:
        import bench_fleet

        figures = bench_fleet.run(args)
        for key, value in figures.items():
            print(f"{key:36s} {value}")
        if args.out:
            args.out.write_text(json.dumps(figures, indent=2))
        return 0

    t0 = time.perf_counter()
    from qtpy import QtWidgets

    from rcon_core.app.config import AppConfig
    from rcon_core.app.main_window import MainWindow
    from rcon_core.bridge import BridgeClient, ConnectionState
    from rcon_core.canvas import Canvas, Geometry, WidgetInstance, Workspace
    from rcon_core.plugins import Binding, Role

    app = QtWidgets.QApplication.instance() or QtWidgets.QApplication([])
    figures: dict = {"widgets": args.widgets, "hz": args.hz, "view": args.view,
                     "background_load": args.background_load,
                     "mode": "operator" if args.operator else "edit",
                     "sim": "in process" if args.in_process_sim else "own process"}
    with tempfile.TemporaryDirectory() as tmp, sim_url(args.in_process_sim) as url:
        # ---- start-up to the first painted (empty) canvas, and idle memory
        t_start = time.perf_counter()
        from rcon_core.gcpolicy import CollectorPolicy

        window = MainWindow(AppConfig(Path(tmp) / "cfg"), make_plugins(args.view),
                            collector=None if args.no_gc_policy else CollectorPolicy())
        window.show()
        spin(app, 10, lambda: window.first_paint_at is not None)
        figures["startup_s"] = round(window.first_paint_at - t_start, 3)
        figures["startup_with_imports_s"] = round(window.first_paint_at - t0, 3)
        window.connect_to(url)
        spin(app, 10, lambda: window.connection.state is ConnectionState.CONNECTED)
        spin(app, 1.0)
        figures["idle_rss_mb"] = round(rss_mb(), 1)

        # ---- 50 widgets, each on its own topic published at 20 Hz by a separate client
        topics = [f"/bench/v{i}" for i in range(args.widgets)]
        canvas = Canvas("c-bench", "Bench")
        # a grid of frames that do not overlap (overlapping frames repaint each other), all on screen:
        # 160 x 112 is about the smallest frame at 48 px touch targets
        cols = 8
        for i, topic in enumerate(topics):
            x, y = 16 + (i % cols) * 168, 16 + (i // cols) * 128
            canvas.widgets.append(WidgetInstance(
                f"w-{i}", "bench.value", Binding(topic, "std_msgs/Float64", Role.SUBSCRIBE, ("data",)),
                Geometry(x, y, 160, 112), {}, topic))
        window.resize(1700, 1100)
        window.open_workspace(Workspace([canvas], canvas.id))
        if args.operator:
            window.lock_button.setChecked(True)
        probe = make_paint_probe(window)

        latencies: list[float] = []

        def on_paint(hosted, state) -> None:
            stamp = value_stamp(state)
            if stamp is not None:
                latencies.append(time.perf_counter() - stamp)

        window.host.paint_hooks.append(on_paint)

        bt = window.link.thread
        pub_client = BridgeClient(url, reconnect=False)

        async def publisher() -> None:
            import asyncio

            await pub_client.connect()
            node = pub_client.node("bench-publisher")
            pubs = [node.advertise(t, "std_msgs/Float64") for t in topics]
            await asyncio.sleep(0.5)
            period = 1.0 / args.hz
            nxt = time.perf_counter()
            while True:
                for p in pubs:
                    p.publish({"data": time.perf_counter()})
                nxt += period
                await asyncio.sleep(max(0.0, nxt - time.perf_counter()))

        task = bt.run(publisher())
        # warm up until every widget painted once
        spin(app, 10, lambda: sum(1 for h in window.host.hosted.values() if h.painted_seq > 2) >= args.widgets)
        frames_geo = [h.frame.geometry() for h in window.host.hosted.values()]
        figures["overlapping_frames"] = sum(1 for i, a in enumerate(frames_geo) for b in frames_geo[i + 1:]
                                            if a.intersects(b))
        surface = next(iter(window.host.hosted.values())).frame.parentWidget()
        figures["frames_off_screen"] = sum(1 for g in frames_geo if not surface.rect().contains(g))
        latencies.clear()
        PAINTED.clear()
        VIEW_PAINTED.clear()
        PASS_TIMES.clear()
        passes0 = PASSES[0]
        window.clock.work_times.clear()
        window.clock.gaps.clear()
        wakes0 = window.waker.wakes

        # wake-up passes (outside the clock tick) count as frame work too
        pump = window._pump

        def timed_pump(ids=None) -> None:
            t = time.perf_counter()
            pump(ids)
            BUSY[0] += time.perf_counter() - t

        window.waker.handler = timed_pump
        window._due_timer.timeout.disconnect()
        window._due_timer.timeout.connect(lambda: timed_pump(set()))

        # frame time: the clock's work plus the paint passes and wake-ups that follow it, per frame
        frame_busy: list[float] = []
        works = window.clock.work_times

        def measure_tick(_now: float) -> None:
            # called first in a tick: the previous tick's work plus the paints that followed it
            if works:
                frame_busy.append(works[-1] + BUSY[0])
            BUSY[0] = 0.0

        window.clock._consumers.insert(0, measure_tick)
        cpu0, wall0 = time.process_time(), time.perf_counter()
        spin(app, args.seconds)
        cpu = (time.process_time() - cpu0) / (time.perf_counter() - wall0)
        task.cancel()
        works_ms = [w * 1000 for w in window.clock.work_times]
        frames = [b * 1000 for b in frame_busy[1:]]
        window.removeEventFilter(probe)

        def lat(name: str, values: list[float]) -> dict:
            ms = [v * 1000 for v in values]
            return {f"{name}_p{q}_ms": round(pct(ms, q), 2) for q in (50, 95, 99)}

        figures.update({
            "frame_work_p50_ms": round(pct(works_ms, 50), 2),
            "frame_work_p95_ms": round(pct(works_ms, 95), 2),
            "frame_p50_ms": round(pct(frames, 50), 2),
            "frame_p95_ms": round(pct(frames, 95), 2),
            "frame_interval_p50_ms": round(pct([g * 1000 for g in window.clock.gaps], 50), 2),
            **lat("paint_latency", PAINTED),
            **(lat("view_paint_latency", VIEW_PAINTED) if args.view == "label" else {}),
            **lat("latency", latencies),
            "refreshes": len(latencies),
            "paints": len(PAINTED),
            "paint_passes_per_s": round((PASSES[0] - passes0) / args.seconds, 1),
            "paint_pass_p50_ms": round(pct([v * 1000 for v in PASS_TIMES], 50), 2),
            "paint_pass_p95_ms": round(pct([v * 1000 for v in PASS_TIMES], 95), 2),
            "wakes_per_s": round((window.waker.wakes - wakes0) / args.seconds, 1),
            "messages_expected": int(args.widgets * args.hz * args.seconds),
            "cpu_share": round(cpu, 3),
            "peak_rss_mb": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1),
        })
        try:
            bt.run(pub_client.close()).result(5)
        except Exception:
            pass
        window.shutdown()
    figures["median_frame_budget_ok"] = statistics.median(frames or [0]) < 16
    for key, target in TARGETS.items():
        figures[f"{key}_target"] = target
        figures[f"{key}_ok"] = bool(figures.get(key, float("inf")) < target)
    for key, value in figures.items():
        print(f"{key:28s} {value}")
    if args.out:
        args.out.write_text(json.dumps(figures, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
