"""wss:// with certificate verification, against a websockets TLS server with a self-signed certificate."""

from __future__ import annotations

import datetime
import ipaddress
import ssl

import pytest
from replay_server import ScriptedServer

from rcon_core.bridge import BridgeClient, ConnectionState

pytestmark = pytest.mark.usefixtures("transport")  # every test runs on each transport

cryptography = pytest.importorskip("cryptography")


@pytest.fixture(scope="module")
def cert_files(tmp_path_factory):
    from cryptography import x509
    from cryptography.hazmat.primitives import hashes, serialization
    from cryptography.hazmat.primitives.asymmetric import ec
    from cryptography.x509.oid import NameOID

    key = ec.generate_private_key(ec.SECP256R1())
    name = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, "rcon test robot")])
    now = datetime.datetime.now(datetime.UTC)
    cert = (x509.CertificateBuilder().subject_name(name).issuer_name(name).public_key(key.public_key())
            .serial_number(x509.random_serial_number())
            .not_valid_before(now - datetime.timedelta(minutes=5)).not_valid_after(now + datetime.timedelta(days=1))
            .add_extension(x509.SubjectAlternativeName([x509.IPAddress(ipaddress.ip_address("127.0.0.1"))]),
                           critical=False)
            .add_extension(x509.BasicConstraints(ca=True, path_length=None), critical=True)
            .sign(key, hashes.SHA256()))
    d = tmp_path_factory.mktemp("tls")
    (d / "cert.pem").write_bytes(cert.public_bytes(serialization.Encoding.PEM))
    (d / "key.pem").write_bytes(key.private_bytes(serialization.Encoding.PEM, serialization.PrivateFormat.PKCS8,
                                                  serialization.NoEncryption()))
    return d / "cert.pem", d / "key.pem"


@pytest.fixture
async def tls_server(cert_files):
    ctx = ssl.SSLContext(ssl.PROTOCOL_TLS_SERVER)
    ctx.load_cert_chain(*cert_files)
    async with ScriptedServer(replay=False, ssl=ctx) as srv:
        srv.services["/ping"] = lambda f: {"op": "service_response", "id": f["id"], "service": "/ping",
                                           "values": {"pong": True}, "result": True}
        yield srv


async def test_wss_with_trusted_ca_file(tls_server, cert_files):
    assert tls_server.url.startswith("wss://")
    c = BridgeClient(tls_server.url, ca_file=str(cert_files[0]), reconnect=False)
    await c.connect()
    assert c.state is ConnectionState.CONNECTED
    assert await c.call_service("/ping") == {"pong": True}
    await c.close()


async def test_wss_rejects_an_untrusted_certificate(tls_server):
    c = BridgeClient(tls_server.url, reconnect=False)
    with pytest.raises(ssl.SSLCertVerificationError):
        await c.connect()
    assert c.state is ConnectionState.CLOSED


async def test_certificate_errors_are_not_retried(tls_server):
    """With reconnect on, a certificate problem is fatal: connect() raises instead of retrying forever."""
    c = BridgeClient(tls_server.url, backoff_min=0.05)
    with pytest.raises(ssl.SSLCertVerificationError):
        await c.connect(timeout=5)
    assert c.state is ConnectionState.CLOSED
    assert isinstance(c.last_error, ssl.SSLCertVerificationError)
    await c.close()
