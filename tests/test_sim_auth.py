"""The sim's rosauth (issue 22, items 11 and 16): ``rcon sim --auth`` reads the secret as the client does
(``RCON_AUTH_SECRET`` or ``--auth-secret-file``), never from the command line; a non-ASCII MAC is a wrong
one (4001), not an internal error (1011); an address that keeps failing is locked out for a while."""

from __future__ import annotations

import asyncio
import json
import os
import re
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest
import websockets

from rcon_core.cli.main import main
from rcon_core.sim import SimServer
from rcon_core.sim.auth import MAX_FAILURES, AuthLockout, make_mac

SECRET = "lab-secret"


def auth_op(secret: str = SECRET, **override: Any) -> str:
    now = int(time.time())
    fields = {"client": "10.0.0.5", "dest": "10.0.0.2", "rand": "r", "t": now, "level": "admin", "end": now + 60}
    fields.update(override)
    mac = make_mac(secret, fields["client"], fields["dest"], fields["rand"], fields["t"], fields["level"],
                   fields["end"])
    return json.dumps({"op": "auth", "mac": override.get("mac", mac), **fields})


async def attempt(server: SimServer, frame: str) -> tuple[int | None, str]:
    """Send ``frame`` first, then a call: ``(None, "")`` when the call is answered, else the close code and
    reason."""
    async with websockets.connect(server.url) as ws:
        try:
            await ws.send(frame)  # a locked-out address may be closed before this is written
            await ws.send(json.dumps({"op": "call_service", "service": "/rosapi/get_time", "id": "probe"}))
            reply = json.loads(await asyncio.wait_for(ws.recv(), 10))
            assert reply["id"] == "probe"
            return None, ""
        except websockets.ConnectionClosed as exc:
            assert exc.rcvd is not None
            return exc.rcvd.code, exc.rcvd.reason


@pytest.fixture
async def guarded():
    server = SimServer(robot=False, auth_secret=SECRET)
    await server.start()
    yield server
    await server.stop()


# ------------------------------------------------------------------------------------------------ item 16


async def test_a_non_ascii_mac_is_a_wrong_mac_4001_not_1011(guarded: SimServer, caplog) -> None:
    """The probe: a MAC with non-ASCII characters closed the connection with 1011 and a traceback."""
    code, reason = await attempt(guarded, auth_op(mac="é" * 128))
    assert code == 4001 and "mac does not match" in reason
    assert not [r for r in caplog.records if r.exc_info]


async def test_five_failures_lock_the_address_out_then_it_may_try_again(guarded: SimServer) -> None:
    """The probe guessed 226 secrets a second from one process; now the fifth failure within a minute locks
    the address out for a minute, even for the right secret, and a success clears the count."""
    now = [1000.0]
    guarded.auth_lockout = AuthLockout(clock=lambda: now[0])
    assert await attempt(guarded, auth_op()) == (None, "")
    for _ in range(MAX_FAILURES - 1):
        assert (await attempt(guarded, auth_op("guess")))[0] == 4001
    assert await attempt(guarded, auth_op()) == (None, "")  # four failures, then the right one: fine
    for _ in range(MAX_FAILURES):
        code, reason = await attempt(guarded, auth_op("guess"))
        assert code == 4001 and "mac does not match" in reason
    code, reason = await attempt(guarded, auth_op())
    assert code == 4001 and "too many failed authentication attempts" in reason and "60 s" in reason
    now[0] += 61
    assert await attempt(guarded, auth_op()) == (None, "")
    assert guarded.auth_lockout.lockouts == 1


def test_the_lockout_counts_failures_within_the_window_only() -> None:
    now = [0.0]
    lock = AuthLockout(max_failures=3, window_s=10.0, lockout_s=5.0, clock=lambda: now[0])
    for _ in range(2):
        lock.failed("a")
    now[0] = 11.0
    lock.failed("a")  # the first two are older than the window
    assert lock.locked("a") == 0.0
    lock.failed("a")
    lock.failed("a")
    assert lock.locked("a") == pytest.approx(5.0) and lock.locked("b") == 0.0
    now[0] = 16.5
    assert lock.locked("a") == 0.0


# ------------------------------------------------------------------------------------------------ item 11


def test_rcon_sim_refuses_a_secret_on_the_command_line(capsys) -> None:
    """``rcon sim --auth SECRET`` put the secret where ``ps`` shows it to every user."""
    assert main(["sim", "--port", "0", "--auth", "s3cret"]) == 2
    err = capsys.readouterr().err
    assert "process list" in err and "RCON_AUTH_SECRET" in err and "--auth-secret-file" in err


def test_rcon_sim_auth_without_a_secret_says_where_to_put_it(capsys, monkeypatch) -> None:
    monkeypatch.delenv("RCON_AUTH_SECRET", raising=False)
    assert main(["sim", "--port", "0", "--auth"]) == 2
    assert "RCON_AUTH_SECRET" in capsys.readouterr().err
    assert main(["sim", "--port", "0", "--auth-secret-file", "/nonexistent/secret"]) == 2
    assert "no such file" in capsys.readouterr().err


@pytest.mark.parametrize("source", ["env", "file"])
async def test_rcon_sim_reads_the_secret_as_the_client_does(source: str, tmp_path: Path) -> None:
    env = {k: v for k, v in os.environ.items() if k != "RCON_AUTH_SECRET"}
    args = [sys.executable, "-m", "rcon_core.cli.main", "sim", "--port", "0", "--no-plugin-types"]
    if source == "env":
        env["RCON_AUTH_SECRET"] = SECRET
        args.append("--auth")
    else:
        path = tmp_path / "lab.secret"
        path.write_text(SECRET + "\n")
        args += ["--auth-secret-file", str(path)]
    proc = subprocess.Popen(args, stdout=subprocess.PIPE, text=True, env=env)
    try:
        line = await asyncio.wait_for(asyncio.to_thread(proc.stdout.readline), 60)
        url = re.search(r"ws://\S+", line).group(0)
        assert SECRET not in Path(f"/proc/{proc.pid}/cmdline").read_bytes().decode()
        async with websockets.connect(url) as ws:
            await ws.send(auth_op())
            await ws.send(json.dumps({"op": "call_service", "service": "/rosapi/get_time", "id": "ok"}))
            assert json.loads(await asyncio.wait_for(ws.recv(), 10))["result"] is True
        async with websockets.connect(url) as ws:
            await ws.send(auth_op("not the secret"))
            with pytest.raises(websockets.ConnectionClosed) as info:
                await asyncio.wait_for(ws.recv(), 10)
            assert info.value.rcvd is not None and info.value.rcvd.code == 4001
    finally:
        proc.terminate()
        proc.wait(timeout=30)
