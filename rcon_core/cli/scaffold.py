"""The files ``rcon new-widget`` writes: a complete widget distribution that installs and passes its tests.

Each template is ``str.format`` text; ``{{``/``}}`` are literal braces. The names:
``dist`` (rcon-lab-winch), ``module`` (rcon_lab_winch), ``kind`` (lab.winch), ``cls`` (Winch),
``title`` (Winch), ``type`` (the bound message or service type), ``types_hook`` (the type contribution,
or ""), ``ep`` (the entry-point name), ``role`` (subscribe, publish or call), ``name`` (the topic or
service the canvas template binds), ``what`` (what the widget does, in words), ``api_version`` (the widget
API the package is written against: ``rcon_core.plugins.api.API_VERSION`` when it was generated).

A generated package uses RCON's public widget API only (``rcon_core.plugins.api.PUBLIC_API``;
``tests/test_plugin_api.py`` holds every template to it).

The subscriber's model, view and tests are here; the publisher's and the service caller's are in
:mod:`rcon_core.cli.scaffold_roles`. :func:`files_for` gives the files of one role.
"""

from __future__ import annotations

PYPROJECT = '''\
[build-system]
requires = ["setuptools>=68"]
build-backend = "setuptools.build_meta"

[project]
name = "{dist}"
version = "0.1.0"
description = "RCON widget: {title}"
readme = "README.md"
requires-python = ">=3.11"
dependencies = ["rcon-core>=0.1"]

[project.optional-dependencies]
test = ["rcon-core[test]"]

[project.entry-points."rcon.widgets"]
{ep} = "{module}.plugin"

[tool.setuptools.packages.find]
include = ["{module}*"]

[tool.setuptools.package-data]
# the canvas template (*.json) must be listed: an editable install finds it anyway, a wheel does not
"{module}" = ["py.typed", "*.json"]

[tool.pytest.ini_options]
asyncio_mode = "auto"
asyncio_default_fixture_loop_scope = "function"
testpaths = ["tests"]
'''

INIT = '''\
"""{title}: an RCON widget package (see README.md)."""
'''

PLUGIN = '''\
"""Entry point (group ``rcon.widgets``): hooks only, no Qt."""

from importlib.resources import files

from rcon_core.plugins import Accepts, Role, WidgetSpec, hookimpl

KIND = "{kind}"
TYPE = "{type}"
TEMPLATE = "{title} canvas"
{types_hook}

@hookimpl
def rcon_register_widgets(registry):
    registry.add(
        WidgetSpec(
            kind=KIND,  # stored in layouts: never rename it
            title="{title}",
            description="{what_cap}",
            roles={{Role.{role_upper}}},
            accepts=Accepts({accepts}),
            api_version="{api_version}",  # the widget API this package is written against
            settings="{module}.model:{cls}Settings",
            model="{module}.model:{cls}Model",
            view="{module}.view:{cls}View",
        )
    )


@hookimpl
def rcon_canvas_templates(registry):  # a ready canvas with the widget, under "New canvas from template"
    registry.add(TEMPLATE, files(__package__) / "template.json", description="The {title} widget on {name}")
'''

TEMPLATE_JSON = '''\
{{
  "format": "rcon-canvas",
  "version": 1,
  "canvas": {{
    "id": "c-{module}",
    "name": "{title} canvas",
    "locked": false,
    "widgets": [
      {{
        "id": "w-{module}",
        "kind": "{kind}",
        "title": "{title}",
        "binding": {{"name": "{name}", "type": "{type}", "role": "{role}", "field_paths": {field_paths}}},
        "geometry": {{"x": 32.0, "y": 32.0, "w": 320.0, "h": 160.0}},
        "settings": {{}}
      }}
    ]
  }}
}}
'''

TYPES_HOOK = '''
# {type} is not a standard type RCON ships, so the package contributes its definition: RCON (and the
# embedded robot in the tests) then knows it. Replace it with your {kind_word}'s own .{ext} text.
DEFINITION = "{definition}"


@hookimpl
def rcon_register_types(registry):
    registry.add_{ext}(TYPE, DEFINITION)
'''

MODEL = '''\
"""The {title} widget's settings and model: pure Python, no Qt (testable against the embedded robot)."""

import attrs

from rcon_core.plugins import WidgetModel


@attrs.define
class {cls}Settings:
    unit: str = attrs.field(default="", metadata={{"label": "Unit", "help": "shown after the number"}})
    decimals: int = attrs.field(default=2, metadata={{"label": "Decimals", "min": 0, "max": 6}})

    def problems(self) -> list[str]:
        """Sentences for the widget's "not configured" warning; [] means configured."""
        return [] if 0 <= self.decimals <= 6 else ["decimals must be between 0 and 6"]


class {cls}Model(WidgetModel):
    """Value: the bound field as text, e.g. "1.50 m". Runs on the bridge thread."""

    def to_value(self, value, msg):  # the bound field of each message -> what the view shows
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            text = str(value)
        else:
            text = f"{{value:.{{self.settings.decimals}}f}}"
        return f"{{text}} {{self.settings.unit}}".strip()
'''

VIEW = '''\
"""The {title} widget's Qt view: imported only when a canvas shows it."""

from qtpy import QtCore, QtWidgets


class {cls}View(QtWidgets.QLabel):
    def __init__(self, model, parent=None):
        super().__init__(parent)
        self.model = model
        self.setAlignment(QtCore.Qt.AlignmentFlag.AlignCenter)
        font = self.font()
        font.setPointSize(22)
        self.setFont(font)

    def refresh(self, state):  # GUI thread, at most once per frame: only show what the model computed
        self.setText(state.value if state.value is not None else "–")
'''

CONFTEST = '''\
# The embedded simulated robot's fixtures (sim, sim_thread, sim_url) come from RCON itself.
pytest_plugins = ["rcon_core.testing"]
'''

TEST_MODEL = '''\
"""The model against the embedded robot: installed, the package's types are known to it."""

from {module}.model import {cls}Model, {cls}Settings
from {module}.plugin import KIND, TEMPLATE, TYPE

from rcon_core.bridge import BridgeClient
from rcon_core.matcher import match
from rcon_core.plugins import Binding, PluginManager, set_path
from rcon_core.testing import until


def bound_field(pm, types):
    """The field RCON binds when the widget is placed on TYPE (what `rcon match` shows)."""
    [found] = [m for m in match(TYPE, "subscribe", types, pm) if m.kind == KIND]
    return found.field_path


def test_the_canvas_template_is_offered():
    pm = PluginManager()
    pm.load_entry_points()
    [template] = [t for t in pm.canvas_templates() if t.title == TEMPLATE]
    assert template.path.is_file()  # shipped in the wheel too: *.json is package data


async def test_shows_the_bound_number(sim):
    pm = PluginManager()
    pm.load_entry_points()
    assert pm.widget(KIND).title  # found through the entry point: the package is installed
    types = pm.type_registry()
    path = bound_field(pm, types)
    client = BridgeClient(sim.url, reconnect=False)
    await client.connect()
    model = {cls}Model({cls}Settings(unit="u", decimals=1), Binding("/test_value", TYPE, "subscribe", path),
                       client.node("test"), types=types)
    model.start()
    robot = client.node("robot").advertise("/test_value", TYPE, latch=True)  # plays the robot
    robot.publish(set_path(types.default(TYPE), path, 1.5))
    await until(lambda: model.state.count > 0, what="a message")
    assert model.state.value == "1.5 u"
    assert model.state.error is None
    model.stop()
    await client.close()


def test_settings_problems():
    assert {cls}Settings().problems() == []
    assert {cls}Settings(decimals=9).problems() == ["decimals must be between 0 and 6"]
'''

TEST_VIEW = '''\
"""The view, built from a model and a state the way the app builds it, rendered to a PNG."""

from {module}.model import {cls}Model, {cls}Settings
from {module}.plugin import TYPE
from {module}.view import {cls}View

from rcon_core.plugins import Binding
from rcon_core.testing import RecordingPort, build_view, grab_view, widget_state


def test_view_shows_the_value(qapp, tmp_path):
    model = {cls}Model({cls}Settings(), Binding("/test_value", TYPE, "subscribe"), RecordingPort())
    view = build_view({cls}View, model, widget_state("1.50 m"))
    assert view.text() == "1.50 m"
    image = grab_view({cls}View, model, widget_state("1.50 m"), path=tmp_path / "view.png")
    assert (image.width(), image.height()) == (320, 160)
    assert (tmp_path / "view.png").stat().st_size > 0
'''

TEST_CONFORMANCE = '''\
"""The widget against RCON's widget API: what the app relies on (the same check RCON runs on its own)."""

from {module}.plugin import KIND

from rcon_core.plugins import PluginManager
from rcon_core.testing import check_conformance


def test_the_widget_conforms_to_the_widget_api(qapp):
    pm = PluginManager()
    pm.load_entry_points()
    check_conformance(pm.widget(KIND), catalog=pm)
'''

README = '''\
# {dist}

An RCON widget package: **{title}** (`{kind}`) {what}.

```sh
pip install -e ".[test]"          # install it (and the test tools) into RCON's environment
pytest                            # the model against the embedded simulated robot, the view to a PNG
rcon plugins --check              # RCON finds it (exit 1, with the reason, if it fails to load)
rcon match {type}                 # the widget is offered for the type
```

- `{module}/plugin.py`: the hooks (no Qt): the widget's spec{types_note}, and a canvas template.
- `{module}/template.json`: the template, a canvas with the widget (package data: listed in
  `pyproject.toml` so the wheel carries it).
- `{module}/model.py`: settings (an attrs class; `problems()` is the "not configured" warning) and the
  model (no Qt; it runs on the bridge thread).
- `{module}/view.py`: the Qt view; `refresh(state)` shows what the model computed.
- `tests/`: `conftest.py` loads RCON's fixtures; the model is tested against the embedded robot (which
  also {robot_part}), the view with `rcon_core.testing.grab_view`, the whole widget against RCON's widget
  API with `rcon_core.testing.check_conformance`.

RCON's guide: `docs/writing-a-widget-plugin.md` and `docs/hooks.md` in RCON's repository.
'''

COMMON = {
    "pyproject.toml": PYPROJECT,
    "README.md": README,
    "{module}/__init__.py": INIT,
    "{module}/py.typed": "",
    "{module}/plugin.py": PLUGIN,
    "{module}/template.json": TEMPLATE_JSON,
    "tests/conftest.py": CONFTEST,
    "tests/test_conformance.py": TEST_CONFORMANCE,
}
#: the subscriber's own files (the default role)
FILES = {**COMMON, "{module}/model.py": MODEL, "{module}/view.py": VIEW, "tests/test_model.py": TEST_MODEL,
         "tests/test_view.py": TEST_VIEW}


def files_for(role: str) -> dict[str, str]:
    """The files (relative path -> template) of a package whose widget takes ``role``."""
    if role == "subscribe":
        return FILES
    from . import scaffold_roles

    return {**COMMON, **scaffold_roles.FILES[role]}
