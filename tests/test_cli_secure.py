"""The CLI over a secure link, end to end: ``rcon sim --tls-cert --tls-key --auth`` in its own process,
``rcon topics/call`` with ``--ca-file`` and the secret from ``$RCON_AUTH_SECRET`` or a file; without the
CA, with the wrong secret or an expired certificate they fail at once with one line saying why."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import time

import pytest

from rcon_core.cli.main import main
from rcon_core.sim import SimServer

pytest.importorskip("cryptography")
from tls_certs import make_pki  # noqa: E402

SECRET = "cli-robot-secret"


@pytest.fixture(scope="module")
def pki(tmp_path_factory):
    return make_pki(tmp_path_factory.mktemp("pki"))


@pytest.fixture(scope="module")
def secure_sim_url(pki):
    """``rcon sim`` serving wss:// with rosauth, on a free loopback port, in its own process."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "rcon_core.cli.main", "sim", "--port", "0", "--tls-cert", str(pki.server.cert),
         "--tls-key", str(pki.server.key), "--auth"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1", "RCON_AUTH_SECRET": SECRET})
    try:
        line = proc.stdout.readline()
        match = re.search(r"(wss://127\.0\.0\.1:\d+)", line)
        assert match, (line, proc.stderr.read() if proc.poll() is not None else "")
        yield match.group(1)
    finally:
        proc.terminate()
        proc.wait(10)


def run(capsys, *argv):
    start = time.monotonic()
    rc = main(list(argv))
    out, err = capsys.readouterr()
    return rc, out, err, time.monotonic() - start


def test_ca_file_and_secret_from_the_environment(secure_sim_url, pki, capsys, monkeypatch):
    monkeypatch.setenv("RCON_AUTH_SECRET", SECRET)
    rc, out, err, _ = run(capsys, "topics", "--url", secure_sim_url, "--ca-file", str(pki.ca))
    assert rc == 0, err
    assert any(line.split() == ["/cmd_vel", "geometry_msgs/Twist"] for line in out.splitlines())


def test_secret_from_a_file(secure_sim_url, pki, capsys, monkeypatch, tmp_path):
    monkeypatch.delenv("RCON_AUTH_SECRET", raising=False)
    secret_file = tmp_path / "secret"
    secret_file.write_text(SECRET + "\n")
    rc, out, err, _ = run(capsys, "call", "/rosapi/get_time", "--url", secure_sim_url, "--ca-file", str(pki.ca),
                          "--auth-secret-file", str(secret_file), "--json")
    assert rc == 0, err
    assert "time" in out


@pytest.mark.parametrize("case, sentence", [
    ("no CA", "certificate not trusted (self-signed? pass the CA file)"),
    ("wrong secret", "robot refused authentication"),
    ("no secret", "robot refused authentication"),
])
def test_fails_fast_in_one_line(secure_sim_url, pki, capsys, monkeypatch, case, sentence):
    monkeypatch.setenv("RCON_AUTH_SECRET", "wrong" if case == "wrong secret" else SECRET)
    argv = ["topics", "--url", secure_sim_url]
    if case != "no CA":
        argv += ["--ca-file", str(pki.ca)]
    if case == "no secret":
        monkeypatch.delenv("RCON_AUTH_SECRET")
        argv[0] = "call"
        argv.insert(1, "/rosapi/get_time")
    rc, out, err, took = run(capsys, *argv)
    assert rc == 1 and out == ""
    if case == "no secret":  # no auth op at all: the robot hangs up on the first frame
        sentence = "robot wants authentication (give the secret: RCON_AUTH_SECRET or --auth-secret-file)"
    assert err == f"rcon: cannot connect to {secure_sim_url}: {sentence}\n"
    assert took < 2.0, took


def test_expired_certificate(pki, capsys):
    with SimServer.in_thread(port=0, robot=False, ssl=pki.expired.server_context()) as server:
        rc, _, err, took = run(capsys, "topics", "--url", server.url, "--ca-file", str(pki.ca))
    assert rc == 1 and took < 2.0
    assert err == f"rcon: cannot connect to {server.url}: certificate expired (check its dates and the clocks)\n"


def test_unreadable_files_are_named(capsys, tmp_path):
    rc, _, err, _ = run(capsys, "topics", "--url", "wss://127.0.0.1:9", "--ca-file", str(tmp_path / "nope.pem"))
    assert rc == 1 and err == f"rcon: CA file {tmp_path / 'nope.pem'}: no such file\n"
    rc, _, err, _ = run(capsys, "topics", "--url", "ws://127.0.0.1:9", "--auth-secret-file", str(tmp_path / "s"))
    assert rc == 1 and err == f"rcon: auth secret file {tmp_path / 's'}: no such file\n"


def test_refused_port_says_so(capsys):
    rc, _, err, took = run(capsys, "topics", "--url", "ws://127.0.0.1:9")
    assert rc == 1 and err == "rcon: cannot connect to ws://127.0.0.1:9: connection refused\n" and took < 2.0


def test_sim_warns_loudly_when_open_to_the_network(capsys, monkeypatch):
    # 192.0.2.1 (TEST-NET-1) is never a local address: the warning is printed, then binding fails
    rc = main(["sim", "--host", "192.0.2.1", "--port", "0"])
    _, err = capsys.readouterr()
    assert rc == 1
    assert "WARNING: listening on 192.0.2.1 without --auth" in err
    monkeypatch.setenv("RCON_AUTH_SECRET", "x")
    rc = main(["sim", "--host", "192.0.2.1", "--port", "0", "--auth"])
    _, err = capsys.readouterr()
    assert rc == 1 and "WARNING" not in err


def test_sim_tls_options_go_together(capsys, pki):
    assert main(["sim", "--port", "0", "--tls-cert", str(pki.server.cert)]) == 2
    assert "--tls-cert and --tls-key go together" in capsys.readouterr().err


def test_client_certificate_for_a_robot_that_asks_for_one(pki, capsys):
    with SimServer.in_thread(port=0, robot=False, ssl=pki.server.server_context(client_ca=pki.ca)) as server:
        rc, out, err, _ = run(capsys, "services", "--url", server.url, "--ca-file", str(pki.ca),
                              "--client-cert", str(pki.client.cert), "--client-key", str(pki.client.key))
        assert rc == 0 and "/rosapi/get_time" in out, err
        rc, _, err, _ = run(capsys, "services", "--url", server.url, "--ca-file", str(pki.ca))
    assert rc == 1
    assert err == (f"rcon: cannot connect to {server.url}: connection closed during the handshake "
                   "(does the robot ask for a client certificate?)\n")
