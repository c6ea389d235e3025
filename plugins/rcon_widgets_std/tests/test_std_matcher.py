"""Which standard widgets the matcher offers for which types and roles (and with which field), with the
plugin manager loaded from the installed entry points, as the app does."""

import pytest

from rcon_core.matcher import match
from rcon_core.msgs import TypeRegistry

# (type, role, {kind: expected field path}, kinds that must NOT be offered)
TABLE = [
    ("std_msgs/Float64", "publish", {"std.slider": "data"}, {"std.label", "std.switch"}),
    ("std_msgs/Float64", "subscribe", {"std.label": "data", "std.slider": "data"}, {"std.switch", "std.button"}),
    ("std_msgs/UInt8", "publish", {"std.slider": "data"}, {"std.switch"}),
    ("std_msgs/Int64", "subscribe", {"std.slider": "data", "std.label": "data"}, {"std.switch"}),
    ("std_msgs/Float32", "publish", {"std.slider": "data"}, {"std.label"}),
    ("sensor_msgs/BatteryState", "subscribe", {"std.label": "percentage", "std.slider": "percentage",
                                               "std.switch": "present"}, {"std.button"}),
    ("std_msgs/Bool", "subscribe", {"std.switch": "data", "std.label": "data"}, {"std.slider", "std.button"}),
    ("std_msgs/Bool", "publish", {"std.switch": "data"}, {"std.slider", "std.label"}),
    ("std_srvs/SetBool", "call", {"std.switch": "request.data", "std.button": ""}, {"std.slider", "std.label"}),
    ("std_srvs/SetBool", "serve", {}, {"std.switch", "std.button", "std.slider", "std.label"}),
    ("std_srvs/Trigger", "call", {"std.button": "request"}, {"std.switch", "std.slider", "std.label"}),
    ("std_srvs/Empty", "call", {"std.button": "request"}, {"std.switch"}),
    ("geometry_msgs/Twist", "publish", {"std.slider": "linear.x", "std.button": ""}, {"std.switch", "std.label"}),
    ("sensor_msgs/Image", "subscribe", {"std.label": "height"}, {"std.switch", "std.button"}),
    ("std_msgs/String", "subscribe", {"std.label": "data"}, {"std.slider", "std.switch"}),
    ("std_msgs/String", "publish", {"std.textview": ""}, {"std.slider", "std.switch", "std.label"}),
    ("nav_msgs/OccupancyGrid", "subscribe", {"std.label": "info.map_load_time"}, {"std.switch"}),
    ("sensor_msgs/Imu", "subscribe", {"std.label": "orientation.x"}, {"std.switch"}),
    # Text Field, Stepper, Text View, Compound
    ("std_msgs/String", "publish", {"std.textfield": "data", "std.textview": ""}, {"std.stepper"}),
    ("std_msgs/Float64", "publish", {"std.stepper": "data", "std.textfield": "data", "std.compound": ""},
     {"std.textview"}),
    ("std_msgs/Int8", "publish", {"std.stepper": "data"}, {"std.textview"}),
    ("std_msgs/Float64", "subscribe", {"std.textfield": "data"}, {"std.stepper", "std.compound"}),
    ("rosgraph_msgs/Log", "subscribe", {"std.textview": "", "std.label": "msg"}, {"std.stepper"}),
    ("rcl_interfaces/msg/Log", "subscribe", {"std.textview": ""}, {"std.stepper"}),
    ("std_msgs/String", "subscribe", {"std.textview": "", "std.textfield": "data"}, {"std.compound"}),
    ("sensor_msgs/Imu", "publish", {"std.compound": "", "std.textfield": "orientation.x",
                                    "std.stepper": "orientation.x"}, {"std.textview"}),
    ("sensor_msgs/BatteryState", "subscribe", {"std.textfield": "percentage"},
     {"std.textview", "std.stepper", "std.compound"}),
    ("std_srvs/SetBool", "serve", {"std.compound": ""}, {"std.textview", "std.textfield"}),
    ("std_srvs/Trigger", "call", {"std.compound": ""}, {"std.stepper", "std.textview", "std.textfield"}),
    ("sensor_msgs/Image", "subscribe", {"std.textfield": "height"}, {"std.textview", "std.compound"}),
    ("geometry_msgs/Twist", "subscribe", {"std.textfield": "linear.x"}, {"std.textview", "std.compound"}),
]


@pytest.fixture(scope="module")
def types(plugins):
    types = TypeRegistry.standard()
    plugins.apply_types(types)
    return types


@pytest.mark.parametrize("type_,role,expected,absent", TABLE, ids=[f"{t}-{r}" for t, r, *_ in TABLE])
def test_matcher_table(plugins, types, type_, role, expected, absent):
    found = {m.kind: m for m in match(type_, role, types, plugins) if m.kind.startswith("std.")}
    for kind, path in expected.items():
        assert kind in found, f"{kind} not offered for {type_} ({role})"
        assert found[kind].field_path == path, (kind, found[kind].field_path)
    assert not (absent & set(found)), f"offered but should not be: {absent & set(found)}"


def test_exact_types_rank_first_and_label_leads_for_subscribers(plugins, types):
    kinds = [m.kind for m in match("std_msgs/Float64", "subscribe", types, plugins)]
    assert kinds.index("std.label") < kinds.index("std.slider")
    assert [m.kind for m in match("std_msgs/Bool", "subscribe", types, plugins)][0] == "std.switch"
    assert [m.kind for m in match("std_srvs/SetBool", "call", types, plugins)][0] == "std.switch"
    assert [m.kind for m in match("std_msgs/Float64", "publish", types, plugins)][0] == "std.slider"


def test_a_type_learned_from_typedefs_matches_structurally(plugins):
    """A lab's type the app never shipped: known only through the server's typedefs."""
    types = TypeRegistry.standard()
    lab = TypeRegistry.empty()
    lab.add_msg_text("lab_msgs/Winch", "float32 rope_out\nbool brake\nstring mode\n")
    types.add_typedefs(lab.typedefs("lab_msgs/Winch"))
    found = {m.kind: m.field_path for m in match("lab_msgs/Winch", "publish", types, plugins)}
    assert found["std.slider"] == "rope_out" and found["std.switch"] == "brake"
    found = {m.kind: m.field_path for m in match("lab_msgs/Winch", "subscribe", types, plugins)}
    assert found["std.label"] == "rope_out"


def test_every_std_widget_is_registered_with_its_package(plugins):
    std = [s for s in plugins.widgets() if s.kind.startswith("std.")]
    assert {s.package for s in std} == {"rcon-widgets-std"}
    assert {s.kind for s in std} == {"std.label", "std.slider", "std.switch", "std.button", "std.textfield",
                                     "std.stepper", "std.textview", "std.compound", "std.action"}
    for s in std:
        assert s.load_model() and s.load_settings_class()
        expected = ["add at least one child widget"] if s.kind == "std.compound" else []
        assert s.settings_problems({}) == expected, s.kind
    slider = plugins.widget("std.slider")
    (problem,) = slider.settings_problems({"minimum": "low"})
    assert "invalid settings" in problem and "minimum" in problem
