"""Type names: the canonical spelling ``pkg/msg/Type`` and the ROS 1 / ROS 2 spellings.

Canonical names are what rosbags uses:

* messages ``pkg/msg/Type``; services ``pkg/srv/Type``; actions ``pkg/action/Type``;
* the two halves of a service ``pkg/srv/Type_Request`` and ``pkg/srv/Type_Response``;
* the parts of an action ``pkg/action/Type_Goal``, ``..._Result`` and ``..._Feedback``.

ROS 1 servers spell all of these ``pkg/Type`` (``pkg/TypeRequest``, ``pkg/TypeGoal`` for the parts).
A bare ROS 1 name is ambiguous (``pkg/FooRequest`` may be a message or half of ``pkg/Foo``), so
:func:`normalize` reads it as a message and :func:`candidates` lists every canonical name it may stand
for, which is how :class:`~rcon_core.msgs.registry.TypeRegistry` resolves it.
"""

from __future__ import annotations

import re

__all__ = [
    "KINDS",
    "SERVICE_PARTS",
    "ACTION_PARTS",
    "normalize",
    "to_ros1",
    "to_ros2",
    "split",
    "candidates",
    "service_part",
    "action_part",
    "part_name",
    "package",
    "short",
    "pkg_type",
]

KINDS = ("msg", "srv", "action")
SERVICE_PARTS = ("Request", "Response")
ACTION_PARTS = ("Goal", "Result", "Feedback")

_IDENT = re.compile(r"[A-Za-z][A-Za-z0-9_]*\Z")
_SUFFIX = {"srv": SERVICE_PARTS, "action": ACTION_PARTS}


def _check(name: str, piece: str, what: str) -> None:
    if not _IDENT.match(piece):
        raise ValueError(
            f"not a ROS type name: {name!r} ({what} {piece!r} must start with a letter and hold only "
            "letters, digits and '_'; expected 'pkg/Type' or 'pkg/msg/Type')"
        )


def split(name: str) -> tuple[str, str, str]:
    """``(package, kind, type)`` of any accepted spelling; kind is ``msg`` for the two-part form."""
    if not isinstance(name, str):
        raise ValueError(f"not a ROS type name: {name!r} (expected a string like 'pkg/Type')")
    text = name.strip().strip("/")
    parts = text.split("/")
    if len(parts) == 1 and parts[0] == "Header":
        return "std_msgs", "msg", "Header"
    if len(parts) == 2:
        pkg, kind, typ = parts[0], "msg", parts[1]
    elif len(parts) == 3:
        pkg, kind, typ = parts
        if kind not in KINDS:
            raise ValueError(
                f"not a ROS type name: {name!r} (the middle part must be one of msg, srv, action; got {kind!r})"
            )
    else:
        raise ValueError(f"not a ROS type name: {name!r} (expected 'pkg/Type' or 'pkg/msg/Type')")
    _check(name, pkg, "package")
    _check(name, typ, "type")
    return pkg, kind, typ


def normalize(name: str) -> str:
    """The canonical spelling of ``name``.

    ``pkg/Type`` becomes ``pkg/msg/Type``. Under ``srv`` and ``action`` the ROS 1 part suffixes are
    rewritten: ``pkg/srv/SetBoolRequest`` becomes ``pkg/srv/SetBool_Request``. Raises ``ValueError`` for
    anything that is not a type name.
    """
    pkg, kind, typ = split(name)
    if kind in _SUFFIX:
        for suffix in _SUFFIX[kind]:
            if typ.endswith(suffix) and not typ.endswith("_" + suffix) and len(typ) > len(suffix):
                typ = typ[: -len(suffix)] + "_" + suffix
                break
    return f"{pkg}/{kind}/{typ}"


def to_ros2(name: str) -> str:
    """The ROS 2 spelling, which is the canonical one."""
    return normalize(name)


def to_ros1(name: str) -> str:
    """The ROS 1 spelling ``pkg/Type``; service and action parts lose their underscore (``pkg/TypeRequest``)."""
    pkg, kind, typ = split(normalize(name))
    if kind in _SUFFIX:
        for suffix in _SUFFIX[kind]:
            if typ.endswith("_" + suffix):
                typ = typ[: -len(suffix) - 1] + suffix
                break
    return f"{pkg}/{typ}"


def package(name: str) -> str:
    """The package of a type name."""
    return split(name)[0]


def short(name: str) -> str:
    """The bare type name (``Twist`` for ``geometry_msgs/msg/Twist``)."""
    return split(name)[2]


def pkg_type(name: str) -> str:
    """``pkg/msg/Type`` (or ``pkg/srv/...``, ``pkg/action/...``) -> ``pkg/Type``; other text is returned
    without its outer slashes.  Never raises: a lookup key under which both spellings of a name from a
    server, a file or a person meet (unlike :func:`to_ros1`, it does not check the name nor rewrite the
    ``_Request``/``_Goal`` part suffixes)."""
    text = name.strip("/")
    parts = text.split("/")
    return f"{parts[0]}/{parts[2]}" if len(parts) == 3 else text


def service_part(name: str) -> tuple[str, str] | None:
    """``("pkg/srv/Type", "request"|"response")`` when ``name`` names half of a service, else ``None``.

    Only the explicit forms count: ``pkg/srv/Type_Request`` and ``pkg/srv/TypeRequest``.
    """
    pkg, kind, typ = split(normalize(name))
    if kind != "srv":
        return None
    for suffix in SERVICE_PARTS:
        if typ.endswith("_" + suffix):
            return f"{pkg}/srv/{typ[: -len(suffix) - 1]}", suffix.lower()
    return None


def action_part(name: str) -> tuple[str, str] | None:
    """``("pkg/action/Type", "goal"|"result"|"feedback")`` for an action part name, else ``None``."""
    pkg, kind, typ = split(normalize(name))
    if kind != "action":
        return None
    for suffix in ACTION_PARTS:
        if typ.endswith("_" + suffix):
            return f"{pkg}/action/{typ[: -len(suffix) - 1]}", suffix.lower()
    return None


def part_name(parent: str, part: str) -> str:
    """Canonical name of one part of a service or action: ``part_name("std_srvs/SetBool", "request")``."""
    pkg, kind, typ = split(parent)
    part = part.lower()
    if kind == "msg":
        # a ROS 1 spelling: decide by the part asked for
        kind = "srv" if part in ("request", "response") else "action"
    suffixes = _SUFFIX.get(kind, ())
    for suffix in suffixes:
        if suffix.lower() == part:
            return f"{pkg}/{kind}/{typ}_{suffix}"
    raise ValueError(f"{parent!r} has no part {part!r} (expected one of {', '.join(s.lower() for s in suffixes)})")


def candidates(name: str) -> list[str]:
    """Every canonical name that ``name`` may stand for, most likely first.

    ``pkg/Foo`` -> ``pkg/msg/Foo``, ``pkg/srv/Foo``, ``pkg/action/Foo``;
    ``pkg/FooRequest`` -> ``pkg/msg/FooRequest``, ``pkg/srv/Foo_Request``;
    ``pkg/FooGoal`` -> ``pkg/msg/FooGoal``, ``pkg/action/Foo_Goal``.
    Names that already carry a kind give just their canonical form.
    """
    text = name.strip().strip("/") if isinstance(name, str) else name
    pkg, kind, typ = split(name)
    if isinstance(text, str) and text.count("/") == 2:
        return [normalize(name)]
    out = [f"{pkg}/msg/{typ}", f"{pkg}/srv/{typ}", f"{pkg}/action/{typ}"]
    for kind2, suffixes in _SUFFIX.items():
        for suffix in suffixes:
            if typ.endswith(suffix) and len(typ) > len(suffix):
                stem = typ[: -len(suffix)].rstrip("_")
                if stem:
                    out.insert(1, f"{pkg}/{kind2}/{stem}_{suffix}")
    return out
