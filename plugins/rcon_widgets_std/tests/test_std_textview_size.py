"""Text View under load (issue 22.1): one huge message and a flood cost the GUI a bounded pass.

A single 100 KB String froze the window 1.8 s, 500 KB 21 s, 5 MB more than 200 s (``appendHtml`` of the
whole text); 10,000 messages a second stalled the GUI up to 3.2 s (the whole history copied per message,
one ``appendHtml`` per line). The times are measured by ``benchmarks/soak.py --parts gui``; these tests
hold what bounds them: what reaches the document, how much of it per pass, and that no snapshot copies
the history."""

import pytest
from qtpy import QtWidgets
from rcon_widgets_std.textview import (
    DISPLAY_CHARS,
    DISPLAY_ROWS,
    FULL_TEXT_BUDGET,
    TextViewModel,
    TextViewSettings,
    display_text,
)
from rcon_widgets_std.textview_view import DOC_LINES, PASS_LINES, TextViewView
from std_testkit import build


def string_model(**settings):
    return build(TextViewModel, TextViewSettings(**settings), "/chat", "std_msgs/String", "subscribe")


@pytest.mark.parametrize("size", [100_000, 500_000, 5_000_000])
def test_one_huge_string_is_shown_shortened_and_kept_whole(qtbot, size):
    """100 KB froze the window 1.8 s, 500 KB 21 s, 5 MB over 200 s: the document now gets at most
    DISPLAY_CHARS of it (and a note), the whole text stays one right-click away."""
    m = string_model()
    whole = "x" * size
    m.on_message({"data": whole})
    line = m.state.value.lines[-1]
    assert len(line.text) == DISPLAY_CHARS and line.length == size and line.shortened
    assert m.full_text(line) is whole  # kept, not copied
    view = TextViewView(m)
    qtbot.addWidget(view)
    view.refresh(m.state)
    shown = view.history.toPlainText()
    assert len(shown) < DISPLAY_CHARS + 100
    assert f"{size:,} characters: right-click to see them all" in shown
    dialog = view.show_whole(line)
    qtbot.addWidget(dialog)
    body = dialog.findChild(QtWidgets.QPlainTextEdit)
    assert body.toPlainText().replace("\n", "") == whole[:200_000]
    assert view.copy_whole(line)
    assert QtWidgets.QApplication.clipboard().text() == whole


def test_many_rows_are_cut_too():
    text = "\n".join(f"row {i}" for i in range(1000))  # a short text of many rows (a traceback)
    shown, length = display_text(text)
    assert shown.count("\n") == DISPLAY_ROWS - 1 and length == len(text)
    assert display_text("short\r\nline") == ("short\nline", None)


def test_not_a_string_is_shown_bounded():
    """A message that is no string (a wrong binding, a hostile server) is shown in a bounded form: never
    ``str()`` of a value nested 1000 deep or a million items long."""
    m = string_model()
    deep: object = 0
    for _ in range(5000):
        deep = [deep]
    m.on_message({"data": deep})
    m.on_message({"data": list(range(1_000_000))})
    lines = m.state.value.lines
    assert len(lines) == 2 and all(len(x.text) <= DISPLAY_CHARS for x in lines)


def test_whole_texts_are_kept_within_their_budget():
    m = string_model()
    size = FULL_TEXT_BUDGET // 3
    for i in range(5):
        m.on_message({"data": str(i) * size})
    lines = m.state.value.lines
    kept = [m.full_text(x) is not None for x in lines]
    assert kept == [False, False, True, True, True]  # the newest, within the budget
    assert m.full_text(lines[-1]) == "4" * size


def test_a_snapshot_per_message_copies_no_history():
    """At 10,000 messages a second the whole history (up to 50,000 lines) was copied into each snapshot:
    now every snapshot is a window onto one ring of lines."""
    m = string_model(max_lines=50_000)
    snaps = []
    for i in range(3000):
        m.on_message({"data": f"line {i}"})
        if i % 1000 == 0:
            snaps.append(m.state.value)
    assert len({id(h.ring) for h in snaps}) == 1
    assert [h.end for h in snaps] == [1, 1001, 2001]
    assert snaps[0].lines[0].text == "line 0" and len(snaps[1]) == 1001


def test_a_flood_is_painted_a_bounded_number_of_lines_per_pass(qtbot):
    """10,000 lines arrived between two passes: one pass inserts at most PASS_LINES, the newest first;
    the following passes (a frame apart) fill the rest up to the document's cap."""
    m = string_model(max_lines=50_000)
    view = TextViewView(m)
    qtbot.addWidget(view)
    for i in range(30_000):
        m.on_message({"data": f"flood {i}"})
    view.refresh(m.state)
    assert 0 < view.painted <= PASS_LINES  # the newest first (fewer when the pass's time is up)
    assert view.history.toPlainText().splitlines()[0] == f"flood {30_000 - PASS_LINES}"
    qtbot.waitUntil(lambda: view.history.document().blockCount() == DOC_LINES, timeout=20_000)
    rows = view.history.toPlainText().splitlines()
    assert rows[0] == f"flood {30_000 - DOC_LINES}" and rows[-1] == "flood 29999"
    assert rows == [f"flood {i}" for i in range(30_000 - DOC_LINES, 30_000)]  # in order, none twice
    before = view.painted
    for i in range(30_000, 30_050):
        m.on_message({"data": f"flood {i}"})
    view.refresh(m.state)
    qtbot.waitUntil(lambda: view.history.toPlainText().splitlines()[-1] == "flood 30049", timeout=10_000)
    assert view.painted - before == 50
    assert view.history.document().blockCount() == DOC_LINES


def test_a_filter_change_paints_the_newest_first_then_the_rest(qtbot):
    m = string_model(max_lines=2000)
    view = TextViewView(m)
    qtbot.addWidget(view)
    for i in range(2000):
        m.on_message({"data": f"{'even' if i % 2 == 0 else 'odd'} {i}"})
    view.refresh(m.state)
    view.filter.setText("odd")
    view.refresh(m.state)
    qtbot.waitUntil(lambda: view.history.toPlainText().splitlines()[-1:] == ["odd 1999"], timeout=10_000)
    qtbot.waitUntil(lambda: view.history.document().blockCount() == 1000, timeout=10_000)
    assert view.history.toPlainText().splitlines() == [f"odd {i}" for i in range(1, 2000, 2)]
    # each block still knows its line (the whole text on demand), also where the older lines were put above
    doc = view.history.document()
    states = [doc.findBlockByNumber(k).userState() for k in range(doc.blockCount())]
    assert states == [n + 1 for n in range(1, 2000, 2)]  # line numbers n start at 1


def test_the_context_menu_finds_the_line_under_the_finger(qtbot):
    m = string_model()
    view = TextViewView(m)
    qtbot.addWidget(view)
    view.resize(400, 300)
    view.show()
    m.on_message({"data": "y" * 50_000})
    view.refresh(m.state)
    qtbot.waitExposed(view)
    line = view.line_at(view.history.cursorRect(view.history.textCursor()).center())
    assert line is not None and line.length == 50_000
