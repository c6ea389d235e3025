"""The sim's memory and log lines stay bounded whatever clients send (issue 22, items 9, 14, 15, 17): what
clients published is kept by bytes, a frame's decoded size is budgeted before it is parsed, topic names
clients made are forgotten, and a malformed op is one short line in the log, never a traceback."""

from __future__ import annotations

import asyncio
import json
import logging
import tracemalloc
from typing import Any

import websockets

from rcon_core.sim import SimServer
from rcon_core.sim.frames import DECODED_BUDGET, parse_frame
from rcon_core.sim.published import TOPIC_BYTES, PublishedLog
from rcon_core.testing import until


def connect(sim: SimServer) -> Any:
    return websockets.connect(sim.url, max_size=None, max_queue=None)


async def answered(ws: Any, call_id: Any, timeout: float = 10.0) -> dict[str, Any]:
    async def wait() -> dict[str, Any]:
        while True:
            msg = json.loads(await ws.recv())
            if msg.get("op") == "service_response" and msg.get("id") == call_id:
                return msg

    return await asyncio.wait_for(wait(), timeout)


# ----------------------------------------------------------------------------------- what was published


async def test_published_messages_are_kept_by_bytes_not_500_a_topic(sim: SimServer) -> None:
    """The probe: 500 big messages a topic took the sim from 72 to 872 MB. 40 messages of 1 MB now keep
    at most TOPIC_BYTES (and the newest)."""
    big = "x" * (1 << 20)
    async with connect(sim) as ws:
        await ws.send(json.dumps({"op": "advertise", "topic": "/big", "type": "std_msgs/String"}))
        for i in range(40):
            await ws.send(json.dumps({"op": "publish", "topic": "/big", "msg": {"data": f"{i:02d}{big}"}}))
        await sim.wait_for_published("/big", lambda m: m["data"].startswith("39"), timeout=30)
    kept = sim.published("/big")
    assert sum(len(m["data"]) for m in kept) <= TOPIC_BYTES + len(big) + 2
    assert kept[-1]["data"].startswith("39") and len(kept) < 40
    assert sim.published_log.bytes <= TOPIC_BYTES + len(big) + 200


def test_the_published_log_keeps_a_total_over_all_topics_and_never_grows_unseen() -> None:
    log = PublishedLog(keep=3, topic_bytes=1000, total_bytes=2500, total_messages=50)
    for i in range(10):
        log.add("/a", {"i": i}, 400)
    assert [m["i"] for m in log.messages("/a")] == [8, 9]  # 1000 bytes a topic
    for i in range(10):
        log.add(f"/t{i}", {"i": i}, 400)
    assert log.bytes <= 2500 and log.messages("/a") == []  # the oldest of all went first
    assert [m["i"] for m in log.messages("/t9")] == [9]
    for i in range(10_000):  # one busy topic among quiet ones: the order book does not grow without end
        log.add("/busy", {"i": i}, 1)
    assert len(log) <= 50 and len(log._order) <= 2 * len(log) + 1000


# -------------------------------------------------------------------------------- decoded-size budget


def test_a_frame_that_would_decode_past_the_budget_is_refused_before_parsing(caplog) -> None:
    """The probe: a 30 MB frame peaked at +300-450 MB while parsed (measured here: 30 MB of ``{},`` took
    +880 MB and 0.8 s; of ``[],`` 6 s). The same shape at 5.2 MB (1.75 million values, more than the
    budget) is refused unparsed; a 30 MB camera image as rosbridge sends it (base64 text) is read."""
    values = 1_750_000
    assert values * 100 > DECODED_BUDGET
    hostile = '{"op": "publish", "topic": "/x", "msg": {"data": [' + "{}," * values + "{}]}}"
    tracemalloc.start()
    try:
        assert parse_frame(hostile, "[Client 9]") == []
        _now, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 16 << 20, f"peak {peak >> 20} MB"
    assert any("up to" in r.getMessage() and "MB" in r.getMessage() for r in caplog.records)
    image = '{"op": "publish", "topic": "/cam", "msg": {"data": "' + "QUJD" * (30 << 18) + '"}}'
    [frame] = parse_frame(image, "[Client 9]")
    assert len(frame["msg"]["data"]) == 30 << 20


async def test_a_refused_big_frame_keeps_the_connection(sim: SimServer) -> None:
    async with connect(sim) as ws:
        await ws.send("[" + "[]," * 1_500_000 + "[]]")
        await ws.send(json.dumps({"op": "call_service", "service": "/rosapi/get_time", "id": "after"}))
        assert (await answered(ws, "after"))["result"] is True


# --------------------------------------------------------------------------------- topics are forgotten


async def test_topic_names_clients_make_are_forgotten_when_unused(sim: SimServer) -> None:
    """The probe: 100,000 names clients made stayed in the sim, and /rosapi/topics took 455 ms. 2,000
    names made by subscribing, advertising and publishing are gone again once unused."""
    before = set(sim.topics)
    async with connect(sim) as ws:
        for i in range(500):
            await ws.send(json.dumps({"op": "subscribe", "topic": f"/made/s{i}", "type": "std_msgs/Int32"}))
            await ws.send(json.dumps({"op": "unsubscribe", "topic": f"/made/s{i}"}))
            await ws.send(json.dumps({"op": "advertise", "topic": f"/made/a{i}", "type": "std_msgs/Int32"}))
            await ws.send(json.dumps({"op": "publish", "topic": f"/made/a{i}", "msg": {"data": i}}))
            await ws.send(json.dumps({"op": "unadvertise", "topic": f"/made/a{i}"}))
            await ws.send(json.dumps({"op": "subscribe", "topic": f"/made/d{i}", "type": "std_msgs/Int32"}))
            await ws.send(json.dumps({"op": "advertise", "topic": f"/made/e{i}", "type": "std_msgs/Int32",
                                      "latch": True}))
        await until(lambda: sim.ops_received[("advertise", "/made/e499")] == 1, what="every op read")
        assert len(sim.topics) >= len(before) + 1000  # the client's live topics are there meanwhile
        topics = await asyncio.wait_for(_call(ws, "/rosapi/topics"), 10)
        assert "/made/d7" in topics["values"]["topics"] and "/made/s7" not in topics["values"]["topics"]
    await until(lambda: set(sim.topics) == before, what="the names forgotten after the client left")


async def test_a_topic_still_used_by_the_robot_or_another_client_is_kept(sim: SimServer) -> None:
    async with connect(sim) as a, connect(sim) as b:
        for ws in (a, b):
            await ws.send(json.dumps({"op": "subscribe", "topic": "/shared", "type": "std_msgs/Int32"}))
            await ws.send(json.dumps({"op": "subscribe", "topic": "/odom"}))
        await until(lambda: sim.topic_subscriber_count("/shared") == 2, what="two subscribers")
        await a.send(json.dumps({"op": "unsubscribe", "topic": "/shared"}))
        await a.send(json.dumps({"op": "unsubscribe", "topic": "/odom"}))
        await until(lambda: sim.topic_subscriber_count("/shared") == 1, what="one left")
        assert "/shared" in sim.topics
    await until(lambda: "/shared" not in sim.topics, what="forgotten")
    assert "/odom" in sim.topics and "/cmd_vel" in sim.topics  # the robot's own stay


async def _call(ws: Any, service: str) -> dict[str, Any]:
    await ws.send(json.dumps({"op": "call_service", "service": service, "id": service}))
    return await answered(ws, service)


# -------------------------------------------------------------------------------------- one line, bounded


async def test_malformed_ops_log_one_bounded_line_not_a_traceback(sim: SimServer, caplog) -> None:
    """Found by fuzzing (the probe saw tracebacks too): a subscribe whose id or compression is an object, a
    call whose id has a lone surrogate (the answer could not be encoded: a traceback and no answer),
    an unknown op with a megabyte of name."""
    caplog.set_level(logging.INFO, logger="rcon.sim")
    async with connect(sim) as ws:
        await ws.send(json.dumps({"op": "subscribe", "topic": "/odom", "id": {"a": 1}}))
        await ws.send(json.dumps({"op": "subscribe", "topic": "/odom", "id": [1], "compression": {"x": 1}}))
        await ws.send(json.dumps({"op": "subscribe", "topic": "/depth", "compression": {"x": 1}}))
        await ws.send(json.dumps({"op": "unsubscribe", "topic": "/odom", "id": {"a": 1}}))
        await ws.send('{"op": "call_service", "service": "/rosapi/get_time", "id": "\\udcff"}')
        reply = await answered(ws, "\udcff")
        assert reply["result"] is True
        await ws.send(json.dumps({"op": "x" * 1_000_000, "id": "y" * 1_000_000}))
        await ws.send(json.dumps({"op": "call_service", "service": "/rosapi/get_time", "id": "end"}))
        await answered(ws, "end")
    records = [r for r in caplog.records if r.name.startswith("rcon")]
    assert records and not [r for r in records if r.exc_info], [r.getMessage()[:200] for r in records if r.exc_info]
    assert max(len(r.getMessage()) for r in records) < 2000
    assert any("Unknown operation" in r.getMessage() for r in records)


async def test_a_flood_of_bad_frames_costs_a_few_lines(sim: SimServer, caplog) -> None:
    async with connect(sim) as ws:
        for i in range(2000):
            await ws.send(json.dumps({"op": "no_such_op", "id": i}))
        await ws.send(json.dumps({"op": "call_service", "service": "/rosapi/get_time", "id": "end"}))
        await answered(ws, "end", timeout=30)
    lines = [r.getMessage() for r in caplog.records if "no_such_op" in r.getMessage()]
    assert 1 <= len(lines) < 200, len(lines)  # 2000 bad frames: the first 20 lines, then 5 a second
