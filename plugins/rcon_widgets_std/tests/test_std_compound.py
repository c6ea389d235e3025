"""Compound: children composing a message, a service request and a service response, of types learned
from the robot's typedefs; children from another package; problems."""


import pytest
from rcon_widgets_std import compound as compound_mod
from rcon_widgets_std.compound import ChildSpec, CompoundModel, CompoundSettings
from std_testkit import bridge, build

from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import Accepts, PluginManager, Role, WidgetContext, WidgetModel, WidgetSpec, hookimpl
from rcon_core.testing import until


def child(kind, path, **settings):
    return ChildSpec(kind, path, settings)


def by_path(m, path):
    return next(c.model for c in m.children if c.cfg.field_path == path)


async def test_publish_one_imu_composed_from_children_with_types_learned_from_the_robot(sim):
    async with bridge(sim) as client:
        types = TypeRegistry.empty()
        settings = CompoundSettings(children=[
            child("std.slider", "linear_acceleration.z", minimum=-20, maximum=20, step=0.1),
            child("std.textfield", "angular_velocity"),
            child("std.slider", "orientation.w", minimum=-1, maximum=1, step=0.01),
            child("std.textfield", "header.frame_id"),
        ])
        m = build(CompoundModel, settings, "/rcon_test/imu", "sensor_msgs/Imu", "publish", client=client,
                  types=types)
        m.start()
        await until(lambda: m.children, what="children built once Imu is learned")
        assert types.has("sensor_msgs/Imu") and m.problems() == []
        by_path(m, "linear_acceleration.z").release(9.81)
        by_path(m, "angular_velocity").submit("{x: 0.1, z: -0.05}")
        by_path(m, "orientation.w").release(1.0)
        by_path(m, "header.frame_id").submit("imu_link")
        assert m.state.value.message["linear_acceleration"]["z"] == 9.8  # snapped to the 0.1 step grid
        m.send()
        got = await sim.wait_for_published("/rcon_test/imu", timeout=10)
        assert got["linear_acceleration"] == {"x": 0.0, "y": 0.0, "z": 9.8}
        assert got["angular_velocity"] == {"x": 0.1, "y": 0.0, "z": -0.05}
        assert got["orientation"]["w"] == 1.0 and got["header"]["frame_id"] == "imu_link"
        assert len(got["orientation_covariance"]) == 9  # the rest is the type's default
        assert m.state.value.status.phase == "ok"
        m.stop()
        assert not any(c.model.running for c in m.children)


async def test_auto_send_drives_cmd_vel(sim):
    async with bridge(sim) as client:
        settings = CompoundSettings(auto_send=True, rate_hz=20, children=[
            child("std.slider", "linear.x", minimum=-1, maximum=1, step=0.1),
            child("std.slider", "angular.z", minimum=-1, maximum=1, step=0.1),
        ])
        m = build(CompoundModel, settings, "/cmd_vel", "geometry_msgs/Twist", "publish", client=client)
        m.start()
        by_path(m, "linear.x").release(0.5)
        by_path(m, "angular.z").release(-0.2)
        got = await sim.wait_for_published(
            "/cmd_vel", lambda msg: msg["linear"]["x"] == 0.5 and msg["angular"]["z"] == -0.2, timeout=10)
        assert got["linear"]["y"] == 0.0
        await until(lambda: sim.robot.cmd_surge > 0, what="the robot taking the command")
        m.stop()


async def test_call_with_a_composed_request_and_children_showing_the_response(sim):
    async with bridge(sim) as client:
        settings = CompoundSettings(children=[
            child("std.switch", "request.data"),
            child("std.label", "response.message"),
            child("std.label", "response.success"),
        ])
        m = build(CompoundModel, settings, "/lights/set", "std_srvs/SetBool", "call", client=client,
                  types=TypeRegistry.empty())
        m.start()
        await until(lambda: m.children, what="children")
        roles = [c.model.binding.role for c in m.children]
        assert roles == [Role.PUBLISH, Role.SUBSCRIBE, Role.SUBSCRIBE]
        by_path(m, "request.data").set(True)
        m.send()
        await until(lambda: sim.robot.lights is True, what="lights on")
        await until(lambda: by_path(m, "response.message").state.value is not None, what="the response shown")
        assert by_path(m, "response.message").state.value.text == "lights on"
        assert by_path(m, "response.success").state.value.text == "true"
        assert m.state.value.status.phase == "ok" and m.state.value.message["response"]["success"] is True
        m.stop()


LAB_SRV = "float32 target_m\n---\nbool accepted\nstring reason\nfloat32 eta_s\n"


async def test_serve_a_lab_service_known_only_from_typedefs(sim):
    lab = TypeRegistry.empty()
    lab.add_msg_text("lab_srvs/srv/Winch", LAB_SRV)
    types = TypeRegistry.standard()
    for part in ("request", "response"):  # as the app learns them from a server's service details
        types.add_typedefs(lab.service_typedefs("lab_srvs/Winch", part), root=f"lab_srvs/srv/Winch_{part.title()}")
    assert types.has_service("lab_srvs/Winch")
    async with bridge(sim) as client:
        settings = CompoundSettings(children=[
            child("std.switch", "response.accepted"),
            child("std.textfield", "response.reason"),
            child("std.slider", "response.eta_s", minimum=0, maximum=600, step=1),
            child("std.label", "request.target_m"),
        ])
        m = build(CompoundModel, settings, "/rcon_test/winch", "lab_srvs/Winch", "serve", client=client,
                  types=types)
        m.start()
        by_path(m, "response.accepted").set(True)
        by_path(m, "response.reason").submit("clear to lower")
        by_path(m, "response.eta_s").release(42)
        await until(lambda: "/rcon_test/winch" in sim.services, what="the service advertised")
        answer = await client.node("caller").call_service("/rcon_test/winch", {"target_m": 12.5}, timeout=10)
        assert answer == {"accepted": True, "reason": "clear to lower", "eta_s": 42.0}
        await until(lambda: by_path(m, "request.target_m").state.value is not None, what="the request shown")
        assert by_path(m, "request.target_m").state.value.text == "12.50"
        assert m.state.value.served == 1
        m.stop()


async def test_serving_with_a_child_whose_text_does_not_parse_fails_the_call_naming_it(sim):
    async with bridge(sim) as client:
        settings = CompoundSettings(children=[child("std.textfield", "response.success")])
        m = build(CompoundModel, settings, "/rcon_test/trigger2", "std_srvs/Trigger", "serve", client=client,
                  types=TypeRegistry.standard())
        m.start()
        by_path(m, "response.success").set_draft("maybe")
        await until(lambda: "/rcon_test/trigger2" in sim.services, what="the service advertised")
        failed = await client.node("caller").call_service("/rcon_test/trigger2", {}, timeout=10)
        # a failed handler is answered with the default response carrying the reason, not as if it were set
        assert "child 1 (Text Field) on response.success: success: expected true or false" in failed["message"]
        assert m.state.error.startswith("not answered: child 1 (Text Field) on response.success")
        by_path(m, "response.success").set_draft("true")  # read when the next call comes: nothing to wait for
        answer = await client.node("caller").call_service("/rcon_test/trigger2", {}, timeout=10)
        assert answer == {"success": True, "message": ""}
        m.stop()


class Knob(WidgetModel):
    """Another package's widget: a model that publishes a value through its port."""

    def turn(self, v):
        self.publish_value(v)


class OtherPackage:
    @hookimpl
    def rcon_register_widgets(self, registry):
        registry.add(WidgetSpec(kind="lab.knob", title="Knob", model=Knob, roles=[Role.PUBLISH],
                                accepts=Accepts(fields=["numeric"])))


async def test_a_child_from_another_package(sim):
    pm = PluginManager(environ={})
    pm.register(OtherPackage(), "lab")
    async with bridge(sim) as client:
        settings = CompoundSettings(children=[child("lab.knob", "data")])
        m = build(CompoundModel, settings, "/speed_limit", "std_msgs/Float64", "publish", client=client,
                  context=WidgetContext(pm.widget))
        m.start()
        knob = m.children[0].model
        assert knob.context.catalog is m.context.catalog  # a child finds kinds where the compound does
        assert m.child_models() == [knob]  # built through the context: the runtime and the host know it
        m.children[0].model.turn(1.5)
        m.send()
        await sim.wait_for_published("/speed_limit", lambda msg: msg["data"] == 1.5, timeout=10)
        m.stop()


def test_a_disabled_plugins_widget_is_not_built_as_a_child():
    """The compound finds its children's kinds through the app's plugin manager (its context): a kind of
    a plugin the operator disabled is unknown there, so no child is built and the problem names it."""
    enabled = PluginManager(environ={})
    enabled.register(OtherPackage(), "lab")
    disabled = PluginManager(disabled=["lab"], environ={})
    disabled.register(OtherPackage(), "lab")
    settings = CompoundSettings(children=[child("lab.knob", "data")])
    on = build(CompoundModel, settings, "/speed_limit", "std_msgs/Float64", "publish",
               context=WidgetContext(enabled.widget))
    off = build(CompoundModel, settings, "/speed_limit", "std_msgs/Float64", "publish",
                context=WidgetContext(disabled.widget))
    on.build_children()
    off.build_children()
    assert [type(c.model) for c in on.children] == [Knob]
    assert off.children == [] and any("lab.knob" in p for p in off.problems()), off.problems()


@pytest.mark.parametrize(
    "children,role,expected",
    [([], "publish", "add at least one child widget"),
     ([child("std.nothing", "data")], "publish", "child 1 (std.nothing)"),
     ([child("std.slider", "linear.q")], "publish", "no field 'q'"),
     ([child("std.label", "linear.x")], "publish", "Label cannot publish"),
     ([child("std.slider", "linear.x", minimum=3, maximum=1)], "publish", "less than maximum"),
     ([child("std.compound", "linear")], "publish", "cannot contain a compound"),
     ([child("std.slider", "linear..x")], "publish", "malformed field path")],
)
def test_problems(children, role, expected):
    m = build(CompoundModel, CompoundSettings(children=children), "/cmd_vel", "geometry_msgs/Twist", role)
    assert any(expected in p for p in m.problems()), m.problems()


def test_settings_round_trip_through_the_spec():
    spec = compound_mod.find_spec("std.compound")
    data = {"children": [{"kind": "std.slider", "field_path": "linear.x", "settings": {"maximum": 2.0}}],
            "auto_send": True}
    s = spec.make_settings(data)
    assert s.children[0].settings == {"maximum": 2.0} and s.auto_send
    assert spec.settings_to_dict(s)["children"][0]["field_path"] == "linear.x"
