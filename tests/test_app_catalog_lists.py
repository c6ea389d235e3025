"""The side panel's lists at scale (issue 22.6) and what an empty list says (issue 21.13).

22.6: 10^5 topics froze the side panel 6.3 s at every change (the list cleared and built again). The
list now shows the first ``MAX_ROWS`` entries that match the search and says how many there are, and a
new catalogue changes only the rows that differ. The pass times are measured by
``benchmarks/bench_catalog.py --parts panel``.

21.13: after the link dropped, the old topic list stayed; on first start the bar said CONNECTED beside
"No topics yet: connect to a robot.". The lists now empty when the link is lost and say why they are
empty: connecting, listing, lost, or the robot has none."""

from __future__ import annotations

import pytest
from app_helpers import window_session

from rcon_core.app.catalog_panel import MAX_ROWS, CatalogList
from rcon_core.bridge import ConnectionState
from rcon_core.sim import SimServer

pytestmark = pytest.mark.usefixtures("qapp")
N = 100_000


def names(n: int = N) -> list[tuple[str, str]]:
    return [(f"/bench/topic_{i:06d}", "std_msgs/Float64") for i in range(n)]


def rows(lst: CatalogList) -> list[str]:
    return [lst.tree.topLevelItem(i).data(0, 256) for i in range(lst.tree.topLevelItemCount())]


def test_10e5_topics_show_the_first_rows_and_say_how_many(qtbot):
    lst = CatalogList("topics", with_rate=True)
    qtbot.addWidget(lst)
    entries = names()
    lst.set_entries(entries)
    assert lst.tree.topLevelItemCount() == MAX_ROWS and lst.total == N
    assert rows(lst)[0] == "/bench/topic_000000" and rows(lst)[-1] == f"/bench/topic_{MAX_ROWS - 1:06d}"
    assert lst.more.text() == f"Showing the first {MAX_ROWS:,} of {N:,} topics: search to find the others."
    kept = lst.item("/bench/topic_000010")
    lst.tree.setCurrentItem(lst.item("/bench/topic_000500"))
    # one topic more: one row changes, the others stay as they are (the same items)
    lst.set_entries(sorted([*entries, ("/bench/topic_000010_b", "std_msgs/String")]))
    assert lst.item("/bench/topic_000010") is kept
    assert rows(lst)[11] == "/bench/topic_000010_b" and lst.tree.topLevelItemCount() == MAX_ROWS
    assert lst.current() == ("/bench/topic_000500", "std_msgs/Float64")
    assert lst.more.text().startswith(f"Showing the first {MAX_ROWS:,} of {N + 1:,} topics")
    # a topic's type changes: only its row
    lst.set_entries(sorted([*entries[:20], ("/bench/topic_000010_b", "std_msgs/Int32"), *entries[20:]]))
    assert lst.item("/bench/topic_000010_b").data(0, 257) == "std_msgs/Int32" and lst.item("/bench/topic_000010") is kept


def test_a_search_over_10e5_topics_finds_those_past_the_first_rows(qtbot):
    lst = CatalogList("topics", with_rate=True)
    qtbot.addWidget(lst)
    lst.set_entries(names())
    lst.filter.setText("topic_0995")  # past the first rows: found a slice per pass
    qtbot.waitUntil(lambda: not lst.filling, timeout=30_000)
    assert rows(lst) == [f"/bench/topic_0995{i:02d}" for i in range(100)] and not lst.more.isVisible()
    lst.filter.setText("no such thing")
    qtbot.waitUntil(lambda: not lst.filling, timeout=30_000)
    assert lst.tree.topLevelItemCount() == 0 and "No topics match" in lst.more.text()
    lst.filter.setText("")
    assert lst.tree.topLevelItemCount() == MAX_ROWS


def test_rates_touch_only_the_rows_that_have_one(qtbot):
    lst = CatalogList("topics", with_rate=True)
    qtbot.addWidget(lst)
    lst.set_entries(names(50))
    lst.set_rates({"/bench/topic_000001": 20.0, "/bench/topic_000002": 2.5, "/not/listed": 1.0})
    assert lst.item("/bench/topic_000001").text(1) == "20 Hz" and lst.item("/bench/topic_000002").text(1) == "2.5 Hz"
    lst.set_rates({"/bench/topic_000002": 3.0})
    assert lst.item("/bench/topic_000001").text(1) == "" and lst.item("/bench/topic_000002").text(1) == "3.0 Hz"


@pytest.fixture
def own_sim():
    """A sim of this test's own (the test stops it to drop the link)."""
    with SimServer.in_thread(host="127.0.0.1", port=0) as server:
        yield server


@pytest.fixture
def window(qtbot, tmp_path, plugins):
    yield from window_session(qtbot, tmp_path / "config", plugins)


def test_a_lost_link_empties_the_lists_and_they_say_why(window, qtbot, own_sim, monkeypatch):
    import asyncio
    import threading

    from rcon_core.app import link as link_mod

    listed = threading.Event()  # the robot's first listing waits for the test (as a slow robot's would)
    real = link_mod.fetch_catalog

    async def slow_fetch(*args, **kwargs):
        await asyncio.get_running_loop().run_in_executor(None, listed.wait)
        return await real(*args, **kwargs)

    monkeypatch.setattr(link_mod, "fetch_catalog", slow_fetch)
    assert window.topics.empty.text() == "No topics yet: connect to a robot."
    window.connect_to(own_sim.url)
    qtbot.waitUntil(lambda: window.connection.state is ConnectionState.CONNECTED, timeout=10_000)
    # connected, nothing listed yet: the list says it is listing, not "connect to a robot"
    qtbot.waitUntil(lambda: window.topics.empty.text() == "Listing the robot's topics…", timeout=10_000)
    assert window.topics.empty.isVisible() and window.topics.tree.topLevelItemCount() == 0
    assert window.services.empty.text() == "Listing the robot's services…"
    listed.set()
    qtbot.waitUntil(lambda: window.topics.item("/cmd_vel") is not None, timeout=10_000)
    assert not window.topics.empty.isVisible()
    # the link drops (the robot is gone): the old list goes, the lists say so
    asyncio.run_coroutine_threadsafe(own_sim.stop(), own_sim.loop).result(10)
    qtbot.waitUntil(lambda: window.topics.tree.topLevelItemCount() == 0, timeout=10_000)
    assert window.topics.empty.isVisible()
    qtbot.waitUntil(lambda: window.topics.empty.text() == ("The link to the robot is lost: its topics are "
                                                           "listed again when it is back."), timeout=10_000)
    assert window.services.empty.text().startswith("The link to the robot is lost: its services")
    assert window.catalog["topics"] == []
