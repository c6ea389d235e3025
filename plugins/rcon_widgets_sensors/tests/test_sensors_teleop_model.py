"""Teleop model against the embedded sim: a stream while held, one zero on every way of letting go
(release, stop, link drop), then silence; two pads merge; the vessel moves.

Exact rates and "the zero goes out at once" are checked on a manual clock in ``test_sensors_teleop_rate.py``;
here the robot's side only checks what arrives, with no timing window a loaded machine could miss: where a
test says "then silence", the pad's timer runs on a ``ManualClock`` (:func:`tick`: every command it would
send in that time is sent at once) and :meth:`Receiver.barrier` sends a marker through the same client and
waits for it at the robot, so anything the pad sent has arrived before the test looks."""

import asyncio
import time

import pytest
from rcon_widgets_sensors.teleop import TeleopModel, TeleopSettings, TeleopValue, shape_axes

from rcon_core.bridge import BridgeClient, ConnectionState
from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import Binding, SharedResources, WidgetContext
from rcon_core.testing import ManualClock, until

TWIST = "geometry_msgs/Twist"
MARKER = "/rcon_test/marker"


class Receiver:
    """The robot's side: every /cmd_vel message with its monotonic receipt time."""

    def __init__(self, sim, topic="/cmd_vel", type_name="geometry_msgs/Twist"):
        self.got = []
        self.markers = set()
        self._marker_pubs = {}
        sim.subscribe_internal(topic, type_name, "/rcon_test_receiver", self._on)
        sim.subscribe_internal(MARKER, "std_msgs/String", "/rcon_test_receiver",
                               lambda m: self.markers.add(m["data"]))

    def _on(self, msg):
        self.got.append((time.monotonic(), msg))

    async def barrier(self, client):
        """Send a marker through ``client`` (again every poll until one arrives) and wait until the robot has
        it: everything ``client`` sent before has arrived by then (one connection, frames in order)."""
        token = f"m{len(self.markers)}-{time.monotonic_ns()}"
        pub = self._marker_pubs.get(id(client))
        if pub is None:
            pub = self._marker_pubs[id(client)] = client.node("rcon_test_marker").advertise(MARKER, "std_msgs/String")

        def arrived():
            if token in self.markers:
                return True
            pub.publish({"data": token})
            return False

        await until(arrived, 10.0, "the marker sent after the pad's commands")

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


async def tick(clock, seconds):
    """Run a pad's timer ``seconds`` forward on its manual clock: every command it would send meanwhile is
    sent now (on this loop, in order)."""
    clock.advance(seconds)
    await asyncio.sleep(0)


async def ticking_until(clock, predicate, what, step=0.05):
    """:func:`until` while the pad's manual clock moves ``step`` s per poll: a held pad keeps sending."""
    await until(lambda: clock.advance(step) or predicate(), 10.0, what)


def pad(client, settings=None, name="/cmd_vel", type_name=TWIST, node="pad", guarded=False, shared=None,
        clock=None):
    """A pad on its own node of ``client``; ``shared``: the store of the runtime the pads share (pads on one
    link merge through it, as the canvas runtime arranges with ``WidgetContext``); ``clock``: a
    ``ManualClock`` its publish timer runs on (None: the loop's)."""
    context = WidgetContext(link=id(client), resources=shared) if shared is not None else None
    port = client.node(node)
    if guarded:  # as the canvas runtime gives it: a GuardedPort naming the robot's link, no way to the client
        from rcon_core.canvas.port import GuardedPort

        port = GuardedPort(port, link=id(client))
    return TeleopModel(settings or TeleopSettings(), Binding(name, type_name, "publish"), port,
                       types=TypeRegistry.standard(), context=context, ticker_clock=clock)


async def test_stream_while_held_zero_on_release_then_silence(sim, client):
    rx, clock = Receiver(sim), ManualClock()
    model = pad(client, TeleopSettings(rate_hz=20, max_linear=2.0), clock=clock)
    model.start()
    try:
        await tick(clock, 0.3)
        await rx.barrier(client)
        assert rx.got == []  # idle: nothing at all, not even zeros
        t0 = time.monotonic()
        model.set_axes(0.0, 0.5)  # half way up: linear.x = 2.0 * (0.5 - 0.1) / 0.9
        await ticking_until(clock, lambda: len(rx.since(t0)) >= 5, "a stream of commands")
        held = rx.since(t0)
        assert all(m["linear"]["x"] == pytest.approx(2.0 * 0.4 / 0.9) and m["angular"]["z"] == 0.0
                   for m in held)
        assert model.state.value.active
        t_rel = time.monotonic()
        model.release()
        await until(lambda: rx.first_zero_since(t_rel)[0], 2.0, "the zero")
        await tick(clock, 0.5)
        await rx.barrier(client)
        assert rx.first_zero_since(t_rel)[1] == []  # one zero, then silence
        model.release()  # releasing an idle pad sends nothing
        await tick(clock, 0.2)
        await rx.barrier(client)
        assert rx.first_zero_since(t_rel)[1] == []
    finally:
        model.stop()


async def test_runtime_focus_lost_sends_one_zero_then_silence(sim, client):
    # the app calls on_focus_lost() when its window goes inactive, whether or not the pad had focus
    rx, clock = Receiver(sim), ManualClock()
    model = pad(client, clock=clock)
    model.start()
    try:
        model.set_axes(0.0, 0.8)
        await ticking_until(clock, lambda: rx.got, "driving")
        t = time.monotonic()
        model.on_focus_lost()
        await until(lambda: rx.first_zero_since(t)[0], 2.0, "the zero on focus loss")
        await tick(clock, 0.4)
        await rx.barrier(client)
        assert rx.first_zero_since(t)[1] == []
    finally:
        model.stop()


async def test_runtime_focus_lost_holds_the_pad_until_the_finger_lifts(sim, client):
    """Focus lost (or Edit mode) while a finger is still on the pad: the touch keeps going to the pad, and
    its next move drove the robot again. Now the pad stays stopped until that finger lifts; the next touch
    drives."""
    rx, clock = Receiver(sim), ManualClock()
    model = pad(client, clock=clock)
    model.start()
    try:
        model.set_axes(0.0, 0.8)
        await ticking_until(clock, lambda: rx.got, "driving")
        t = time.monotonic()
        model.on_focus_lost()
        await until(lambda: rx.first_zero_since(t)[0], 2.0, "the zero on focus loss")
        model.set_axes(0.0, 0.9)  # the same finger moves on
        await tick(clock, 0.4)
        await rx.barrier(client)
        assert rx.first_zero_since(t)[1] == []
        model.release()  # it lifts; the next touch drives
        model.set_axes(0.0, 0.8)
        await ticking_until(clock, lambda: len(rx.first_zero_since(t)[1]) > 0, "driving after the lift")
        model.release()
    finally:
        model.stop()


async def test_stop_sends_zero_and_locks_until_lift(sim, client):
    rx, clock = Receiver(sim), ManualClock()
    model = pad(client, clock=clock)
    model.start()
    model.set_axes(0.3, 0.9)
    await ticking_until(clock, lambda: rx.got, "driving")
    t = time.monotonic()
    model.stop()  # the canvas is switched away
    await until(lambda: rx.first_zero_since(t)[0], 2.0, "the zero on stop")
    await tick(clock, 0.4)
    await rx.barrier(client)
    assert rx.first_zero_since(t)[1] == []
    # back on the canvas: a fresh view sends a fresh touch; the lock ended with the stop
    model.release()
    model.start()
    model.set_axes(0.3, 0.9)
    await ticking_until(clock, lambda: len(rx.first_zero_since(t)[1]) > 0, "driving after a restart")
    model.release()
    model.stop()


async def test_link_drop_zero_after_reconnect_then_silence(sim, client):
    rx, clock = Receiver(sim), ManualClock()
    model = pad(client, TeleopSettings(rate_hz=10), clock=clock)
    states = []

    def on_state(st):
        states.append(st)
        model.set_link(st is ConnectionState.CONNECTED)

    client.add_state_listener(on_state)
    model.start()
    try:
        model.set_axes(0.0, 1.0)
        await ticking_until(clock, lambda: len(rx.got) >= 2, "driving")
        assert rx.got[-1][1]["linear"]["x"] == pytest.approx(1.0)
        t = time.monotonic()
        for conn in list(sim.connections):  # the network drops: the socket dies without a close frame
            conn.ws.transport.abort()
        await until(lambda: ConnectionState.RECONNECTING in states, 3.0, "link down seen")
        await until(lambda: states[-1] is ConnectionState.CONNECTED, 5.0, "reconnected")
        value = model.state.value
        assert value.locked and not value.active and value.reason == "link down"
        await until(lambda: any(is_zero(m) for m in rx.since(t)), 3.0, "a zero after the drop")
        await rx.barrier(client)
        _when, after = rx.first_zero_since(t)
        assert after == [] or all(is_zero(m) for m in after)  # never the old command again
        n = len(rx.since(t))
        model.set_axes(0.0, 1.0)  # the finger is still down: locked until it lifts
        await tick(clock, 0.5)
        await rx.barrier(client)
        assert len(rx.since(t)) == n
        model.release()  # lift: unlocks, sends nothing (already idle)
        await tick(clock, 0.2)
        await rx.barrier(client)
        assert len(rx.since(t)) == n
        model.set_axes(0.0, 1.0)  # a new touch drives again
        await ticking_until(clock, lambda: len(rx.since(t)) > n and not is_zero(rx.since(t)[-1]), "driving again")
        model.release()
    finally:
        model.stop()


@pytest.mark.parametrize("guarded", [False, True], ids=["bare-nodes", "runtime-ports"])
async def test_two_pads_merge_into_one_stream(sim, client, guarded):
    rx, clock = Receiver(sim), ManualClock()
    shared = SharedResources()
    linear = pad(client, TeleopSettings(horizontal="", vertical="linear.x", rate_hz=10), node="left",
                 guarded=guarded, shared=shared, clock=clock)
    angular = pad(client, TeleopSettings(horizontal="-angular.z", vertical="", rate_hz=10, dead_zone=0),
                  node="right", guarded=guarded, shared=shared, clock=clock)

    def both(m):
        return m["linear"]["x"] == pytest.approx(1.0) and m["angular"]["z"] == pytest.approx(-0.5)

    linear.start()
    angular.start()
    try:
        t = time.monotonic()
        linear.set_axes(0.0, 1.0)
        angular.set_axes(0.5, 0.0)  # right: turn right (negative yaw rate)
        # one message carries both pads' axes: merged (two streams would each carry one axis)
        await ticking_until(clock, lambda: sum(1 for m in rx.since(t) if both(m)) >= 3, "the merged stream")
        t2 = time.monotonic()
        linear.release()  # only its own axis drops to zero; the other pad keeps driving

        def later():  # (one sent before the release may still arrive after t2)
            return [m for m in rx.since(t2) if m["linear"]["x"] == 0]

        await ticking_until(clock, lambda: len(later()) >= 3, "the other pad still driving")
        assert all(m["angular"]["z"] == pytest.approx(-0.5) for m in later())
        assert rx.since(t2)[-1]["linear"]["x"] == 0
        t3 = time.monotonic()
        angular.release()
        await tick(clock, 0.4)
        await rx.barrier(client)
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
    rx, clock = Receiver(sim), ManualClock()
    client = BridgeClient(sim.url, reconnect=False)
    await client.connect()
    model = pad(client, clock=clock)
    client.add_state_listener(lambda st: model.set_link(st is ConnectionState.CONNECTED))
    model.start()
    try:
        model.set_axes(0.0, 1.0)
        await ticking_until(clock, lambda: len(rx.got) >= 2, "driving")
        await client.close()  # the operator's side goes away
        t = time.monotonic()
        await tick(clock, 0.5)  # the ticks due while down: nothing can (and nothing tries to) go out
        assert rx.since(t) == []
        assert model.state.link_down and model.state.value.locked
        await client.connect()  # back: exactly one zero, then silence
        await until(lambda: rx.first_zero_since(t)[0], 3.0, "the zero after reconnecting")
        await tick(clock, 0.4)
        await rx.barrier(client)
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
