"""The widget API as code (issue 24, items 1-6): one module states it (``rcon_core/plugins/api.py``), nothing
looks a capability up by its name, a package built for another major version is refused with a sentence,
the bundled packages and the scaffold import only the public API, the small hook and the staleness rules,
no hidden plugin manager, children built through the context, and the guide documents the module."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

from rcon_core.canvas import Binding as CanvasBinding
from rcon_core.canvas import Document, Workspace
from rcon_core.canvas.runtime import CanvasRuntime
from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import (
    Accepts,
    Binding,
    NotAValue,
    PluginManager,
    PluginStatus,
    Role,
    UnknownWidget,
    WidgetContext,
    WidgetModel,
    WidgetSpec,
    api,
    hookimpl,
)
from rcon_core.plugins.api import API_VERSION, CAPABILITIES, PUBLIC_API, Port, as_port
from rcon_core.plugins.staleness import NO_DATA_AFTER, Staleness
from rcon_core.testing import ManualClock, RecordingPort, until, widget_catalog

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = [ROOT / "plugins" / d / d for d in ("rcon_widgets_std", "rcon_widgets_sensors", "rcon_widgets_map")]


# ------------------------------------------------------------------------------------------ getattr count
def capability_lookups(roots: list[Path]) -> list[str]:
    """Every ``getattr(x, "name", ...)`` / ``hasattr(x, "name")`` whose name is one of the API's declared
    capabilities (:data:`CAPABILITIES`), found by an AST walk over the package code under ``roots``."""
    hits = []
    for root in roots:
        for path in sorted(root.rglob("*.py")):
            for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
                if (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
                        and node.func.id in ("getattr", "hasattr") and len(node.args) >= 2
                        and isinstance(node.args[1], ast.Constant) and node.args[1].value in CAPABILITIES):
                    hits.append(f"{path.relative_to(root.parent)}:{node.lineno}: {node.args[1].value}")
    return hits


def test_no_capability_is_looked_up_by_its_name():
    """Figure: run-time ``getattr``/``hasattr`` lookups of a capability's name in rcon_core and the three
    packages: 31 before issue 24 (the runtime's on_focus_lost, on_fleet, on_robot_link, dry_run; the host's
    refresh; the ports' envelope, composes, widget_id; settings' problems, commands...), 0 now."""
    assert capability_lookups([ROOT / "rcon_core", *PACKAGES]) == []


def test_the_count_sees_a_lookup(tmp_path):
    (tmp_path / "pkg").mkdir()
    (tmp_path / "pkg" / "m.py").write_text('hook = getattr(model, "on_focus_lost", None)\n'
                                           'ok = getattr(args, "url", None)\nhasattr(port, "envelope")\n')
    assert capability_lookups([tmp_path / "pkg"]) == ["pkg/m.py:1: on_focus_lost", "pkg/m.py:3: envelope"]


def test_every_capability_is_declared_in_the_api():
    declared = set()
    for proto in (api.Port, api.HostedModel, api.ModelHooks, api.WidgetView, api.WidgetSettings, api.CommandBounds,
                  api.SizedSettings, api.StaleAfterSettings):
        declared |= {n for c in proto.__mro__ for n in vars(c)} | set(getattr(proto, "__annotations__", {}))
        declared |= {n for c in proto.__mro__ for n in getattr(c, "__annotations__", {})}
    assert CAPABILITIES <= declared, CAPABILITIES - declared
    for hook in ("on_focus_lost", "on_fleet", "on_robot_link", "shown_message", "dry_run", "fleet_wide"):
        assert hasattr(WidgetModel, hook), hook  # a documented no-op (or default) on the base class


# ------------------------------------------------------------------------------------------ version
def _package(version: str):
    class Lab:
        @hookimpl
        def rcon_register_widgets(self, registry):
            registry.add(WidgetSpec(kind="lab.gauge", title="Gauge", model=WidgetModel, api_version=version))

    return Lab()


@pytest.mark.parametrize("version", ["", "1.0", "1", API_VERSION, "1.9"])
def test_a_package_built_for_this_major_version_loads(version):
    pm = PluginManager(environ={})
    info = pm.register(_package(version), "lab")
    assert info.status is PluginStatus.LOADED and pm.has_widget("lab.gauge")


@pytest.mark.parametrize("version, words", [
    ("2.0", "was built for RCON's widget API 2.0, but this RCON offers API 1.1: install a version of the "
            "package built for API 1.x, or a newer rcon-core"),
    ("0.9", "was built for RCON's widget API 0.9, but this RCON offers API 1.1: install a version of the "
            "package built for API 1.x"),
    ("one", "declares api_version 'one', which is not a version such as '1.1'"),
])
def test_a_package_built_for_another_major_version_is_refused_with_a_sentence(version, words):
    pm = PluginManager(environ={})
    pm.register(_package(version), "lab")
    [info] = pm.failed
    assert words in info.error and "'lab.gauge'" in info.error
    assert not pm.has_widget("lab.gauge")


# ------------------------------------------------------------------------------------------ the port
class BareNode:
    """What a package's test passes as the port: a node's methods, none of the port's attributes."""

    def __init__(self):
        self.subscribed = []

    def subscribe(self, topic, callback, **options):
        self.subscribed.append(topic)
        return self

    def unsubscribe(self):
        pass

    def advertise(self, topic, type, **options):
        return self

    async def call_service(self, name, args=None, timeout=None):
        return {}

    def advertise_service(self, name, type, handler):
        return self

    def close(self):
        pass


def test_a_model_always_sees_a_complete_port():
    node = BareNode()
    model = WidgetModel(None, Binding("/x", "std_msgs/Float64"), node)
    port: Port = model.port
    assert isinstance(port, Port) and port is not node
    assert (port.view_only, port.envelope, port.widget_id, port.composes) == (None, None, None, False)
    port.changed()  # nobody to wake: a no-op
    model.start()
    assert port.subscribed == ["/x"]  # the rest of what the node offers is still there (a test's records)
    with pytest.raises(RuntimeError, match="cannot send action goals"):
        port.send_action_goal("/a", "pkg/action/A", {})
    full = RecordingPort()
    assert as_port(full) is full and WidgetModel(None, Binding(), full).port is full
    model.port = BareNode()  # one assigned later is completed too
    assert isinstance(model.port, Port)


# ------------------------------------------------------------------------------------------ the small hook
class Celsius(WidgetModel):
    def to_value(self, field_value, msg):
        if not isinstance(field_value, (int, float)):
            raise NotAValue(f"{self.binding.field_path} is not a number: {field_value!r}")
        return round(field_value - 273.15, 1)


def test_to_value_turns_the_bound_field_and_not_a_value_skips_the_message_with_a_sentence():
    port = RecordingPort()
    model = Celsius(None, Binding("/t", "sensor_msgs/Temperature", "subscribe", "temperature"), port)
    model.start()
    port.deliver("/t", {"temperature": 300.0})
    assert (model.state.value, model.state.message, model.state.count) == (26.9, {"temperature": 300.0}, 1)
    port.deliver("/t", {"temperature": "hot"})
    assert model.state.error == "temperature is not a number: 'hot'" and model.state.value == 26.9
    port.deliver("/t", {"variance": 1.0})  # the field is missing: said by the base, as before
    assert "temperature" in model.state.error and model.state.count == 1
    port.deliver("/t", {"temperature": 273.15})
    assert (model.state.value, model.state.error, model.state.count) == (0.0, None, 2)


# ------------------------------------------------------------------------------------------ staleness
@pytest.mark.parametrize("stale_after, deliveries, first_after, age, now, expected", [
    (5.0, 0, None, None, 4.0, (False, False)),  # nothing yet, within stale_after: not NO DATA yet
    (5.0, 0, None, None, 6.0, (True, False)),  # nothing for longer: NO DATA
    (0.0, 0, None, None, NO_DATA_AFTER + 1, (True, False)),  # static, but nothing at all came
    (5.0, 1, 0.2, 60.0, 60.2, (False, True)),  # one delivery right after subscribing: latched, never stale
    (5.0, 1, 7.0, 60.0, 67.0, (True, False)),  # one delivery, long after subscribing: a dead stream
    (5.0, 2, 0.2, 6.0, 30.0, (True, False)),  # a stream that stopped
    (5.0, 2, 0.2, 1.0, 30.0, (False, False)),  # a live stream
    (0.0, 5, 0.2, 600.0, 900.0, (False, True)),  # the settings say static
    (None, 2, 0.2, 600.0, 900.0, (False, False)),  # never stale
])
def test_the_staleness_rules(stale_after, deliveries, first_after, age, now, expected):
    s = Staleness()
    s.started(0.0)
    for i in range(deliveries):
        s.delivered(first_after if i == 0 else first_after + i)
    assert s.judge(now, age, stale_after, watching=True) == expected
    assert s.judge(now, age, stale_after, watching=False)[0] is False  # a stopped or sending widget


def test_a_model_started_at_time_zero_still_shows_no_data():
    """Bug found writing the staleness object: ``started_at or now`` took a start at t=0 for "not started",
    so a model on a clock starting at 0 never showed NO DATA."""
    clock = ManualClock(0.0)
    model = WidgetModel(None, Binding("/x", "std_msgs/Float64"), RecordingPort(), clock=clock)
    model.start()
    clock.advance(6.0)
    assert model.state.stale and model.state.count == 0


# ------------------------------------------------------------------------------------------ no hidden manager
def test_no_hidden_plugin_manager(monkeypatch):
    """A model built without a catalog knows no other kind and loads no entry point to find one."""
    def no(*_a, **_k):
        raise AssertionError("an entry point was loaded behind the test's back")

    monkeypatch.setattr(PluginManager, "load_entry_points", no)
    model = WidgetModel(None, Binding("/x", "std_msgs/Float64"), RecordingPort())
    assert model.context.catalog is None
    with pytest.raises(UnknownWidget, match="no widget catalog: 'std.slider' is unknown here"):
        model.context.spec("std.slider")
    assert WidgetContext.standalone().catalog is None  # the deprecated name: the same, no manager
    context_source = (ROOT / "rcon_core" / "plugins" / "context.py").read_text()
    assert "PluginManager(" not in context_source and "global " not in context_source


def test_a_unit_test_sees_only_what_it_registers():
    class Lab:
        @hookimpl
        def rcon_register_widgets(self, registry):
            registry.add(WidgetSpec(kind="lab.knob", title="Knob", model=WidgetModel, roles=[Role.PUBLISH],
                                    accepts=Accepts(fields=["numeric"])))

    catalog = widget_catalog(Lab(), names=["lab"])
    assert [s.kind for s in catalog.widgets()] == ["lab.knob"]
    context = WidgetContext(catalog)
    assert context.spec("lab.knob").title == "Knob"
    with pytest.raises(UnknownWidget):
        context.spec("std.label")  # installed, but not registered by this test


# ------------------------------------------------------------------------------------------ children
class Pad(WidgetModel):
    focus_lost = 0

    def on_focus_lost(self):
        Pad.focus_lost += 1
        self.publish_value(0.0)


class Lab:
    @hookimpl
    def rcon_register_widgets(self, registry):
        registry.add(WidgetSpec(kind="lab.pad", title="Pad", model=Pad, roles=[Role.PUBLISH],
                                accepts=Accepts(fields=["numeric"])))


async def test_children_are_built_through_the_context_and_hosted_by_the_runtime(sim):
    """The Compound builds its children with ``context.build_child``: the runtime tells them focus loss and
    link state like any widget, and a child's change wakes the front end for the compound at once."""
    from rcon_widgets_std import plugin as std_plugin
    from rcon_widgets_std.compound import ChildSpec, CompoundSettings

    from rcon_core.bridge import BridgeClient

    pm = widget_catalog(std_plugin, Lab(), names=["std", "lab"])
    doc = Document(Workspace.new("Ops"))
    settings = CompoundSettings(children=[ChildSpec("lab.pad", "linear.x")])
    inst = doc.add_widget(doc.current.id, "std.compound", CanvasBinding("/cmd_vel", "geometry_msgs/Twist",
                                                                        "publish"),
                          settings=pm.widget("std.compound").settings_to_dict(settings))
    woken: list[str] = []
    client = BridgeClient(sim.url, reconnect=False)
    await client.connect()
    rt = CanvasRuntime(pm, client, types=TypeRegistry.standard(), on_activity=woken.append)
    rt.start(doc.current)
    compound = rt.models[inst.id]
    await until(lambda: compound.child_models(), what="the compound's child")
    [pad] = compound.child_models()
    assert isinstance(pad, Pad) and pad.context.catalog is pm
    before, woken[:] = compound.state.seq, []
    pad.set_error("a child's own problem")
    assert compound.state.seq > before and inst.id in woken  # no clock of the compound's: woken at once
    Pad.focus_lost = 0
    rt.focus_lost()
    assert Pad.focus_lost == 1
    await client.close()  # the robot's link drops: the child hears it like any widget
    await until(lambda: pad.state.link_down, what="the child told the link is down")
    rt.stop()
    assert compound.child_models() == [] and not pad.state.running


# ------------------------------------------------------------------------------------------ public API
def _imports(source: str) -> list[tuple[str, list[str]]]:
    out = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("rcon_core"):
            out.append((node.module, [a.name for a in node.names]))
        elif isinstance(node, ast.Import):
            out += [(a.name, ["*"]) for a in node.names if a.name.startswith("rcon_core")]
    return out


def _not_public(source: str) -> list[str]:
    import importlib

    bad = []
    for module, names in _imports(source):
        allowed = PUBLIC_API.get(module)
        if allowed is None:
            bad.append(f"{module} is not public")
            continue
        if allowed == "*":
            exported = getattr(importlib.import_module(module), "__all__", None)
            if exported is None:
                exported = [n for n in vars(importlib.import_module(module)) if not n.startswith("_")]
            allowed = frozenset(exported)
        bad += [f"{module}.{n} is not public" for n in names if n not in allowed and f"{module}.{n}" not in PUBLIC_API]
    return bad


def test_the_bundled_packages_use_only_the_public_api():
    """Their code (hooks, models, views); their own tests, which live in RCON's repository, also exercise the
    app around them (frames, themes, the runtime)."""
    bad = []
    for package in PACKAGES:
        for path in sorted(package.rglob("*.py")):
            bad += [f"{path.relative_to(ROOT)}: {b}" for b in _not_public(path.read_text(encoding="utf-8"))]
    assert bad == []


@pytest.mark.parametrize("role, type_name", [("subscribe", "lab_msgs/Winch"), ("publish", "std_msgs/Float64"),
                                             ("call", "std_srvs/SetBool")])
def test_the_scaffold_and_the_example_use_only_the_public_api(tmp_path, role, type_name):
    from rcon_core.cli.new_widget import write_package

    files = write_package(tmp_path, "rcon-lab-x", "lab.x", type_name, role)
    files += sorted((ROOT / "tests" / "example_plugin").rglob("*.py"))
    bad = [f"{p.name}: {b}" for p in files if p.suffix == ".py" for b in _not_public(p.read_text(encoding="utf-8"))]
    assert bad == []


def test_the_public_api_check_can_fail():
    assert _not_public("from rcon_core.canvas.runtime import CanvasRuntime\n") == [
        "rcon_core.canvas.runtime is not public"]
    assert _not_public("from rcon_core.plugins.children import ChildCatalog\n") == [
        "rcon_core.plugins.children.ChildCatalog is not public"]
    assert _not_public("from rcon_core.plugins import WidgetModel, Port\n") == []


# ------------------------------------------------------------------------------------------ the guide
def test_the_guide_documents_the_contract_from_the_module():
    """Every name the API module exports, every capability and the version are in the guide's contract
    section, and the section names nothing the module does not export."""
    guide = (ROOT / "docs" / "writing-a-widget-plugin.md").read_text(encoding="utf-8")
    section = guide.split("## The contract at a glance", 1)[1].split("\n## ", 1)[0]
    named = set(re.findall(r"`([A-Za-z_][A-Za-z0-9_]*)", section))
    missing = [n for n in [*api.__all__, *CAPABILITIES] if n not in named]
    assert missing == []
    assert f'`API_VERSION` is `"{API_VERSION}"`' in section
    first = [m.group(1) for m in re.finditer(r"^\| `([A-Za-z_]\w*)`", section, re.M)]
    assert first and set(first) <= set(api.__all__), set(first) - set(api.__all__)
