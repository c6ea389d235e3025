"""Button: press/release calls against the robot, progress without blocking, results, the server's errors,
request text checked against the definition, and the PUBLISH role."""

import asyncio

from rcon_widgets_std.button import ButtonModel, ButtonSettings
from std_testkit import bridge, build

from rcon_core.msgs import TypeRegistry
from rcon_core.testing import flushed, until


def status(m):
    return m.state.value


async def test_press_calls_dock_and_shows_the_result(sim):
    async with bridge(sim) as client:
        b = build(ButtonModel, ButtonSettings(), "/dock", "std_srvs/Trigger", "call", client=client)
        b.start()
        b.press()
        assert status(b).busy and status(b).target == "/dock"
        await until(lambda: not status(b).busy, what="the answer")
        assert status(b).phase == "ok" and status(b).text.startswith("dock")  # "docked" / "docking started..."
        assert sim.robot.docking or sim.robot.docked
        assert status(b).seconds is not None and b.state.error is None


async def test_success_false_shows_the_servers_message_as_a_failure(sim):
    async with bridge(sim) as client:
        sim.robot.docked = True
        b = build(ButtonModel, ButtonSettings(), "/dock", "std_srvs/Trigger", "call", client=client)
        b.start()
        b.press()
        await until(lambda: not status(b).busy, what="the answer")
        assert status(b).phase == "failed" and status(b).text == "already docked"
        assert "already docked" in b.state.error


async def test_unknown_service_error_is_the_servers_message(sim):
    async with bridge(sim) as client:
        b = build(ButtonModel, ButtonSettings(), "/no/such/service", "std_srvs/Trigger", "call", client=client)
        b.start()
        b.press()
        await until(lambda: not status(b).busy, what="the failure")
        assert status(b).phase == "failed" and "/no/such/service" in status(b).text


async def test_press_and_release_call_two_services_with_yaml_requests(sim):
    async with bridge(sim) as client:
        settings = ButtonSettings(payload="data: true", release_service="/lights/set",
                                  release_payload='{"data": false}')
        b = build(ButtonModel, settings, "/lights/set", "std_srvs/SetBool", "call", client=client)
        b.start()
        assert b.problems() == []
        b.press()
        await until(lambda: sim.robot.lights is True, what="lights on while pressed")
        await until(lambda: status(b).phase == "ok", what="the press answer")
        assert status(b).text == "lights on"
        b.release()
        await until(lambda: sim.robot.lights is False, what="lights off on release")
        await until(lambda: status(b).phase == "ok" and status(b).text == "lights off", what="release answer")


async def test_a_slow_service_never_blocks_the_caller(sim):
    async with bridge(sim) as client:
        gate, asked = asyncio.Event(), []

        async def slow(req):
            asked.append(req)
            await gate.wait()
            return {"success": True, "message": "finally"}

        client.node("robot-side").advertise_service("/rcon_test/slow", "std_srvs/Trigger", slow)
        await until(lambda: "/rcon_test/slow" in sim.services, what="the service advertised")
        b = build(ButtonModel, ButtonSettings(), "/rcon_test/slow", "std_srvs/Trigger", "call", client=client)
        b.start()
        b.press()  # returns at once
        await until(lambda: asked, what="the call reaching the (held) service")
        assert status(b).busy  # still waiting, and we got here: nothing blocked
        gate.set()
        await until(lambda: status(b).phase == "ok", what="the slow answer")
        assert status(b).text == "finally"


async def test_request_of_a_type_learned_from_the_robot(sim):
    async with bridge(sim) as client:
        types = TypeRegistry.empty()
        b = build(ButtonModel, ButtonSettings(payload="data: yes"), "/lights/set", "std_srvs/SetBool", "call",
                  client=client, types=types)
        b.start()
        await until(lambda: b.types_ready, what="SetBool typedefs")
        assert b.problems() == []  # 'yes' is YAML for true
        b.press()
        await until(lambda: sim.robot.lights is True, what="lights on")


def test_request_text_is_checked_against_the_definition():
    b = build(ButtonModel, ButtonSettings(payload="data: maybe"), "/lights/set", "std_srvs/SetBool", "call")
    (problem,) = b.problems()
    assert problem.startswith("request: data:") and "maybe" in problem
    b = build(ButtonModel, ButtonSettings(payload="colour: red"), "/lights/set", "std_srvs/SetBool", "call")
    assert "colour" in b.problems()[0]
    assert "not valid YAML" in ButtonSettings(payload="data: [").problems()[0]
    assert ButtonSettings(release_service="lights").problems() == [
        "release service 'lights' must start with '/'"]
    b = build(ButtonModel, ButtonSettings(payload="linear: {x: fast}"), "/cmd_vel", "geometry_msgs/Twist",
              "publish")
    assert b.problems()[0].startswith("message: linear.x:")


async def test_publish_role_sends_a_fixed_message_and_another_on_release(sim):
    async with bridge(sim) as client:
        settings = ButtonSettings(payload="linear: {x: 0.4}\nangular: {z: 0.1}", release_payload="{}")
        b = build(ButtonModel, settings, "/cmd_vel", "geometry_msgs/Twist", "publish", client=client)
        b.start()
        b.press()
        got = await sim.wait_for_published("/cmd_vel", lambda m: m["linear"]["x"] == 0.4, timeout=10)
        assert got["angular"]["z"] == 0.1 and got["linear"]["y"] == 0.0
        assert status(b).phase == "ok"
        b.release()
        await sim.wait_for_published("/cmd_vel", lambda m: m["linear"]["x"] == 0.0, timeout=10)
        b.stop()


async def test_bad_message_publishes_nothing(sim):
    async with bridge(sim) as client:
        b = build(ButtonModel, ButtonSettings(payload="data: lots"), "/speed_limit", "std_msgs/Float64",
                  "publish", client=client)
        b.start()
        b.press()
        assert "data" in b.state.error and status(b) is None
        await flushed(client, sim)
        assert sim.published("/speed_limit") == []
