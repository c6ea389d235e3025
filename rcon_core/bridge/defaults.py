"""All-zero messages for answers the client must give without a handler's help -- the registry's defaults.

Used when an advertised service's handler fails: rosbridge 0.11 rejects a ``service_response`` whose
``values`` is not an object and the ROS caller then waits forever (``client_service.jsonl:7``), so the client answers
with the response type's default message instead (``services.py``).  There is one notion of a default
message, :meth:`rcon_core.msgs.TypeRegistry.default`: a type the client's registry does not know is learned
from the server's ``/rosapi/service_response_details`` typedefs (ROS 1 ``pkg/Type`` base names, or ROS 2 IDL
names such as ``boolean``/``double``/``octet``) into a throw-away registry of the typedefs' flavour.  What
the typedefs leave out becomes ``{}`` (a nested type they do not describe) or is skipped (an entry or field
that is not a name), so an odd answer still gives an object.
"""

from __future__ import annotations

import logging
from typing import Any

from rcon_core.msgs import MsgDef, TypeRegistry

from .cdrdecode import flavour_from_typedefs

log = logging.getLogger(__name__)

Default = tuple[dict[str, Any], set[str]]


def default_of(reg: Any, name: str) -> Default:
    """The registry's default message of ``name`` and the names of its scalar string fields."""
    strings = {f.name for f in reg.fields(name) if f.base in ("string", "wstring") and f.array_len is None}
    return reg.default(name), strings


def _clean(typedefs: list[Any]) -> list[dict[str, Any]]:
    """The usable part of typedefs from the server: entries that are objects, fields with string names."""
    out = []
    for td in typedefs:
        if not isinstance(td, dict) or not isinstance(td.get("type"), str):
            continue
        names = td.get("fieldnames") or []
        types = td.get("fieldtypes") or []
        lens = td.get("fieldarraylen") or [-1] * len(names)
        keep = [(n, t, a if isinstance(a, int) else -1) for n, t, a in zip(names, types, lens, strict=False)
                if isinstance(n, str) and isinstance(t, str)]
        out.append({"type": td["type"], "fieldnames": [k[0] for k in keep], "fieldtypes": [k[1] for k in keep],
                    "fieldarraylen": [k[2] for k in keep], "examples": [], "constnames": [], "constvalues": []})
    return out


def default_from_typedefs(typedefs: Any) -> Default:
    """The all-zero message of the first (root) typedef, and the names of its scalar string fields."""
    if not isinstance(typedefs, list) or not typedefs or not isinstance(typedefs[0], dict):
        return {}, set()
    clean = _clean(typedefs)
    if not clean:
        return {}, set()
    reg = TypeRegistry.empty(ros2=flavour_from_typedefs(clean) == 2)
    try:
        learned = reg.add_typedefs(clean)
        if not learned:
            return {}, set()
        for md in [reg.msgdef(n) for n in reg.names()]:  # nested types the typedefs do not describe: {}
            for f in md.fields:
                if not f.is_builtin and not reg.has(f.base):
                    reg.add(MsgDef(f.base, (), ()))
        return default_of(reg, learned[0])
    except (ValueError, KeyError) as exc:
        log.debug("typedefs of %r give no default message: %s", typedefs[0].get("type"), exc)
        return {}, set()
