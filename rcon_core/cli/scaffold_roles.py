"""``rcon new-widget --role publish|call``: the model, view and tests of a publisher and of a service caller.

Same names as :mod:`rcon_core.cli.scaffold` (``str.format`` text; ``{{``/``}}`` are literal braces). The
caller shows the whole round trip a lab needs: a request typed in the settings (YAML, checked against the
request type), ``call`` from the view, ``call_async`` in tests, ``on_response`` turning the answer into
the value, and every way a call fails (the robot refuses, a response that says no, no answer, a request
that does not fit) becoming the widget's error. Its tests provide the service on the embedded robot.
"""

from __future__ import annotations

PUBLISH_MODEL = '''\
"""The {title} widget's settings and model: pure Python, no Qt (testable against the embedded robot)."""

import attrs

from rcon_core.plugins import WidgetModel, get_path


@attrs.define
class {cls}Settings:
    step: float = attrs.field(default=0.5, metadata={{"label": "Step", "help": "how much a tap on the arrows changes the number"}})
    unit: str = attrs.field(default="", metadata={{"label": "Unit", "help": "shown after the number"}})

    def problems(self) -> list[str]:
        """Sentences for the widget's "not configured" warning; [] means configured."""
        return [] if self.step > 0 else ["the step must be more than 0"]


class {cls}Model(WidgetModel):
    """Publishes a number at the bound field of an otherwise default message. Value: the last one sent."""

    def send(self, number):
        """The view's Send button (GUI thread; the publish itself runs on the bridge thread). Returns
        False when nothing was sent (the widget is not running: the error says so)."""
        path = self.binding.field_path
        known = self.types.has(self.binding.type)  # a test may build the model without your type's definition
        current = get_path(self.types.default(self.binding.type), path) if known else 0.0
        value = round(number) if isinstance(current, int) and not isinstance(current, bool) else float(number)
        if not self.publish_value(value):
            return False
        self.set_value(value)
        return True
'''

PUBLISH_VIEW = '''\
"""The {title} widget's Qt view: imported only when a canvas shows it."""

from qtpy import QtWidgets


class {cls}View(QtWidgets.QWidget):
    def __init__(self, model, parent=None):
        super().__init__(parent)
        self.model = model
        self.number = QtWidgets.QDoubleSpinBox()
        self.number.setRange(-1e9, 1e9)
        self.number.setSingleStep(model.settings.step)
        self.number.setSuffix(f" {{model.settings.unit}}" if model.settings.unit else "")
        self.send = QtWidgets.QPushButton("Send")
        self.send.clicked.connect(lambda: self.model.send(self.number.value()))
        self.send.setEnabled(model.view_only is None)  # a view-only robot: nothing may be sent
        self.status = QtWidgets.QLabel("–")
        row = QtWidgets.QHBoxLayout()
        row.addWidget(self.number, 1)
        row.addWidget(self.send)
        layout = QtWidgets.QVBoxLayout(self)
        layout.addLayout(row)
        layout.addWidget(self.status)

    def refresh(self, state):  # GUI thread, at most once per frame: only show what the model computed
        self.status.setText(state.error or ("–" if state.value is None else f"sent {{state.value}}"))
'''

PUBLISH_TEST_MODEL = '''\
"""The model against the embedded robot: what it publishes arrives on the topic."""

from {module}.model import {cls}Model, {cls}Settings
from {module}.plugin import KIND, TEMPLATE, TYPE

from rcon_core.bridge import BridgeClient
from rcon_core.matcher import match
from rcon_core.plugins import Binding, PluginManager, get_path
from rcon_core.testing import until


def test_the_canvas_template_is_offered():
    pm = PluginManager()
    pm.load_entry_points()
    [template] = [t for t in pm.canvas_templates() if t.title == TEMPLATE]
    assert template.path.is_file()  # shipped in the wheel too: *.json is package data


async def test_sends_the_number(sim):
    pm = PluginManager()
    pm.load_entry_points()
    types = pm.type_registry()
    [found] = [m for m in match(TYPE, "publish", types, pm) if m.kind == KIND]  # what `rcon match` binds
    client = BridgeClient(sim.url, reconnect=False)
    await client.connect()
    heard = []
    client.node("robot").subscribe("/test_value", heard.append, type=TYPE)  # plays the robot
    model = {cls}Model({cls}Settings(), Binding("/test_value", TYPE, "publish", found.field_path),
                       client.node("test"), types=types)
    model.start()
    assert model.send(2.0)  # one connection: the robot's subscription reached the server first
    await until(lambda: heard, what="the published message")
    assert get_path(heard[-1], found.field_path) == 2
    assert model.state.value == 2 and model.state.error is None
    model.stop()
    assert not model.send(3.0) and model.state.error  # not running: nothing sent, and it says so
    await client.close()


def test_settings_problems():
    assert {cls}Settings().problems() == []
    assert {cls}Settings(step=0).problems() == ["the step must be more than 0"]
'''

PUBLISH_TEST_VIEW = '''\
"""The view, built from a model and a state the way the app builds it, rendered to a PNG."""

from {module}.model import {cls}Model, {cls}Settings
from {module}.plugin import TYPE
from {module}.view import {cls}View

from rcon_core.plugins import Binding, get_path
from rcon_core.testing import RecordingPort, build_view, grab_view, widget_state


def test_view_sends_and_shows_the_value(qapp, tmp_path):
    port = RecordingPort()  # reaches no robot; records what is published
    model = {cls}Model({cls}Settings(), Binding("/test_value", TYPE, "publish", "{path}"), port)
    model.start()
    view = build_view({cls}View, model, widget_state(1.5))
    assert view.status.text() == "sent 1.5"
    view.number.setValue(2.5)
    view.send.click()
    [(topic, msg)] = port.published
    assert topic == "/test_value" and get_path(msg, "{path}") == 2.5
    image = grab_view({cls}View, model, widget_state(1.5), path=tmp_path / "view.png")
    assert (image.width(), image.height()) == (320, 160)
'''

CALL_MODEL = '''\
"""The {title} widget's settings and model: pure Python, no Qt (testable against the embedded robot)."""

import attrs

from rcon_core.plugins import WidgetModel


@attrs.define
class {cls}Settings:
    label: str = attrs.field(default="{title}", metadata={{"label": "Button text"}})
    request: str = attrs.field(default="{{}}", metadata={{
        "label": "Request", "multiline": True,
        "help": "the request as YAML, e.g. {{data: true}}; fields left out take their defaults"}})

    def problems(self) -> list[str]:
        """Sentences for the widget's "not configured" warning; [] means configured."""
        return [] if self.label.strip() else ["the button needs a text"]


class {cls}Model(WidgetModel):
    """Calls the bound service with the request of its settings. Value: the answer, in words.

    ``press()`` (the view's button, GUI thread) hands the call to the bridge thread and returns a future;
    ``call_async(request)`` does the same on the bridge loop (tests). The answer reaches ``on_response``
    (bridge thread). Every failure becomes the widget's error: a request that does not fit the type, the
    robot refusing or failing the call, no answer within ``call_timeout`` s, a link that is down, and a
    response that says no (``success: false``).
    """

    call_timeout = 5.0

    def request(self):
        """The settings' request read against the request type (missing fields take their defaults);
        raises ``rcon_core.msgs.MessageTextError`` (a ValueError) naming the field that does not fit."""
        part = self.types.service_part_name(self.binding.type, "request")
        return self.types.from_text(part, self.settings.request)

    def press(self):
        try:
            request = self.request()
        except ValueError as exc:
            self.set_error(f"bad request: {{exc}}")
            return None
        return self.call(request)  # a concurrent.futures.Future; never wait on it in the view

    def on_response(self, response):
        if response.get("success") is False:  # std_srvs/SetBool, Trigger and many lab services say so
            self.set_error(f"{{self.binding.name}} said no: {{response.get('message') or 'no reason given'}}")
            return
        words = ", ".join(f"{{k}}: {{v}}" for k, v in response.items()) or "done"
        self.set_value(words, message=response)
'''

CALL_VIEW = '''\
"""The {title} widget's Qt view: imported only when a canvas shows it."""

from qtpy import QtCore, QtWidgets


class {cls}View(QtWidgets.QWidget):
    def __init__(self, model, parent=None):
        super().__init__(parent)
        self.model = model
        self.button = QtWidgets.QPushButton(model.settings.label)
        self.button.clicked.connect(self.model.press)
        self.button.setEnabled(model.view_only is None)  # a view-only robot: nothing may be called
        self.status = QtWidgets.QLabel("–")
        self.status.setAlignment(QtCore.Qt.AlignmentFlag.AlignCenter)
        self.status.setWordWrap(True)
        layout = QtWidgets.QVBoxLayout(self)
        layout.addWidget(self.button)
        layout.addWidget(self.status)

    def refresh(self, state):  # GUI thread, at most once per frame: only show what the model computed
        self.status.setText(state.error or (state.value if state.value is not None else "–"))
'''

CALL_TEST_MODEL = '''\
"""The model against the embedded robot, which provides the service (as the real robot would)."""

import pytest
from {module}.model import {cls}Model, {cls}Settings
from {module}.plugin import TEMPLATE, TYPE

from rcon_core.bridge import BridgeClient, ServiceError
from rcon_core.plugins import Binding, PluginManager
from rcon_core.testing import RecordingPort

SERVICE = "/test_service"


def test_the_canvas_template_is_offered():
    pm = PluginManager()
    pm.load_entry_points()
    [template] = [t for t in pm.canvas_templates() if t.title == TEMPLATE]
    assert template.path.is_file()  # shipped in the wheel too: *.json is package data


def installed_types():
    pm = PluginManager()
    pm.load_entry_points()
    return pm.type_registry()


async def test_calls_the_service_and_shows_the_answer(sim):
    types = installed_types()
    answer = types.default(types.service_part_name(TYPE, "response"))
    answer.update({{"success": True}} if "success" in answer else {{}})
    requests = []

    def serve(request):  # runs on the robot's side: the request in, the response out
        requests.append(request)
        return answer

    client = BridgeClient(sim.url, reconnect=False)
    await client.connect()
    client.node("robot").advertise_service(SERVICE, TYPE, serve)  # plays the robot's service
    model = {cls}Model({cls}Settings(), Binding(SERVICE, TYPE, "call"), client.node("test"), types=types)
    model.start()
    response = await model.call_async(model.request())
    assert response == answer and requests == [model.request()]
    assert model.state.message == answer and model.state.error is None and model.state.value
    await client.close()


async def test_a_call_the_robot_refuses_becomes_the_error(sim):
    client = BridgeClient(sim.url, reconnect=False)
    await client.connect()  # nobody provides SERVICE: the robot refuses the call
    model = {cls}Model({cls}Settings(), Binding(SERVICE, TYPE, "call"), client.node("test"), types=installed_types())
    model.start()
    with pytest.raises(ServiceError):
        await model.call_async(model.request())
    assert model.state.error.startswith(f"call {{SERVICE}} failed")
    await client.close()


async def test_a_response_that_says_no_becomes_the_error():
    types = installed_types()
    port = RecordingPort()  # no robot: it answers what the test scripts
    port.answer(SERVICE, {{"success": False, "message": "interlock open"}})
    model = {cls}Model({cls}Settings(), Binding(SERVICE, TYPE, "call"), port, types=types)
    await model.call_async({{}})
    assert model.state.error == f"{{SERVICE}} said no: interlock open"
    assert port.calls == [(SERVICE, {{}})]


def test_a_request_that_does_not_fit_is_refused_before_sending():
    port = RecordingPort()
    model = {cls}Model({cls}Settings(request="{{no_such_field: 1}}"), Binding(SERVICE, TYPE, "call"), port,
                       types=installed_types())
    assert model.press() is None
    assert model.state.error.startswith("bad request: no_such_field")
    assert port.calls == []


def test_settings_problems():
    assert {cls}Settings().problems() == []
    assert {cls}Settings(label=" ").problems() == ["the button needs a text"]
'''

CALL_TEST_VIEW = '''\
"""The view, built from a model and a state the way the app builds it, rendered to a PNG."""

from {module}.model import {cls}Model, {cls}Settings
from {module}.plugin import TYPE
from {module}.view import {cls}View

from rcon_core.plugins import Binding
from rcon_core.testing import RecordingPort, build_view, grab_view, widget_state


def test_view_shows_the_answer_or_the_error(qapp, tmp_path):
    model = {cls}Model({cls}Settings(label="Start"), Binding("/test_service", TYPE, "call"), RecordingPort())
    view = build_view({cls}View, model, widget_state("success: True, message: started"))
    assert view.button.text() == "Start" and view.status.text() == "success: True, message: started"
    view.refresh(widget_state(None, error="/test_service said no: interlock open"))
    assert view.status.text() == "/test_service said no: interlock open"
    image = grab_view({cls}View, model, widget_state("done"), path=tmp_path / "view.png")
    assert (image.width(), image.height()) == (320, 160)
'''

FILES = {
    "publish": {"{module}/model.py": PUBLISH_MODEL, "{module}/view.py": PUBLISH_VIEW,
                "tests/test_model.py": PUBLISH_TEST_MODEL, "tests/test_view.py": PUBLISH_TEST_VIEW},
    "call": {"{module}/model.py": CALL_MODEL, "{module}/view.py": CALL_VIEW,
             "tests/test_model.py": CALL_TEST_MODEL, "tests/test_view.py": CALL_TEST_VIEW},
}
