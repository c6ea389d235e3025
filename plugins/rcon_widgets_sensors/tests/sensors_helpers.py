"""Shared helpers for this package's tests (imported by basename: keep the name unique)."""

from __future__ import annotations

import asyncio
import time


async def until(predicate, timeout=10.0, what="condition"):
    """Poll ``predicate`` on the test's loop until true; AssertionError naming ``what`` after ``timeout``."""
    deadline = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out waiting for {what}")
        await asyncio.sleep(0.01)


async def in_thread(fn, *args):
    """Run a blocking call without blocking the test's loop (the bridge and the sim live on it)."""
    return await asyncio.get_running_loop().run_in_executor(None, fn, *args)
