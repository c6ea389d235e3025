"""issue 22.13: the server's ``status`` messages were logged without limit (200 MB of log in 8 s; lines of
10 MB). Each is now cut to ``STATUS_TEXT`` characters, and they are logged at a bounded rate, the rest
counted (``stats["status_not_logged"]``) and said with the next line logged."""

from __future__ import annotations

import logging

import orjson
import pytest

from rcon_core.bridge import ServiceError
from rcon_core.bridge.safety import LogBudget
from rcon_core.bridge.session import STATUS_TEXT
from rcon_core.loopback import HostileServer
from rcon_core.testing import ManualClock, connected, until


def test_the_budget_lets_a_burst_through_then_a_steady_rate():
    clock = ManualClock()
    budget = LogBudget(per_second=5, burst=20, clock=clock)
    assert [budget.take() for _ in range(20)] == [0] * 20
    assert budget.take() is None and budget.take() is None
    clock.advance(0.2)  # one line's worth
    assert budget.take() == 2  # two held back, said with this one
    assert budget.take() is None
    clock.advance(100)
    assert [budget.take() for _ in range(20)] == [1] + [0] * 19  # the bucket holds a burst, no more
    assert budget.held_total == 3


@pytest.fixture
async def hostile():
    async with HostileServer() as srv:
        yield srv


async def test_a_flood_of_10_mb_status_lines_logs_a_bounded_amount(hostile, caplog):
    caplog.set_level(logging.INFO, logger="rcon_core.bridge")
    async with connected(hostile.url) as client:
        clock = ManualClock()  # the flood takes seconds here: the budget's clock stands still meanwhile
        client.session.status_log = LogBudget(clock=clock)
        await hostile.wait(lambda: hostile.ws is not None)
        huge = "E" * 10_000_000
        frame = orjson.dumps({"op": "status", "level": "error", "msg": huge}).decode()
        for _ in range(40):
            await hostile.send(frame)
        small = orjson.dumps({"op": "status", "level": "info", "msg": "tick"}).decode()
        for _ in range(400):
            await hostile.send(small)
        await until(lambda: client.stats["status_not_logged"] >= 400 - 20, timeout=120, what="the flood read")
        lines = [r.getMessage() for r in caplog.records if "server status" in r.getMessage()]
        assert len(lines) == 20
        clock.advance(1.0)
        await hostile.send(small)
        await until(lambda: sum("server status" in r.getMessage() for r in caplog.records) == 21, timeout=60,
                    what="one more")
        assert "(420 more status messages were not logged)" in caplog.records[-1].getMessage()
        assert max(len(x) for x in lines) < STATUS_TEXT + 200
        assert "(10,000,000 characters)" in lines[0]
        assert sum(len(x) for x in lines) < 20_000  # 400 MB of status text, a few KB of log
        assert client.stats["status_not_logged"] == 420


async def test_an_error_status_for_a_call_fails_it_with_the_cut_text(hostile):
    async with connected(hostile.url, call_timeout=5) as client:
        await hostile.wait(lambda: hostile.ws is not None)

        async def answer() -> None:
            [op] = await hostile.wait_for("call_service")
            await hostile.send({"op": "status", "level": "error", "id": op["id"], "msg": "x" * 5_000_000})

        import asyncio

        task = asyncio.ensure_future(answer())
        with pytest.raises(ServiceError) as err:
            await client.call_service("/any", {})
        await task
        assert len(str(err.value)) < STATUS_TEXT + 100 and "5,000,000 characters" in str(err.value)
