"""Label and Compound with huge values (issue 22.1: "check every other widget that renders text or arrays"):
what reaches the GUI is bounded whatever arrives, and the Compound copies a big message as few times as
it can. Measured before the fix (one run, shared 2-core machine): a Label given a 1 MB String took the
GUI 1.07 s per value (FitLabel measuring it), a message of 200,000 keys 9.7 s on the bridge thread (YAML)
and 0.9 s in the GUI; a Compound serving a request holding a 1,000,000-element array spent 2.6 s on the
bridge thread (five deep copies) -- long enough for the stall watchdog to cut the link."""

import copy
import math

from rcon_widgets_std.common import SHOW_CHARS, SHOW_ROWS, copy_message, shorten_text
from rcon_widgets_std.compound import ChildSpec, CompoundModel, CompoundSettings
from rcon_widgets_std.label import LabelModel, LabelSettings
from std_testkit import build

from rcon_core.msgs import TypeRegistry
from rcon_core.plugins import PluginManager, WidgetContext
from rcon_core.plugins.context import SharedResources


def test_a_label_shows_a_1_mb_string_shortened_and_copies_all_of_it(qtbot):
    from qtpy import QtWidgets
    from rcon_widgets_std.label_view import LabelView

    m = build(LabelModel, LabelSettings(), "/chat", "std_msgs/String", "subscribe", ("data",))
    whole = "z" * 1_000_000
    m.on_message({"data": whole})
    assert len(m.state.value.text) == SHOW_CHARS and m.state.value.raw is whole
    view = LabelView(m)
    qtbot.addWidget(view)
    view.refresh(m.state)
    assert len(view.value.text()) == SHOW_CHARS
    view.copy_value()
    assert QtWidgets.QApplication.clipboard().text() == whole


def test_a_label_summarises_a_message_of_200000_keys_in_bounded_text():
    m = build(LabelModel, LabelSettings(), "/odd", "lab_msgs/Odd", "subscribe")
    m.on_message({f"k{i}": i for i in range(200_000)})
    text = m.state.value.text
    assert len(text) <= SHOW_CHARS and text.count("\n") == SHOW_ROWS - 1 and text.startswith("k0: 0\n")
    deep: object = 1.0
    for _ in range(500):
        deep = {"a": deep}
    m.on_message(deep)  # nested 500 deep: summarised to a bounded depth, not an error
    assert m.state.error is None and m.state.value.text.count("\n") < SHOW_ROWS


def test_shorten_text_cuts_characters_and_rows():
    assert shorten_text("abc") == ("abc", None)
    assert shorten_text("x" * 10, chars=4) == ("xxxx", 10)
    text = "\r\n".join(["row"] * 100)
    shown, length = shorten_text(text, rows=3)
    assert shown == "row\nrow\nrow" and length == len(text)


def test_copy_message_is_a_deep_copy():
    msg = {"a": [1, 2.5, {"b": [3, None, b"x"]}], "c": "s", "d": {"e": [[1], [2]]}, "f": float("nan"),
           "g": (1, 2)}
    got = copy_message(msg)
    assert got == {**msg, "f": got["f"]} and math.isnan(got["f"])
    assert got["a"] is not msg["a"] and got["a"][2] is not msg["a"][2] and got["d"]["e"][0] is not msg["d"]["e"][0]
    got["a"][2]["b"].append(4)
    assert msg["a"][2]["b"] == [3, None, b"x"]
    assert copy_message(msg) == copy.deepcopy(msg) or math.isnan(msg["f"])


def test_a_serving_compound_copies_a_1e6_array_request_once_for_all_its_display_children():
    """2.6 s of bridge-thread time for one request of 1,000,000 floats (five deep copies): the display
    children now share one copy, the state one other."""
    pm = PluginManager(environ={})
    pm.load_entry_points()
    types = TypeRegistry.standard()
    types.add_msg_text("lab_srvs/srv/Big", "float64[] data\nstring note\n---\nbool ok\nstring message\n")
    settings = CompoundSettings(children=[ChildSpec("std.label", "request.data"),
                                          ChildSpec("std.label", "request.note"),
                                          ChildSpec("std.switch", "response.ok")])
    m = build(CompoundModel, settings, "/big", "lab_srvs/srv/Big", "serve", types=types,
              context=WidgetContext(pm.widget, None, SharedResources()))
    m.on_types_ready()
    request = {"data": [0.5] * 1_000_000, "note": "n" * 1_000_000}
    m.handle_request(request)
    shown = [c.model.state.message for c in m.children if not c.is_input]
    assert len(shown) == 2 and shown[0] is shown[1] and shown[0] is not request
    assert shown[0]["data"] == request["data"]
    assert m.state.message is m.state.value.message  # one copy for the value and the message
    assert all(len(c.model.state.value.text) <= SHOW_CHARS for c in m.children if not c.is_input)


def test_a_text_field_showing_what_arrives_shows_a_5_mb_string_shortened(qtbot):
    """The Text Field bound to subscribe put the whole text in its box (Qt lays out a 5 MB line for
    seconds, like the Text View did)."""
    from rcon_widgets_std.textfield import TextFieldModel, TextFieldSettings
    from rcon_widgets_std.textfield_view import TextFieldView

    m = build(TextFieldModel, TextFieldSettings(), "/chat", "std_msgs/String", "subscribe", ("data",))
    m.on_message({"data": "q" * 5_000_000})
    view = TextFieldView(m)
    qtbot.addWidget(view)
    view.refresh(m.state)
    assert len(view.text.toPlainText()) == SHOW_CHARS


def test_a_service_answer_of_5_mb_makes_a_bounded_status_line():
    from rcon_widgets_std.button import describe_response

    assert len(describe_response({"success": True, "message": "m" * 5_000_000})) == SHOW_CHARS
    assert len(describe_response({"data": list(range(1_000_000))})) <= SHOW_CHARS
