"""Bytes in by topic (rcon_core.bridge.traffic): the counting rules, the rates, and a real client against the
sim counting what came off its socket."""

from __future__ import annotations

import pytest

from rcon_core.bridge.traffic import MAX_KEYS, OTHER, Traffic, TrafficRates, rate_text
from rcon_core.testing import ManualClock, until


def test_publishes_count_by_topic_other_ops_in_brackets():
    t = Traffic()
    t.count({"op": "publish", "topic": "/cam", "msg": {}}, 1000)
    t.count({"op": "publish", "topic": "/cam", "msg": {}}, 500)
    t.count({"op": "service_response", "id": "x"}, 40)
    t.count(["not", "a", "dict"], 7)
    t.count({"op": "publish", "topic": ["a list"]}, 3)
    total, counts = t.snapshot()
    assert total == 1550 and t.total_frames == 5
    assert counts == {"/cam": (1500, 2), "(service_response)": (40, 1), "(other)": (10, 2)}


def test_a_server_inventing_names_cannot_grow_it():
    t = Traffic()
    for i in range(MAX_KEYS + 300):
        t.count_name(f"/t{i}", 1)
    _total, counts = t.snapshot()
    assert len(counts) == MAX_KEYS + 1 and counts[OTHER] == (300, 300)


def test_rates_over_the_window_biggest_first():
    clock = ManualClock()
    t, r = Traffic(), TrafficRates(window=2.0, clock=clock)
    r.update(t)
    for _ in range(10):
        clock.advance(0.5)
        t.count_name("/cam", 50_000)
        t.count_name("/odom", 500)
        r.update(t)
    assert r.total == 101_000 and [(n, round(b), round(m)) for n, b, m in r.topics] == [
        ("/cam", 100_000, 2), ("/odom", 1000, 2)]
    clock.advance(0.5)
    r.update(t)  # nothing new in the last half second: the window still holds the last 2 s
    assert r.total == 75_750
    r.update(None)  # the link went away
    assert r.total == 0 and r.topics == []
    assert rate_text(812) == "812 B/s" and rate_text(6400) == "6.4 kB/s" and rate_text(64_000) == "64 kB/s"
    assert rate_text(9_230_000) == "9.2 MB/s"


async def test_a_client_counts_what_its_subscriptions_cost(sim, client):
    got: dict[str, list[int]] = {"/camera/rear/image_raw/compressed": [], "/odom": []}
    node = client.node("traffic")
    for topic in got:
        node.subscribe(topic, lambda m, topic=topic: got[topic].append(1), compression="cbor")
    await until(lambda: all(len(v) >= 5 for v in got.values()), 15, "both topics delivering")
    await until(lambda: all(client.traffic.snapshot()[1].get(t, (0, 0))[1] >= 5 for t in got), what="counted")
    _total, counts = client.traffic.snapshot()
    cam, odom = counts["/camera/rear/image_raw/compressed"], counts["/odom"]
    assert cam[1] >= 5 and odom[1] >= 5
    # a JPEG frame is tens of kB, an odometry message a few hundred bytes
    assert cam[0] / cam[1] > 10_000 and 100 < odom[0] / odom[1] < 2_000
    assert client.traffic.total_bytes >= cam[0] + odom[0]


@pytest.mark.usefixtures("transport")  # on each transport
async def test_the_hot_path_counts_exact_sizes_per_topic_across_resubscribing_and_past_the_name_limit():
    """Small publishes are counted where they are delivered (``receive.py``, the entry's ``tally`` row): the
    bytes as they came off the socket, the same row after the topic was dropped and taken again, and under
    ``(other topics)`` for a topic first seen once MAX_KEYS names are kept."""
    import orjson

    from rcon_core.loopback import HostileServer
    from rcon_core.testing import connected

    def frame(topic: str, i: int) -> bytes:
        return orjson.dumps({"op": "publish", "topic": topic, "msg": {"i": i}})

    async with HostileServer() as srv, connected(srv.url) as client:
        got: list = []
        node = client.node("n")
        node.subscribe("/a", got.append)
        await srv.wait_for("subscribe", topic="/a")
        for i in range(3):
            await srv.send(frame("/a", i), text=True)
        await until(lambda: len(got) == 3)
        assert client.traffic.snapshot()[1]["/a"] == (3 * len(frame("/a", 0)), 3)
        node.close()
        await srv.wait_for("unsubscribe", topic="/a")
        node = client.node("m")
        node.subscribe("/a", got.append)
        await srv.wait_for("subscribe", topic="/a", count=2)
        await srv.send(frame("/a", 7), text=True)
        await until(lambda: len(got) == 4)
        assert client.traffic.snapshot()[1]["/a"] == (4 * len(frame("/a", 0)), 4)
        for k in range(MAX_KEYS):
            client.traffic.count_name(f"/filler{k}", 1)
        node.subscribe("/b", got.append)
        await srv.wait_for("subscribe", topic="/b")
        before = client.traffic.snapshot()[1][OTHER]
        await srv.send(frame("/b", 1), text=True)
        await until(lambda: len(got) == 5)
        counts = client.traffic.snapshot()[1]
        assert "/b" not in counts and counts[OTHER] == (before[0] + len(frame("/b", 1)), before[1] + 1)
