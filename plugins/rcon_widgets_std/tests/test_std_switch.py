"""Switch: publish a bool, reflect the robot's state, call /lights/set with /lights/state as the truth."""


from rcon_widgets_std.switch import SwitchModel, SwitchSettings, SwitchValue
from std_testkit import bridge, build

from rcon_core.msgs import TypeRegistry
from rcon_core.testing import until


async def test_call_lights_set_and_follow_lights_state(sim):
    async with bridge(sim) as client:
        settings = SwitchSettings(state_topic="/lights/state")
        sw = build(SwitchModel, settings, "/lights/set", "std_srvs/SetBool", "call", "request.data",
                   client=client, node="sw")
        shown = build(SwitchModel, SwitchSettings(), "/lights/state", "std_msgs/Bool", "subscribe", "data",
                      client=client, node="shown")
        sw.start()
        shown.start()
        await until(lambda: isinstance(sw.state.value, SwitchValue) and sw.state.value.on is False,
                    what="the latched /lights/state")
        assert shown.state.value.on is False
        sw.set(True)
        assert sw.state.value.busy and sw.state.value.wanted is True  # shown at once, before the answer
        await until(lambda: sw.state.value.on is True and not sw.state.value.busy, what="lights on")
        assert sim.robot.lights is True and sw.state.value.reply == "lights on"
        await until(lambda: shown.state.value.on is True, what="the subscriber switch")
        sw.toggle()
        await until(lambda: sw.state.value.on is False and not sw.state.value.busy, what="lights off")
        assert sim.robot.lights is False
        sw.stop()
        shown.stop()


async def test_without_state_topic_the_last_successful_request_is_the_state(sim):
    async with bridge(sim) as client:
        sw = build(SwitchModel, SwitchSettings(), "/lights/set", "std_srvs/SetBool", "call", "request.data",
                   client=client, types=TypeRegistry.empty())
        sw.start()
        await until(lambda: sw.types_ready, what="SetBool learned from the robot")
        assert sw.request_for(True) == {"data": True}
        sw.set(True)
        await until(lambda: sw.state.value.on is True, what="lights on")
        assert sim.robot.lights is True


async def test_a_failing_call_reverts_and_shows_the_servers_message(sim):
    async with bridge(sim) as client:
        node = client.node("robot-side")
        node.advertise_service("/rcon_test/arm", "std_srvs/SetBool",
                               lambda req: {"success": False, "message": "interlock open"})
        await until(lambda: "/rcon_test/arm" in sim.services, what="the service advertised")
        sw = build(SwitchModel, SwitchSettings(), "/rcon_test/arm", "std_srvs/SetBool", "call", "request.data",
                   client=client)
        sw.start()
        sw.set(True)
        await until(lambda: sw.state.error, what="the refusal")
        assert "interlock open" in sw.state.error and sw.state.value.on is None and not sw.state.value.busy
        gone = build(SwitchModel, SwitchSettings(), "/no/such/service", "std_srvs/SetBool", "call",
                     "request.data", client=client, node="gone")
        gone.start()
        gone.set(True)
        await until(lambda: gone.state.error, what="the server's error")
        assert "/no/such/service" in gone.state.error and not gone.state.value.busy


async def test_publish_a_bool_field_of_a_larger_message(sim):
    async with bridge(sim) as client:
        sw = build(SwitchModel, SwitchSettings(), "/rcon_test/battery", "sensor_msgs/BatteryState", "publish",
                   "present", client=client)
        sw.start()
        sw.set(True)
        got = await sim.wait_for_published("/rcon_test/battery", lambda m: m["present"] is True, timeout=10)
        assert got["percentage"] == 0.0 and sw.state.value.on is True
        sw.toggle()
        await sim.wait_for_published("/rcon_test/battery", lambda m: m["present"] is False, timeout=10)
        sw.stop()


async def test_subscribe_a_bool_field_inside_battery_state(sim):
    async with bridge(sim) as client:
        sw = build(SwitchModel, SwitchSettings(), "/battery", "sensor_msgs/BatteryState", "subscribe", "present",
                   client=client)
        sw.start()
        await until(lambda: sw.state.value is not None, what="a battery message")
        assert sw.state.value.on is True
        sw.set(False)  # a subscriber cannot change the robot
        assert "only shows" in sw.state.error
        sw.stop()


def test_problems_for_non_bool_fields_and_bad_settings():
    sw = build(SwitchModel, SwitchSettings(), "/battery", "sensor_msgs/BatteryState", "subscribe", "voltage")
    assert sw.problems() == ["voltage of sensor_msgs/msg/BatteryState is not a bool field"]
    sw = build(SwitchModel, SwitchSettings(), "/dock", "std_srvs/Trigger", "call", "request.data")
    assert "no field 'data'" in sw.problems()[0]
    assert SwitchSettings(state_topic="lights/state").problems() == [
        "state topic 'lights/state' must start with '/'"]
    ok = build(SwitchModel, SwitchSettings(), "/lights/set", "std_srvs/SetBool", "call", "request.data")
    assert ok.problems() == []
