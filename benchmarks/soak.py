"""Reliability soak: what a hostile server, a flapping or stalled link and kill -9 during saves do to RCON.

Usage: ``python benchmarks/soak.py [--quick] [--out FILE] [--parts fuzz flap stall saves gui reconnect]``.
Everything runs on 127.0.0.1, bounded in count and time (about 3.5 minutes in full, 20 s with --quick).

* ``fuzz``: 100,000 seeded frames from a hostile rosbridge server (``rcon_core.fuzz``: invalid UTF-8, bad
  JSON, deep JSON, wrong field types, bogus fragments, bad png/cbor, PNG bombs, unknown ops, non-object
  msgs) mixed with valid publishes.  Figures: client deaths (target 0), valid messages delivered (100 %),
  RSS growth of this process over the run.
* ``flap``: the embedded sim behind a loopback TCP proxy that resets every connection every 2 s and refuses
  new ones for 0.5 s, for 2 minutes.  The client subscribes to /odom, advertises and publishes a topic and
  provides a service.  Figures: lost subscriptions / advertisements / services (0), time from the link
  being back to the first /odom message (p50, p99).
* ``stall``: a 5 s silent stall (the proxy forwards nothing, no FIN nor RST) while a publisher sends
  commands at 50 Hz.  Figures: stale commands delivered (arriving later than their 0.25 s freshness
  limit; target 0), the oldest delivered, time until the client reported DEGRADED.
* ``saves``: 200 child processes save a layout in a loop through ``WorkspaceStore.save`` and are killed
  with SIGKILL at a random point; after each kill the store is opened again (``load``).  Figures:
  complete layouts (200/200), temp files left (``.*.tmp``, target 0) once the store is opened again
  after its age guard (``canvas.files.STALE_AFTER_S``: a younger temp file may be a live writer's).
* ``gui`` and ``reconnect`` (``benchmarks/soak_app.py``, each in a process of its own): the GUI's worst
  pass while a Text View gets one 5 MB String and a 10,000 msg/s flood (target < 50 ms, no stall cut),
  and the app's RSS growth per reconnect on the demo workspace with the link cut every 3 s (target
  < 0.05 MB per reconnect).
"""

from __future__ import annotations

import argparse
import asyncio
import json
import logging
import multiprocessing
import os
import random
import signal
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from rcon_core.bridge import BridgeClient, ConnectionState
from rcon_core.fuzz import FuzzRun, fuzz_frames
from rcon_core.loopback import HostileServer, StallProxy
from rcon_core.sim import SimServer


def rss_mb() -> float:
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    return float("nan")


#: the app's parts (``soak_app.py``)
APP_PARTS = ["gui", "reconnect"]


def pct(values: list[float], p: float) -> float:
    if not values:
        return float("nan")
    values = sorted(values)
    return values[min(len(values) - 1, round(p / 100 * (len(values) - 1)))]


# ----------------------------------------------------------------------------------------------- fuzz


async def part_fuzz(frames: int, seed: int = 11) -> dict[str, Any]:
    deaths = 0

    def on_state(st: ConnectionState) -> None:
        nonlocal deaths
        if st is ConnectionState.CLOSED and not closing:
            deaths += 1

    closing = False
    async with HostileServer() as server:
        run = FuzzRun(server, fuzz_frames(seed, frames, bomb_pixels=40 << 20))
        client = BridgeClient(server.url, backoff_min=0.01, backoff_max=0.05)
        client.add_state_listener(on_state)
        got: list[Any] = []  # the seq of each delivered message (anything else as it came): small, so RSS
        client.node("soak").subscribe("/fuzz", lambda m: got.append(m["seq"] if m.keys() == {"seq"} else m))
        rss0 = rss_mb()
        samples: list[tuple[int, float]] = []  # (frames sent, RSS MB)

        async def sample_rss() -> None:
            while True:
                samples.append((run.sent, rss_mb()))
                await asyncio.sleep(0.25)

        sampler = asyncio.ensure_future(sample_rss())
        t0 = time.perf_counter()
        await client.connect(timeout=10)
        try:
            await asyncio.wait_for(run.done.wait(), 600)
            async with asyncio.timeout(30):
                while len(got) < len(run.expected):
                    await asyncio.sleep(0.05)
        except TimeoutError:
            pass
        elapsed = time.perf_counter() - t0
        sampler.cancel()
        rss1 = rss_mb()
        warm = next((mb for sent, mb in samples if sent >= run.sent // 10), rss0)
        exact = got == run.expected
        stats = dict(client.stats)
        closing = True
        await client.close()
    return {"frames": run.sent, "valid_sent": len(run.expected), "valid_delivered": len(got),
            "delivered_pct": 100.0 * len(got) / max(1, len(run.expected)), "delivered_exactly_in_order": exact,
            "client_deaths": deaths, "reconnects_after_invalid_utf8": run.fatal, "connects": stats["connects"],
            "bad_frames": stats["bad_frames"], "frame_errors": stats["frame_errors"],
            "png_refused": stats["png_refused"], "non_object_msgs": stats["non_object_msgs"],
            "seconds": round(elapsed, 2), "frames_per_s": round(run.sent / elapsed),
            "rss_start_mb": round(rss0, 1), "rss_after_first_10pct_mb": round(warm, 1), "rss_end_mb": round(rss1, 1),
            "rss_max_mb": round(max((mb for _s, mb in samples), default=rss1), 1),
            "rss_growth_mb": round(rss1 - rss0, 1), "rss_growth_after_first_10pct_mb": round(rss1 - warm, 1)}


# ----------------------------------------------------------------------------------------------- flap


async def part_flap(seconds: float, period: float = 2.0, down: float = 0.5) -> dict[str, Any]:
    sim = SimServer(host="127.0.0.1", port=0)
    await sim.start()
    cmd_times: list[float] = []
    sim.subscribe_internal("/soak/cmd", "std_msgs/Float64", "/soak", lambda m: cmd_times.append(time.monotonic()))
    odom_times: list[float] = []
    async with StallProxy("127.0.0.1", sim.port) as proxy:
        client = BridgeClient(proxy.url)
        node = client.node("soak")
        node.subscribe("/odom", lambda m: odom_times.append(time.monotonic()))
        pub = node.advertise("/soak/cmd", "std_msgs/Float64")
        node.advertise_service("/soak/srv", "std_srvs/Trigger", lambda req: {"success": True, "message": "ok"})
        await client.connect(timeout=10)

        async def publisher() -> None:
            while True:
                pub.publish({"data": 1.0})
                await asyncio.sleep(0.05)

        pub_task = asyncio.ensure_future(publisher())
        recover: list[float] = []
        missed = {"subscription": 0, "advertisement": 0, "service": 0}
        cycles = 0
        end = time.monotonic() + seconds
        try:
            await asyncio.sleep(period - down)
            while time.monotonic() < end:
                proxy.refuse(True)
                proxy.cut()
                await asyncio.sleep(down)
                proxy.refuse(False)
                back = time.monotonic()
                cycles += 1
                next_cut = back + period - down
                while time.monotonic() < next_cut and not any(t > back for t in odom_times[-5:]):
                    await asyncio.sleep(0.005)
                first = next((t for t in odom_times[-5:] if t > back), None)
                if first is not None:
                    recover.append(first - back)
                else:
                    missed["subscription"] += 1
                await asyncio.sleep(max(0.0, next_cut - time.monotonic() - 0.3))
                if not any(t > back for t in cmd_times[-5:]):
                    missed["advertisement"] += 1
                try:
                    ok, _ = await asyncio.wait_for(sim.call("/soak/srv", {}), 0.25)
                except (TimeoutError, Exception):
                    ok = False
                if not ok:
                    missed["service"] += 1
                await asyncio.sleep(max(0.0, next_cut - time.monotonic()))
            # the link stays up: is everything there?
            settle = time.monotonic()
            await asyncio.sleep(3.0)
            lost = {"subscriptions": int(not any(t > settle + 1 for t in odom_times)),
                    "advertisements": int(not any(t > settle + 1 for t in cmd_times)),
                    "services": 0}
            try:
                ok, _ = await asyncio.wait_for(sim.call("/soak/srv", {}), 2.0)
            except (TimeoutError, Exception):
                ok = False
            lost["services"] = int(not ok)
        finally:
            pub_task.cancel()
            stats = dict(client.stats)
            await client.close()
    await sim.stop()
    return {"seconds": seconds, "cuts": cycles, "lost": lost,
            "cycles_not_restored_before_next_cut": missed,
            "first_message_after_link_back_s": {"p50": round(pct(recover, 50), 3), "p99": round(pct(recover, 99), 3),
                                                "max": round(max(recover, default=float("nan")), 3),
                                                "samples": len(recover)},
            "connects": stats["connects"]}


# ----------------------------------------------------------------------------------------------- stall


async def part_stall(stall: float, rate_hz: float = 50.0) -> dict[str, Any]:
    sim = SimServer(host="127.0.0.1", port=0)
    await sim.start()
    ages: list[float] = []
    sim.subscribe_internal("/soak/cmd", "std_msgs/Float64", "/soak",
                           lambda m: ages.append(time.monotonic() - m["data"]))
    states: list[tuple[float, ConnectionState]] = []
    async with StallProxy("127.0.0.1", sim.port) as proxy:
        client = BridgeClient(proxy.url)
        client.add_state_listener(lambda st: states.append((time.monotonic(), st)))
        pub = client.node("soak").advertise("/soak/cmd", "std_msgs/Float64")
        await client.connect(timeout=10)
        published = 0

        async def drive(seconds: float) -> None:
            nonlocal published
            end = time.monotonic() + seconds
            while time.monotonic() < end:
                pub.publish({"data": time.monotonic()})
                published += 1
                await asyncio.sleep(1.0 / rate_hz)

        await drive(1.0)
        stalled_at = time.monotonic()
        proxy.stall()
        await drive(stall)
        proxy.resume()
        await drive(2.0)
        await asyncio.sleep(0.5)
        stats = dict(client.stats)
        await client.close()
    await sim.stop()
    degraded = next((t - stalled_at for t, st in states if st is ConnectionState.DEGRADED and t >= stalled_at), None)
    stale = [a for a in ages if a > pub.max_age]
    accounted = len(ages) + stats["stale_dropped"] + stats["dropped_while_down"]
    return {"stall_s": stall, "commands_published": published, "commands_delivered": len(ages),
            "stale_commands_delivered": len(stale), "oldest_delivered_s": round(max(ages, default=0.0), 3),
            "freshness_limit_s": pub.max_age, "stale_dropped": stats["stale_dropped"],
            "dropped_while_reconnecting": stats["dropped_while_down"],
            "written_before_the_stall_was_seen_and_discarded_by_the_cut": published - accounted,
            "stall_cuts": stats["stall_cuts"], "degraded_reported_after_s": None if degraded is None else round(degraded, 2),
            "proxy_bytes_discarded_by_the_reset": proxy.discarded}


# ----------------------------------------------------------------------------------------------- saves


def _layout(n: int) -> Any:
    from rcon_core.canvas.workspace import Canvas, Geometry, WidgetInstance, Workspace
    from rcon_core.plugins.model import Binding

    canvases = [Canvas(f"c-{c}", f"Canvas {c}", [
        WidgetInstance(f"w-{c}-{i}", "std.label", Binding(f"/topic/{i}", "std_msgs/Float64", "subscribe"),
                       Geometry(i * 10.0, c * 5.0, 160.0, 80.0), {"title": f"save {n}", "pad": "x" * 64})
        for i in range(60)]) for c in range(4)]
    return Workspace(canvases, canvases[0].id)


def _saver(path: str) -> None:
    from rcon_core.canvas.store import WorkspaceStore

    store = WorkspaceStore(path)
    n = 0
    while True:
        n += 1
        store.save(_layout(n))


def part_saves(kills: int, seed: int = 7) -> dict[str, Any]:
    from rcon_core.canvas.store import WorkspaceFileError, WorkspaceStore

    rng = random.Random(seed)
    ctx = multiprocessing.get_context("fork")
    complete = broken = mid_save = 0
    problems: list[str] = []
    with tempfile.TemporaryDirectory(prefix="rcon-soak-") as tmp:
        path = Path(tmp) / "workspace.json"
        WorkspaceStore(path).save(_layout(0))
        for _ in range(kills):
            child = ctx.Process(target=_saver, args=(str(path),), daemon=True)
            child.start()
            time.sleep(rng.uniform(0.02, 0.15))
            os.kill(child.pid, signal.SIGKILL)
            child.join(5)
            if list(Path(tmp).glob(".*.tmp")):
                mid_save += 1
            try:
                ws = WorkspaceStore(path).load()  # the normal open path
                if len(ws.canvases) == 4 and all(len(c.widgets) == 60 for c in ws.canvases):
                    complete += 1
                else:
                    broken += 1
            except WorkspaceFileError as exc:
                broken += 1
                problems.append(str(exc)[:200])
        # the next start after the last crash: a temp file younger than the store's age guard may belong
        # to a writer that has not locked it yet, so a start within STALE_AFTER_S keeps it for a later one
        from rcon_core.canvas.files import STALE_AFTER_S

        young = len(list(Path(tmp).glob(".*.tmp")))
        time.sleep(STALE_AFTER_S + 0.5)
        WorkspaceStore(path).load()
        left = list(Path(tmp).glob(".*.tmp"))
        left_bytes = sum(p.stat().st_size for p in left)
    return {"kills": kills, "complete_layouts": complete, "broken_layouts": broken,
            "killed_with_a_temp_file_on_disk": mid_save,
            "temp_files_kept_by_the_age_guard_right_after_the_last_kill": young,
            "temp_files_left_after_reopen": len(left),
            "temp_bytes_left": left_bytes, "problems": problems[:5]}


# ----------------------------------------------------------------------------------------------- gui, reconnect


def part_app(part: str, quick: bool) -> dict[str, Any]:
    """One of ``soak_app.py``'s parts (``gui``, ``reconnect``) in a process of its own."""
    import subprocess

    here = Path(__file__).resolve().parent
    with tempfile.TemporaryDirectory(prefix="rcon-soak-app-") as tmp:
        out = Path(tmp) / f"{part}.json"
        cmd = [sys.executable, str(here / "soak_app.py"), part, "--out", str(out)] + (["--quick"] if quick else [])
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=1800,
                              env={**os.environ, "QT_QPA_PLATFORM": os.environ.get("QT_QPA_PLATFORM", "offscreen")})
        if not out.exists():
            return {"error": (proc.stderr or proc.stdout)[-1500:]}
        return dict(json.loads(out.read_text()))


def app_targets(r: dict[str, Any]) -> list[tuple[str, Any, bool]]:
    out: list[tuple[str, Any, bool]] = []
    if "gui" in r:
        g = r["gui"]
        ok = "error" not in g
        out.append(("gui: worst GUI pass, one 5 MB String on a Text View < 50 ms",
                    g.get("text_5mb_worst_gui_pass_ms", g.get("error")), ok and g["text_5mb_worst_gui_pass_ms"] < 50))
        out.append(("gui: worst GUI pass, 10,000 msg/s on a Text View < 50 ms",
                    g.get("flood_worst_gui_pass_ms"), ok and g["flood_worst_gui_pass_ms"] < 50))
        out.append(("gui: stall cuts during both = 0", ok and g["text_5mb_stall_cuts"] + g["flood_stall_cuts"],
                    ok and g["text_5mb_stall_cuts"] + g["flood_stall_cuts"] == 0))
    if "reconnect" in r:
        c = r["reconnect"]
        per = c.get("rss_per_reconnect_mb")
        out.append(("reconnect: app RSS growth < 0.05 MB per reconnect", per if per is not None else c.get("error"),
                    per is not None and per < 0.05))
    return out


# ----------------------------------------------------------------------------------------------- main


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="a short smoke run (about 20 s)")
    parser.add_argument("--out", type=Path, help="write the figures as JSON here")
    parser.add_argument("--parts", nargs="*", default=["fuzz", "flap", "stall", "saves", *APP_PARTS],
                        choices=["fuzz", "flap", "stall", "saves", *APP_PARTS])
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.ERROR)  # the bad frames are the point here: no warning per frame
    q = args.quick
    results: dict[str, Any] = {"quick": q}
    # the saves part forks: run it before any event loop or thread exists in this process
    if "saves" in args.parts:
        results["saves"] = part_saves(10 if q else 200)
        print("saves:", json.dumps(results["saves"]), flush=True)
    if "fuzz" in args.parts:
        results["fuzz"] = asyncio.run(part_fuzz(2000 if q else 100_000))
        print("fuzz:", json.dumps(results["fuzz"]), flush=True)
    if "flap" in args.parts:
        results["flap"] = asyncio.run(part_flap(6.0 if q else 120.0))
        print("flap:", json.dumps(results["flap"]), flush=True)
    if "stall" in args.parts:
        results["stall"] = asyncio.run(part_stall(2.0 if q else 5.0))
        print("stall:", json.dumps(results["stall"]), flush=True)
    for part in APP_PARTS:
        if part in args.parts:
            results[part] = part_app(part, q)
            print(f"{part}:", json.dumps(results[part]), flush=True)
    results["targets"] = targets(results) + app_targets(results)
    print("\ntargets:")
    for what, value, met in results["targets"]:
        print(f"  {'ok  ' if met else 'MISS'} {what}: {value}")
    if args.out:
        args.out.write_text(json.dumps(results, indent=2))
    return 0 if all(met for _w, _v, met in results["targets"]) else 1


def targets(r: dict[str, Any]) -> list[tuple[str, Any, bool]]:
    out: list[tuple[str, Any, bool]] = []
    if "fuzz" in r:
        f = r["fuzz"]
        out.append(("fuzz: client deaths = 0", f["client_deaths"], f["client_deaths"] == 0))
        out.append(("fuzz: valid messages delivered = 100 %, in order", f"{f['delivered_pct']:.2f} %",
                    f["delivered_exactly_in_order"]))
    if "flap" in r:
        lost = r["flap"]["lost"]
        out.append(("flap: lost subscriptions/advertisements/services = 0", lost, not any(lost.values())))
    if "stall" in r:
        s = r["stall"]
        out.append(("stall: stale commands delivered = 0", s["stale_commands_delivered"],
                    s["stale_commands_delivered"] == 0))
        out.append(("stall: DEGRADED reported within 1.5 s", s["degraded_reported_after_s"],
                    s["degraded_reported_after_s"] is not None and s["degraded_reported_after_s"] <= 1.5))
    if "saves" in r:
        s = r["saves"]
        out.append(("saves: complete layouts = all", f"{s['complete_layouts']}/{s['kills']}",
                    s["complete_layouts"] == s["kills"]))
        out.append(("saves: temp files left after reopen = 0", s["temp_files_left_after_reopen"],
                    s["temp_files_left_after_reopen"] == 0))
    return out


if __name__ == "__main__":
    sys.exit(main())
