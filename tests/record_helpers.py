"""Shared by the flight recorder's tests: where the recordings are, and a recording served as a robot."""

from __future__ import annotations

import contextlib
from collections.abc import AsyncIterator
from pathlib import Path
from typing import Any

FIXTURES = Path(__file__).parent / "fixtures" / "recordings"
DEMO_BAG = FIXTURES / "demo.bag"
DEMO_SQLITE3 = FIXTURES / "demo_sqlite3"
DEMO_MCAP = FIXTURES / "demo_mcap"
TALKER_MCAP = FIXTURES / "rosbag2_project" / "talker_mcap"
TALKER_SQLITE3 = FIXTURES / "rosbag2_project" / "talker_sqlite3"
CDR_TEST = FIXTURES / "rosbag2_project" / "cdr_test"


@contextlib.asynccontextmanager
async def playing(path: Any, **options: Any) -> AsyncIterator[tuple[Any, Any]]:
    """``(server, player)``: the recording at ``path`` served as a robot (``sim/playback.py``)."""
    from rcon_core.sim.playback import serve_recording

    server, player = await serve_recording(str(path), **options)
    try:
        yield server, player
    finally:
        await player.stop()
        await server.stop()
        player.recording.close()
