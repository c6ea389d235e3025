"""Latest-only topics (``rcon_core/bridge/latest.py``): when the client falls behind, stale frames of a topic
whose consumers asked for ``queue_length`` 1 are skipped before decoding and counted; the newest is
delivered; other topics get every frame, in order."""

from __future__ import annotations

import time

import orjson
import pytest

from rcon_core.bridge import BridgeClient
from rcon_core.bridge.latest import topic_of
from rcon_core.sim import encoding
from rcon_core.testing import until

pytestmark = pytest.mark.usefixtures("transport")  # every test runs on each transport

PAYLOAD = "x" * 40_000  # above latest.MIN_SIZE: big enough to be worth skipping
BURST = 6


def test_topic_of_reads_the_head_of_json_and_cbor_publish_frames():
    frame = encoding.publish_frame("/cam/image", {"data": PAYLOAD})
    assert topic_of(encoding.dumps(frame)) == "/cam/image"
    assert topic_of(encoding.dumps(frame).encode()) == "/cam/image"
    assert topic_of(encoding.cbor_dumps(frame)) == "/cam/image"
    long_name = "/" + "n" * 100  # a one-byte CBOR length
    assert topic_of(encoding.cbor_dumps(encoding.publish_frame(long_name, {"data": 1}))) == long_name


def test_topic_of_never_takes_a_string_inside_the_message_for_the_topic():
    # "topic" after "msg": the frame is not recognised (and so never skipped)
    text = orjson.dumps({"op": "publish", "msg": {"topic": "/fake", "data": PAYLOAD}, "topic": "/real"})
    assert topic_of(text) is None
    assert topic_of(encoding.cbor_dumps({"op": "publish", "msg": {"topic": "/fake"}, "topic": "/real"})) is None
    assert topic_of(orjson.dumps({"op": "service_response", "values": {"topic": "/x"}})) is None
    assert topic_of(b"\xff\x00garbage") is None and topic_of("") is None


async def test_stale_frames_of_a_latest_only_topic_are_skipped_and_counted(sim_thread):
    """The client's loop is held while the sim sends a burst on two topics: of the queue_length-1 topic
    only the newest of the frames waiting is delivered (the rest counted as skipped); the other topic
    gets every frame in order."""
    node = "/burst_pub"
    for name in ("/burst/latest", "/burst/all"):
        sim_thread.run_sync(lambda name=name: sim_thread.advertise_internal(name, "std_msgs/String", node))

    def publish(i: int) -> None:
        for name in ("/burst/latest", "/burst/all"):
            sim_thread.run_sync(lambda name=name: sim_thread.publish(name, {"data": f"{i}:{PAYLOAD}"}, node))

    latest: list[int] = []
    every: list[int] = []

    def on_latest(msg):
        i = int(msg["data"].split(":", 1)[0])
        latest.append(i)
        if i == 0:  # hold the client's loop while the sim sends the burst (the client falls behind)
            for k in range(1, BURST):
                publish(k)
                time.sleep(0.03)  # the sim writes each frame before the next (its own queue drops nothing)
            time.sleep(0.2)

    c = BridgeClient(sim_thread.url, reconnect=False, latency_interval=3600)
    await c.connect(timeout=10)
    try:
        n = c.node("burst")
        n.subscribe("/burst/latest", on_latest, type="std_msgs/String", queue_length=1)
        n.subscribe("/burst/all", lambda m: every.append(int(m["data"].split(":", 1)[0])), type="std_msgs/String")
        await until(lambda: sim_thread.has_subscribers("/burst/latest") and sim_thread.has_subscribers("/burst/all"))
        publish(0)
        await until(lambda: len(every) == BURST and latest and latest[-1] == BURST - 1, what="the burst delivered")
        skipped = c.stats["stale_skipped"]
        entry = c.session.topics["/burst/latest"]
        assert every == list(range(BURST))  # the other topic: every frame, in order
        assert latest == sorted(latest) and latest[0] == 0 and latest[-1] == BURST - 1
        assert skipped >= 1, "stale frames waiting behind a newer one were delivered"
        assert entry.skipped == skipped
        assert len(latest) + skipped == BURST  # every frame delivered or deliberately skipped
        assert c.session.topics["/burst/all"].skipped == 0
    finally:
        await c.close()


async def test_the_read_loop_gives_the_event_loop_a_turn_within_a_backlog(sim_thread):
    """A backlog of small frames already received is not read in one go: past the first ``YIELD_BYTES`` (4 kB)
    of frames of a turn, once they have taken its budget (``receive.TURN_BUDGET``, 1 ms; the clock is read
    every ``YIELD_BYTES`` of frames), timers and other links on the loop get a turn (a teleop pad's tick is
    not held by a backlog).  Each frame here is about 560 bytes and each callback spends 0.2 ms of CPU, so
    the frames of 4 kB are over the budget however fast or loaded the machine is: a turn holds at most the
    frames of twice ``YIELD_BYTES`` and two more, far fewer than the backlog."""
    import asyncio

    from rcon_core.bridge.receive import YIELD_BYTES

    node = "/backlog_pub"
    count = 150
    pad = "x" * 500
    sim_thread.run_sync(lambda: sim_thread.advertise_internal("/backlog/v", "std_msgs/String", node))
    sim_thread.run_sync(lambda: sim_thread.advertise_internal("/backlog/start", "std_msgs/Int32", node))
    got: list[int] = []
    turns: list[int] = []  # len(got) each time the probe ran

    def burst():
        for i in range(count):
            sim_thread.publish("/backlog/v", {"data": f"{i:04d}{pad}"}, node)

    def on_start(_msg):  # hold the client's loop while the sim writes the whole burst
        sim_thread.run_sync(burst)
        time.sleep(0.3)

    loop = asyncio.get_running_loop()
    done = asyncio.Event()

    def probe():
        turns.append(len(got))
        if len(got) < count:
            loop.call_soon(probe)
        else:
            done.set()

    c = BridgeClient(sim_thread.url, reconnect=False, latency_interval=3600)
    await c.connect(timeout=10)
    try:
        n = c.node("backlog")
        def busy(m):
            got.append(int(m["data"][:4]))
            start = time.thread_time()
            while time.thread_time() - start < 0.0002:
                pass

        n.subscribe("/backlog/v", busy, type="std_msgs/String")
        n.subscribe("/backlog/start", on_start, type="std_msgs/Int32")
        await until(lambda: sim_thread.has_subscribers("/backlog/v") and sim_thread.has_subscribers("/backlog/start"))
        probe()
        sim_thread.run_sync(lambda: sim_thread.publish("/backlog/start", {"data": 1}, node))
        await asyncio.wait_for(done.wait(), 10)
        assert got == list(range(count))  # every frame, in order
        steps = [b - a for a, b in zip(turns, turns[1:], strict=False)]
        nbytes, frames = c.traffic.snapshot()[1]["/backlog/v"]
        most = 2 * (YIELD_BYTES // (nbytes // frames) + 1) + 1  # the frames are all of one size
        assert most < count // 2
        assert max(steps) <= most, f"the client delivered {max(steps)} frames without a turn (at most {most})"
    finally:
        await c.close()


async def test_frames_bigger_than_one_read_are_skipped_when_a_newer_one_is_in_the_kernel(sim_thread):
    """Camera-sized frames (600 kB, more than asyncio reads per turn): the backlog sits in the kernel's
    buffers, not yet in websockets' queue; the read loop reads ahead before deciding, so stale frames are
    still skipped and the newest is delivered."""
    node = "/big_pub"
    big = "y" * 600_000
    count = 4
    sim_thread.run_sync(lambda: sim_thread.advertise_internal("/big/cam", "std_msgs/String", node))
    got: list[int] = []

    def publish(i: int) -> None:
        sim_thread.run_sync(lambda: sim_thread.publish("/big/cam", {"data": f"{i}:{big}"}, node))

    def on_frame(msg):
        i = int(msg["data"].split(":", 1)[0])
        got.append(i)
        if i == 0:  # hold the client's loop while the sim writes the burst into the socket
            for k in range(1, count):
                publish(k)
                time.sleep(0.05)
            time.sleep(0.2)

    c = BridgeClient(sim_thread.url, reconnect=False, latency_interval=3600)
    await c.connect(timeout=10)
    try:
        c.node("big").subscribe("/big/cam", on_frame, type="std_msgs/String", queue_length=1)
        await until(lambda: sim_thread.has_subscribers("/big/cam"))
        publish(0)
        await until(lambda: got and got[-1] == count - 1, what="the newest frame delivered")
        assert got == sorted(got) and got[0] == 0
        assert c.stats["stale_skipped"] >= 1, f"delivered {got}: no stale frame was skipped"
        assert len(got) + c.stats["stale_skipped"] <= count
    finally:
        await c.close()
