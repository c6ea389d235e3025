"""Every installed widget kind -- the three bundled packages and any lab package installed beside them --
against the widget API (``rcon_core.plugins.api``), through ``rcon_core.testing.check_conformance`` (which a
lab's package runs in its own tests too): its model is a ``WidgetModel`` that the runtime and the front end
can use, its settings round-trip through a layout, its view builds offscreen as ``View(model)`` and takes
``refresh(state)``."""

from __future__ import annotations

import attrs
import pytest

from rcon_core.plugins import Accepts, Binding, PluginManager, Role, WidgetModel, WidgetSpec
from rcon_core.plugins.api import API_VERSION, HostedModel
from rcon_core.testing import RecordingPort, check_conformance

PM = PluginManager(environ={})
PM.load_entry_points()
SPECS = PM.widgets()
BUNDLED = ("rcon-widgets-std", "rcon-widgets-sensors", "rcon-widgets-map")


def test_the_bundled_packages_are_installed_and_loaded():
    kinds = {s.kind for s in SPECS}
    assert {"std.label", "std.compound", "sensors.teleop", "map.gps"} <= kinds, sorted(kinds)
    assert not PM.failed, [(p.name, p.error) for p in PM.failed]
    assert {s.api_version for s in SPECS if s.package in BUNDLED} == {API_VERSION}


@pytest.mark.parametrize("spec", SPECS, ids=lambda s: s.kind)
def test_every_installed_kind_conforms(spec, qapp):
    check_conformance(spec, catalog=PM)


def test_a_placeholder_and_a_model_are_both_what_the_runtime_hosts():
    from rcon_core.canvas.placeholders import MissingWidgetModel
    from rcon_core.canvas.workspace import WidgetInstance

    hosted: list[HostedModel] = [MissingWidgetModel(WidgetInstance(id="w-1", kind="gone.x"), "not installed"),
                                 WidgetModel(None, Binding("/x", "std_msgs/Float64"), RecordingPort())]
    for m in hosted:
        m.start()
        m.on_focus_lost()
        assert m.state.running and not m.fleet_wide and list(m.child_models()) == []
        m.stop()
    assert not isinstance(hosted[0], WidgetModel)  # a small class of its own, no model's private state


class _NoView:
    """A view without refresh()."""

    def __init__(self, model):
        self.model = model

    def resize(self, *size):
        pass

    def deleteLater(self):  # noqa: N802 - Qt's name
        pass


class _Unbound(WidgetModel):
    def problems(self):
        return []  # claims to be configured while unbound


def test_the_check_fails_a_kind_that_does_not_conform(qapp):
    good = WidgetSpec(kind="t.good", title="Good", model=WidgetModel, roles={Role.SUBSCRIBE}, accepts=Accepts(),
                      view="rcon_widgets_std.label_view:LabelView")
    check_conformance(good)
    with pytest.raises(AssertionError, match="is not a WidgetModel"):
        check_conformance(attrs.evolve(good, model=dict))
    with pytest.raises(AssertionError, match="must say what it lacks"):
        check_conformance(attrs.evolve(good, model=_Unbound))
    with pytest.raises(AssertionError, match="no refresh"):
        check_conformance(attrs.evolve(good, view=f"{__name__}:_NoView"))
