"""The matcher against a table of types x roles, with test widget specs (not the bundled plugins)."""

import pytest

from rcon_core.matcher import Rank, candidate_paths, match
from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import Accepts, PluginManager, Role, WidgetSpec, hookimpl

M = "rcon_core.plugins.model:WidgetModel"
SPECS = [
    WidgetSpec(kind="t.slider", title="Slider", model=M, roles=["subscribe", "publish"],
               accepts=Accepts(fields=["numeric"], prefer=["percentage", "data"])),
    WidgetSpec(kind="t.switch", title="Switch", model=M, roles=["subscribe", "publish", "call"],
               accepts=Accepts(types=["std_msgs/Bool", "std_srvs/srv/SetBool"], fields=["bool"],
                               service_parts=["request"])),
    WidgetSpec(kind="t.button", title="Button", model=M, roles=["publish", "call"],
               accepts=Accepts(types=["std_msgs/Empty"], messages=["empty"], service_parts=["request"])),
    WidgetSpec(kind="t.text", title="Text View", model=M, roles=["subscribe", "call", "serve"],
               accepts=Accepts(messages=["any"])),
    WidgetSpec(kind="t.image", title="Image", model=M, roles=["subscribe"],
               accepts=Accepts(messages=["image", "compressed_image"])),
    WidgetSpec(kind="t.accel", title="Accelerometer", model=M, roles=["subscribe"],
               accepts=Accepts(types=["sensor_msgs/Imu"], messages=["vector3"], prefer=["linear_acceleration"])),
    WidgetSpec(kind="t.map", title="Map", model=M, roles=["subscribe"], accepts=Accepts(messages=["geo"])),
    WidgetSpec(kind="t.nav", title="Nav panel", model=M, roles=["subscribe"],
               accepts=Accepts(packages=["nav_msgs"])),
    WidgetSpec(kind="t.teleop", title="Teleop", model=M, roles=["publish"], priority=5,
               accepts=Accepts(messages=["twist"])),
    WidgetSpec(kind="t.entry", title="Text Field", model=M, roles=["publish", "call"],
               accepts=Accepts(fields=["string"], service_parts=["request"])),
    WidgetSpec(kind="t.server", title="Responder", model=M, roles=["serve"],
               accepts=Accepts(fields=["bool"], service_parts=["response"])),
]


class TestPlugin:
    @hookimpl
    def rcon_register_widgets(self, registry):
        for s in SPECS:
            registry.add(s)


@pytest.fixture(scope="module")
def pm():
    pm = PluginManager(environ={})
    pm.register(TestPlugin(), "test-widgets")
    return pm


@pytest.fixture(scope="module")
def types():
    return TypeRegistry.standard()


def top(found):
    return [(m.kind, m.rank, m.field_path) for m in found]


# type, role, expected leading (kind, rank, field path) entries in order, kinds that must not appear
TABLE = [
    ("sensor_msgs/BatteryState", "subscribe",
     [("t.slider", Rank.STRUCTURAL, "percentage")], ["t.button", "t.teleop"]),
    ("sensor_msgs/msg/BatteryState", "subscribe",
     [("t.slider", Rank.STRUCTURAL, "percentage")], []),
    ("std_msgs/Bool", "subscribe", [("t.switch", Rank.EXACT, "data")], ["t.button"]),
    ("std_msgs/Bool", "publish", [("t.switch", Rank.EXACT, "data")], ["t.text"]),
    ("std_msgs/Float64", "publish", [("t.slider", Rank.STRUCTURAL, "data")], ["t.switch", "t.text"]),
    ("std_msgs/Empty", "publish", [("t.button", Rank.EXACT, "")], ["t.slider"]),
    ("std_srvs/SetBool", "call", [("t.switch", Rank.EXACT, "request.data"),
                                  ("t.text", Rank.GENERIC, "")], ["t.button", "t.slider"]),
    ("std_srvs/srv/Trigger", "call", [("t.button", Rank.STRUCTURAL, "request")], ["t.switch"]),
    ("std_srvs/Trigger", "serve", [("t.server", Rank.STRUCTURAL, "response.success")], ["t.button"]),
    ("sensor_msgs/Image", "subscribe", [("t.image", Rank.STRUCTURAL, "")], []),
    ("sensor_msgs/CompressedImage", "subscribe", [("t.image", Rank.STRUCTURAL, "")], []),
    ("sensor_msgs/Imu", "subscribe", [("t.accel", Rank.EXACT, "linear_acceleration")], []),
    ("sensor_msgs/NavSatFix", "subscribe", [("t.map", Rank.STRUCTURAL, "")], ["t.image"]),
    ("nav_msgs/Odometry", "subscribe", [("t.nav", Rank.PACKAGE, "")], ["t.map"]),
    ("geometry_msgs/Twist", "publish", [("t.teleop", Rank.STRUCTURAL, "")], ["t.map"]),
    ("std_msgs/String", "publish", [("t.entry", Rank.STRUCTURAL, "data")], ["t.slider"]),
    ("made_up/Unknown", "subscribe", [("t.text", Rank.GENERIC, "")], ["t.slider"]),
]


@pytest.mark.parametrize("type_name, role, expected, absent", TABLE, ids=[f"{t}-{r}" for t, r, *_ in TABLE])
def test_table(pm, types, type_name, role, expected, absent):
    found = match(type_name, role, types, pm)
    assert top(found)[: len(expected)] == expected, top(found)
    kinds = {m.kind for m in found}
    assert not kinds & set(absent), f"unexpected {kinds & set(absent)}"
    assert [m.rank for m in found] == sorted(m.rank for m in found)
    for m in found:
        assert Role.parse(role) in m.spec.roles


def test_structural_paths_skip_header_and_list_alternatives(pm, types):
    (slider,) = [m for m in match("sensor_msgs/Imu", "subscribe", types, pm) if m.kind == "t.slider"]
    assert not slider.field_path.startswith("header.")
    assert slider.field_path == "orientation.x"
    assert "header.seq" in slider.field_paths  # still offered, just last
    assert slider.field_paths.index("header.seq") > slider.field_paths.index("linear_acceleration.z")


def test_unknown_type_learned_from_typedefs_alone(pm):
    types = TypeRegistry.standard()
    assert [m.kind for m in match("lab_msgs/Tank", "subscribe", types, pm)] == ["t.text"]
    types.add_typedefs([
        {"type": "lab_msgs/Tank", "fieldnames": ["level", "label", "valve_open"],
         "fieldtypes": ["float32", "string", "bool"], "fieldarraylen": [-1, -1, -1],
         "examples": ["0.0", "", "False"], "constnames": [], "constvalues": []},
    ])
    found = {m.kind: m for m in match("lab_msgs/Tank", "subscribe", types, pm)}
    assert found["t.slider"].field_path == "level" and found["t.slider"].rank is Rank.STRUCTURAL
    assert found["t.switch"].field_path == "valve_open"
    assert found["t.text"].rank is Rank.GENERIC


def test_custom_predicates_and_a_raising_predicate(types):
    def named_level(field):
        return field.name == "level"

    def explodes(field):
        raise RuntimeError("bug in a plugin's predicate")

    class P:
        @hookimpl
        def rcon_register_widgets(self, registry):
            registry.add(WidgetSpec(kind="c.level", title="Level", model=M, accepts=Accepts(fields=[named_level])))
            registry.add(WidgetSpec(kind="c.boom", title="Boom", model=M, accepts=Accepts(fields=[explodes])))
            registry.add(WidgetSpec(kind="c.cells", title="Cells", model=M,
                                    accepts=Accepts(messages=[lambda t, f: t.endswith("/BatteryState")])))

    pm = PluginManager(environ={})
    pm.register(P(), "custom")
    types.add_typedefs([{"type": "lab_msgs/Level", "fieldnames": ["level"], "fieldtypes": ["float64"],
                         "fieldarraylen": [-1], "examples": ["0"], "constnames": [], "constvalues": []}])
    assert top(match("lab_msgs/Level", "subscribe", types, pm)) == [("c.level", Rank.STRUCTURAL, "level")]
    assert top(match("sensor_msgs/BatteryState", "subscribe", types, pm)) == [("c.cells", Rank.STRUCTURAL, "")]


def test_ties_broken_by_priority_then_title(pm, types):
    found = match("geometry_msgs/Twist", "publish", types, pm)
    structural = [m.kind for m in found if m.rank is Rank.STRUCTURAL]
    assert structural[0] == "t.teleop"  # priority 5 beats the Slider's 0


def test_bad_inputs_get_clear_errors(pm, types):
    with pytest.raises(ValueError, match="unknown role"):
        match("std_msgs/Bool", "listen", types, pm)
    with pytest.raises(ValueError, match="not a ROS type name"):
        match("std msgs Bool", "subscribe", types, pm)
    assert [m.kind for m in match("std_msgs/Bool", "subscribe", None, pm)][0] == "t.switch"


def test_candidate_paths_for_service_roles(types):
    spec = next(s for s in SPECS if s.kind == "t.slider")
    assert candidate_paths(spec, "subscribe", "geometry_msgs/Vector3", types) == ["x", "y", "z"]


def test_foxglove_schemas_match_the_widgets_that_fit():
    """Foxglove's own schemas (the Foxglove link's topic types) are offered the widgets of their ROS
    equivalent; another foreign type (a JSON channel) gets the any-message widgets (rcon_core.msgs.foreign)."""
    from app_helpers import entry_point_plugins

    from rcon_core.msgs import TypeRegistry

    plugins = entry_point_plugins()
    types = TypeRegistry.standard(ros2=True)
    image = match("foxglove.CompressedImage", "subscribe", types, plugins)
    assert image[0].kind == "sensors.image" and image[0].rank is Rank.EXACT
    fix = match("foxglove.LocationFix", "subscribe", types, plugins)
    assert fix[0].kind == "map.gps" and fix[0].rank is Rank.EXACT
    chatter = match("json.schema_bglyvMWM", "subscribe", types, plugins)
    assert chatter and {m.rank for m in chatter} == {Rank.GENERIC}
    with pytest.raises(ValueError, match="not a ROS type name"):
        match("std msgs Bool", "subscribe", types, plugins)
