"""The children part of the plugin contract (``rcon_core.plugins.children``), without Qt: the one place a
child is named and checked, shared by the children editor's catalog and the std Compound's settings and
model, so the three say the same thing about the same child."""

from __future__ import annotations

import pytest

from rcon_core.msgs import TypeRegistry, walk_fields
from rcon_core.plugins import Binding, Role, WidgetContext
from rcon_core.plugins.children import ChildCatalog, child_name, child_problems, child_role, kind_problems

pytest.importorskip("rcon_widgets_std")
from rcon_widgets_std.compound import ChildSpec, CompoundModel, CompoundSettings  # noqa: E402


def test_a_child_is_named_by_its_title_else_its_widget_else_its_kind(plugins) -> None:
    slider = plugins.widget("std.slider")
    assert child_name(2, ChildSpec("std.slider", "linear.x"), slider) == "child 2 (Slider) on linear.x"
    assert child_name(1, ChildSpec("std.slider", "", title="Speed"), slider) == "child 1 (Speed) on the whole message"
    assert child_name(3, ChildSpec("lab.knob", "data"), None) == "child 3 (lab.knob) on data"


def test_what_is_wrong_with_a_child_without_a_type(plugins) -> None:
    assert kind_problems(ChildSpec(""), None) == ["no widget chosen"]
    assert child_problems(ChildSpec("lab.knob"), None) == ["no installed widget package offers 'lab.knob'"]
    label = plugins.widget("std.label")
    assert child_problems(ChildSpec("std.label", "linear.x"), label, Role.PUBLISH) == ["Label cannot publish"]
    assert child_problems(ChildSpec("std.label", "linear.x"), label, Role.SUBSCRIBE) == []
    slider = plugins.widget("std.slider")
    bad = ChildSpec("std.slider", "linear.x", {"minimum": 3, "maximum": 1})
    assert any("less than maximum" in p for p in child_problems(bad, slider, Role.PUBLISH))


def test_the_editor_and_the_compound_name_and_refuse_a_child_alike(plugins) -> None:
    types = TypeRegistry.standard()
    binding = Binding("/cmd_vel", "geometry_msgs/Twist", Role.PUBLISH)
    wrong = ChildSpec("std.label", "linear.x")  # a Label shows: it cannot fill what a publisher sends
    cat = ChildCatalog(types, plugins, binding)
    [placed] = cat.placement_problems(wrong)
    assert cat.child_name(0, wrong) == "child 1 (Label) on linear.x" and placed.startswith("Label cannot publish")
    model = CompoundModel(CompoundSettings(children=[wrong]), binding, None, types=types,
                          context=WidgetContext(plugins))  # the same catalog as the editor's
    assert any("Label cannot publish" in p for p in model.problems()), model.problems()
    assert child_role(Role.CALL, "response") is Role.SUBSCRIBE and child_role(Role.SERVE, "response") is Role.PUBLISH


def test_one_walk_gives_the_catalog_its_fields_in_definition_order() -> None:
    types = TypeRegistry.standard()
    steps = [(s.path, s.is_message) for s in walk_fields(types, "geometry_msgs/Twist")]
    assert steps == [("linear", True), ("linear.x", False), ("linear.y", False), ("linear.z", False),
                     ("angular", True), ("angular.x", False), ("angular.y", False), ("angular.z", False)]
    cat = ChildCatalog(types, None, Binding("/cmd_vel", "geometry_msgs/Twist", Role.PUBLISH))
    assert [c.path for c in cat.all_fields()] == ["", *(p for p, _ in steps)]
