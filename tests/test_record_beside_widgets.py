"""The recorder beside the widgets on one topic (found running the fleet benchmark with Record pressed: each
press switched the widgets' value topics from JSON to ``cbor-raw`` and back, the frames of the old encoding
still in flight were reported as "bad frame ... malformed cbor-raw message", and every value then reached
its widget through a slower decoder).

* Pressing Record never re-subscribes a topic a widget reads: the widgets' encoding stays, the recorder
  takes the messages as the widgets get them (re-serialized by the robot's definition).
* A topic whose encoding does change while messages flow (the last widget leaves and only the recorder's
  ``cbor-raw`` remains, or a widget joins a topic only the recorder had) loses nothing to the switch: a
  message of the old encoding is delivered as what it is, never reported as a bad frame, and a widget never
  gets a ``{secs, nsecs, bytes}`` payload."""

from __future__ import annotations

import asyncio
import contextlib
import struct
from collections.abc import AsyncIterator
from pathlib import Path
from typing import Any

from mcap.reader import make_reader

from rcon_core.bridge.topics import RawPayload
from rcon_core.record.ingest import RobotRecorder
from rcon_core.record.writer import McapSink
from rcon_core.sim import SimServer
from rcon_core.testing import connected, until

TOPIC = "/fast/value"


@contextlib.asynccontextmanager
async def fast_topic(server: SimServer, hz: float = 400.0) -> AsyncIterator[list[float]]:
    """``/fast/value`` (std_msgs/Float64) published at ``hz`` by the sim, the values 1.0, 2.0, ..."""
    server.advertise_internal(TOPIC, "std_msgs/Float64", "/fast")
    sent: list[float] = []

    async def run() -> None:
        while True:
            value = float(len(sent) + 1)
            sent.append(value)
            server.publish(TOPIC, {"data": value}, "/fast")
            await asyncio.sleep(1 / hz)

    task = asyncio.get_running_loop().create_task(run())
    try:
        yield sent
    finally:
        task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await task


def values_in(path: Path) -> list[float]:
    with open(path, "rb") as f:
        return [struct.unpack("<d", m.data)[0] for _s, c, m in make_reader(f).iter_messages()
                if c.topic == TOPIC]


async def test_record_does_not_resubscribe_a_topic_a_widget_reads(sim: SimServer, tmp_path: Path) -> None:
    async with fast_topic(sim), connected(sim.url) as client:
        widget: list[Any] = []
        client.node("widget").subscribe(TOPIC, widget.append, type="std_msgs/Float64")
        await until(lambda: len(widget) >= 20, what="the widget's values")
        entry = client.session.topics[TOPIC]
        sid, options = entry.sid, entry.sent_options
        sink = McapSink(str(tmp_path / "run.mcap"), "ros1")
        rec = RobotRecorder(client, sink, ros2=False, topics=[TOPIC], types={TOPIC: "std_msgs/Float64"},
                            operator=False)
        await rec.start()
        await until(lambda: sink.stats.messages >= 100, what="values recorded")
        rec.stop()
        n = len(widget)
        await until(lambda: len(widget) >= n + 20, what="the widget's values after the recording")
        sink.close()
        # the widget's subscription was never touched: same id, same options, still JSON
        assert (entry.sid, entry.sent_options) == (sid, options)
        assert options["compression"] == "none" and entry.raw_type is None
        assert client.stats["bad_frames"] == 0
        assert all(isinstance(m, dict) and set(m) == {"data"} for m in widget)
    recorded = values_in(tmp_path / "run.mcap")
    assert len(recorded) >= 100
    # the recorder wrote what the widget received, in order, with no gap
    assert recorded == [float(v) for v in range(int(recorded[0]), int(recorded[0]) + len(recorded))]
    assert set(recorded) <= {m["data"] for m in widget}


async def test_switching_a_topics_encoding_under_traffic_loses_nothing(sim: SimServer) -> None:
    """The recorder alone (cbor-raw), a widget joins (JSON), the widget leaves (cbor-raw again), five times
    with 400 messages a second flowing: no bad frame, the widget only ever gets messages, the recorder only
    raw payloads or messages (from the frames still in flight)."""
    async with fast_topic(sim), connected(sim.url) as client:
        raw: list[Any] = []
        client.node("recorder").subscribe(TOPIC, raw.append, type="std_msgs/Float64", raw=True)
        await until(lambda: len(raw) >= 20, what="raw values")
        entry = client.session.topics[TOPIC]
        assert entry.raw_type is not None  # the recorder alone: cbor-raw
        widget: list[Any] = []
        for _ in range(5):
            sub = client.node("widget").subscribe(TOPIC, widget.append, type="std_msgs/Float64")
            n = len(widget)
            await until(lambda n=n: len(widget) >= n + 40, what="the widget's values")
            assert entry.raw_type is None  # a widget reads it: JSON, as the widget asked
            sub.unsubscribe()
            n = len(raw)
            await until(lambda n=n: len(raw) >= n + 40 and entry.raw_type is not None, what="raw values again")
        assert client.stats["bad_frames"] == 0, client.session.bad.counts if hasattr(client.session, "bad") else ""
        assert widget and all(isinstance(m, dict) and set(m) == {"data"} for m in widget)
        assert all(isinstance(m, RawPayload) or (isinstance(m, dict) and set(m) == {"data"}) for m in raw)
        assert any(isinstance(m, RawPayload) for m in raw)
