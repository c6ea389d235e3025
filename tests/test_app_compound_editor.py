"""The children editor: a Compound built on the device, end to end against the embedded robot.

The window uses the installed widget packages (the Compound is the std package's) and an *empty* type
registry, so the bound type's fields come from the robot's rosapi typedefs.
"""

from __future__ import annotations

import pytest
from app_helpers import choose_kind, compound_in_operate, tap, tap_item, tap_topic, window_session
from qtpy import QtWidgets
from qtpy.QtTest import QTest

from rcon_core.app.children_editor import ChildrenEditor
from rcon_core.app.main_window import MainWindow
from rcon_core.app.settings_form import SettingsForm
from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import Accepts, Binding, PluginManager, Role, WidgetSpec, hookimpl
from rcon_core.plugins.children import ChildCatalog, child_role, children_item_class

pytest.importorskip("rcon_widgets_std")
from rcon_widgets_std.compound import ChildSpec, CompoundSettings  # noqa: E402

pytestmark = pytest.mark.usefixtures("qapp")


@pytest.fixture
def window(qtbot, tmp_path, sim_thread, plugins):
    yield from _window(qtbot, tmp_path, sim_thread, plugins, TypeRegistry.empty())


@pytest.fixture
def window_standard_types(qtbot, tmp_path, sim_thread, plugins):
    yield from _window(qtbot, tmp_path, sim_thread, plugins, TypeRegistry.standard())


def _window(qtbot, tmp_path, sim_thread, plugins, types):
    # a 1280x800 tablet (the offscreen test screen is 800x800)
    yield from window_session(qtbot, tmp_path / "config", plugins, url=sim_thread.url, types=types,
                              wait_connected=True, topics=("/cmd_vel",))


def button(editor: QtWidgets.QWidget, name: str) -> QtWidgets.QPushButton:
    """The visible button called ``name`` (pages are rebuilt; replaced ones are hidden until deleted)."""
    [found] = [b for b in editor.findChildren(QtWidgets.QPushButton, name) if b.isVisible()]
    return found


def set_number(form: SettingsForm, name: str, value: float) -> None:
    editor = form.editor(name)
    editor.setFocus()
    editor.selectAll()
    QTest.keyClicks(editor, str(value))
    assert editor.value() == pytest.approx(value)


def add_child(qtbot, editor: ChildrenEditor, path: str, kind: str, offered_not: tuple[str, ...] = ()) -> None:
    tap(editor.add_button)
    qtbot.waitUntil(lambda: editor.current_page == "fields", timeout=10_000)  # typedefs from the robot
    tap(editor.field_buttons[path])
    assert editor.current_page == "kinds"
    for other in offered_not:
        assert other not in editor.kind_buttons
    tap(editor.kind_buttons[kind])
    assert editor.current_page == "child" and editor.child_form is not None


def open_compound_on_cmd_vel(window: MainWindow):
    tap_topic(window, "/cmd_vel")
    panel = choose_kind(window, Role.PUBLISH, "std.compound")
    assert panel.stack.currentWidget() is panel.settings_page
    return panel, panel.form.children_editors["children"]


# ------------------------------------------------------------------------------------- end to end
def test_build_a_compound_on_the_device_and_publish_what_its_children_compose(window, sim_thread, qtbot):
    panel, editor = open_compound_on_cmd_vel(window)
    assert "add at least one child widget" in panel.problems()
    assert not panel.place_button.isEnabled()

    # child 1: a slider on linear.x; a label cannot publish, a compound cannot nest
    add_child(qtbot, editor, "linear.x", "std.slider", offered_not=("std.label", "std.compound"))
    assert "linear" in editor.field_buttons and "angular.z" in editor.field_buttons  # Twist, learned
    form = editor.child_form
    set_number(form, "maximum", 2.0)
    set_number(form, "minimum", 3.0)  # a child problem: named on the parent's warning
    named = [p for p in panel.problems() if p.startswith("child 1 (Slider) on linear.x")]
    assert named and "minimum" in named[0], panel.problems()
    assert not panel.place_button.isEnabled()
    assert "child 1 (Slider) on linear.x" in panel.drag_handle.text()
    assert editor.child_problems_label.isVisible()
    qtbot.waitUntil(lambda: "child 1 (Slider) on linear.x" in panel.preview_frame.problems.text(), timeout=5_000)
    set_number(form, "minimum", 0.0)
    set_number(form, "step", 0.5)
    tap(button(editor, "childDone"))
    assert editor.current_page == "list" and len(editor.rows) == 1

    # child 2: a stepper on angular.z, titled; a third one removed; reordering
    add_child(qtbot, editor, "angular.z", "std.stepper")
    set_number(editor.child_form, "minimum", -1.0)
    set_number(editor.child_form, "maximum", 1.0)
    set_number(editor.child_form, "step", 0.25)
    QTest.keyClicks(editor.child_title, "Turn")
    tap(button(editor, "childDone"))
    add_child(qtbot, editor, "linear.y", "std.textfield")
    tap(button(editor, "childDone"))
    assert [c.field_path for c in panel.draft.settings.children] == ["linear.x", "angular.z", "linear.y"]
    tap(button(editor, "childUp_1"))
    assert [c.field_path for c in panel.draft.settings.children] == ["angular.z", "linear.x", "linear.y"]
    tap(button(editor, "childDown_0"))
    tap(button(editor, "childRemove_2"))
    children = panel.draft.settings.children
    assert [(c.kind, c.field_path, c.title) for c in children] == [
        ("std.slider", "linear.x", ""), ("std.stepper", "angular.z", "Turn")]
    assert children[0].settings["maximum"] == 2.0 and children[1].settings["step"] == 0.25
    assert panel.problems() == [] and panel.place_button.isEnabled()

    # place it, operate the children, publish: the robot gets one Twist with both values
    tap(panel.place_button)
    [inst] = window.controller.canvas.widgets
    assert inst.kind == "std.compound" and inst.binding.name == "/cmd_vel"
    # placed at the size its children need, not the kind's fixed default
    pw, ph = CompoundSettings(children=list(children)).preferred_size()
    assert inst.geometry.w >= pw and inst.geometry.h >= ph
    assert inst.settings["children"][1] == {"kind": "std.stepper", "field_path": "angular.z", "title": "Turn",
                                            "settings": children[1].settings}
    hosted, view = compound_in_operate(qtbot, window, inst.id, 2)
    (_c1, slider), (_c2, stepper) = view.child_views
    qtbot.waitUntil(lambda: stepper.plus.isVisible() and slider.slider.isVisible(), timeout=5_000)
    slider.slider.setValue(slider.position_of(1.5))
    tap(stepper.plus)
    tap(stepper.plus)
    qtbot.waitUntil(lambda: hosted.model.composed()["angular"]["z"] == 0.5, timeout=5_000)
    tap(view.button)
    got = sim_thread.wait_for_published_sync(
        "/cmd_vel", lambda m: m["linear"]["x"] == 1.5 and m["angular"]["z"] == 0.5, timeout=10)
    assert got["linear"] == {"x": 1.5, "y": 0.0, "z": 0.0}
    assert got["angular"] == {"x": 0.0, "y": 0.0, "z": 0.5}


def test_configure_a_placed_compound_edits_its_children_in_the_dialog(window, qtbot, plugins):
    doc = window.controller
    settings = CompoundSettings(children=[ChildSpec("std.slider", "linear.x", {"maximum": 1.0})])
    spec = plugins.widget("std.compound")
    from rcon_core.canvas import Geometry

    inst = window.doc.add_widget(doc.canvas.id, "std.compound", Binding("/cmd_vel", "geometry_msgs/Twist",
                                 Role.PUBLISH), Geometry(16, 16, 320, 240), spec.settings_to_dict(settings), "Drive")
    window.configurer.open(inst.id)
    dialog = window.configurer.dialog
    form = dialog.findChild(SettingsForm)
    editor = form.children_editors["children"]
    assert editor.catalog().binding.name == "/cmd_vel"  # found from the placed widget
    tap(button(editor, "childEdit_0"))
    set_number(editor.child_form, "maximum", 4.0)
    tap(button(editor, "childDone"))
    add_child(qtbot, editor, "angular.z", "std.slider")  # the type is learned from the robot
    tap(button(editor, "childDone"))
    dialog.accept()
    _c, saved = window.controller.workspace.find_widget(inst.id)
    assert [(c["field_path"], c["settings"]["maximum"]) for c in saved.settings["children"]] == [
        ("linear.x", 4.0), ("angular.z", 1.0)]


# ------------------------------------------------------------------------------------- the catalog
@pytest.fixture(scope="module")
def types() -> TypeRegistry:
    return TypeRegistry.standard(ros2=False)


def kinds(cat: ChildCatalog, path: str) -> list[str]:
    choice = cat.choice(path)
    assert choice is not None, path
    return [k.spec.kind for k in cat.kinds_for(choice)]


def test_a_children_field_is_declared_by_its_type():
    import attrs

    assert children_item_class(attrs.fields_dict(CompoundSettings)["children"].type) is ChildSpec
    assert children_item_class(list[str]) is None and children_item_class(str) is None


def test_fields_and_fitting_kinds_of_a_published_twist(types, plugins):
    cat = ChildCatalog(types, plugins, Binding("/cmd_vel", "geometry_msgs/Twist", Role.PUBLISH), ("std.compound",))
    paths = [c.path for c in cat.fields()]
    assert paths[:5] == ["", "linear", "linear.x", "linear.y", "linear.z"]
    assert {"std.slider", "std.stepper", "std.textfield"} <= set(kinds(cat, "linear.x"))
    assert "std.label" not in kinds(cat, "linear.x")  # subscribe only
    assert "std.compound" not in kinds(cat, "")  # no nesting
    assert "std.slider" not in kinds(cat, "linear")  # a slider needs a number, not a Vector3
    assert cat.placement_problems(ChildSpec("std.slider", "linear.q")) == [
        "geometry_msgs/Twist has no field 'linear.q'"]
    assert cat.placement_problems(ChildSpec("std.label", "linear.x")) == ["Label cannot publish linear.x (float64)"]
    assert cat.placement_problems(ChildSpec("lab.nothing", "linear.x")) == [
        "no installed widget package offers 'lab.nothing'"]
    assert cat.placement_problems(ChildSpec("std.slider", "angular.z")) == []


class _Knobs:
    @hookimpl
    def rcon_register_widgets(self, registry):
        registry.add(WidgetSpec(kind="knobs.knob", title="Knob", model="rcon_core.plugins.model:WidgetModel",
                                roles=[Role.PUBLISH], accepts=Accepts(fields=["numeric"])))


def test_a_disabled_plugins_widget_is_not_offered_as_a_child(types):
    """The children editor lists the kinds of the app's plugin manager: a disabled plugin's are not offered
    and a child of one is refused (the Compound does not build it either: its context is the same manager)."""
    offers = {}
    for disabled in ((), ("knobs",)):
        pm = PluginManager(disabled=disabled, environ={})
        pm.register(_Knobs(), "knobs")
        cat = ChildCatalog(types, pm, Binding("/speed_limit", "std_msgs/Float64", Role.PUBLISH))
        offers[disabled] = kinds(cat, "data")
        problems = cat.placement_problems(ChildSpec("knobs.knob", "data"))
        assert problems == ([] if not disabled else ["no installed widget package offers 'knobs.knob'"])
    assert "knobs.knob" in offers[()] and "knobs.knob" not in offers[("knobs",)]


def test_an_imu_from_accelerometer_gyroscope_and_magnetometer_children(types, plugins):
    pytest.importorskip("rcon_widgets_sensors")
    cat = ChildCatalog(types, plugins, Binding("/phone/imu", "sensor_msgs/Imu", Role.PUBLISH))
    for path in ("linear_acceleration", "angular_velocity"):
        assert {"sensors.accelerometer", "sensors.gyroscope", "sensors.magnetometer"} <= set(kinds(cat, path))
    assert cat.child_binding(0, ChildSpec("sensors.gyroscope", "angular_velocity")) == Binding(
        "/phone/imu#1", "sensor_msgs/msg/Imu", Role.PUBLISH, ("angular_velocity",))


def test_a_service_request_filled_and_its_response_shown(types, plugins):
    assert child_role(Role.CALL, "request") is Role.PUBLISH and child_role(Role.CALL, "response") is Role.SUBSCRIBE
    assert child_role(Role.SERVE, "response") is Role.PUBLISH and child_role(Role.SERVE, "request") is Role.SUBSCRIBE
    cat = ChildCatalog(types, plugins, Binding("/lights/set", "std_srvs/SetBool", Role.CALL))
    paths = [c.path for c in cat.fields()]
    assert {"request.data", "response.success", "response.message"} <= set(paths)
    assert "std.switch" in kinds(cat, "request.data")
    assert "std.label" in kinds(cat, "response.message") and "std.label" not in kinds(cat, "request.data")
    assert cat.choice("response.message").role is Role.SUBSCRIBE
    assert cat.placement_problems(ChildSpec("std.switch", "data")) == [
        "service field path 'data' must start with 'request' or 'response'"]


def test_a_form_given_its_context_composes_a_service_request(qtbot, types, plugins):
    from rcon_core.plugins.children import ChildContext

    bound = {"binding": Binding("/lights/set", "std_srvs/SetBool", Role.CALL)}
    form = SettingsForm(CompoundSettings(), context=ChildContext(types, plugins, lambda: bound["binding"]))
    qtbot.addWidget(form)
    form.show()
    editor = form.children_editors["children"]
    tap(editor.add_button)
    assert {"request.data", "response.message"} <= set(editor.field_buttons)
    tap(editor.field_buttons["request.data"])
    assert "std.label" not in editor.kind_buttons  # the request is filled, not shown
    tap(editor.kind_buttons["std.switch"])
    tap(button(editor, "childDone"))
    assert [(c.kind, c.field_path) for c in form.value().children] == [("std.switch", "request.data")]
    assert form.problems() == []
    bound["binding"] = Binding("/cmd_vel", "geometry_msgs/Twist", Role.PUBLISH)  # the binding changed under it
    assert form.problems() == [
        "child 1 (Switch) on request.data: geometry_msgs/Twist has no field 'request.data'"]
    qtbot.waitUntil(lambda: any("has no field 'request.data'" in lbl.text()
                                for lbl in editor.findChildren(QtWidgets.QLabel) if lbl.isVisible()),
                    timeout=5_000)  # the child's row says so too (the editor notices the new binding)


def test_a_child_on_a_field_the_new_topic_lacks_blocks_placing(window_standard_types, qtbot):
    window = window_standard_types
    # pathway 3: the widget first, then its topic
    window.side.setCurrentWidget(window.palette_panel)
    item = window.palette_panel.item("std.compound")
    tap_item(window.palette_panel.tree, window.palette_panel.tree.indexFromItem(item))
    panel = window.add_panel
    panel.choose_target("/cmd_vel")
    editor = panel.form.children_editors["children"]
    add_child(qtbot, editor, "linear.x", "std.slider")
    tap(button(editor, "childDone"))
    assert panel.problems() == [] and panel.place_button.isEnabled()
    # the operator then binds the Compound to a Float64 topic: the child's field is gone
    panel.choose_target("/speed_limit")
    assert any("has no field 'linear.x'" in p for p in panel.problems()), panel.problems()
    assert not panel.place_button.isEnabled()
    assert panel.take_draft() is None
