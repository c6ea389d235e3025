"""Other work on the machine, for the benchmarks: N busy processes, bounded, always ended.

``with busy_processes(n, max_seconds):`` starts ``n`` child processes that each spin one core in pure
Python (nothing else: no memory, no I/O), at the normal priority and in the benchmark's own session (so
on Linux, where the scheduler groups processes by session, they share the app's group thread by thread:
the harder case, whatever the desktop's grouping), and ends them when the block is left -- normally, by an
exception, by Ctrl-C, or by SIGTERM (turned into ``SystemExit`` while the block runs). Should the
benchmark itself be killed, each child still ends on its own: on Linux the kernel signals it when its
parent dies (``PR_SET_PDEATHSIG``), elsewhere it notices that its parent changed within 0.2 s; and none
runs longer than ``max_seconds`` in any case.

``python benchmarks/background_load.py N [SECONDS]`` runs the load alone (Ctrl-C ends it).
"""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator

#: at most this many busy processes (a benchmark on a two-core machine needs no more to be loaded)
MAX_PROCESSES = 8
#: the longest a busy process lives, whatever it is asked (s)
MAX_SECONDS = 3600.0

_CHILD = """
import os, signal, sys, time
parent, end = int(sys.argv[1]), time.monotonic() + float(sys.argv[2])
signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the benchmark's to handle: it ends us
if sys.platform.startswith("linux"):
    try:
        import ctypes
        ctypes.CDLL(None).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG: killed when the parent dies
    except Exception:
        pass
n = 0
while True:
    for _ in range(20000):
        n = (n * 1103515245 + 12345) & 0x7FFFFFFF
    now = time.monotonic()
    if now > end or os.getppid() != parent:
        break
"""


def die_with_parent() -> None:
    """Let the kernel end this process (SIGTERM) when its parent dies (Linux; elsewhere nothing): for the
    children a benchmark starts, so a benchmark killed outright leaves nothing running."""
    if not sys.platform.startswith("linux"):
        return
    parent = os.getppid()
    with contextlib.suppress(Exception):
        import ctypes

        ctypes.CDLL(None).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG
    if os.getppid() != parent:  # the parent died before the request took effect
        os.kill(os.getpid(), signal.SIGTERM)


@contextlib.contextmanager
def busy_processes(n: int, max_seconds: float = 600.0) -> Iterator[list[int]]:
    """Run ``n`` busy processes (0..MAX_PROCESSES) for the block, at most ``max_seconds``; yields their pids."""
    if not 0 <= n <= MAX_PROCESSES:
        raise ValueError(f"the background load must be from 0 to {MAX_PROCESSES} processes, not {n}")
    seconds = min(float(max_seconds), MAX_SECONDS)
    procs: list[subprocess.Popen[bytes]] = []
    old_term = None
    if n and signal.getsignal(signal.SIGTERM) is signal.SIG_DFL:
        with contextlib.suppress(ValueError):  # not the main thread: SIGTERM stays the default
            def on_term(_sig: int, _frame: object) -> None:
                for p in procs:  # at once: a SystemExit raised inside a Qt slot may not unwind this block
                    with contextlib.suppress(OSError):
                        p.kill()
                raise SystemExit(128 + signal.SIGTERM)

            old_term = signal.signal(signal.SIGTERM, on_term)
    try:
        for _ in range(n):
            procs.append(subprocess.Popen(
                [sys.executable, "-c", _CHILD, str(os.getpid()), str(seconds)],
                stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        yield [p.pid for p in procs]
    finally:
        for p in procs:
            with contextlib.suppress(OSError):
                p.kill()
        for p in procs:
            with contextlib.suppress(Exception):
                p.wait(5)
        if old_term is not None:
            signal.signal(signal.SIGTERM, old_term)


def main(argv: list[str] | None = None) -> int:
    args = (argv if argv is not None else sys.argv[1:]) or ["1"]
    n, seconds = int(args[0]), float(args[1]) if len(args) > 1 else 60.0
    with busy_processes(n, seconds) as pids:
        print(f"{len(pids)} busy processes for at most {seconds:g} s: {pids}", flush=True)
        with contextlib.suppress(KeyboardInterrupt):
            time.sleep(seconds)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
