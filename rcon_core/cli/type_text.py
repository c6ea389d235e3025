"""Helpers of ``rcon type`` and ``rcon call``: types as text, and a request read against its type.

- :func:`typedefs_text`: rosapi typedefs as ``.msg`` text, each nested type after it (``gendeps`` style).
- :func:`expanded_text`: ``rcon type --recursive``: every nested field written out under its field,
  indented (``rosmsg show`` style), from the server's typedefs or the local registry's alike.
- :func:`typed_request`: ``rcon call``'s request text read like ``rcon pub`` reads a message: YAML whose
  keys stay text (``{on: true}`` is the field ``on``), checked against the service's request type, which
  comes from the registry (standard types, installed plugins') or, failing that, from the robot.
"""

from __future__ import annotations

from typing import Any

PSEUDO = ("time", "duration")  # rosapi lists these builtins as types of their own


def typedefs_text(typedefs: list[dict[str, Any]]) -> str:
    """rosapi typedefs as ``.msg``-style text: the type first, then each nested type (like gendeps)."""
    blocks = []
    typedefs = [td for td in typedefs if td.get("type") not in PSEUDO]
    for i, td in enumerate(typedefs):
        lines = [] if i == 0 else ["=" * 80, f"MSG: {td.get('type')}"]
        for cname, cvalue in zip(td.get("constnames", []), td.get("constvalues", []), strict=False):
            lines.append(f"{cname}={cvalue}")
        for fname, ftype, alen in _fields(td):
            lines.append(f"{ftype}{_suffix(alen)} {fname}")
        blocks.append("\n".join(lines))
    return "\n".join(blocks)


def _fields(td: dict[str, Any]) -> list[tuple[str, str, Any]]:
    return list(zip(td.get("fieldnames", []), td.get("fieldtypes", []), td.get("fieldarraylen", []), strict=False))


def _suffix(alen: Any) -> str:
    return "" if alen is None or alen < 0 else ("[]" if alen == 0 else f"[{alen}]")


def expanded_text(typedefs: list[dict[str, Any]]) -> str:
    """The first type of ``typedefs`` with each nested type's fields written out below its field, two
    spaces deeper per level (``rosmsg show``); constants first at each level."""
    by_name: dict[str, dict[str, Any]] = {}
    for td in typedefs:
        name = str(td.get("type", ""))
        by_name.setdefault(name, td)
        if "/msg/" in name:  # ROS 2 servers name nested types either way
            by_name.setdefault(name.replace("/msg/", "/"), td)
    if not typedefs:
        return ""
    lines: list[str] = []

    def write(td: dict[str, Any], indent: str, seen: tuple[str, ...]) -> None:
        for cname, cvalue in zip(td.get("constnames", []), td.get("constvalues", []), strict=False):
            lines.append(f"{indent}{cname}={cvalue}")
        for fname, ftype, alen in _fields(td):
            lines.append(f"{indent}{ftype}{_suffix(alen)} {fname}")
            nested = by_name.get(ftype)
            if nested is not None and ftype not in PSEUDO and ftype not in seen:
                write(nested, indent + "  ", (*seen, ftype))

    write(typedefs[0], "", (str(typedefs[0].get("type", "")),))
    return "\n".join(lines)


def service_expanded_text(typedefs: dict[str, list[dict[str, Any]]]) -> str:
    return expanded_text(typedefs.get("request", [])) + "\n---\n" + expanded_text(typedefs.get("response", []))


def local_typedefs(reg: Any, name: str) -> Any:
    """The local registry's typedefs of ``name``: a list for a message, {"request", "response"} for a
    service."""
    if reg.has_service(name):
        return {part: reg.service_typedefs(name, part) for part in ("request", "response")}
    return reg.typedefs(name)


async def typed_request(client: Any, service: str, text: str, reg: Any, timeout: float) -> dict[str, Any]:
    """``text`` read as a request of ``service``'s type: a complete request (missing fields take their
    defaults). Raises ``MessageTextError`` (a ValueError) naming the field that does not fit. When the
    robot does not say the service's type, or nobody knows it, the YAML is sent as read (keys as text)."""
    import asyncio

    from rcon_core.bridge import BridgeError
    from rcon_core.msgs import names
    from rcon_core.msgs.text import parse_text

    try:
        type_name = await asyncio.wait_for(client.rosapi.service_type(service), timeout)
    except (BridgeError, TimeoutError):
        type_name = None
    if not type_name:
        return _mapping(parse_text(text))
    if not reg.has_service(type_name):
        try:
            details = await asyncio.wait_for(client.rosapi.service_request_details(names.pkg_type(type_name)),
                                             timeout)
        except (BridgeError, TimeoutError, ValueError):
            details = []
        if not details:
            return _mapping(parse_text(text))
        pkg, _kind, short = names.split(type_name)
        reg.add_typedefs(details, root=f"{pkg}/srv/{short}_Request")
        return dict(reg.from_text(f"{pkg}/srv/{short}_Request", text))
    return dict(reg.from_text(reg.service_part_name(type_name, "request"), text))


def _mapping(value: Any) -> Any:
    from rcon_core.msgs.text import MessageTextError

    if value is not None and not isinstance(value, dict | list):
        raise MessageTextError("", "ARGS must be a mapping like '{data: true}' or a list")
    return value
