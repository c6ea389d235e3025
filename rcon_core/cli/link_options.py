"""Connection options shared by the app (``rcon``) and the bridge subcommands: TLS files and where the
rosauth secret comes from (``RCON_AUTH_SECRET`` or ``--auth-secret-file``; never the command line).

``open_client(url, args)`` connects once (no retry loop) and proves the robot listens with one call
(``secure.confirm_auth``): a robot refusing the secret, or wanting one, hangs up instead of answering.
On failure it prints one line saying why, in the words of :mod:`rcon_core.bridge.reasons`, and returns
None so the command exits non-zero at once.
"""

from __future__ import annotations

import argparse
import asyncio
import logging
import sys
from typing import Any

from rcon_core.bridge.secure import AUTH_ENV

CONNECT_TIMEOUT = 5.0


def add_link_options(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group("secure link (wss:// and rosauth)")
    group.add_argument("--ca-file", metavar="PATH",
                       help="trust the robot's certificate when this CA file (PEM) signed it (wss://)")
    group.add_argument("--client-cert", metavar="PATH",
                       help="client certificate (PEM) for a robot that asks for one")
    group.add_argument("--client-key", metavar="PATH", help="the client certificate's private key (PEM)")
    group.add_argument("--protocol", choices=("rosbridge", "foxglove"), default=None,
                       help="the robot's protocol (default: detected -- a server that picks a Foxglove "
                            "WebSocket subprotocol speaks Foxglove, any other rosbridge)")
    group.add_argument("--auth-secret-file", metavar="PATH",
                       help=f"authenticate (rosauth) with the secret in this file; ${AUTH_ENV} also works. "
                            "The secret is never taken on the command line")


def link_settings(args: argparse.Namespace, url: str) -> dict[str, Any]:
    """``BridgeClient`` keyword arguments from the options; raises ``LinkSettingsError`` for a file that
    cannot be used (checked here, before any connection)."""
    from rcon_core.bridge.secure import read_secret, rosauth, ssl_context

    ca_file = getattr(args, "ca_file", None)
    cert, key = getattr(args, "client_cert", None), getattr(args, "client_key", None)
    if ca_file or cert or key:
        ssl_context(ca_file, cert, key)  # names an unreadable file before anything else happens
    secret = read_secret(getattr(args, "auth_secret_file", None))
    return {"ca_file": ca_file, "client_cert": cert, "client_key": key,
            "auth": rosauth(secret, url) if secret else None}


async def open_client(url: str, args: argparse.Namespace, *, call_timeout: float = 10.0,
                      quiet: bool = False) -> Any:
    """A connected robot link (``BridgeClient`` or ``FoxgloveClient``: ``--protocol``, else detected;
    authenticated when a secret is given and the protocol has rosauth), or None after one line on stderr
    saying why not (``quiet``: say nothing)."""
    from rcon_core.bridge import AuthRefusedError, LinkSettingsError
    from rcon_core.bridge.reasons import AUTH_NEEDED, describe
    from rcon_core.bridge.secure import confirm_auth
    from rcon_core.link import detect, make_client

    try:
        settings = link_settings(args, url)
        protocol = getattr(args, "protocol", None)
        client = None if protocol is None else make_client(url, protocol, reconnect=False,
                                                           call_timeout=call_timeout, **settings)
    except (LinkSettingsError, ValueError) as exc:
        _say(quiet, str(exc))
        return None
    if client is None:
        try:  # one handshake offering the Foxglove subprotocols (rcon_core/link/detect.py)
            protocol = await asyncio.wait_for(detect(url, ca_file=settings["ca_file"], client_cert=settings[
                "client_cert"], client_key=settings["client_key"]), CONNECT_TIMEOUT)
        except Exception as exc:  # the handshake failed: said as any connection failure
            why = describe(exc, ca_file=settings["ca_file"],
                           wss_without_cert=url.startswith("wss:") and not settings["client_cert"])
            _say(quiet, f"cannot connect to {url}: {why.reason}")
            return None
        client = make_client(url, str(protocol), reconnect=False, call_timeout=call_timeout, **settings)
    if client.protocol == "foxglove":
        return await _open_foxglove(client, url, settings, quiet)
    bridge_log = logging.getLogger("rcon_core.bridge.client")
    level = bridge_log.level
    bridge_log.setLevel(logging.ERROR)  # while connecting, the one line below says it all
    try:
        await asyncio.wait_for(client.connect(), CONNECT_TIMEOUT)
        # also without a secret: a robot that wants one hangs up on the probe, and we can say so
        await confirm_auth(client, timeout=CONNECT_TIMEOUT)
    except Exception as exc:
        await client.close()
        if isinstance(exc, AuthRefusedError) and settings["auth"] is None:
            _say(quiet, f"cannot connect to {url}: {AUTH_NEEDED}")
            return None
        failure = client.failure if client.failure is not None and exc is client.last_error else None
        why = (failure or describe(exc, ca_file=settings["ca_file"],
                                   wss_without_cert=url.startswith("wss:") and not settings["client_cert"]))
        _say(quiet, f"cannot connect to {url}: {why.reason}")
        return None
    finally:
        bridge_log.setLevel(level)
    return client


async def _open_foxglove(client: Any, url: str, settings: dict[str, Any], quiet: bool) -> Any:
    """Connect a Foxglove link (no rosauth on that protocol: a given secret is said unused)."""
    from rcon_core.bridge.reasons import describe
    from rcon_core.foxglove import CANNOT

    if settings["auth"] is not None:
        _say(quiet, f"note: {CANNOT['rosauth']}")
    try:
        await asyncio.wait_for(client.connect(), CONNECT_TIMEOUT)
    except Exception as exc:
        await client.close()
        why = client.failure or describe(exc, ca_file=settings["ca_file"])
        _say(quiet, f"cannot connect to {url}: {why.reason}")
        return None
    return client


def _say(quiet: bool, text: str) -> None:
    if not quiet:
        print(f"rcon: {text}", file=sys.stderr)
