"""Teleop model against the embedded sim: a stream while held, one zero on every way of letting go
(release, stop, link drop), then silence; two pads merge; the vessel moves.

Exact rates and "the zero goes out at once" are checked on a manual clock in ``test_sensors_teleop_rate.py``;
here the robot's side only checks what arrives, with no timing window a loaded machine could miss."""

import asyncio
import time

import pytest
from rcon_widgets_sensors.teleop import TeleopModel, TeleopSettings, TeleopValue, shape_axes

from rcon_core.bridge import BridgeClient, ConnectionState
from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import Binding, SharedResources, WidgetContext
from rcon_core.testing import until

TWIST = "geometry_msgs/Twist"


class Receiver:
    """The robot's side: every /cmd_vel message with its monotonic receipt time."""

    def __init__(self, sim, topic="/cmd_vel", type_name="geometry_msgs/Twist"):
        self.got = []
        sim.subscribe_internal(topic, type_name, "/rcon_test_receiver", self._on)

    def _on(self, msg):
        self.got.append((time.monotonic(), msg))

    def since(self, t):
        return [m for when, m in self.got if when >= t]

    def first_zero_since(self, t):
        """(receipt time, messages received after it) of the first zero command at or after ``t``."""
        for i, (when, m) in enumerate(self.got):
            if when >= t and is_zero(m):
                return when, [x for _w, x in self.got[i + 1:]]
        return None, []


def is_zero(msg):
    return all(v == 0 for part in ("linear", "angular") for v in msg[part].values())


@pytest.fixture
async def client(sim):
    c = BridgeClient(sim.url, reconnect=True, backoff_min=0.05, backoff_max=0.2)
    await c.connect()
    yield c
    await c.close()


def pad(client, settings=None, name="/cmd_vel", type_name=TWIST, node="pad", guarded=False, shared=None):
    """A pad on its own node of ``client``; ``shared``: the store of the runtime the pads share (pads on one
    link merge through it, as the canvas runtime arranges with ``WidgetContext``)."""
    context = WidgetContext(link=id(client), resources=shared) if shared is not None else None
    port = client.node(node)
    if guarded:  # as the canvas runtime gives it: a GuardedPort naming the robot's link, no way to the client
        from rcon_core.canvas.port import GuardedPort

        port = GuardedPort(port, link=id(client))
    return TeleopModel(settings or TeleopSettings(), Binding(name, type_name, "publish"), port,
                       types=TypeRegistry.standard(), context=context)


async def test_stream_while_held_zero_on_release_then_silence(sim, client):
    rx = Receiver(sim)
    model = pad(client, TeleopSettings(rate_hz=20, max_linear=2.0))
    model.start()
    try:
        await asyncio.sleep(0.3)
        assert rx.got == []  # idle: nothing at all, not even zeros
        t0 = time.monotonic()
        model.set_axes(0.0, 0.5)  # half way up: linear.x = 2.0 * (0.5 - 0.1) / 0.9
        await until(lambda: len(rx.since(t0)) >= 5, 5.0, "a stream of commands")  # the rate is not timed here
        held = rx.since(t0)
        assert all(m["linear"]["x"] == pytest.approx(2.0 * 0.4 / 0.9) and m["angular"]["z"] == 0.0
                   for m in held)
        assert model.state.value.active
        t_rel = time.monotonic()
        model.release()
        await until(lambda: rx.first_zero_since(t_rel)[0], 2.0, "the zero")
        await asyncio.sleep(0.5)
        assert rx.first_zero_since(t_rel)[1] == []  # one zero, then silence
        model.release()  # releasing an idle pad sends nothing
        await asyncio.sleep(0.2)
        assert rx.first_zero_since(t_rel)[1] == []
    finally:
        model.stop()


async def test_runtime_focus_lost_sends_one_zero_then_silence(sim, client):
    # the app calls on_focus_lost() when its window goes inactive, whether or not the pad had focus
    rx = Receiver(sim)
    model = pad(client)
    model.start()
    try:
        model.set_axes(0.0, 0.8)
        await until(lambda: rx.got, 2.0, "driving")
        t = time.monotonic()
        model.on_focus_lost()
        await until(lambda: rx.first_zero_since(t)[0], 2.0, "the zero on focus loss")
        await asyncio.sleep(0.4)
        assert rx.first_zero_since(t)[1] == []
    finally:
        model.stop()


async def test_stop_sends_zero_and_locks_until_lift(sim, client):
    rx = Receiver(sim)
    model = pad(client)
    model.start()
    model.set_axes(0.3, 0.9)
    await until(lambda: rx.got, 2.0, "driving")
    t = time.monotonic()
    model.stop()  # the canvas is switched away
    await until(lambda: rx.first_zero_since(t)[0], 2.0, "the zero on stop")
    await asyncio.sleep(0.4)
    assert rx.first_zero_since(t)[1] == []
    # back on the canvas: a fresh view sends a fresh touch; the lock ended with the stop
    model.release()
    model.start()
    model.set_axes(0.3, 0.9)
    await until(lambda: len(rx.first_zero_since(t)[1]) > 0, 2.0, "driving after a restart")
    model.release()
    model.stop()


async def test_link_drop_zero_after_reconnect_then_silence(sim, client):
    rx = Receiver(sim)
    model = pad(client, TeleopSettings(rate_hz=10))
    states = []

    def on_state(st):
        states.append(st)
        model.set_link(st is ConnectionState.CONNECTED)

    client.add_state_listener(on_state)
    model.start()
    try:
        model.set_axes(0.0, 1.0)
        await until(lambda: len(rx.got) >= 2, 3.0, "driving")
        assert rx.got[-1][1]["linear"]["x"] == pytest.approx(1.0)
        t = time.monotonic()
        for conn in list(sim.connections):  # the network drops: the socket dies without a close frame
            conn.ws.transport.abort()
        await until(lambda: ConnectionState.RECONNECTING in states, 3.0, "link down seen")
        await until(lambda: states[-1] is ConnectionState.CONNECTED, 5.0, "reconnected")
        value = model.state.value
        assert value.locked and not value.active and value.reason == "link down"
        await until(lambda: any(is_zero(m) for m in rx.since(t)), 3.0, "a zero after the drop")
        _when, after = rx.first_zero_since(t)
        assert after == [] or all(is_zero(m) for m in after)  # never the old command again
        n = len(rx.since(t))
        model.set_axes(0.0, 1.0)  # the finger is still down: locked until it lifts
        await asyncio.sleep(0.5)
        assert len(rx.since(t)) == n
        model.release()  # lift: unlocks, sends nothing (already idle)
        await asyncio.sleep(0.2)
        assert len(rx.since(t)) == n
        model.set_axes(0.0, 1.0)  # a new touch drives again
        await until(lambda: len(rx.since(t)) > n and not is_zero(rx.since(t)[-1]), 2.0, "driving again")
        model.release()
    finally:
        model.stop()


@pytest.mark.parametrize("guarded", [False, True], ids=["bare-nodes", "runtime-ports"])
async def test_two_pads_merge_into_one_stream(sim, client, guarded):
    rx = Receiver(sim)
    shared = SharedResources()
    linear = pad(client, TeleopSettings(horizontal="", vertical="linear.x", rate_hz=10), node="left",
                 guarded=guarded, shared=shared)
    angular = pad(client, TeleopSettings(horizontal="-angular.z", vertical="", rate_hz=10, dead_zone=0),
                  node="right", guarded=guarded, shared=shared)

    def both(m):
        return m["linear"]["x"] == pytest.approx(1.0) and m["angular"]["z"] == pytest.approx(-0.5)

    linear.start()
    angular.start()
    try:
        t = time.monotonic()
        linear.set_axes(0.0, 1.0)
        angular.set_axes(0.5, 0.0)  # right: turn right (negative yaw rate)
        # one message carries both pads' axes: merged (two streams would each carry one axis)
        await until(lambda: sum(1 for m in rx.since(t) if both(m)) >= 3, 5.0, "the merged stream")
        t2 = time.monotonic()
        linear.release()  # only its own axis drops to zero; the other pad keeps driving

        def later():  # (one sent before the release may still arrive after t2)
            return [m for m in rx.since(t2) if m["linear"]["x"] == 0]

        await until(lambda: len(later()) >= 3, 5.0, "the other pad still driving")
        assert all(m["angular"]["z"] == pytest.approx(-0.5) for m in later())
        assert rx.since(t2)[-1]["linear"]["x"] == 0
        t3 = time.monotonic()
        angular.release()
        await asyncio.sleep(0.4)
        when, after = rx.first_zero_since(t3)
        assert when is not None and after == []
    finally:
        linear.stop()
        angular.stop()


async def test_vessel_moves_when_driven(sim, client):
    model = pad(client, TeleopSettings(max_linear=1.0, rate_hz=10))
    model.start()
    x0, y0 = sim.robot.x, sim.robot.y
    try:
        model.set_axes(0.0, 1.0)
        await until(lambda: abs(sim.robot.x - x0) + abs(sim.robot.y - y0) > 0.2, 10.0, "the vessel moving")
        assert sim.robot.cmd_surge == pytest.approx(1.0)
        model.release()
        await until(lambda: sim.robot.cmd_surge == 0.0, 2.0, "the thrusters stopped")
    finally:
        model.stop()


@pytest.mark.parametrize("type_name,field,axes,expect", [
    ("geometry_msgs/TwistStamped", "twist", (0.0, 1.0), {"twist.linear.x": 1.0}),
    ("geometry_msgs/Vector3", "", (1.0, 0.0), {"y": -1.0}),
    ("geometry_msgs/PointStamped", "point", (0.0, -1.0), {"point.x": -1.0}),
    ("geometry_msgs/Pose2D", "", (0.0, 1.0), {"x": 1.0}),
    ("geometry_msgs/Accel", "", (-1.0, 0.0), {"angular.z": 2.0}),
])
async def test_other_planar_types(sim, client, type_name, field, axes, expect):
    topic = "/rcon_test/motion"
    got = []
    sim.subscribe_internal(topic, type_name, "/rcon_test_receiver", got.append)
    model = pad(client, TeleopSettings(dead_zone=0, max_angular=2.0), name=topic, type_name=type_name)
    assert model.problems() == [] and model.body_path == field
    model.start()
    try:
        model.set_axes(*axes)
        await until(lambda: got, 3.0, "a message")
        from rcon_core.plugins.paths import get_path
        for path, value in expect.items():
            assert get_path(got[-1], path) == pytest.approx(value)
        if "header" in got[-1]:
            assert got[-1]["header"]["stamp"]["secs"] > 0
    finally:
        model.release()
        model.stop()


def test_settings_and_axis_problems():
    assert TeleopSettings().problems() == []
    bad = TeleopSettings(horizontal="linear x", vertical="", max_linear=0, max_angular=99, dead_zone=0.95, rate_hz=0)
    text = " | ".join(bad.problems())
    for part in ("'linear x' is not a field path", "maximum linear speed", "maximum angular speed", "dead zone",
                 "publish rate"):
        assert part in text
    assert "both axes are unused" in " ".join(TeleopSettings(horizontal="", vertical="").problems())
    m = TeleopModel(TeleopSettings(vertical="linear.q"), Binding("/c", TWIST, "publish"), None,
                    types=TypeRegistry.standard())
    assert m.problems() == ["geometry_msgs/Twist has no field 'linear.q' for the pad's axis"]
    m2 = TeleopModel(None, Binding("/c", "geometry_msgs/Twist", "publish"), None)  # no registry: built-in table
    assert m2.problems() == [] and m2.template()["linear"] == {"x": 0.0, "y": 0.0, "z": 0.0}
    assert isinstance(m2.state.value, TeleopValue) and not m2.state.value.active


def test_dead_zone_and_clamp():
    assert shape_axes(0.05, 0.05, 0.1) == (0.0, 0.0)
    x, y = shape_axes(3.0, 4.0, 0.0)
    assert (x, y) == pytest.approx((0.6, 0.8))
    assert shape_axes(0.0, 0.55, 0.1)[1] == pytest.approx(0.5)
    m = TeleopModel(TeleopSettings(dead_zone=0.2, max_linear=0.5, max_angular=1.5), Binding("/c", TWIST, "publish"),
                    None)
    assert m.command_for(0.1, 0.1) == {"angular.z": 0.0, "linear.x": 0.0}
    cmd = m.command_for(1.0, 0.0)
    assert cmd["angular.z"] == pytest.approx(-1.5) and cmd["linear.x"] == 0.0


def test_set_axes_before_start_publishes_nothing():
    sent = []

    class Port:
        def advertise(self, *a, **k):
            raise AssertionError("not started")

    m = TeleopModel(None, Binding("/c", TWIST, "publish"), Port())
    m.set_axes(0, 1)  # not running: no publish, no error
    assert sent == [] and not m.active and m.state.error is None


async def test_client_closed_then_reopened_sends_one_zero(sim):
    rx = Receiver(sim)
    client = BridgeClient(sim.url, reconnect=False)
    await client.connect()
    model = pad(client)
    client.add_state_listener(lambda st: model.set_link(st is ConnectionState.CONNECTED))
    model.start()
    try:
        model.set_axes(0.0, 1.0)
        await until(lambda: len(rx.got) >= 2, 3.0, "driving")
        await client.close()  # the operator's side goes away
        t = time.monotonic()
        await asyncio.sleep(0.5)
        assert rx.since(t) == []  # nothing can (and nothing tries to) go out while down
        assert model.state.link_down and model.state.value.locked
        await client.connect()  # back: exactly one zero, then silence
        await until(lambda: rx.first_zero_since(t)[0], 3.0, "the zero after reconnecting")
        await asyncio.sleep(0.4)
        assert rx.first_zero_since(t)[1] == [] and len(rx.since(t)) == 1
    finally:
        model.stop()
        await client.close()


async def test_silent_stall_stops_the_pad_and_never_delivers_a_late_command(sim):
    """Issue 11 item 5: a 2.5 s stall with no FIN nor RST while the finger is down.  The link goes DEGRADED
    (down for the pad: forced stop, locked), no command reaches the robot later than its freshness limit,
    and the zero arrives once the link is back."""
    from rcon_widgets_sensors.teleop import COMMAND_MAX_AGE

    from rcon_core.loopback import StallProxy

    arrivals = []  # (age at arrival in s, msg)

    def on_cmd(msg):
        stamp = msg["header"]["stamp"]
        arrivals.append((time.time() - stamp["secs"] - stamp["nsecs"] * 1e-9, msg))

    sim.subscribe_internal("/cmd_stamped", "geometry_msgs/TwistStamped", "/rcon_test_receiver", on_cmd)
    async with StallProxy("127.0.0.1", sim.port) as proxy:
        c = BridgeClient(proxy.url, backoff_min=0.05, backoff_max=0.2)
        await c.connect()
        model = pad(c, TeleopSettings(rate_hz=20), name="/cmd_stamped", type_name="geometry_msgs/TwistStamped")
        states = []

        def on_state(st):
            states.append(st)
            model.set_link(st is ConnectionState.CONNECTED)

        c.add_state_listener(on_state)
        model.start()
        try:
            model.set_axes(0.0, 1.0)
            await until(lambda: len(arrivals) >= 3, 3.0, "driving")
            proxy.stall()
            await until(lambda: ConnectionState.DEGRADED in states, 1.5, "DEGRADED within 1.5 s")
            assert model.state.value.locked and model.state.value.reason == "link down"
            await asyncio.sleep(1.5)
            n = len(arrivals)
            proxy.resume()
            await until(lambda: states[-1] is ConnectionState.CONNECTED, 5.0, "link back")
            await until(lambda: any(is_zero(m["twist"]) for _age, m in arrivals[n:]), 3.0, "a zero after the stall")
            late = [round(age, 2) for age, _m in arrivals if age > COMMAND_MAX_AGE + 0.5]
            assert late == [], f"commands delivered late: {late}"
            assert all(is_zero(m["twist"]) for _age, m in arrivals[n:])  # never the old command again
            assert c.stats["stale_dropped"] >= 1  # the zero sent while DEGRADED could not go out in time
        finally:
            model.release()
            model.stop()
            await c.close()


async def test_a_pad_started_after_the_limit_was_set_shows_that_limit(sim):
    """The operator set the robot's speed limit from another app, which then closed; a pad started later
    hears the limit at once: the robot holds /speed_limit latched (ROS 1 latched / ROS 2 transient local),
    so rosbridge gives the last value to a new subscriber."""
    setter = BridgeClient(sim.url, reconnect=False)
    await setter.connect()
    limit = setter.node("slider").advertise("/speed_limit", "std_msgs/Float64")
    limit.publish({"data": 0.4})
    await until(lambda: sim.robot.speed_limit == 0.4, what="the robot taking the limit")
    await setter.close()  # the app that set it is gone: its own publisher with it
    later = BridgeClient(sim.url, reconnect=False)
    await later.connect()
    try:
        p = pad(later, TeleopSettings(max_linear=1.0, speed_limit_topic="/speed_limit"))
        p.start()
        await until(lambda: p.limits()[0] == 0.4, what="the pad hearing the limit set before it started")
        assert p.limits()[2] == "≤ 0.4 m/s (speed limit)"
        p.stop()
    finally:
        await later.close()


async def test_commands_held_behind_a_call_stop_the_pad_with_one_zero_and_nothing_more(sim, client):
    """The runtime says the robot's bridge holds the link's commands behind an unanswered call
    (``rcon_core/bridge/held.py``): the pad sends one zero (it waits behind the call with whatever went out
    since, so the robot ends stopped), then nothing, finger or not, and says why; once the call is answered
    the finger is lifted and put down again to drive."""
    rx = Receiver(sim)
    model = pad(client, TeleopSettings(rate_hz=20))
    model.start()
    try:
        t0 = time.monotonic()
        model.set_axes(0.0, 0.8)
        await until(lambda: len(rx.since(t0)) >= 2, 5.0, "commands")
        held = "commands held: the robot's bridge is still busy with /dock"
        t_held = time.monotonic()
        model.on_commands_held(held)
        await until(lambda: rx.first_zero_since(t_held)[0], 2.0, "the zero")
        sent = model.state.value.sent
        assert model.state.value.commands_held == held and not model.state.value.active
        model.set_axes(0.0, 0.9)  # the finger moves on: nothing
        model.release()
        model.set_axes(0.0, 0.9)  # lifted and put down again while still held: nothing
        assert model.state.value.sent == sent and not model.state.value.active
        model.on_commands_held(None)  # answered
        assert model.state.value.commands_held == ""
        model.release()
        model.set_axes(0.0, 0.9)
        assert model.state.value.active and model.state.value.sent == sent + 1  # drives again at once
    finally:
        model.stop()
