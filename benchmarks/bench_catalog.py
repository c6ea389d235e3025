"""Discovery at scale (issue 22.6): a robot with 10^5 topics and 10^5 services, listed by the app's link and
shown in the side panel.

Usage: ``python benchmarks/bench_catalog.py [--names 100000] [--quick] [--out FILE]``.

The robot is the embedded sim in its own process (``--serve``), with ``--names`` extra topics and services
added through its graph API (``advertise_internal``, ``add_service``: no test hook in the sim). The app
side runs the real :class:`rcon_core.app.link.RobotConnection` (its bridge thread, its catalogue loop) and, in the GUI
thread, the real side-panel lists (:class:`rcon_core.app.catalog_panel.CatalogList`).

Figures:

* ``bridge``: seconds until the first complete catalogue (every service's type known), rosapi calls made
  for it and for the next refresh (unchanged lists: no ``service_type`` call again), the bridge loop's
  worst lateness (a 10 ms ticker on the bridge thread: how long the loop was held) and the stall watchdog's
  cuts (``stall_cuts``, target 0).
* ``panel``: the GUI's worst pass while the lists fill with 10^5 rows, one pass to add one topic to a full
  list, one filter keystroke, one rates update (target: every pass under 50 ms).

Timing figures on a shared machine are noisy: the load average is printed with them.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import re
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

TARGETS = {"loop_worst_lateness_ms": 250.0, "stall_cuts": 0, "panel_worst_pass_ms": 50.0}


def serve(names: int) -> None:
    """The robot: a sim with ``names`` more topics and services (prints its URL, serves until killed)."""
    from rcon_core.sim import SimServer

    async def main() -> None:
        sim = SimServer(host="127.0.0.1", port=0)
        await sim.start()
        for i in range(names):
            sim.advertise_internal(f"/bench/topic_{i:06d}", "std_msgs/Float64", "/bench")
            sim.add_service(f"/bench/service_{i:06d}", "std_srvs/Trigger", "/bench",
                            lambda _req: {"success": True, "message": ""})
        print(sim.url, flush=True)
        await asyncio.Event().wait()

    asyncio.run(main())


def load() -> str:
    return " ".join(Path("/proc/loadavg").read_text().split()[:3])


class Robot:
    """The sim process."""

    def __init__(self, names: int) -> None:
        self.proc = subprocess.Popen([sys.executable, __file__, "--serve", "--names", str(names)],
                                     stdout=subprocess.PIPE, text=True)
        line = self.proc.stdout.readline() if self.proc.stdout else ""
        match = re.search(r"ws://\S+", line)
        if not match:
            self.proc.kill()
            raise RuntimeError(f"the sim did not start: {line!r}")
        self.url = match.group(0)

    def stop(self) -> None:
        self.proc.kill()
        self.proc.wait(10)


def bench_bridge(url: str, names: int, seconds: float) -> dict[str, Any]:
    """The app's RobotConnection lists the robot: time to the full catalogue, calls, loop lateness, stall cuts."""
    from rcon_core.app.link import RobotConnection

    link = RobotConnection()
    lateness: list[float] = []

    async def ticker() -> None:
        loop = asyncio.get_running_loop()
        while True:
            due = loop.time() + 0.01
            await asyncio.sleep(0.01)
            lateness.append(max(0.0, loop.time() - due))

    tick = link.thread.run(ticker())
    t0 = time.perf_counter()
    link.connect_to(url)
    full_at = None
    catalogs = 0
    deadline = t0 + seconds
    calls_first: dict[str, int] = {}
    while time.perf_counter() < deadline:
        ok, catalog = link.catalog_box.take()
        if ok and catalog.get("services"):
            catalogs += 1
            known = sum(1 for _n, t in catalog["services"] if t)
            if full_at is None and known >= names and len(catalog["topics"]) >= names:
                full_at = time.perf_counter() - t0
                calls_first = dict(getattr(link.client.rosapi, "calls", {}))
                break
        time.sleep(0.05)
    # the next refresh of unchanged lists: which calls does it make?
    rosapi = link.client.rosapi if link.client is not None else None
    before = dict(getattr(rosapi, "calls", {}))
    refreshed = time.perf_counter()
    while time.perf_counter() < refreshed + 15 and full_at is not None:
        now = dict(getattr(rosapi, "calls", {}))
        if now.get("services", 0) > before.get("services", 0) and now.get("topics", 0) > before.get("topics", 0):
            time.sleep(1.0)  # let that refresh finish
            break
        time.sleep(0.1)
    after = dict(getattr(rosapi, "calls", {}))
    stats = dict(link.client.stats) if link.client is not None else {}
    tick.cancel()
    link.shutdown()
    return {
        "names": names,
        "first_full_catalogue_s": None if full_at is None else round(full_at, 2),
        "catalogues_published_until_then": catalogs,
        "rosapi_calls_for_the_first": calls_first,
        "rosapi_calls_for_the_next_refresh": {k: after.get(k, 0) - before.get(k, 0) for k in after
                                              if after.get(k, 0) != before.get(k, 0)},
        "loop_worst_lateness_ms": round(max(lateness, default=0.0) * 1000, 1),
        "loop_lateness_p99_ms": round(sorted(lateness)[int(0.99 * (len(lateness) - 1))] * 1000, 1) if lateness else None,
        "stall_cuts": stats.get("stall_cuts", 0), "degraded": stats.get("degraded", 0),
        "connects": stats.get("connects", 0),
    }


def bench_panel(names: int) -> dict[str, Any]:
    """The side panel's lists with ``names`` topics: the GUI's worst pass while filling, and per change."""
    os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
    from qtpy import QtWidgets

    from rcon_core.app.catalog_panel import CatalogList

    app = QtWidgets.QApplication.instance() or QtWidgets.QApplication([])
    lst = CatalogList("topics", with_rate=True)
    lst.resize(320, 700)
    lst.show()
    app.processEvents()
    entries = [(f"/bench/topic_{i:06d}", "std_msgs/Float64") for i in range(names)]
    passes: list[float] = []

    def timed(fn: Any) -> float:
        t = time.perf_counter()
        fn()
        app.processEvents()
        dt = time.perf_counter() - t
        passes.append(dt)
        return dt

    t0 = time.perf_counter()
    timed(lambda: lst.set_entries(entries))
    while getattr(lst, "filling", False) and time.perf_counter() - t0 < 120:
        timed(lambda: None)  # the frames that follow: the list fills a slice per pass
        time.sleep(0.016)
    filled_s = time.perf_counter() - t0
    fill_worst = max(passes)
    more = sorted([*entries, ("/bench/topic_000500_b", "std_msgs/String")])
    add_one = timed(lambda: lst.set_entries(more))
    same = timed(lambda: lst.set_entries(list(more)))
    key = timed(lambda: lst.filter.setText("topic_0995"))
    searched = time.perf_counter()
    while lst.filling and time.perf_counter() - searched < 60:
        timed(lambda: None)
        time.sleep(0.016)
    search_s = time.perf_counter() - searched
    found = lst.tree.topLevelItemCount()
    clear = timed(lambda: lst.filter.setText(""))
    rates = timed(lambda: lst.set_rates({"/bench/topic_000001": 10.0, "/bench/topic_099999": 2.5}))
    shown = lst.item("/bench/topic_000500_b") is not None
    return {"rows": names, "fill_s": round(filled_s, 2), "fill_worst_pass_ms": round(fill_worst * 1000, 1),
            "add_one_topic_ms": round(add_one * 1000, 1), "same_list_again_ms": round(same * 1000, 1),
            "filter_keystroke_ms": round(key * 1000, 1), "search_done_s": round(search_s, 2),
            "search_found": found, "filter_cleared_ms": round(clear * 1000, 1),
            "rates_update_ms": round(rates * 1000, 1), "added_topic_listed": shown,
            "rows_shown": lst.tree.topLevelItemCount(), "note_under_the_list": lst.more.text(),
            "panel_worst_pass_ms": round(max(passes) * 1000, 1)}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--names", type=int, default=100_000, help="topics and services the robot adds")
    parser.add_argument("--quick", action="store_true", help="10,000 names")
    parser.add_argument("--serve", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--parts", nargs="*", default=["bridge", "panel"], choices=["bridge", "panel"])
    parser.add_argument("--out", type=Path)
    args = parser.parse_args(argv)
    names = 10_000 if args.quick else args.names
    if args.serve:
        serve(names)
        return 0
    results: dict[str, Any] = {"load_before": load()}
    if "bridge" in args.parts:
        robot = Robot(names)
        try:
            results["bridge"] = bench_bridge(robot.url, names, seconds=300)
        finally:
            robot.stop()
        print("bridge:", json.dumps(results["bridge"]), flush=True)
    if "panel" in args.parts:
        results["panel"] = bench_panel(names)
        print("panel:", json.dumps(results["panel"]), flush=True)
    results["load_after"] = load()
    print(f"load average: {results['load_before']} before, {results['load_after']} after (shared machine)")
    met = []
    if "bridge" in results:
        b = results["bridge"]
        met.append(("bridge loop worst lateness < 250 ms", b["loop_worst_lateness_ms"], b["loop_worst_lateness_ms"] < 250))
        met.append(("stall cuts = 0", b["stall_cuts"], b["stall_cuts"] == 0))
        met.append(("every service's type known", b["first_full_catalogue_s"], b["first_full_catalogue_s"] is not None))
    if "panel" in results:
        p = results["panel"]
        met.append(("panel worst pass < 50 ms", p["panel_worst_pass_ms"], p["panel_worst_pass_ms"] < 50))
    for what, value, ok in met:
        print(f"  {'ok  ' if ok else 'MISS'} {what}: {value}")
    if args.out:
        args.out.write_text(json.dumps(results, indent=2))
    return 0 if all(ok for *_x, ok in met) else 1


if __name__ == "__main__":
    sys.exit(main())
