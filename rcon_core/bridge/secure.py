"""A link's security settings: the TLS context, the rosauth ``auth`` op made from a secret, and where a
secret may come from.  No Qt: the app and the CLI both use it.

Decisions
    The secret never comes from the command line (other users see it in the process list): it comes from
    the ``RCON_AUTH_SECRET`` environment variable or a file (``--auth-secret-file``; its first line, so a
    trailing newline does not count), or, in the app, from the OS credential store.
    A fresh ``auth`` op is made for every (re)connect: rosauth rejects a ``t`` more than a few seconds
    away from the robot's clock, so a stored op would go stale.  Its ``client`` and ``dest`` are
    ``rcon`` and the URL's host (rosauth only hashes them), ``level`` is ``admin``, and it stays valid for
    :data:`AUTH_LIFETIME` seconds.
    rosbridge never answers ``auth``; :func:`confirm_auth` proves the robot accepted it by calling a
    service and getting *any* answer (rosbridge answers even an unknown service), while a refused link
    is closed by the robot first.
"""

from __future__ import annotations

import hashlib
import os
import secrets
import ssl
import time
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any
from urllib.parse import urlparse

from .errors import (
    AuthRefusedError,
    ConnectionLostError,
    LinkSettingsError,
    NotConnectedError,
    ServiceError,
    ServiceTimeoutError,
)

AUTH_ENV = "RCON_AUTH_SECRET"
#: seconds an ``auth`` op stays valid (its ``end``)
AUTH_LIFETIME = 3600
#: the service :func:`confirm_auth` calls (any answer will do)
PROBE_SERVICE = "/rosapi/get_time"


def ssl_context(ca_file: str | None = None, client_cert: str | None = None,
                client_key: str | None = None) -> ssl.SSLContext:
    """A verifying client TLS context: the system's CAs, or only ``ca_file``'s; with ``client_cert``
    (and ``client_key`` unless the key is in the certificate file) presented when the robot asks."""
    if client_key and not client_cert:
        raise LinkSettingsError("a client key needs its client certificate")
    try:
        ctx = ssl.create_default_context(cafile=ca_file) if ca_file else ssl.create_default_context()
    except (OSError, ssl.SSLError) as exc:
        raise LinkSettingsError(f"CA file {ca_file}: {_why(exc)}") from None
    if client_cert:
        try:
            ctx.load_cert_chain(client_cert, client_key or None)
        except (OSError, ssl.SSLError) as exc:
            raise LinkSettingsError(f"client certificate {client_cert}: {_why(exc)}") from None
    return ctx


def _why(exc: BaseException) -> str:
    if isinstance(exc, FileNotFoundError):
        return "no such file"
    if isinstance(exc, PermissionError):
        return "not allowed to read it"
    if isinstance(exc, ssl.SSLError):
        return "not a PEM certificate (or key) file"
    return getattr(exc, "strerror", None) or str(exc)


def auth_mac(secret: str, client: str, dest: str, rand: str, t: int, level: str, end: int) -> str:
    """rosauth's MAC: hex SHA-512 of ``secret + client + dest + rand + t + level + end``."""
    return hashlib.sha512(f"{secret}{client}{dest}{rand}{t}{level}{end}".encode()).hexdigest()


def rosauth(secret: str, url: str, *, level: str = "admin",
            lifetime: int = AUTH_LIFETIME) -> Callable[[], dict[str, Any]]:
    """The ``auth`` argument for :class:`~rcon_core.bridge.BridgeClient`: a function making a fresh
    rosauth op (the seven fields) signed with ``secret`` each time it is called."""
    if not isinstance(secret, str) or not secret:
        raise LinkSettingsError("the auth secret is empty")
    dest = urlparse(url).hostname or ""

    def make() -> dict[str, Any]:
        t = int(time.time())
        rand = secrets.token_hex(8)
        end = t + lifetime
        return {"mac": auth_mac(secret, "rcon", dest, rand, t, level, end), "client": "rcon", "dest": dest,
                "rand": rand, "t": t, "level": level, "end": end}

    return make


def read_secret(file: str | os.PathLike[str] | None = None,
                environ: Mapping[str, str] | None = None) -> str | None:
    """The rosauth secret from ``file`` (its first line) or else ``$RCON_AUTH_SECRET``; None when neither
    is given.  An unreadable or empty file raises :class:`LinkSettingsError`."""
    if file:
        try:
            text = Path(file).read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as exc:
            raise LinkSettingsError(f"auth secret file {file}: {_why(exc)}") from None
        secret = text.splitlines()[0].strip() if text.strip() else ""
        if not secret:
            raise LinkSettingsError(f"auth secret file {file} is empty")
        return secret
    value = (os.environ if environ is None else environ).get(AUTH_ENV, "")
    return value or None


async def confirm_auth(client: Any, timeout: float = 5.0) -> None:
    """Return once the robot answered a call after ``auth``; raise :class:`AuthRefusedError` when it closed
    the link instead.  A robot that answers nothing within ``timeout`` is given the benefit of the doubt."""
    try:
        await client.call_service(PROBE_SERVICE, timeout=timeout)
    except (ConnectionLostError, NotConnectedError):
        raise AuthRefusedError("robot refused authentication") from None
    except ServiceTimeoutError:
        if not client.connected:
            raise AuthRefusedError("robot refused authentication") from None
    except ServiceError:
        pass  # an answer, even "no such service", means the robot accepted the auth op
