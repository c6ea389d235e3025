"""The app's parts of the reliability soak (issue 22): the GUI under one huge message and a flood, and the
app's memory per reconnect. Run by ``benchmarks/soak.py --parts gui reconnect`` (each part in a process
of its own, so its RSS and its GUI thread are its alone); also runnable alone:
``python benchmarks/soak_app.py gui|reconnect [--quick] [--out FILE]``.

* ``gui``: the main window (offscreen) shows a Text View bound to ``/soak/text``; the robot (the embedded
  sim in another process) sends one 5 MB ``std_msgs/String``, then floods the topic at 10,000 messages a
  second for a few seconds. Figures: the GUI's worst pass in each phase -- how long the GUI thread did not
  get back to its event loop, measured by a 5 ms timer's lateness (target < 50 ms) -- and what the stall
  watchdog did meanwhile (``stall_cuts``, ``degraded``: 0).
* ``reconnect``: the main window on the demo workspace (cameras, gauges, the pad...) connected through a
  loopback proxy that resets the link every ``period`` seconds. Figure: the app's RSS growth per
  reconnect, the slope of RSS over the reconnects after a warm-up (target < 0.05 MB per reconnect; the
  app grew 0.85 MB per reconnect while the collector froze each dropped connection's buffers).
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import re
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

TEXT_TOPIC = "/soak/text"
BIG = 5_000_000
FLOOD_HZ = 10_000


def rss_mb() -> float:
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    return float("nan")


def load() -> str:
    return " ".join(Path("/proc/loadavg").read_text().split()[:3])


# ------------------------------------------------------------------------------------------ the robot


def serve(proxy_period: float | None) -> None:
    """The robot process: a sim, (optionally) behind a proxy that cuts the link every ``proxy_period`` s;
    prints its URL, then takes commands on stdin: ``big``, ``flood HZ SECONDS``."""
    from rcon_core.loopback import StallProxy
    from rcon_core.sim import SimServer

    async def main() -> None:
        sim = SimServer(host="127.0.0.1", port=0)
        await sim.start()
        sim.advertise_internal(TEXT_TOPIC, "std_msgs/String", "/soak")
        url = sim.url
        proxy = None
        if proxy_period:
            proxy = await StallProxy("127.0.0.1", sim.port).start()
            url = proxy.url
        print(url, flush=True)
        loop = asyncio.get_running_loop()
        commands: asyncio.Queue[str] = asyncio.Queue()

        def read_stdin() -> None:
            for line in sys.stdin:
                loop.call_soon_threadsafe(commands.put_nowait, line.strip())
            loop.call_soon_threadsafe(commands.put_nowait, "quit")

        threading.Thread(target=read_stdin, daemon=True).start()

        async def cutter() -> None:
            while proxy is not None:
                await asyncio.sleep(proxy_period)
                proxy.cut()

        cuts = asyncio.ensure_future(cutter())
        while True:
            cmd = await commands.get()
            if cmd == "quit":
                break
            if cmd == "big":
                sim.publish(TEXT_TOPIC, {"data": "x" * BIG}, "/soak")
            elif cmd.startswith("flood"):
                _, hz, seconds = cmd.split()
                per_tick, tick = int(hz) // 100, 0.01
                end = loop.time() + float(seconds)
                n = 0
                while loop.time() < end:
                    t = loop.time()
                    for _ in range(per_tick):
                        n += 1
                        sim.publish(TEXT_TOPIC, {"data": f"flood line {n}"}, "/soak")
                    await asyncio.sleep(max(0.0, tick - (loop.time() - t)))
            print("done", flush=True)
        cuts.cancel()
        await sim.stop()

    asyncio.run(main())


class Robot:
    """The robot process, driven through its stdin; ``finished()`` says a command is done."""

    def __init__(self, proxy_period: float | None = None) -> None:
        cmd = [sys.executable, __file__, "serve"] + (["--period", str(proxy_period)] if proxy_period else [])
        self.proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        line = self.proc.stdout.readline() if self.proc.stdout else ""
        match = re.search(r"ws://\S+", line)
        if not match:
            self.proc.kill()
            raise RuntimeError(f"the robot did not start: {line!r}")
        self.url = match.group(0)
        self._done = 0
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            if line.strip() == "done":
                self._done += 1

    def send(self, cmd: str) -> int:
        """Send a command; returns the count ``finished`` waits for."""
        assert self.proc.stdin is not None
        self.proc.stdin.write(cmd + "\n")
        self.proc.stdin.flush()
        return self._done + 1

    def finished(self, count: int) -> bool:
        return self._done >= count

    def stop(self) -> None:
        try:
            self.send("quit")
            self.proc.wait(10)
        except Exception:  # noqa: BLE001 - it is going anyway
            self.proc.kill()


# ------------------------------------------------------------------------------------------ the app


class Lateness:
    """How late a 5 ms timer in the GUI thread fires: the GUI's longest pass, phase by phase."""

    def __init__(self, qt: Any) -> None:
        QtCore = qt  # noqa: N806 - the module
        self.gaps: list[float] = []
        self._last = time.perf_counter()
        self.timer = QtCore.QTimer()
        self.timer.setTimerType(QtCore.Qt.TimerType.PreciseTimer)
        self.timer.setInterval(5)
        self.timer.timeout.connect(self._tick)
        self.timer.start()

    def _tick(self) -> None:
        now = time.perf_counter()
        self.gaps.append(max(0.0, now - self._last - 0.005))
        self._last = now

    def take(self) -> list[float]:
        out, self.gaps = self.gaps, []
        return out


def _window(workspace: Any, plugins: Any, collector: Any = None) -> Any:
    from rcon_core.app.config import AppConfig
    from rcon_core.app.main_window import MainWindow

    window = MainWindow(AppConfig(Path(tempfile.mkdtemp(prefix="rcon-soak-")) / "cfg"), plugins,
                        demo=lambda: workspace, collector=collector)
    window.resize(1280, 800)
    window.show()
    return window


def _pump(app: Any, seconds: float, until: Any = None) -> bool:
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        app.processEvents()
        if until is not None and until():
            return True
        time.sleep(0.002)
    return until() if until is not None else True


def part_gui(quick: bool) -> dict[str, Any]:
    os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
    from qtpy import QtCore, QtWidgets

    from rcon_core.bridge import ConnectionState
    from rcon_core.canvas import Binding, Canvas, Geometry, WidgetInstance, Workspace
    from rcon_core.plugins import PluginManager

    app = QtWidgets.QApplication.instance() or QtWidgets.QApplication([])
    plugins = PluginManager(environ={})
    plugins.load_entry_points()
    canvas = Canvas("c-soak", "Soak", [WidgetInstance("w-text", "std.textview",
                                                      Binding(TEXT_TOPIC, "std_msgs/String", "subscribe"),
                                                      Geometry(24, 24, 520, 400), {"max_lines": 1000}, "Text")])
    robot = Robot()
    window = _window(Workspace([canvas], canvas.id), plugins)
    try:
        window.connect_to(robot.url)
        assert _pump(app, 30, lambda: window.connection.state is ConnectionState.CONNECTED), "not connected"
        hosted = window.host.hosted["w-text"]
        assert _pump(app, 30, lambda: hosted.view is not None), "no Text View"
        _pump(app, 2.0)
        client = window.link.client
        stats0 = dict(client.stats)
        late = Lateness(QtCore)
        _pump(app, 1.0)
        idle = late.take()
        # one 5 MB String: until the view has painted it, and 2 s more
        t0 = time.perf_counter()
        robot.send("big")
        shown = _pump(app, 120, lambda: hosted.model.state.count >= 1
                      and hosted.painted_seq == hosted.model.state.seq)
        shown_s = time.perf_counter() - t0
        _pump(app, 2.0)
        big = late.take()
        stats1 = dict(client.stats)
        # 10,000 messages a second for a few seconds, and 2 s after
        seconds = 2.0 if quick else 5.0
        before = hosted.model.state.count
        wanted = robot.send(f"flood {FLOOD_HZ} {seconds}")
        t1 = time.perf_counter()
        _pump(app, seconds + 60, lambda: robot.finished(wanted))
        flood_s = time.perf_counter() - t1
        _pump(app, 2.0)
        flood = late.take()
        stats2 = dict(client.stats)
        received = hosted.model.state.count - before
        painted_text = hosted.view.history.toPlainText().splitlines()[-1:] if hosted.view is not None else []
    finally:
        window.shutdown()
        robot.stop()
    return {
        "idle_worst_gui_pass_ms": _ms(idle),
        "text_5mb_shown": shown, "text_5mb_shown_after_s": round(shown_s, 2),
        "text_5mb_worst_gui_pass_ms": _ms(big), "text_5mb_gui_pass_p99_ms": _p99(big),
        "text_5mb_stall_cuts": stats1["stall_cuts"] - stats0["stall_cuts"],
        "text_5mb_degraded": stats1["degraded"] - stats0["degraded"],
        "flood_hz": FLOOD_HZ, "flood_s": seconds, "flood_sent_in_s": round(flood_s, 2),
        "flood_messages_received": received,
        "flood_worst_gui_pass_ms": _ms(flood), "flood_gui_pass_p99_ms": _p99(flood),
        "flood_stall_cuts": stats2["stall_cuts"] - stats1["stall_cuts"],
        "flood_degraded": stats2["degraded"] - stats1["degraded"],
        "last_line_painted": painted_text[0][:40] if painted_text else None,
        "load": load(),
    }


def part_reconnect(quick: bool, period: float = 3.0) -> dict[str, Any]:
    """The demo workspace through a proxy that cuts the link every ``period`` s: RSS per reconnect."""
    os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
    from qtpy import QtWidgets

    from rcon_core.app.demo import demo_workspace
    from rcon_core.bridge import ConnectionState
    from rcon_core.gcpolicy import CollectorPolicy
    from rcon_core.plugins import PluginManager

    app = QtWidgets.QApplication.instance() or QtWidgets.QApplication([])
    plugins = PluginManager(environ={})
    plugins.load_entry_points()
    robot = Robot(proxy_period=period)
    window = _window(demo_workspace(plugins), plugins, collector=CollectorPolicy())  # as `rcon` runs
    cycles = 12 if quick else 60
    warm = 4
    samples: list[tuple[int, float]] = []
    try:
        window.connect_to(robot.url)
        client = window.link.client
        assert _pump(app, 30, lambda: window.connection.state is ConnectionState.CONNECTED), "not connected"
        started = time.monotonic()
        deadline = started + cycles * period * 3 + 60
        while client.stats["connects"] <= cycles and time.monotonic() < deadline:
            seen = client.stats["connects"]
            _pump(app, period * 3, lambda seen=seen: client.stats["connects"] > seen
                  and window.connection.state is ConnectionState.CONNECTED)
            _pump(app, period * 0.5)  # the widgets streaming again, the collector's settle after connect
            samples.append((client.stats["connects"], rss_mb()))
        connects = client.stats["connects"]
        seconds = time.monotonic() - started
    finally:
        window.shutdown()
        robot.stop()
    use = [(c, mb) for c, mb in samples if c > warm]
    slope = _slope(use)
    return {"period_s": period, "reconnects": connects - 1, "seconds": round(seconds, 1),
            "rss_first_mb": round(samples[0][1], 1) if samples else None,
            "rss_after_warmup_mb": round(use[0][1], 1) if use else None,
            "rss_last_mb": round(samples[-1][1], 1) if samples else None,
            "rss_per_reconnect_mb": None if slope is None else round(slope, 4),
            "samples": len(use), "load": load()}


def _slope(points: list[tuple[int, float]]) -> float | None:
    """Least-squares slope of RSS (MB) over the reconnect count."""
    if len(points) < 3:
        return None
    n = len(points)
    mx = sum(x for x, _ in points) / n
    my = sum(y for _, y in points) / n
    var = sum((x - mx) ** 2 for x, _ in points)
    return sum((x - mx) * (y - my) for x, y in points) / var if var else None


def _ms(values: list[float]) -> float:
    return round(max(values, default=0.0) * 1000, 1)


def _p99(values: list[float]) -> float:
    if not values:
        return 0.0
    values = sorted(values)
    return round(values[int(0.99 * (len(values) - 1))] * 1000, 1)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("part", choices=["gui", "reconnect", "serve"])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--period", type=float, default=None, help="serve: cut the link every PERIOD s")
    parser.add_argument("--out", type=Path)
    args = parser.parse_args(argv)
    if args.part == "serve":
        serve(args.period)
        return 0
    import logging

    logging.basicConfig(level=logging.ERROR)  # the cuts are the point here: no warning per reconnect
    if args.part == "gui":
        result = part_gui(args.quick)
    else:
        result = part_reconnect(args.quick, period=2.0 if args.quick else 3.0)
    print(json.dumps(result), flush=True)
    if args.out:
        args.out.write_text(json.dumps(result, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
