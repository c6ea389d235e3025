"""PluginManager: direct registration, entry-point discovery, broken and disabled plugins, hook docs."""

import sys
import textwrap
from pathlib import Path

import pytest

from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import (
    Accepts,
    DuplicateWidget,
    PluginManager,
    Role,
    UnknownWidget,
    WidgetSpec,
    hookimpl,
    hookspecs,
)

ROOT = Path(__file__).resolve().parents[1]


def _spec(kind, **kw):
    return WidgetSpec(kind=kind, title=kind.split(".")[-1].title(), model="rcon_core.plugins.model:WidgetModel", **kw)


class Good:
    @hookimpl
    def rcon_register_widgets(self, registry):
        registry.add(_spec("good.label", accepts=Accepts(messages=["any"])))
        registry.add(_spec("good.gauge", roles=[Role.SUBSCRIBE], accepts=Accepts(fields=["numeric"])))


class RaisesInHook:
    @hookimpl
    def rcon_register_widgets(self, registry):
        registry.add(_spec("bad.first"))
        raise RuntimeError("cannot find my icons")


class Duplicate:
    @hookimpl
    def rcon_register_widgets(self, registry):
        registry.add(_spec("good.label"))


class Types:
    @hookimpl
    def rcon_register_types(self, registry):
        registry.add_msg("lab_msgs/Finger", "float64 angle\nstring name\n")
        registry.add_srv("lab_msgs/Grip", "float64 force\n---\nbool ok\n")


class BadTypes:
    @hookimpl
    def rcon_register_widgets(self, registry):
        registry.add(_spec("badtypes.w"))

    @hookimpl
    def rcon_register_types(self, registry):
        registry.add_msg("lab_msgs/Broken", "float64 ok\nfloat64\n")


def test_direct_registration_fills_package_and_finds_kinds():
    pm = PluginManager(environ={})
    info = pm.register(Good(), "good", dist="rcon-good", version="1.2")
    kinds = [s.kind for s in pm.widgets()]
    assert kinds == ["good.label", "good.gauge"]
    assert pm.widget("good.gauge").package == "rcon-good"
    assert info.status == "loaded" and [s.kind for s in info.widgets] == kinds
    with pytest.raises(UnknownWidget, match="no installed widget plugin offers 'x.y'.*good.gauge"):
        pm.widget("x.y")
    with pytest.raises(ValueError, match="already registered"):
        pm.register(Good(), "good")


def test_a_hook_that_raises_fails_only_its_plugin():
    pm = PluginManager(environ={})
    pm.register(RaisesInHook(), "bad")
    pm.register(Good(), "good")
    assert {s.kind for s in pm.widgets()} == {"good.label", "good.gauge"}
    (bad,) = pm.failed
    assert bad.name == "bad" and bad.error == "RuntimeError: cannot find my icons"
    assert "Traceback" in bad.details and bad.widgets == []


def test_duplicate_kind_fails_the_second_plugin():
    pm = PluginManager(environ={})
    pm.register(Good(), "good", dist="rcon-good")
    pm.register(Duplicate(), "dup")
    assert pm.widget("good.label").package == "rcon-good"
    (dup,) = pm.failed
    assert "DuplicateWidget" in dup.error and "already registered by 'rcon-good'" in dup.error
    assert issubclass(DuplicateWidget, ValueError)


def test_misspelled_hook_is_reported_not_ignored():
    class Typo:
        @hookimpl
        def rcon_register_widget(self, registry):  # missing "s"
            pass

    pm = PluginManager(environ={})
    with pytest.raises(Exception, match="rcon_register_widget"):
        pm.register(Typo(), "typo")


def test_disable_by_configuration_and_environment():
    pm = PluginManager(disabled=["good"], environ={"RCON_DISABLE_PLUGINS": " other , dup "})
    assert pm.disabled == {"good", "other", "dup"}
    assert pm.register(Good(), "good").status == "disabled"
    assert pm.register(Duplicate(), "dup").status == "disabled"
    assert pm.widgets() == []


def test_contributed_types_reach_the_type_registry():
    pm = PluginManager(environ={})
    pm.register(Types(), "types", dist="rcon-lab")
    pm.register(BadTypes(), "badtypes")
    types = TypeRegistry.standard()
    added = pm.apply_types(types)
    assert "lab_msgs/msg/Finger" in added and "lab_msgs/srv/Grip_Request" in added
    assert [f.name for f in types.fields("lab_msgs/Finger")] == ["angle", "name"]
    assert types.has_service("lab_msgs/Grip")
    (bad,) = pm.failed
    assert bad.name == "badtypes" and "Broken" in bad.error
    assert not pm.has_widget("badtypes.w")  # its widgets are withdrawn with it


def _write_dist(root: Path, dist: str, version: str, module: str, ep_name: str, code: str) -> None:
    (root / module).mkdir(parents=True)
    (root / module / "__init__.py").write_text(textwrap.dedent(code))
    info = root / f"{dist.replace('-', '_')}-{version}.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {dist}\nVersion: {version}\n")
    (info / "entry_points.txt").write_text(f"[rcon.widgets]\n{ep_name} = {module}\n")


def test_entry_points_broken_import_does_not_stop_others(tmp_path, monkeypatch):
    _write_dist(tmp_path, "rcon-test-broken", "0.0.1", "rcon_test_broken_ep", "testbroken",
                "raise ImportError('needs libfoo, which is not installed')\n")
    _write_dist(tmp_path, "rcon-test-fine", "2.0", "rcon_test_fine_ep", "testfine", """
        from rcon_core.plugins import WidgetSpec, hookimpl

        @hookimpl
        def rcon_register_widgets(registry):
            registry.add(WidgetSpec(kind="fine.dial", title="Dial", model="rcon_test_fine_ep:Model"))
        """)
    monkeypatch.syspath_prepend(str(tmp_path))
    pm = PluginManager(environ={})
    found = {i.name: i for i in pm.load_entry_points()}
    broken, fine = found["testbroken"], found["testfine"]
    assert broken.status == "failed" and broken.dist == "rcon-test-broken" and broken.version == "0.0.1"
    assert broken.error == "ImportError: needs libfoo, which is not installed"
    assert fine.status == "loaded" and fine.version == "2.0"
    assert pm.widget("fine.dial").package == "rcon-test-fine"
    # the bundled packages load too (whatever widgets they have by now)
    assert {"std", "sensors", "map"} <= {i.name for i in pm.plugins if i.status == "loaded"}
    assert pm.load_entry_points() == pm.plugins  # idempotent
    for mod in ("rcon_test_fine_ep", "rcon_test_broken_ep"):
        sys.modules.pop(mod, None)


def test_entry_point_disabled_by_dist_name(tmp_path, monkeypatch):
    _write_dist(tmp_path, "rcon-test-off", "1.0", "rcon_test_off_ep", "testoff",
                "raise AssertionError('a disabled plugin must not even be imported')\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    pm = PluginManager(environ={"RCON_DISABLE_PLUGINS": "rcon-test-off"})
    info = next(i for i in pm.load_entry_points() if i.name == "testoff")
    assert info.status == "disabled" and info.error is None
    assert "rcon_test_off_ep" not in sys.modules


def test_every_hookspec_is_documented():
    doc = (ROOT / "docs" / "hooks.md").read_text()
    specs = [n for n in dir(hookspecs) if n.startswith("rcon_")]
    assert specs, "no hookspecs found"
    missing = [n for n in specs if f"## `{n}(" not in doc]
    assert not missing, f"hooks missing a section in docs/hooks.md: {missing}"
    pm = PluginManager(environ={})
    assert sorted(specs) == sorted(n for n in dir(pm.pluggy.hook) if n.startswith("rcon_"))
