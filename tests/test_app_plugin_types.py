"""issue 15.2: the window's type registry holds what installed plugins contribute, so the matcher, the add
panel and the children editor know a lab's own type (lab_msgs/Winch) without asking the robot."""

from __future__ import annotations

import pytest
from app_helpers import window_session

from rcon_core.app.children_editor import ChildCatalog
from rcon_core.matcher import match
from rcon_core.plugins import Binding, PluginManager, Role, hookimpl

pytest.importorskip("rcon_widgets_std")
pytestmark = pytest.mark.usefixtures("qapp")


class WinchTypes:
    """A lab package that only contributes its message type."""

    @hookimpl
    def rcon_register_types(self, registry):
        registry.add_msg("lab_msgs/Winch", "float64 payout   # metres\nfloat64 tension\nbool braked\n")


@pytest.fixture
def window(qtbot, tmp_path):
    pm = PluginManager(environ={})
    pm.load_entry_points()
    pm.register(WinchTypes(), name="winch")
    yield from window_session(qtbot, tmp_path / "config", pm)  # no types given: the window builds them


def test_the_window_knows_plugin_types(window):
    assert window.types.has("lab_msgs/Winch")
    assert window.types.default("lab_msgs/Winch") == {"payout": 0.0, "tension": 0.0, "braked": False}


def test_the_matcher_binds_a_field_of_the_plugin_type(window):
    found = {m.spec.kind: m for m in match("lab_msgs/Winch", Role.SUBSCRIBE, window.types, window.plugins)}
    assert found["std.label"].field_path  # a structural match needs the definition
    assert found["std.slider"].field_path == "payout" if "std.slider" in found else True


def test_the_children_editor_offers_the_plugin_types_fields(window):
    catalog = ChildCatalog(window.types, window.plugins, Binding("/winch", "lab_msgs/Winch", "subscribe"))
    assert catalog.known()
    paths = [c.path for c in catalog.fields()]
    assert {"payout", "tension", "braked"} <= set(paths)
