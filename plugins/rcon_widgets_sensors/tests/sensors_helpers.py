"""Shared helpers for this package's tests (imported by basename: keep the name unique)."""

from __future__ import annotations

import asyncio


async def in_thread(fn, *args):
    """Run a blocking call without blocking the test's loop (the bridge and the sim live on it)."""
    return await asyncio.get_running_loop().run_in_executor(None, fn, *args)
