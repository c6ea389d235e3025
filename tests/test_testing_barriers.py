"""The waiting helpers every test uses (``rcon_core.testing``): ``until``/``until_sync`` fail naming what they
waited for, and ``flushed`` is a real barrier (everything sent before it has arrived when it returns)."""

from __future__ import annotations

import pytest

from rcon_core.testing import flushed, flushed_sync, until, until_sync


async def test_until_returns_the_value_and_fails_naming_what_it_waited_for():
    box = [0]

    def bump():
        box[0] += 1
        return box[0] if box[0] >= 3 else None

    assert await until(bump) == 3
    with pytest.raises(AssertionError, match="waiting for the impossible"):
        await until(lambda: False, 0.05, "the impossible")


def test_until_sync_returns_the_value_and_fails_naming_what_it_waited_for():
    box = [0]

    def bump():
        box[0] += 1
        return box[0] if box[0] >= 3 else None

    assert until_sync(bump) == 3
    with pytest.raises(AssertionError, match="waiting for the impossible"):
        until_sync(lambda: False, 0.05, "the impossible")


async def test_flushed_returns_only_once_everything_sent_before_it_has_arrived(sim, client):
    pub = client.node("burst").advertise("/rcon_test/burst", "std_msgs/Int32")
    for i in range(200):  # written without yielding: most are still in flight when the barrier starts
        pub.publish({"data": i})
    await flushed(client, sim)
    assert [m["data"] for m in sim.published("/rcon_test/burst")] == list(range(200))


def test_flushed_sync_for_a_client_on_a_bridge_thread(threaded_client, sim_thread):
    thread, client = threaded_client
    pub = thread.call(lambda: client.node("burst").advertise("/rcon_test/burst", "std_msgs/Int32")).result(5)
    thread.call(lambda: [pub.publish({"data": i}) for i in range(200)]).result(5)
    flushed_sync(thread, client, sim_thread)
    assert [m["data"] for m in sim_thread.published("/rcon_test/burst")] == list(range(200))
