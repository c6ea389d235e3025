"""issue 25.4/25.5: what reaches a widget, as docs/writing-a-widget-plugin.md ("What reaches your widget")
says, against the embedded robot: missing fields arrive as defaults, NaN and infinity as None, float32
rounded; a message that does not fit its type is refused at `publish()` (rosbridge would drop it and say
so only in the robot's log) and the refusal is the widget's error; an exception in `on_message` becomes
the error and the next value clears it. And the harness: RecordingPort plays messages and answers."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from rcon_core.plugins import Binding, WidgetModel
from rcon_core.testing import RecordingPort, connected, until


async def subscriber(client, topic, type_name):
    model = WidgetModel(None, Binding(topic, type_name, "subscribe"), client.node(f"show{topic}"))
    model.start()
    return model


RECORDING = Path(__file__).resolve().parent / "recordings" / "rosbridge-ros1" / "publish_json.jsonl"


def test_float32_fields_arrive_as_float32_values_from_a_real_robot(plugins):
    """Ground truth (rosbridge 0.11 recording): a LaserScan's float32 fields carry float32 values widened
    to double, e.g. range_min 0.1 arrives as 0.10000000149011612."""
    types = plugins.type_registry()
    float32 = [f.name for f in types.fields("sensor_msgs/LaserScan") if f.base == "float32" and f.array_len is None]
    scans = [json.loads(line)["received"]["msg"] for line in RECORDING.read_text().splitlines()
             if '"range_min"' in line and json.loads(line).get("received")]
    assert scans and len(float32) >= 6
    for scan in scans:
        for name in float32:
            assert float(np.float32(scan[name])) == scan[name], name
    assert scans[0]["range_min"] == 0.10000000149011612


async def test_missing_fields_arrive_as_defaults_and_nonfinite_as_none(sim, plugins):
    types = plugins.type_registry()
    async with connected(sim.url, reconnect=False) as client:
        twist = await subscriber(client, "/t/twist", "geometry_msgs/Twist")
        f64 = await subscriber(client, "/t/f64", "std_msgs/Float64")
        robot = client.node("robot")
        robot.advertise("/t/twist", "geometry_msgs/Twist").publish({"linear": {"x": 1.5}})
        pub64 = robot.advertise("/t/f64", "std_msgs/Float64")
        pub64.publish({"data": math.nan})
        await until(lambda: twist.state.count and f64.state.count, what="two messages")
        assert twist.state.message == {"linear": {"x": 1.5, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.0}}
        assert f64.state.message == {"data": None}  # JSON has no NaN: it travels as null
        pub64.publish({"data": math.inf})
        await until(lambda: f64.state.count == 2, what="the infinity")
        assert f64.state.message == {"data": None}
        assert types.validate("std_msgs/Float64", {"data": None}) == []  # None is what a model must expect


async def test_a_message_that_does_not_fit_is_refused_at_publish_and_is_the_error(sim, plugins):
    types = plugins.type_registry()
    async with connected(sim.url, reconnect=False) as client:
        shown = await subscriber(client, "/t/speed", "std_msgs/Float64")
        model = WidgetModel(None, Binding("/t/speed", "std_msgs/Float64", "publish"), client.node("send"),
                            types=types)
        model.start()
        assert model.publish({"data": "fast"}) is False
        assert model.state.error == ("not sent: the message does not fit std_msgs/Float64 (data: expected a "
                                     "number, got 'fast')")
        assert model.publish({"speed": 1.0}) is False
        assert "unknown field 'speed' (known: data)" in model.state.error
        assert model.publish({}) is True  # missing fields are the robot's defaults, not a misfit
        assert model.publish({"data": 2.5}) is True
        await until(lambda: shown.state.value == {"data": 2.5}, what="the good message")
        assert shown.state.count == 2  # the misfits never left


def test_an_exception_in_on_message_is_the_error_and_a_value_clears_it():
    class Speed(WidgetModel):
        def on_message(self, msg):
            self.set_value(round(msg["data"], 2), message=msg)

    port = RecordingPort()
    model = Speed(None, Binding("/speed", "std_msgs/Float64", "subscribe"), port)
    model.start()
    assert port.deliver("/speed", {"data": "fast"}) == 1
    assert model.state.error.startswith("TypeError: ") and model.state.value is None
    port.deliver("/speed", {"data": 1.234})
    assert (model.state.value, model.state.error) == (1.23, None)
    model.stop()
    assert port.deliver("/speed", {"data": 2.0}) == 0  # unsubscribed


async def test_recording_port_plays_scripted_answers():
    port = RecordingPort()
    assert await port.call_service("/x", {}) == {}  # unscripted: an empty response
    port.answer("/pump/set", {"success": True}, lambda args: {"success": args["on"]}, TimeoutError("no answer"))
    assert await port.call_service("/pump/set", {"on": True}) == {"success": True}
    assert await port.call_service("/pump/set", {"on": False}) == {"success": False}
    for _ in range(2):  # the last answer repeats
        with pytest.raises(TimeoutError, match="no answer"):
            await port.call_service("/pump/set", {})
    assert port.calls == [("/x", {}), ("/pump/set", {"on": True}), ("/pump/set", {"on": False}),
                          ("/pump/set", {}), ("/pump/set", {})]
    with pytest.raises(ValueError):
        port.answer("/pump/set")
