"""WidgetModel base: state snapshots, staleness and age, link flag, thread-safe hand-off, calls via the sim."""

import asyncio
import threading

import pytest

from rcon_core.bridge import BridgeClient
from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import Binding, Role, WidgetModel
from rcon_core.testing import ManualClock


def test_binding_problems_and_roles():
    assert Binding().problems() == ["no topic chosen"]  # said once: no topic means no type either
    assert Binding("/chat").problems() == ["no topic type set"]
    assert Binding("/lights/set", "", Role.CALL).problems() == ["no service type set"]
    assert Binding("/x", "std_msgs/Bool", "publish", "data").field_paths == ("data",)
    assert Binding("/x", "a/B", "subscribe", ["a", "b"]).field_path == "a"
    with pytest.raises(ValueError, match="unknown role"):
        Binding("/x", "a/B", "watch")


def test_value_age_stale_and_errors():
    clock = ManualClock()
    m = WidgetModel(None, Binding("", "sensor_msgs/BatteryState", "subscribe", "percentage"), None, clock=clock)
    m.start()  # incomplete binding: no port use, but running (and will show its problems)
    assert m.running and m.problems() == ["no topic chosen"]
    s0 = m.state
    assert s0.value is None and s0.age is None and not s0.stale
    clock.now += 6
    assert m.state.stale  # nothing for longer than stale_after since start
    m.on_message({"percentage": 0.8, "voltage": 12.1})
    s1 = m.state
    assert s1.value == 0.8 and s1.count == 1 and s1.age == 0 and not s1.stale and s1.seq > s0.seq
    clock.now += 2.5
    assert m.state.age == 2.5 and m.state.seq == s1.seq  # ageing is not a change
    clock.now += 3
    assert m.state.stale
    m.on_message({"voltage": 1.0})
    assert "percentage" in m.state.error and m.state.value == 0.8
    m.set_link(False)
    assert m.state.link_down
    m.stop()
    assert not m.state.running and not m.state.stale


def test_replace_value_repaints_without_counting_as_robot_data():
    clock = ManualClock()
    m = WidgetModel(None, Binding("/log", "std_msgs/String", "subscribe", "data"), None, clock=clock)
    m.on_message({"data": "hello"})
    before = m.state
    clock.now += 3
    m.replace_value("HELLO (filtered)")
    after = m.state
    assert after.value == "HELLO (filtered)" and after.seq > before.seq
    assert after.count == before.count == 1 and after.age == 3  # still the age of the robot's value


def test_settings_stale_after_and_problems():
    class S:
        stale_after = 1.0

        def problems(self):
            return ["pick a colour"]

    clock = ManualClock()
    m = WidgetModel(S(), Binding("/a", "std_msgs/Float64", "subscribe", "data"), None, clock=clock)
    assert m.stale_after == 1.0 and m.problems() == ["pick a colour"]


def test_publish_without_running_reports_instead_of_raising():
    m = WidgetModel(None, Binding("/a", "std_msgs/Float64", "publish", "data"), None,
                    types=TypeRegistry.standard())
    assert m.publish_value(1.0) is False and "not running" in m.state.error
    assert m.build_message(2.0) == {"data": 2.0}


def test_thread_safe_hand_off_latest_value_wins():
    m = WidgetModel(None, Binding("/a", "std_msgs/Int32", "subscribe", "data"), None)
    seen = []
    stop = threading.Event()

    def reader():
        while not stop.is_set():
            st = m.state
            seen.append((st.count, st.value))

    t = threading.Thread(target=reader)
    t.start()
    for i in range(20000):
        m.on_message({"data": i})
    stop.set()
    t.join()
    assert m.state.value == 19999 and m.state.count == 20000
    assert all(v == c - 1 for c, v in seen if c)  # every snapshot is consistent


async def test_call_through_the_sim_and_dispatch(sim):
    client = BridgeClient(sim.url, reconnect=False)
    await client.connect()
    try:
        dispatched = []

        def dispatch(fn):
            dispatched.append(fn)
            fn()

        m = WidgetModel(None, Binding("/lights/set", "std_srvs/SetBool", "call", ["request.data", "response.message"]),
                        client.node("switch"), types=TypeRegistry.standard(), dispatch=dispatch)
        m.start()
        fut = m.call({"data": True})
        response = await asyncio.wait_for(asyncio.wrap_future(fut), 10)
        assert response["success"] is True and dispatched
        assert m.state.value == response["message"] and m.state.message == response
        bad = WidgetModel(None, Binding("/no/such/service", "std_srvs/Trigger", "call"), client.node("b"))
        with pytest.raises(Exception):  # noqa: B017 - the bridge's error type is its own business
            await bad.call_async()
        assert "/no/such/service" in bad.state.error
        m.stop()
    finally:
        await client.close()


def test_binding_canonical_type():
    assert Binding("/imu", "sensor_msgs/Imu").canonical_type == "sensor_msgs/msg/Imu"
    assert Binding("/imu", "sensor_msgs/msg/Imu").canonical_type == "sensor_msgs/msg/Imu"
    assert Binding("/x").canonical_type == ""
    assert Binding("/x", "not a type").canonical_type == "not a type"


class Port:
    """A bridge port that hands the test the subscription's callback (``deliver``)."""

    def subscribe(self, topic, callback, **options):
        self.deliver = callback
        return self

    def unsubscribe(self):
        pass


def test_a_latched_topic_that_delivered_is_never_stale_but_a_stream_that_stops_is():
    clock = ManualClock()

    def started(settings=None):
        port = Port()
        m = WidgetModel(settings, Binding("/map", "nav_msgs/OccupancyGrid", "subscribe"), port, clock=clock)
        m.start()
        return m, port

    # a latched topic: one message right after subscribing, then silence
    latched, port = started()
    clock.now += 0.05
    port.deliver({"data": [0]})
    clock.now += 600
    assert latched.state.static and not latched.state.stale and latched.state.age == 600
    # the link drops and comes back: delivered again, still static
    latched.set_link(False)
    latched.set_link(True)
    clock.now += 0.1
    port.deliver({"data": [0]})
    clock.now += 60
    assert latched.state.static and not latched.state.stale
    # a stream that stops after some messages: stale as before
    stream, port = started()
    for _ in range(3):
        clock.now += 0.1
        port.deliver({"data": [1]})
    clock.now += 6
    assert stream.state.stale and not stream.state.static
    # a big latched map over a slow link: seconds to arrive, still static
    slow, port = started()
    clock.now += 3
    port.deliver({"data": [0] * 1000})
    clock.now += 60
    assert slow.state.static and not slow.state.stale
    # one message after the widget already said NO DATA is not a latched delivery: stale after stale_after
    late, port = started()
    clock.now += 6
    port.deliver({"data": [2]})
    clock.now += 6
    assert late.state.stale and not late.state.static
    # nothing at all: NO DATA (stale with count 0), latched or not
    quiet, _port = started()
    clock.now += 6
    assert quiet.state.stale and quiet.state.count == 0


def test_stale_after_zero_in_the_settings_means_a_static_topic():
    clock = ManualClock()

    class Static:
        stale_after = 0.0

    port = Port()
    m = WidgetModel(Static(), Binding("/robot_description", "std_msgs/String", "subscribe", "data"), port,
                    clock=clock)
    m.start()
    clock.now += 4
    assert not m.state.stale  # nothing yet, but not for long
    clock.now += 2
    assert m.state.stale and m.state.count == 0  # NO DATA after NO_DATA_AFTER
    clock.now += 1
    port.deliver({"data": "<robot/>"})  # long after subscribing: static because the settings say so
    clock.now += 3600
    assert m.state.static and not m.state.stale
