"""view_common's setters skip when nothing changed: a style sheet (even an identical one) re-polishes the
widget, and views call these on every refresh."""

from qtpy import QtCore, QtWidgets
from rcon_widgets_std.button import ButtonModel, ButtonSettings, CallStatus
from rcon_widgets_std.button_view import ButtonView
from rcon_widgets_std.view_common import BAD, OK, Caption, style_text
from std_testkit import build


class StyleChanges(QtCore.QObject):
    """Counts style changes (what ``setStyleSheet`` causes) on the widgets it watches."""

    def __init__(self, *widgets: QtWidgets.QWidget) -> None:
        super().__init__()
        self.count = 0
        for w in widgets:
            w.installEventFilter(self)

    def eventFilter(self, obj, event):  # noqa: N802 - Qt override
        if event.type() == QtCore.QEvent.Type.StyleChange:
            self.count += 1
        return False


def test_caption_and_style_text_restyle_only_on_a_change(qtbot):
    cap = Caption("x")
    label = QtWidgets.QLabel("1")
    qtbot.addWidget(cap)
    qtbot.addWidget(label)
    cap.show()
    label.show()  # a hidden widget defers its polish
    cap.show_text("ok", OK)
    style_text(label, 30, "", True)
    changes = StyleChanges(cap, label)
    for _ in range(5):
        cap.show_text("ok", OK)
        cap.set_colour(OK)
        style_text(label, 30, "", True)
    assert changes.count == 0
    cap.show_text("bad", BAD)
    style_text(label, 14, "", False)
    assert changes.count == 2 and cap.colour == BAD and "font-size: 14px" in label.styleSheet()


def test_button_refresh_with_the_same_result_does_not_restyle(qtbot):
    m = build(ButtonModel, ButtonSettings(text="Dock"), "/dock", "std_srvs/Trigger", "call")
    view = ButtonView(m)
    qtbot.addWidget(view)
    m.set_value(CallStatus("ok", "/dock", "docking started", seconds=0.012))
    view.refresh(m.state)
    view.show()
    changes = StyleChanges(view.result, view.button)
    for _ in range(10):
        view.refresh(m.state)
    assert changes.count == 0 and view.result.text().startswith("✓ docking started")
