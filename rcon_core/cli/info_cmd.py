"""``rcon info``: which ROS the robot runs (version, distro) and what its rosbridge showed it can do.

Takes ``--url`` (default ws://localhost:9090) and ``--json``.  Exit status 1 when the connection fails.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import sys
from typing import Any

DEFAULT_URL = "ws://localhost:9090"
CONNECT_TIMEOUT = 5.0


def configure(name: str, parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--url", dest="bridge_url", metavar="URL",
                        help=f"rosbridge WebSocket URL (default {DEFAULT_URL})")
    parser.add_argument("--json", action="store_true", help="machine-readable JSON output")
    parser.add_argument("--protocol", choices=("rosbridge", "foxglove"), default=None,
                        help="the robot's protocol (default: detected from the server)")


def run(name: str, args: argparse.Namespace) -> int:
    url = getattr(args, "bridge_url", None) or getattr(args, "url", None) or DEFAULT_URL
    try:
        return asyncio.run(_info(url, bool(args.json), getattr(args, "protocol", None)))
    except KeyboardInterrupt:
        return 0


async def gather(client: Any) -> dict[str, Any]:
    """What ``rcon info`` prints, as a dict (connected ``client``)."""
    from rcon_core.bridge import BridgeError

    info = await client.detect_ros(refresh=True)
    out: dict[str, Any] = {"url": client.url, "ros_version": info.version, "distro": info.distro,
                           "learned_from": info.source, "capabilities": info.capabilities}
    described = client.describe()
    out["protocol"] = described["protocol"]
    if described["protocol"] == "foxglove":  # which server, what it can do (serverInfo), what it cannot
        out.update(server=described["server"], subprotocol=described["subprotocol"],
                   capabilities=described["capabilities"], encodings=described["encodings"],
                   cannot=described["cannot"])
    for key, fetch in (("topics", client.catalog.topics), ("services", client.catalog.services)):
        try:
            out[key] = len(await fetch())
        except BridgeError:
            out[key] = None
    try:
        out["action_servers"] = await client.catalog.action_servers()
    except BridgeError:
        out["action_servers"] = None  # ROS 1 rosapi 0.11 has none
    return out


def _text(report: dict[str, Any]) -> str:
    version = report["ros_version"]
    ros = f"ROS {version}" if version else "unknown (no rosapi answered)"
    if report["distro"]:
        ros += f" ({report['distro']})"
    actions = report["action_servers"]
    lines = [f"url           {report['url']}"]
    if report.get("protocol") == "foxglove":
        lines += [f"protocol      Foxglove WebSocket ({report['subprotocol']}), server {report['server'] or '(unnamed)'}",
                  f"encodings     {', '.join(report['encodings']) or 'none said'}"]
    else:
        lines += ["protocol      rosbridge v2"]
    lines += [
             f"ros           {ros}   [from {report['learned_from']}]",
             f"topics        {report['topics'] if report['topics'] is not None else '?'}",
             f"services      {report['services'] if report['services'] is not None else '?'}",
             f"actions       {', '.join(actions) if actions else ('none' if actions is not None else '-')}",
             "capabilities  " + ("\n              ".join(report["capabilities"]) or "none seen")]
    lines += [f"cannot        {c}" for c in report.get("cannot", [])]
    return "\n".join(lines)


async def _info(url: str, as_json: bool, protocol: str | None = None) -> int:
    from rcon_core.link import detect, make_client

    try:
        if protocol is None:
            protocol = await asyncio.wait_for(detect(url), CONNECT_TIMEOUT)
        client = make_client(url, protocol, reconnect=False, call_timeout=5.0)
        await asyncio.wait_for(client.connect(), CONNECT_TIMEOUT)
    except Exception as exc:  # noqa: BLE001 - any failure to connect is reported the same way
        print(f"rcon: cannot connect to {url}: {exc or type(exc).__name__}", file=sys.stderr)
        return 1
    try:
        report = await gather(client)
    finally:
        await client.close()
    print(json.dumps(report, indent=2) if as_json else _text(report))
    return 0
