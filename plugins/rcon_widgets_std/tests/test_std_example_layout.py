"""The example layout loads with the canvas store, uses each of the eight widgets with valid settings,
and runs against the embedded robot through the canvas runtime."""

from pathlib import Path

from std_testkit import bridge

from rcon_core.canvas.runtime import CanvasRuntime, MissingWidgetModel
from rcon_core.canvas.store import WorkspaceStore, dumps_workspace
from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import PluginManager, WidgetContext
from rcon_core.testing import until

LAYOUT = Path(__file__).resolve().parents[1] / "examples" / "std_widgets_layout.json"
KINDS = {"std.label", "std.slider", "std.switch", "std.button", "std.textfield", "std.stepper", "std.textview",
         "std.compound"}


def load():
    return WorkspaceStore(LAYOUT).load()


def test_the_example_layout_loads_and_is_configured():
    ws = load()
    canvas = ws.current_canvas
    assert canvas.name == "Standard widgets" and {w.kind for w in canvas.widgets} == KINDS
    assert "about" in ws.extra  # the documentation key is kept, and written back
    assert '"about"' in dumps_workspace(ws)
    pm = PluginManager(environ={})
    pm.load_entry_points()
    types = TypeRegistry.standard()
    for w in canvas.widgets:
        spec = pm.widget(w.kind)
        assert w.binding.role in spec.roles, w.id
        assert spec.settings_problems(w.settings) == [], w.id
        model = spec.load_model()(spec.make_settings(w.settings), w.binding, None, types=types,
                                  context=WidgetContext(pm))
        assert model.problems() == [], (w.id, model.problems())


async def test_the_example_layout_runs_against_the_robot(sim):
    ws = load()
    pm = PluginManager(environ={})
    pm.load_entry_points()
    async with bridge(sim) as client:
        rt = CanvasRuntime(pm, client, types=TypeRegistry.standard())
        rt.start(ws.current_canvas)
        models = rt.models
        assert not any(isinstance(m, MissingWidgetModel) for m in models.values())
        await until(lambda: models["w-battery"].state.value is not None, what="the battery label")
        assert models["w-battery"].state.value.text.endswith("%")
        await until(lambda: getattr(models["w-lights"].state.value, "on", None) is False, what="lights state")
        models["w-lights"].set(True)
        await until(lambda: sim.robot.lights is True, what="lights on")
        models["w-speed-slider"].release(1.25)
        await sim.wait_for_published("/speed_limit", lambda m: m["data"] == 1.25, timeout=10)
        await until(lambda: models["w-rosout"].state.value is not None
                    and any("Lights on" in x.text for x in models["w-rosout"].state.value.lines), what="/rosout")
        drive = models["w-drive"]
        await until(lambda: drive.children, what="the compound's children")
        drive.children[0].model.release(0.6)
        drive.send()
        await sim.wait_for_published("/cmd_vel", lambda m: m["linear"]["x"] == 0.6, timeout=10)
        rt.stop()
