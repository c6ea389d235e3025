"""LoopTicker (the teleop pad's and the motion sensors' publish rate) on a ManualClock: a late wake-up
never brings the next call early, and small lateness keeps the rate."""

from __future__ import annotations

import pytest
from rcon_widgets_sensors.slots import LATE_FRACTION, LoopTicker

from rcon_core.testing import ManualClock

PERIOD = 0.05


def ticking(clock: ManualClock) -> tuple[LoopTicker, list[float]]:
    times: list[float] = []
    ticker = LoopTicker(PERIOD, lambda: times.append(clock.now), clock=clock)
    ticker.start()
    return ticker, times


def wake_late(clock: ManualClock, ticker: LoopTicker, late: float) -> None:
    """The loop was busy: the due call runs ``late`` seconds after its time."""
    due = clock.now + PERIOD
    clock.now = due + late  # time passed without the loop running the call
    clock.advance(0)


def test_after_a_late_call_the_next_is_a_whole_period_later_not_a_catch_up():
    clock = ManualClock()
    ticker, times = ticking(clock)
    clock.advance(PERIOD)  # on time
    wake_late(clock, ticker, 0.03)  # 30 ms late (the loop was busy)
    clock.advance(PERIOD * 3)
    intervals = [round(b - a, 6) for a, b in zip(times, times[1:], strict=False)]
    assert intervals[0] == pytest.approx(PERIOD + 0.03)  # the late one: unavoidable
    assert all(i == pytest.approx(PERIOD) for i in intervals[1:]), intervals  # no short catch-up interval
    ticker.stop()


def test_a_call_later_than_several_periods_sends_one_call_not_a_burst():
    clock = ManualClock()
    ticker, times = ticking(clock)
    clock.advance(PERIOD)
    wake_late(clock, ticker, PERIOD * 4)
    n = len(times)
    clock.advance(PERIOD * 0.99)
    assert len(times) == n  # nothing before a whole period has passed
    clock.advance(PERIOD * 0.02)
    assert len(times) == n + 1
    ticker.stop()


def test_small_lateness_keeps_the_phase_so_the_rate_holds():
    clock = ManualClock()
    ticker, times = ticking(clock)
    start = clock.now
    small = PERIOD * LATE_FRACTION * 0.5
    for k in range(1, 21):
        clock.now = start + k * PERIOD + small  # each call runs a little late
        clock.advance(0)
    # every call kept its place on the grid: 20 calls in 20 periods, none drifting later
    assert len(times) == 20
    assert times == pytest.approx([start + k * PERIOD + small for k in range(1, 21)])
    ticker.stop()
