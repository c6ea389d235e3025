"""Why a connection failed, in words (``rcon_core.bridge.reasons``), from real failed attempts: a closed
port, an unknown host, an HTTP server, and the sim behind TLS and rosauth with certificates made here."""

from __future__ import annotations

import asyncio
import ssl
import time

import pytest

from rcon_core.bridge import AuthRefusedError, BridgeClient, ConnectionState, LinkSettingsError, reasons
from rcon_core.bridge.errors import HandshakeError
from rcon_core.bridge.secure import confirm_auth, read_secret, rosauth
from rcon_core.sim import SimServer
from rcon_core.testing import until

pytest.importorskip("cryptography")
from tls_certs import make_pki  # noqa: E402

pytestmark = pytest.mark.usefixtures("transport")  # every test runs on each transport

SECRET = "robot-secret-1"


@pytest.fixture(scope="module")
def pki(tmp_path_factory):
    return make_pki(tmp_path_factory.mktemp("pki"))


@pytest.fixture
async def secure_sim(pki):
    server = SimServer(port=0, rate_scale=2.0, auth_secret=SECRET, ssl=pki.server.server_context(), robot=False)
    await server.start()
    yield server
    await server.stop()


async def _first_failure(url: str, **options) -> tuple[reasons.Failure, BridgeClient, float]:
    """Connect with retries on; the first failure reported to a listener, and how long it took."""
    client = BridgeClient(url, backoff_min=0.05, **options)
    seen: list[reasons.Failure] = []
    client.add_failure_listener(seen.append)
    start = time.monotonic()
    task = asyncio.ensure_future(client.connect())
    await until(lambda: seen, what="the first failure")
    took = time.monotonic() - start
    task.cancel()
    await client.close()
    return seen[0], client, took


async def _http_server() -> asyncio.Server:
    async def answer(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        await reader.read(1000)
        writer.write(b"HTTP/1.1 404 Not Found\r\nContent-Length: 0\r\n\r\n")
        await writer.drain()
        writer.close()

    return await asyncio.start_server(answer, "127.0.0.1", 0)


async def test_refused_port_is_said_at_once_and_retried():
    failure, client, took = await _first_failure("ws://127.0.0.1:1")
    assert failure.reason == reasons.REFUSED and not failure.fatal
    assert failure.retry_at is not None and failure.text().startswith("connection refused · retrying")
    assert took < 2.0, took
    assert client.failure is not None and client.failure.reason == reasons.REFUSED


async def test_unknown_host_and_http_server():
    failure, _, _ = await _first_failure("ws://no-such-robot.invalid:9090")
    assert failure.reason == reasons.NO_SUCH_HOST and not failure.fatal
    server = await _http_server()
    try:
        port = server.sockets[0].getsockname()[1]
        failure, _, _ = await _first_failure(f"ws://127.0.0.1:{port}")
        assert failure.reason == "not a WebSocket server (HTTP 404)" and not failure.fatal
        failure, _, _ = await _first_failure(f"wss://127.0.0.1:{port}")
        assert failure.reason.startswith("not a TLS server") and failure.fatal
    finally:
        server.close()


async def test_retry_times_follow_the_backoff():
    client = BridgeClient("ws://127.0.0.1:1", backoff_min=0.05, backoff_max=0.2)
    seen: list[reasons.Failure] = []
    client.add_failure_listener(seen.append)
    task = asyncio.ensure_future(client.connect())
    await until(lambda: len(seen) >= 4, what="four failures")
    task.cancel()
    await client.close()
    times = [f.retry_at for f in seen]
    assert all(t is not None for t in times) and times == sorted(times)


async def test_secure_sim_accepts_the_ca_file_and_the_secret(secure_sim, pki):
    assert secure_sim.url.startswith("wss://")
    client = BridgeClient(secure_sim.url, ca_file=str(pki.ca), auth=rosauth(SECRET, secure_sim.url),
                          reconnect=False)
    await client.connect()
    await confirm_auth(client)
    assert client.state is ConnectionState.CONNECTED
    assert "time" in await client.call_service("/rosapi/get_time")
    await client.close()


@pytest.mark.parametrize("case, sentence", [
    ("no CA", "certificate not trusted (self-signed? pass the CA file)"),
    ("wrong host", "wrong host name in certificate"),
    ("expired", "certificate expired (check its dates and the clocks)"),
])
async def test_certificate_problems_are_fatal_and_named(pki, case, sentence):
    pair = {"no CA": pki.server, "wrong host": pki.wrong_host, "expired": pki.expired}[case]
    server = SimServer(port=0, robot=False, ssl=pair.server_context())
    await server.start()
    try:
        client = BridgeClient(server.url, ca_file=None if case == "no CA" else str(pki.ca), backoff_min=0.05)
        start = time.monotonic()
        with pytest.raises(ssl.SSLCertVerificationError) as info:
            await client.connect(timeout=10)
        assert time.monotonic() - start < 2.0
        assert client.state is ConnectionState.CLOSED
        assert client.failure is not None and client.failure.fatal and client.failure.retry_at is None
        assert client.failure.reason == sentence, info.value
        await client.close()
    finally:
        await server.stop()


async def test_wrong_secret_is_refused_fast_without_retrying(secure_sim, pki):
    client = BridgeClient(secure_sim.url, ca_file=str(pki.ca), auth=rosauth("not-the-secret", secure_sim.url),
                          backoff_min=0.05)
    closed = asyncio.Event()
    client.add_state_listener(lambda state: state is ConnectionState.CLOSED and closed.set())
    start = time.monotonic()
    await client.connect(timeout=10)  # rosbridge never answers auth: the link opens, then the robot closes it
    await asyncio.wait_for(closed.wait(), 5)
    assert time.monotonic() - start < 2.0
    assert client.failure is not None and client.failure.reason == reasons.AUTH_REFUSED and client.failure.fatal
    assert isinstance(client.last_error, AuthRefusedError)
    assert client.stats["connects"] == 1  # refused once, never retried
    assert client.state is ConnectionState.CLOSED
    await client.close()


async def test_confirm_auth_sees_a_refusal_without_reconnect(secure_sim, pki):
    """The CLI's path: ``reconnect=False`` connects, then the probe call tells a refusal from an answer."""
    client = BridgeClient(secure_sim.url, ca_file=str(pki.ca), auth=rosauth("wrong", secure_sim.url),
                          reconnect=False)
    await client.connect()
    with pytest.raises(AuthRefusedError):
        await confirm_auth(client)
    await client.close()


async def test_client_certificate_when_the_robot_asks_for_one(pki):
    server = SimServer(port=0, robot=False, ssl=pki.server.server_context(client_ca=pki.ca))
    await server.start()
    try:
        client = BridgeClient(server.url, ca_file=str(pki.ca), client_cert=str(pki.client.cert),
                              client_key=str(pki.client.key), reconnect=False)
        await client.connect()
        assert "time" in await client.call_service("/rosapi/get_time")
        await client.close()
        without = BridgeClient(server.url, ca_file=str(pki.ca), reconnect=False)
        with pytest.raises(HandshakeError):
            await without.connect()
            await without.call_service("/rosapi/get_time", timeout=2)
        assert without.failure is not None and "client certificate" in without.failure.reason
    finally:
        await server.stop()


async def test_unreadable_settings_are_named():
    client = BridgeClient("wss://127.0.0.1:1", ca_file="/nonexistent/ca.pem", reconnect=False)
    with pytest.raises(LinkSettingsError, match="CA file /nonexistent/ca.pem: no such file"):
        await client.connect()
    assert client.failure is not None and client.failure.fatal
    assert client.failure.reason == "CA file /nonexistent/ca.pem: no such file"


def test_secret_from_a_file_or_the_environment(tmp_path):
    f = tmp_path / "secret"
    f.write_text("s3cret\n")
    assert read_secret(f, environ={"RCON_AUTH_SECRET": "other"}) == "s3cret"
    assert read_secret(None, environ={"RCON_AUTH_SECRET": "other"}) == "other"
    assert read_secret(None, environ={}) is None
    (tmp_path / "empty").write_text("\n")
    with pytest.raises(LinkSettingsError, match="is empty"):
        read_secret(tmp_path / "empty")
    with pytest.raises(LinkSettingsError, match="no such file"):
        read_secret(tmp_path / "missing")


def test_refusal_needs_a_close_frame_on_an_authenticating_link():
    assert reasons.refused_auth(4001, "authentication required", auth_sent=True, seconds_open=60)
    assert reasons.refused_auth(1005, "", auth_sent=True, seconds_open=0.2)  # rosbridge: close(), no code
    assert not reasons.refused_auth(1005, "", auth_sent=True, seconds_open=30)
    assert not reasons.refused_auth(1006, "", auth_sent=True, seconds_open=0.2)  # robot gone: no close frame
    assert not reasons.refused_auth(1001, "", auth_sent=True, seconds_open=0.2)  # robot shutting down
    assert not reasons.refused_auth(4001, "authentication required", auth_sent=False, seconds_open=0.2)
