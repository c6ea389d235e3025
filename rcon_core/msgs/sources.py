"""Where definitions come from: rosbags' type stores plus the definition files bundled in ``defs/``.

Both are read once per process (per ROS flavour) and shared read-only by every registry.
"""

from __future__ import annotations

import functools
from importlib import resources
from types import MappingProxyType
from typing import Any

from .actions import actionlib_wrappers
from .fielddefs import Constant, FieldDef, MsgDef
from .parse import TIME_NAMES, parse_interface

__all__ = ["standard_defs", "from_rosbags_fielddefs", "bundled_texts"]

_TIME_MSGS = {"builtin_interfaces/msg/Time", "builtin_interfaces/msg/Duration"}


def _node_to_field(fname: str, node: Any) -> FieldDef:
    from rosbags.interfaces import Nodetype

    kind, detail = node
    array_len: int | None = None
    bound = 0
    if kind in (Nodetype.ARRAY, Nodetype.SEQUENCE):
        (kind, detail), n = detail
        array_len = n if node[0] == Nodetype.ARRAY else 0
        if node[0] == Nodetype.SEQUENCE:
            bound = n
    if kind == Nodetype.BASE:
        base, sbound = detail
        bound = bound or sbound
    else:
        base = TIME_NAMES.get(detail, detail)
    return FieldDef.make(fname, base, array_len, bound)


#: the member rosbags (like the ROS 2 IDL) gives an empty message such as std_msgs/Empty
_IDL_PLACEHOLDER = "structure_needs_at_least_one_member"


def from_rosbags_fielddefs(name: str, entry: Any) -> MsgDef:
    """Convert one rosbags ``fielddefs`` entry ``(consts, fields)`` into a :class:`MsgDef`."""
    consts, fields = entry
    if [f[0] for f in fields] == [_IDL_PLACEHOLDER]:
        fields = []  # rosbags' stand-in for an empty message; no ROS wire carries it
    return MsgDef(
        name,
        tuple(_node_to_field(fname, node) for fname, node in fields),
        tuple(Constant(cname, ctype, value) for cname, ctype, value in consts),
    )


def bundled_texts() -> dict[str, str]:
    """``{canonical name: definition text}`` of every file under ``defs/<pkg>/{msg,srv,action}/``."""
    out: dict[str, str] = {}
    root = resources.files("rcon_core.msgs").joinpath("defs")
    for pkg in sorted(root.iterdir(), key=lambda p: p.name):
        if not pkg.is_dir():
            continue
        for kind in ("msg", "srv", "action"):
            folder = pkg.joinpath(kind)
            if not folder.is_dir():
                continue
            for f in sorted(folder.iterdir(), key=lambda p: p.name):
                stem, dot, ext = f.name.rpartition(".")
                if dot and ext == kind:
                    out[f"{pkg.name}/{kind}/{stem}"] = f.read_text(encoding="utf-8")
    return out


def _store_name(ros2: bool) -> Any:
    from rosbags.typesys import Stores

    return Stores.ROS2_HUMBLE if ros2 else Stores.ROS1_NOETIC


@functools.cache
def standard_defs(ros2: bool) -> MappingProxyType[str, MsgDef]:
    """All standard message definitions for one flavour (read-only, built once)."""
    from rosbags.typesys import get_typestore

    store = get_typestore(_store_name(ros2))
    defs: dict[str, MsgDef] = {}
    for name, entry in store.fielddefs.items():
        if name in _TIME_MSGS and not ros2:
            continue  # on ROS 1 these are the built-in time/duration, not messages
        defs[name] = from_rosbags_fielddefs(name, entry)
    for name, text in bundled_texts().items():
        for md in parse_interface(name, text):
            defs.setdefault(md.name, md)
        if "/action/" in name and not ros2:
            for md in actionlib_wrappers(name):
                defs.setdefault(md.name, md)
    return MappingProxyType(defs)


@functools.cache
def standard_interfaces(ros2: bool) -> frozenset[str]:
    """Canonical names of the services and actions bundled (their parts are in :func:`standard_defs`)."""
    return frozenset(n for n in bundled_texts() if "/msg/" not in n)
