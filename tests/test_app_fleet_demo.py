"""The fleet demo (``rcon --demo --robots N``): two embedded vessels on their own ports, one window."""

from __future__ import annotations

import pytest

from rcon_core.app.fleet_demo import fleet_workspace
from rcon_core.app.main import load_plugins

pytestmark = pytest.mark.usefixtures("qapp")
PACKAGES = ("rcon_widgets_std", "rcon_widgets_sensors", "rcon_widgets_map")


@pytest.fixture(scope="module")
def plugins():
    for name in PACKAGES:
        pytest.importorskip(name, reason=f"the fleet demo needs the {name} widget package installed")
    return load_plugins()


def test_fleet_workspace_binds_each_vessel_to_its_robot(plugins):
    ws = fleet_workspace(3, plugins)
    assert [(r.id, r.name, r.url) for r in ws.robots] == [("r-1", "boat1", ""), ("r-2", "boat2", ""),
                                                          ("r-3", "boat3", "")]
    fleet = ws.canvases[0]
    assert fleet.name == "Fleet" and [c.name for c in ws.canvases[1:]] == [f"Drive · boat{k}" for k in (1, 2, 3)]
    for k in (1, 2, 3):
        mine = [w for w in fleet.widgets if w.binding.robot == f"r-{k}" and w.kind != "map.gps"]
        assert sorted(w.kind for w in mine) == ["sensors.image", "sensors.teleop"]
        assert all(w.binding.name.startswith(f"/boat{k}/") for w in mine)
    for canvas in ws.canvases[1:]:
        k = canvas.name[-1]
        for w in canvas.widgets:
            assert w.binding.robot == f"r-{k}" and w.binding.name.startswith(f"/boat{k}/"), w.title
            assert plugins.widget(w.kind).settings_problems(w.settings) == [], w.title
            state_topic = w.settings.get("state_topic")
            assert state_topic in (None, "", f"/boat{k}/lights/state")
    assert sum(w.kind == "map.gps" for w in fleet.widgets) == 1
    with pytest.raises(ValueError, match="from 1 to 6"):
        fleet_workspace(0, plugins)


def test_robots_needs_demo_and_a_sane_count(capsys):
    from rcon_core.cli.main import main

    assert main(["--robots", "2"]) == 2
    assert "use it with --demo" in capsys.readouterr().err
    assert main(["--demo", "--robots", "9"]) == 2
    assert "from 1 to 6" in capsys.readouterr().err
