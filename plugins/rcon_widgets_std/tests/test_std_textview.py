"""Text View: /rosout history from the robot, levels of both ROS flavours, filters, bounded memory, and
the chat room (publish role: input line + history of the same topic)."""

import asyncio

import pytest
from rcon_widgets_std.textview import TextViewModel, TextViewSettings, level_name
from std_testkit import bridge, build

from rcon_core.testing import until


def log(level, text, name="/robot", ros2=False):
    if ros2:
        return {"stamp": {"sec": 5, "nanosec": 0}, "level": level, "name": name, "msg": text}
    return {"header": {"stamp": {"secs": 5, "nsecs": 0}}, "level": level, "name": name, "msg": text}


def test_levels_of_both_flavours():
    assert [level_name(x) for x in (1, 2, 4, 8, 16)] == ["debug", "info", "warn", "error", "fatal"]
    assert [level_name(x) for x in (10, 20, 30, 40, 50)] == ["debug", "info", "warn", "error", "fatal"]
    assert level_name("loud") == "info"


def test_filter_by_level_and_text_and_the_bounded_history():
    m = build(TextViewModel, TextViewSettings(max_lines=10), "/rosout", "rosgraph_msgs/Log", "subscribe")
    for i in range(25):
        m.on_message(log([1, 2, 4, 8][i % 4], f"line {i}", name="/nav" if i % 2 else "/robot"))
    h = m.state.value
    assert len(h.lines) == 10 and h.total == 25 and h.lines[-1].text == "line 24"  # only the last 10 kept
    assert h.lines[-1].stamp == 5.0 and h.lines[-1].node == "/robot"
    m.set_filter(min_level="warn")
    assert {x.level for x in m.state.value.lines} == {"warn", "error"}
    m.set_filter(text="NAV")  # case-insensitive, node names too
    assert all(x.node == "/nav" and x.level in ("warn", "error") for x in m.state.value.lines)
    assert m.state.count == 25  # filtering is not new data
    v0 = m.state.value.filter_version
    m.set_filter(min_level="debug", text="")
    assert len(m.state.value.lines) == 10 and m.state.value.filter_version == v0 + 1
    with pytest.raises(ValueError, match="level must be one of"):
        m.set_filter(min_level="loud")
    m.clear()
    assert m.state.value.lines == ()


def test_ros2_log_and_strings():
    m = build(TextViewModel, TextViewSettings(), "/rosout", "rcl_interfaces/msg/Log", "subscribe")
    m.on_message(log(40, "motor hot", ros2=True))
    line = m.state.value.lines[0]
    assert (line.level, line.text, line.stamp) == ("error", "motor hot", 5.0)
    s = build(TextViewModel, TextViewSettings(), "/chat", "std_msgs/String", "subscribe")
    s.on_message({"data": "hello"})
    assert s.state.value.lines[0].text == "hello" and s.state.value.lines[0].level == "info"


def test_settings_problems():
    assert TextViewSettings().problems() == []
    assert "between 10 and" in TextViewSettings(max_lines=5).problems()[0]
    assert "lowest level" in TextViewSettings(min_level="chatty").problems()[0]


async def test_rosout_from_the_robot(sim):
    async with bridge(sim) as client:
        m = build(TextViewModel, TextViewSettings(), "/rosout", "rosgraph_msgs/Log", "subscribe", client=client)
        m.start()
        await until(lambda: sim.topic_subscriber_count("/rosout") >= 1, what="the subscription")
        sim.log("/rcon_sim", "warn", "Battery low: test line")
        sim.log("/rcon_sim", "error", "Thruster fault: test line")
        await until(lambda: m.state.value is not None and any("Thruster fault" in x.text
                                                              for x in m.state.value.lines), what="the lines")
        lines = {x.text: x for x in m.state.value.lines}
        assert lines["Battery low: test line"].level == "warn"
        assert lines["Thruster fault: test line"].level == "error"
        assert lines["Thruster fault: test line"].node == "/rcon_sim"
        m.stop()


async def test_chat_room_publishes_and_shows_the_topic(sim):
    async with bridge(sim) as client:
        me = build(TextViewModel, TextViewSettings(), "/rcon_test/chat", "std_msgs/String", "publish",
                   client=client, node="me")
        other = build(TextViewModel, TextViewSettings(), "/rcon_test/chat", "std_msgs/String", "publish",
                      client=client, node="other")
        me.start()
        other.start()
        await until(lambda: sim.topic_subscriber_count("/rcon_test/chat") >= 1, what="the consoles subscribed")
        assert me.send("operator 1: heading to the dock")
        assert not me.send("   ")  # blank lines are not sent
        await sim.wait_for_published("/rcon_test/chat", lambda m: "dock" in m["data"], timeout=10)
        await until(lambda: other.state.value is not None, what="the other console's history")
        assert other.state.value.lines[-1].text == "operator 1: heading to the dock"
        other.send("operator 2: ok")
        await until(lambda: me.state.value is not None and me.state.value.lines[-1].text == "operator 2: ok",
                    what="the reply in my history")
        me.stop()
        other.stop()


async def test_operator_note_into_rosout(sim):
    async with bridge(sim) as client:
        m = build(TextViewModel, TextViewSettings(), "/rosout", "rosgraph_msgs/Log", "publish", client=client)
        m.start()
        m.send("note: starting survey")
        got = await sim.wait_for_published("/rosout", lambda msg: msg.get("msg") == "note: starting survey",
                                           timeout=10)
        assert got["level"] == 2 and got["name"] == "rcon_operator"
        m.stop()


async def test_ros2_rosout_from_a_ros2_robot():
    from rcon_core.msgs import TypeRegistry
    from rcon_core.sim import SimServer

    server = SimServer(host="127.0.0.1", port=0, ros2=True, rate_scale=2.0)
    await server.start()
    try:
        async with bridge(server) as client:
            m = build(TextViewModel, TextViewSettings(), "/rosout", "rcl_interfaces/msg/Log", "subscribe",
                      client=client, types=TypeRegistry.standard(ros2=True))
            m.start()
            await until(lambda: server.topic_subscriber_count("/rosout") >= 1, what="the subscription")
            server.log("/rcon_sim", "error", "ROS 2 fault line")
            await until(lambda: m.state.value is not None and any("ROS 2 fault" in x.text
                                                                  for x in m.state.value.lines), what="the line")
            line = next(x for x in m.state.value.lines if "ROS 2 fault" in x.text)
            assert line.level == "error" and line.node == "rcon_sim" and line.stamp
            m.stop()
    finally:
        await server.stop()


async def test_latched_rosout_replay_comes_first_in_time_order_and_marked(sim):
    """rosbridge delivers each node's latched last /rosout line first on subscribe, in node order, not
    time order (the Text View showed 11:57:35 above 11:57:31). Those lines come first, sorted by stamp,
    marked replayed; live lines follow in the order received; a line sent again is not shown twice."""
    sim.log("/node_a", "info", "a: old line")
    await asyncio.sleep(0.05)
    sim.log("/node_b", "warn", "b: line")
    await asyncio.sleep(0.05)
    sim.log("/node_a", "info", "a: newer line")  # node_a's latched line is now newer than node_b's
    await asyncio.sleep(1.3)  # logged well before the console subscribes
    async with bridge(sim) as client:
        m = build(TextViewModel, TextViewSettings(), "/rosout", "rosgraph_msgs/Log", "subscribe", client=client)
        m.start()
        await until(lambda: m.state.value is not None and any("a: newer" in x.text for x in m.state.value.lines)
                    and any("b: line" in x.text for x in m.state.value.lines), what="the latched replay")
        sim.log("/node_c", "info", "c: live line")
        await until(lambda: any("c: live" in x.text for x in m.state.value.lines), what="a live line")
        lines = m.state.value.lines
        replayed = [x for x in lines if x.replayed]
        assert [x.text for x in replayed if x.node.startswith("/node_")] == ["b: line", "a: newer line"]
        assert [x.stamp for x in replayed] == sorted(x.stamp for x in replayed)
        assert lines[:len(replayed)] == tuple(replayed)  # the replay block is at the top
        live = next(x for x in lines if x.text == "c: live line")
        assert not live.replayed
        again = {"header": {"seq": 0, "stamp": {"secs": int(live.stamp), "nsecs": round(live.stamp % 1 * 1e9)},
                            "frame_id": ""}, "level": 2, "name": live.node, "msg": live.text}
        count = len(m.state.value.lines)
        m.on_message(again)  # the same line once more (a re-subscription after a reconnect)
        assert len(m.state.value.lines) == count
        m.stop()


def test_replayed_lines_are_marked_in_the_view(qtbot):
    from rcon_widgets_std.textview_view import TextViewView

    m = build(TextViewModel, TextViewSettings(), "/rosout", "rosgraph_msgs/Log", "subscribe")
    m.wall = lambda: 1_000_000.0
    m.on_start()  # subscribed at wall time 1e6
    for name, secs in (("/late", 999_990), ("/early", 999_980)):  # replay order: not time order
        m.on_message({"header": {"stamp": {"secs": secs, "nsecs": 0}}, "level": 2, "name": name, "msg": name})
    m.on_message({"header": {"stamp": {"secs": 1_000_001, "nsecs": 0}}, "level": 2, "name": "/live", "msg": "now"})
    view = TextViewView(m)
    qtbot.addWidget(view)
    view.refresh(m.state)
    rows = view.history.toPlainText().splitlines()
    assert [r.split()[-1] for r in rows] == ["/early", "/late", "now"]
    assert rows[0].startswith("↺") and rows[1].startswith("↺") and not rows[2].startswith("↺")
