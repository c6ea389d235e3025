"""Why a connection attempt failed, in the operator's words.  No Qt: the app and the CLI both use it.

``describe(exc)`` turns the exception of one failed attempt into a :class:`Failure`: a short sentence
("connection refused", "no such host", "not a WebSocket server", "certificate not trusted (self-signed?
pass the CA file)", "robot refused authentication"...), whether retrying can help (``fatal``), and the
library's own text (``detail``, bounded) for logs and tooltips.  The client fills ``retry_at`` when it
will try again.

Decisions
    *Fatal* (the client stops retrying at once): a certificate the client does not trust, a host name
    the certificate does not name, an expired certificate, a server that is not TLS on a ``wss://`` URL,
    a client certificate the robot asks for or rejects, a URL the library cannot use, and a robot that
    refused authentication.  Trying again with the same settings gives the same answer.
    *Retried*: everything network-shaped (refused, no such host, unreachable, timed out, reset) and a
    server that answers but is not (yet) a WebSocket server -- a rosbridge behind a proxy answers 502 or
    404 while it starts.

Refused authentication
    rosbridge sends no answer to the ``auth`` op: a bad one makes the server close the connection.  So a
    close *frame* from the server (code 1000, 1005 "no code" or 1008 "policy violation") within
    :data:`AUTH_WINDOW` seconds of opening, on a link that sent ``auth``, is read as a refusal; the sim
    closes with code 4001, which is read as a refusal at any time.  A robot restarting drops the TCP
    connection without a close frame (1006) or says it is going away (1001), so it is not mistaken for a
    refusal.
"""

from __future__ import annotations

import errno
import socket
import ssl
import time
from dataclasses import dataclass, replace

from .errors import AuthRefusedError, BadUrlError, HandshakeError, LinkClosedError, LinkSettingsError

#: seconds after opening within which a close frame on an authenticating link counts as a refusal
AUTH_WINDOW = 3.0
#: the close code the sim (and RCON's own servers) use for "authentication required"
AUTH_CLOSE_CODE = 4001
DETAIL_LIMIT = 200
#: close codes a refusing rosbridge sends: 1005 (tornado's close() without a code), 1000, 1008 (policy);
#: not 1001 "going away" or 1012 "restart", which a robot shutting down sends
_REFUSAL_CODES = {1000, 1005, 1008}

NOT_TRUSTED = "certificate not trusted (self-signed? pass the CA file)"
WRONG_HOST = "wrong host name in certificate"
EXPIRED = "certificate expired"
AUTH_REFUSED = "robot refused authentication"
AUTH_NEEDED = "robot wants authentication (give the secret: RCON_AUTH_SECRET or --auth-secret-file)"
REFUSED = "connection refused"
NO_SUCH_HOST = "no such host"
NOT_WEBSOCKET = "not a WebSocket server"
CLOSED_IN_HANDSHAKE = "connection closed during the handshake"

# OpenSSL X509_V_ERR_* codes (ssl.SSLCertVerificationError.verify_code)
_NOT_YET_VALID, _EXPIRED = 9, 10
_UNTRUSTED = {2, 18, 19, 20, 21, 27}
_HOST_MISMATCH = {62, 64}  # HOSTNAME_MISMATCH, IP_ADDRESS_MISMATCH


@dataclass(frozen=True)
class Failure:
    """One failed connection attempt: ``reason`` in words, ``fatal`` when retrying cannot help,
    ``detail`` (the library's text), ``retry_at`` (``time.monotonic()`` of the next attempt, or None)."""

    reason: str
    fatal: bool
    detail: str = ""
    retry_at: float | None = None

    def retrying(self, delay: float) -> Failure:
        """This failure with the next attempt ``delay`` seconds from now."""
        return replace(self, retry_at=time.monotonic() + delay)

    def retry_in(self, now: float | None = None) -> float | None:
        """Seconds until the next attempt (0 when it is due), or None when there will be none."""
        if self.retry_at is None:
            return None
        return max(0.0, self.retry_at - (time.monotonic() if now is None else now))

    def text(self, now: float | None = None) -> str:
        """The reason and what happens next: ``connection refused · retrying in 3 s``."""
        wait = self.retry_in(now)
        if self.fatal or wait is None:
            return self.reason
        return f"{self.reason} · retrying in {wait:.0f} s" if wait >= 0.5 else f"{self.reason} · retrying now"


def _bounded(text: str) -> str:
    text = " ".join(str(text).split())
    return text if len(text) <= DETAIL_LIMIT else text[: DETAIL_LIMIT - 1] + "…"


def describe(exc: BaseException, *, ca_file: str | None = None, wss_without_cert: bool = False) -> Failure:
    """The :class:`Failure` for the exception one connection attempt raised.  ``wss_without_cert``: the
    attempt was TLS without a client certificate (a TLS 1.3 robot that wants one just hangs up after the
    handshake; the reason then says that it may want one)."""
    reason, fatal = _classify(exc, ca_file)
    if wss_without_cert and reason == CLOSED_IN_HANDSHAKE:
        reason += " (does the robot ask for a client certificate?)"
    detail = _bounded(f"{type(exc).__name__}: {exc}" if str(exc) else type(exc).__name__)
    return Failure(reason, fatal, detail)


def _classify(exc: BaseException, ca_file: str | None) -> tuple[str, bool]:
    if isinstance(exc, AuthRefusedError):
        return AUTH_REFUSED, True
    if isinstance(exc, LinkSettingsError):
        return _bounded(str(exc)), True
    if isinstance(exc, ssl.SSLCertVerificationError):
        return _certificate(exc, ca_file), True
    if isinstance(exc, ssl.SSLError):
        return _tls(exc)
    if isinstance(exc, HandshakeError) and isinstance(exc.__cause__, ssl.SSLError):
        return _classify(exc.__cause__, ca_file)
    if isinstance(exc, ConnectionRefusedError):
        return REFUSED, False
    if isinstance(exc, socket.gaierror):
        if exc.errno == socket.EAI_AGAIN:
            return "cannot look up the host name (no name server?)", False
        return NO_SUCH_HOST, False
    if isinstance(exc, TimeoutError):
        return "no answer (timed out)", False
    if isinstance(exc, ConnectionResetError):
        return "connection reset by the robot", False
    if isinstance(exc, OSError):
        if exc.errno == errno.EHOSTUNREACH:
            return "host unreachable", False
        if exc.errno == errno.ENETUNREACH:
            return "network unreachable", False
        return f"network error: {exc.strerror or exc}", False
    if isinstance(exc, BadUrlError):
        return "not a valid rosbridge URL", True
    if isinstance(exc, HandshakeError):
        if exc.status is not None:
            return f"{NOT_WEBSOCKET} (HTTP {exc.status})", False
        if exc.closed:
            return CLOSED_IN_HANDSHAKE, False
        return f"{NOT_WEBSOCKET} ({_bounded(str(exc))})", False
    if isinstance(exc, LinkClosedError):
        return "link lost", False
    return _bounded(f"{type(exc).__name__}: {exc}"), True


def _certificate(exc: ssl.SSLCertVerificationError, ca_file: str | None) -> str:
    code = getattr(exc, "verify_code", None)
    message = str(getattr(exc, "verify_message", "") or exc).lower()
    if code in _HOST_MISMATCH or "mismatch" in message:
        return WRONG_HOST
    if code == _EXPIRED or "expired" in message:
        return f"{EXPIRED} (check its dates and the clocks)"
    if code == _NOT_YET_VALID or "not yet valid" in message:
        return "certificate not yet valid (check the clocks)"
    if code in _UNTRUSTED or "self-signed" in message or "issuer" in message:
        return "certificate not trusted by the CA file" if ca_file else NOT_TRUSTED
    return f"certificate rejected ({_bounded(message)})"


def _tls(exc: ssl.SSLError) -> tuple[str, bool]:
    what = f"{getattr(exc, 'reason', '') or ''} {exc}".upper()
    if "WRONG_VERSION_NUMBER" in what or "HTTP_REQUEST" in what or "RECORD_LAYER" in what:
        return "not a TLS server (try ws:// instead of wss://)", True
    if "CERTIFICATE_REQUIRED" in what:
        return "the robot asks for a client certificate (pass the client certificate and key)", True
    if "BAD_CERTIFICATE" in what or "UNKNOWN_CA" in what or "CERTIFICATE_UNKNOWN" in what:
        return "the robot rejected the client certificate", True
    return f"TLS failed ({_bounded(str(exc))})", False


def refused_auth(close_code: int | None, close_reason: str | None, *, auth_sent: bool,
                 seconds_open: float) -> bool:
    """Whether a link that closed this way was a refused ``auth`` (see the module docstring)."""
    if not auth_sent or close_code is None or close_code == 1006:
        return False
    if close_code == AUTH_CLOSE_CODE or "auth" in (close_reason or "").lower():
        return True
    return close_code in _REFUSAL_CODES and seconds_open < AUTH_WINDOW
