"""The benchmarks' background load (``benchmarks/background_load.py``, ``bench_app.py --background-load N``):
bounded in count and time, and never left running -- not after an exception, not after SIGTERM, not after
the benchmark is killed outright."""

from __future__ import annotations

import asyncio
import importlib.util
import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from rcon_core.testing import until

BENCH = Path(__file__).resolve().parents[1] / "benchmarks"
linux = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the parent-death signal is Linux's")


def load():
    spec = importlib.util.spec_from_file_location("background_load", BENCH / "background_load.py")
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def alive(pid: int) -> bool:
    """True while ``pid`` runs (a zombie -- ended, not yet reaped -- counts as ended)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except FileNotFoundError:
        return False
    except OSError:
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return False
        return True


def wait_ended(pids: list[int], what: str) -> None:
    asyncio.run(until(lambda: not any(alive(p) for p in pids), timeout=15, what=what))


def test_the_load_runs_for_the_block_and_ends_with_it_even_on_an_exception():
    bg = load()
    with pytest.raises(RuntimeError), bg.busy_processes(2, max_seconds=60) as pids:
        assert len(pids) == 2 and all(alive(p) for p in pids)
        raise RuntimeError("the benchmark failed")
    assert not any(alive(p) for p in pids)


def test_the_count_is_bounded():
    bg = load()
    for n in (-1, bg.MAX_PROCESSES + 1):
        with pytest.raises(ValueError, match="background load"), bg.busy_processes(n):
            pass


def test_a_busy_process_ends_on_its_own_after_its_time():
    bg = load()
    with bg.busy_processes(1, max_seconds=0.3) as pids:
        wait_ended(pids, "the busy process ended after its 0.3 s")


def run_holder(tmp_path: Path) -> tuple[subprocess.Popen, list[int]]:
    """A process holding a background load of 2 (as a benchmark does); returns it and the load's pids."""
    script = tmp_path / "holder.py"
    script.write_text(textwrap.dedent(f"""
        import sys, time
        sys.path.insert(0, {str(BENCH)!r})
        from background_load import busy_processes
        with busy_processes(2, max_seconds=60) as pids:
            print(*pids, flush=True)
            time.sleep(60)
    """))
    proc = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE, text=True)
    assert proc.stdout is not None
    pids = [int(p) for p in proc.stdout.readline().split()]
    assert len(pids) == 2 and all(alive(p) for p in pids)
    return proc, pids


@linux
def test_sigterm_to_the_benchmark_ends_the_load(tmp_path):
    proc, pids = run_holder(tmp_path)
    proc.send_signal(signal.SIGTERM)
    assert proc.wait(15) == 128 + signal.SIGTERM
    wait_ended(pids, "the load ended with the benchmark's SIGTERM")


@linux
def test_killing_the_benchmark_outright_ends_the_load(tmp_path):
    proc, pids = run_holder(tmp_path)
    proc.kill()
    proc.wait(15)
    wait_ended(pids, "the load ended when its parent was killed (parent-death signal)")
