"""attrs classes generated at run time for message types, and the (private) cattrs converter for them.

``reg.typed("geometry_msgs/Twist")`` gives a class with one attribute per field, every one defaulted,
constants as class attributes and ``__msgtype__`` holding the canonical name. Time fields are a small
``Time``/``Duration`` class with the flavour's field names (``secs, nsecs`` or ``sec, nanosec``),
``uint8[]``/``char[]`` are ``bytes``,
a field whose name is a Python keyword is the attribute ``name_``, every other array a ``list``. ``structure`` reads wire-shape
dicts (base64 text, bytes or int lists for binary fields; ``None`` for NaN; either time shape);
``unstructure`` writes them back (binary as base64 text, NaN as a float NaN, which JSON encoders such
as orjson send as ``null``).
"""

from __future__ import annotations

import keyword
import math
from typing import TYPE_CHECKING, Any

import attrs
import cattrs

from . import names
from .fielddefs import TIME_TYPES, FieldDef, is_binary, primitive
from .time import read as read_time
from .values import as_bytes, to_base64

if TYPE_CHECKING:
    from .lookup import TypeLookup

__all__ = ["TypedFactory"]

_PY = {"bool": bool, "int": int, "float": float, "string": str}


def _make_time_class(kind: str, ros2: bool) -> type:
    a, b = ("sec", "nanosec") if ros2 else ("secs", "nsecs")
    cls = attrs.make_class(
        "Time" if kind == "time" else "Duration",
        {a: attrs.field(default=0, type=int), b: attrs.field(default=0, type=int)},
        slots=True,
    )

    def to_float(self: Any) -> float:
        return getattr(self, a) + getattr(self, b) / 1e9

    cls.to_float = to_float  # type: ignore[attr-defined]
    cls.__msgtype__ = kind  # type: ignore[attr-defined]
    return cls


class TypedFactory:
    """Builds and caches the classes of one registry, and owns its converter."""

    def __init__(self, reg: TypeLookup) -> None:
        self.reg = reg
        self._classes: dict[str, type] = {}
        self._time = {k: _make_time_class(k, reg.ros2) for k in TIME_TYPES}
        self.converter = cattrs.Converter()
        c = self.converter
        c.register_structure_hook(float, lambda v, _: math.nan if v is None else float(v))
        c.register_structure_hook(bytes, lambda v, _: as_bytes(v))
        c.register_unstructure_hook(bytes, to_base64)
        for k, tcls in self._time.items():
            c.register_structure_hook(tcls, self._time_structure(tcls))
            del k

    def _time_structure(self, tcls: type) -> Any:
        def structure(value: Any, _: Any) -> Any:
            if isinstance(value, tcls):
                return value
            s, ns = read_time(value if value is not None else 0)
            return tcls(s, ns)

        return structure

    # ------------------------------------------------------------------ classes
    def _annotation(self, f: FieldDef) -> Any:
        if is_binary(f.base, f.array_len):
            return bytes
        elem: Any
        if f.base in TIME_TYPES:
            elem = self._time[f.base]
        else:
            p = primitive(f.base, self.reg.ros2)
            elem = _PY[p.kind] if p is not None else self.cls(f.base)
        return elem if f.array_len is None else list[elem]

    def _default(self, f: FieldDef) -> Any:
        if is_binary(f.base, f.array_len):
            n = f.array_len or 0
            return attrs.Factory(lambda: bytes(n))
        if f.base in TIME_TYPES:
            tcls = self._time[f.base]
            if f.array_len is None:
                return attrs.Factory(tcls)
            n = f.array_len
            return attrs.Factory(lambda: [tcls() for _ in range(n)])
        p = primitive(f.base, self.reg.ros2)
        if p is not None:
            zero = {"bool": False, "int": 0, "float": 0.0, "string": ""}[p.kind]
            if f.array_len is None:
                return zero
            n = f.array_len
            return attrs.Factory(lambda: [zero] * n)
        sub = self.cls(f.base)
        if f.array_len is None:
            return attrs.Factory(sub)
        n = f.array_len
        return attrs.Factory(lambda: [sub() for _ in range(n)])

    def cls(self, name: str) -> type:
        """The class for the canonical message ``name``."""
        hit = self._classes.get(name)
        if hit is not None:
            return hit
        md = self.reg.msgdef(name)
        self._classes[name] = None  # type: ignore[assignment]  # cycle guard
        try:
            body = {}
            renamed = {}
            for f in md.fields:
                attr = f.name + "_" if keyword.iskeyword(f.name) else f.name
                if attr != f.name:
                    renamed[attr] = f.name
                body[attr] = attrs.field(default=self._default(f), type=self._annotation(f))
            short = names.short(name)
            cls = attrs.make_class(short, body, slots=True, eq=True, repr=True)
        except BaseException:
            del self._classes[name]
            raise
        cls.__qualname__ = short
        cls.__msgtype__ = name  # type: ignore[attr-defined]
        field_names = {f.name for f in md.fields}
        for const in md.constants:
            if const.name not in field_names:
                setattr(cls, const.name, const.value)
        if renamed:  # Python keywords as field names: attribute "from_" travels as "from"
            from cattrs.gen import make_dict_structure_fn, make_dict_unstructure_fn, override

            conv = self.converter
            over: dict[str, Any] = {a: override(rename=n) for a, n in renamed.items()}
            conv.register_structure_hook(cls, make_dict_structure_fn(cls, conv, **over))
            conv.register_unstructure_hook(cls, make_dict_unstructure_fn(cls, conv, **over))
        self._classes[name] = cls
        return cls

    # ------------------------------------------------------------------ conversion
    def structure(self, msg: Any, name: str) -> Any:
        cls = self.cls(name)
        if msg is None:
            return cls()
        if not isinstance(msg, dict):
            raise ValueError(f"expected a dict for {self.reg.wire_name(name)}, got {type(msg).__name__}")
        try:
            return self.converter.structure(msg, cls)
        except cattrs.BaseValidationError as exc:
            problems = "; ".join(cattrs.transform_error(exc)) if hasattr(cattrs, "transform_error") else str(exc)
            raise ValueError(f"cannot read a {self.reg.wire_name(name)}: {problems}") from None

    def unstructure(self, obj: Any) -> dict[str, Any]:
        if not attrs.has(type(obj)) or not hasattr(type(obj), "__msgtype__"):
            raise TypeError(f"not a typed message: {obj!r}")
        return self.converter.unstructure(obj)
