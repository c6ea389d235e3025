"""Foxglove's own flatbuffer schemas (``foxglove.CompressedImage``, ``foxglove.LocationFix``...) read into dicts.

Decision: Foxglove's generated classes, read by their own accessors
    Foxglove publishes the Python generated from its flatbuffer schemas as ``foxglove-schemas-flatbuffer``
    (one module per type, the ``flatc`` output, on the ``flatbuffers`` runtime); RCON reads a channel whose
    schema is one of them with that class.  The ``flatbuffers`` package has no reflection reader for a
    ``.bfbs`` schema, so a flatbuffer schema that is not one of Foxglove's own stays refused in words at
    subscribe time (``codecs.CodecError``; the flight recorder still records its bytes).  A server whose
    schema is a newer version of the same type still reads: flatbuffers tables are read by slot, so fields the
    package does not know are skipped.

Decision: the dict has the protobuf path's shape
    Fields by the schema's names in snake_case (``frameId`` -> ``frame_id``, as the ``.proto`` names them),
    found from the generated ``<Type>Add<Field>`` functions (tables) or ``Create<Type>`` arguments
    (structs: ``Time``, ``Duration``); ``foxglove.Time`` as ``{"sec", "nsec"}``; a ``uint8`` vector as
    ``bytes``, other number vectors as lists; strings as ``str``; nested tables as dicts.  So the matcher and
    the widgets read a flatbuffer ``foxglove.CompressedImage`` exactly as the protobuf one.

Decision: hostile bytes
    Nothing here trusts the buffer: a vector longer than the buffer or nesting deeper than :data:`MAX_DEPTH`
    raises ``ValueError`` (the session counts the frame as bad and goes on), as does any out-of-range read.
"""

from __future__ import annotations

import importlib
import inspect
import re
from collections.abc import Callable
from typing import Any

__all__ = ["decoder", "available"]

PACKAGE = "foxglove_schemas_flatbuffer"
MAX_DEPTH = 32
_CAMEL = re.compile(r"(?<!^)(?=[A-Z])")
_READERS: dict[type, list[tuple[str, Callable[[Any, int, int], Any]]]] = {}


def available() -> bool:
    try:
        importlib.import_module(PACKAGE)
    except ImportError:
        return False
    return True


def _class_of(schema_name: str) -> Any:
    """The generated class of a Foxglove schema name, or None."""
    if not schema_name.startswith("foxglove.") or "." in schema_name[9:]:
        return None
    short = schema_name[9:]
    if not short.isidentifier():
        return None
    try:
        module = importlib.import_module(f"{PACKAGE}.{short}")
    except ImportError:
        return None
    cls = getattr(module, short, None)
    return cls if hasattr(cls, "GetRootAs") else None


def decoder(schema_name: str) -> Callable[[Any], dict[str, Any]] | None:
    """``decode(payload) -> dict`` for a Foxglove flatbuffer type, or None when RCON cannot read it."""
    cls = _class_of(schema_name)
    if cls is None:
        return None

    def decode(data: Any) -> dict[str, Any]:
        buf = bytes(data)
        try:
            return _table(cls.GetRootAs(buf, 0), len(buf), 0)
        except Exception as exc:  # noqa: BLE001 - out of range, struct.error, bad UTF-8...: one bad frame
            raise ValueError(f"not a {schema_name} flatbuffer ({type(exc).__name__}: {exc})") from None

    return decode


def _snake(name: str) -> str:
    return _CAMEL.sub("_", name).lower()


def _fields(cls: type) -> list[str]:
    """The accessor names of a generated table or struct, in the schema's order."""
    module = inspect.getmodule(cls)
    prefix = f"{cls.__name__}Add"
    names = [n[len(prefix):] for n in vars(module) if n.startswith(prefix)]
    if not names:  # a struct: Create<Type>(builder, field, ...)
        create = getattr(module, f"Create{cls.__name__}", None)
        if create is not None:
            names = [p[:1].upper() + p[1:] for p in list(inspect.signature(create).parameters)[1:]]
    return [n for n in names if hasattr(cls, n)]


def _readers(cls: type) -> list[tuple[str, Callable[[Any, int, int], Any]]]:
    found = _READERS.get(cls)
    if found is None:
        found = _READERS[cls] = [(_snake(n), _reader(cls, n)) for n in _fields(cls)]
    return found


def _reader(cls: type, name: str) -> Callable[[Any, int, int], Any]:
    if hasattr(cls, name + "Length"):
        if hasattr(cls, name + "AsNumpy"):
            def numbers(obj: Any, size: int, depth: int) -> Any:
                if getattr(obj, name + "IsNone")():
                    return []
                arr = getattr(obj, name + "AsNumpy")()
                if getattr(arr, "dtype", None) is None:
                    return []
                return arr.tobytes() if arr.dtype.itemsize == 1 and arr.dtype.kind == "u" else arr.tolist()
            return numbers

        def items(obj: Any, size: int, depth: int) -> Any:
            n = getattr(obj, name + "Length")()
            if n > size:
                raise ValueError(f"a vector of {n} in a buffer of {size} bytes")
            get = getattr(obj, name)
            return [_value(get(j), size, depth) for j in range(n)]
        return items

    def scalar(obj: Any, size: int, depth: int) -> Any:
        return _value(getattr(obj, name)(), size, depth)
    return scalar


def _value(v: Any, size: int, depth: int) -> Any:
    if v is None or isinstance(v, bool | int | float):
        return v
    if isinstance(v, bytes):
        return v.decode("utf-8")
    return _table(v, size, depth + 1)


def _table(obj: Any, size: int, depth: int) -> dict[str, Any]:
    if depth > MAX_DEPTH:
        raise ValueError(f"nested deeper than {MAX_DEPTH}")
    return {field: read(obj, size, depth) for field, read in _readers(type(obj))}
