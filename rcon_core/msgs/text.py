"""Messages typed by a person (YAML or JSON) -> complete wire-shape dicts, with precise errors.

``from_text`` parses, ``complete`` checks and fills a dict, ``validate`` lists every problem. Problems
carry a ``path`` in the message (``linear.x``, ``covariance[3]``, ``header.stamp.secs``) and a
``problem`` in words ("expected a number, got 'abc'").

Accepted spellings: numbers for floats (ints too; ``null``, ``nan``, ``inf`` for NaN/inf only where
non-finite numbers are allowed, see below), integral
numbers for ints (range-checked for the type), ``true``/``false`` (or 0/1) for bool, base64 text, bytes or
a list of 0..255 for ``uint8[]``/``char[]``, time as ``{secs, nsecs}`` or ``{sec, nanosec}`` or a number
of seconds. A message with a single field also accepts that field's value alone (``5`` for
``std_msgs/Float64``). Missing fields take their default; unknown fields are an error.

Non-finite floats. Text typed by a person (:func:`from_text`) refuses NaN and infinity unless the caller
passes ``finite=False``: ``nan`` is almost always a slip, and on the JSON wire it travels as ``null``,
which a robot reads as something else or refuses. A widget allows them only where its operator said so
(the Text Field's "Allow NaN and infinity"). :func:`complete` and :func:`validate` check dicts made by
code and keep accepting them unless told ``finite=True``.
"""

from __future__ import annotations

import base64
import binascii
import math
from typing import TYPE_CHECKING, Any

import attrs

from .fielddefs import TIME_TYPES, FieldDef, is_binary, primitive

if TYPE_CHECKING:
    from .lookup import TypeLookup

__all__ = ["MessageTextError", "Problem", "from_text", "to_text", "complete", "validate"]


@attrs.frozen
class Problem:
    """One problem in a message: where (``path``) and what (``problem``)."""

    path: str
    problem: str

    def __str__(self) -> str:
        return f"{self.path}: {self.problem}" if self.path else self.problem


class MessageTextError(ValueError):
    """A message typed by a person that cannot be used. ``.path`` and ``.problem`` say where and what;
    ``.problems`` holds every problem found (the first one is ``.path``/``.problem``)."""

    def __init__(self, path: str, problem: str, problems: list[Problem] | None = None) -> None:
        self.path = path
        self.problem = problem
        self.problems = problems or [Problem(path, problem)]
        super().__init__(str(Problem(path, problem)))


def _show(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def _join(path: str, name: str) -> str:
    return f"{path}.{name}" if path else name


#: what a refused non-finite number is told
NONFINITE = "is not a finite number (NaN and infinity are refused here: JSON would send them as null)"


class _Walker:
    def __init__(self, reg: TypeLookup, finite: bool = False) -> None:
        self.reg = reg
        self.finite = finite  #: refuse NaN and infinity in float fields
        self.problems: list[Problem] = []

    def bad(self, path: str, problem: str) -> None:
        self.problems.append(Problem(path, problem))

    # -- messages
    def message(self, name: str, value: Any, path: str) -> dict[str, Any]:
        md = self.reg.msgdef(name)
        if value is None:
            value = {}
        if not isinstance(value, dict):
            if len(md.fields) == 1 and path == "":
                value = {md.fields[0].name: value}
            else:
                self.bad(path, f"expected a mapping of the fields of {self.reg.wire_name(md.name)}, got {_show(value)}")
                return self.reg.default(name)
        known = {f.name: f for f in md.fields}
        for key in value:
            if key not in known:
                listing = ", ".join(known) if known else "none"
                self.bad(_join(path, str(key)), f"unknown field {str(key)!r} (known: {listing})")
        out: dict[str, Any] = {}
        for f in md.fields:
            sub = _join(path, f.name)
            out[f.name] = self.field(f, value[f.name], sub) if f.name in value else self.reg.default_value(f)
        return out

    def field(self, f: FieldDef, value: Any, path: str) -> Any:
        if f.array_len is None:
            return self.scalar(f.base, value, path)
        if is_binary(f.base, f.array_len):
            return self.binary(f, value, path)
        if isinstance(value, tuple) or type(value).__name__ == "ndarray":
            value = list(value)
        if not isinstance(value, list):
            self.bad(path, f"expected a list, got {_show(value)}")
            return self.reg.default_value(f)
        if f.array_len and len(value) != f.array_len:
            self.bad(path, f"expected {f.array_len} items, got {len(value)}")
            return self.reg.default_value(f)
        if f.bound and len(value) > f.bound:
            self.bad(path, f"at most {f.bound} items allowed, got {len(value)}")
        return [self.scalar(f.base, v, f"{path}[{i}]") for i, v in enumerate(value)]

    def binary(self, f: FieldDef, value: Any, path: str) -> str:
        data: bytes | None = None
        if isinstance(value, str):
            try:
                data = base64.b64decode(value, validate=True)
            except (binascii.Error, ValueError):
                self.bad(path, f"expected base64 text, bytes or a list of 0..255, got {_show(value)}")
                return self.reg.default_value(f)
        elif isinstance(value, bytes | bytearray | memoryview):
            data = bytes(value)
        elif isinstance(value, list | tuple):
            ok = True
            for i, v in enumerate(value):
                if isinstance(v, bool) or not isinstance(v, int) or not 0 <= v <= 255:
                    self.bad(f"{path}[{i}]", f"expected a byte 0..255, got {_show(v)}")
                    ok = False
            if not ok:
                return self.reg.default_value(f)
            data = bytes(value)
        else:
            self.bad(path, f"expected base64 text, bytes or a list of 0..255, got {_show(value)}")
            return self.reg.default_value(f)
        if f.array_len and len(data) != f.array_len:
            self.bad(path, f"expected {f.array_len} items, got {len(data)}")
            return self.reg.default_value(f)
        return base64.b64encode(data).decode("ascii")

    def scalar(self, base: str, value: Any, path: str) -> Any:
        if base in TIME_TYPES:
            return self.time(base, value, path)
        p = primitive(base, self.reg.ros2)
        if p is None:
            return self.message(base, value, path)
        if p.kind == "float":
            return self.float_(p, value, path)
        if p.kind == "int":
            return self.int_(p, value, path)
        if p.kind == "bool":
            if isinstance(value, bool):
                return value
            if isinstance(value, int) and value in (0, 1):
                return bool(value)
            self.bad(path, f"expected true or false, got {_show(value)}")
            return False
        if isinstance(value, str):
            return value
        self.bad(path, f"expected a string, got {_show(value)} (put quotes around it)")
        return ""

    def float_(self, p: Any, value: Any, path: str) -> float:
        if value is None:
            if self.finite:
                self.bad(path, f"null {NONFINITE}")
                return 0.0
            return math.nan
        if isinstance(value, bool) or not isinstance(value, int | float):
            if isinstance(value, str) and value.strip().lower() in ("nan", "inf", "+inf", "-inf", "infinity", "-infinity"):
                if self.finite:
                    self.bad(path, f"{value.strip()} {NONFINITE}")
                    return 0.0
                return float(value.strip())
            try:
                number = float(value) if not isinstance(value, str | bool) else None
            except (TypeError, ValueError):
                number = None
            if number is None:
                self.bad(path, f"expected a number, got {_show(value)}")
                return 0.0
            value = number
        out = float(value)
        if self.finite and not math.isfinite(out):
            self.bad(path, f"{value} {NONFINITE}")
            return 0.0
        if p.hi is not None and math.isfinite(out) and abs(out) > p.hi:
            self.bad(path, f"value {value} out of range for {p.name}")
            return 0.0
        return out

    def int_(self, p: Any, value: Any, path: str) -> int:
        if isinstance(value, bool) or not isinstance(value, int | float):
            if hasattr(value, "__index__") and not isinstance(value, bool):
                value = int(value)
            else:
                self.bad(path, f"expected an integer, got {_show(value)}")
                return 0
        if isinstance(value, float):
            if not value.is_integer():
                self.bad(path, f"expected an integer, got {value}")
                return 0
            value = int(value)
        if not p.lo <= value <= p.hi:
            self.bad(path, f"value {value} out of range for {p.name} ({p.lo}..{p.hi})")
            return 0
        return value

    def time(self, base: str, value: Any, path: str) -> dict[str, int]:
        a, b = self.reg.time_fields
        if isinstance(value, int | float) and not isinstance(value, bool):
            if not math.isfinite(value):
                self.bad(path, f"expected a time, got {value}")
                return {a: 0, b: 0}
            whole = math.floor(value)
            return {a: int(whole), b: int(round((value - whole) * 1e9)) % 1_000_000_000}
        if not isinstance(value, dict):
            self.bad(path, f"expected a time ({{{a}: ..., {b}: ...}} or seconds), got {_show(value)}")
            return {a: 0, b: 0}
        aliases = {"secs": a, "sec": a, "nsecs": b, "nanosec": b}
        out = {a: 0, b: 0}
        for key, v in value.items():
            if key not in aliases:
                self.bad(_join(path, str(key)), f"unknown field {str(key)!r} (known: {a}, {b})")
                continue
            target = aliases[key]
            lo, hi = (-(1 << 31), (1 << 32) - 1)
            if isinstance(v, bool) or not isinstance(v, int | float) or (isinstance(v, float) and not v.is_integer()):
                self.bad(_join(path, str(key)), f"expected an integer, got {_show(v)}")
                continue
            if not lo <= v <= hi:
                self.bad(_join(path, str(key)), f"value {v} out of range for {base}")
                continue
            out[target] = int(v)
        return out


def complete(reg: TypeLookup, name: str, msg: Any, *, finite: bool = False) -> dict[str, Any]:
    """Check ``msg`` against ``name`` and fill every missing field; raises :class:`MessageTextError`.
    ``finite``: refuse NaN and infinity in float fields."""
    w = _Walker(reg, finite)
    out = w.message(reg.resolve(name), msg, "")
    if w.problems:
        first = w.problems[0]
        raise MessageTextError(first.path, first.problem, w.problems)
    return out


def validate(reg: TypeLookup, name: str, msg: Any, *, finite: bool = False) -> list[Problem]:
    """Every problem in ``msg`` as a message of type ``name``; an empty list when it is fine."""
    w = _Walker(reg, finite)
    w.message(reg.resolve(name), msg, "")
    return w.problems


_YAML: dict[str, Any] = {}
_EXP_FLOAT = r"^[-+]?[0-9]+(?:\.[0-9]*)?[eE][-+]?[0-9]+$"


class _Overflow(ValueError):
    """A number typed by a person that is too large to be one (``1.0e+400`` would become infinity)."""

    def __init__(self, text: str) -> None:
        super().__init__(f"{text} is too large for a number (it would become infinity)")


#: the spellings of infinity a person means as such (YAML's ``.inf``, JSON's ``Infinity``)
_INF_WORDS = frozenset({".inf", "+.inf", "-.inf", "inf", "+inf", "-inf", "infinity", "+infinity", "-infinity"})


def _float_or_overflow(text: str) -> float:
    """``float(text)``, refusing a number that only overflowed to infinity (``1.0e+400``)."""
    value = float(text)
    if math.isinf(value) and text.strip().lower() not in _INF_WORDS:
        raise _Overflow(text.strip())
    return value


def _yaml_classes() -> tuple[Any, Any]:
    """Safe YAML loader/dumper that also read ``1e-5`` and ``1E9`` as floats (YAML 1.1 wants a dot);
    the dumper quotes strings that look like that, so dumped text reads back the same. The loader refuses
    a number that overflows to infinity (``1.0e+400``); ``.inf`` stays infinity."""
    if not _YAML:
        import re

        import yaml

        class Loader(yaml.SafeLoader):
            def construct_mapping(self, node: Any, deep: bool = False) -> dict[Any, Any]:
                # a key is a field name: YAML 1.1 would read `on`, `off`, `yes`, `no`, `null` or `1` as a
                # bool, None or int ({on: true} became {True: True}); a plain key stays the text written
                for key_node, _ in node.value:
                    if isinstance(key_node, yaml.ScalarNode) and key_node.style is None and \
                            key_node.tag != "tag:yaml.org,2002:merge":
                        key_node.tag = "tag:yaml.org,2002:str"
                return super().construct_mapping(node, deep=deep)

        class Dumper(yaml.SafeDumper):
            pass

        for cls in (Loader, Dumper):
            cls.add_implicit_resolver("tag:yaml.org,2002:float", re.compile(_EXP_FLOAT), list("-+0123456789"))

        def construct_float(loader: Any, node: Any) -> float:
            value: float = yaml.SafeLoader.construct_yaml_float(loader, node)
            if math.isinf(value) and str(node.value).strip().lower() not in _INF_WORDS:
                raise _Overflow(str(node.value).strip())
            return value

        Loader.add_constructor("tag:yaml.org,2002:float", construct_float)
        _YAML.update(loader=Loader, dumper=Dumper)
    return _YAML["loader"], _YAML["dumper"]


def _loader() -> Any:
    return _yaml_classes()[0]


def to_text(msg: Any) -> str:
    """A message as YAML that :func:`from_text` reads back unchanged (block style, keys in field order)."""
    import yaml

    return yaml.dump(msg, Dumper=_yaml_classes()[1], sort_keys=False, allow_unicode=True)


def parse_text(text: str) -> Any:
    """YAML (a superset of JSON) -> Python value; raises :class:`MessageTextError` on a syntax error and for
    a number too large to be one (``1.0e+400`` would silently become infinity; ``.inf`` is infinity).
    Numbers read as a person types them: ``1e5`` and ``1E-3`` are floats (YAML 1.1 alone reads them as
    strings). Mapping keys stay text (``{on: true, 1: x}`` -> ``{"on": True, "1": "x"}``): they name fields."""
    import yaml

    if not text or not text.strip():
        return {}
    if text.lstrip()[:1] in ("{", "[", '"'):
        import json

        try:  # real JSON first: YAML does not join \ud83d\ude00 surrogate pairs
            return json.loads(text, parse_float=_float_or_overflow)
        except _Overflow as exc:
            raise MessageTextError("", str(exc)) from None
        except ValueError:
            pass
    try:
        return yaml.load(text, Loader=_loader())  # noqa: S506 - a SafeLoader subclass
    except _Overflow as exc:
        raise MessageTextError("", str(exc)) from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" (line {mark.line + 1}, column {mark.column + 1})" if mark is not None else ""
        what = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise MessageTextError("", f"not valid YAML or JSON{where}: {what}") from None


def from_text(reg: TypeLookup, name: str, text: str, *, finite: bool = True) -> dict[str, Any]:
    """Parse YAML/JSON text typed by a person into a complete message of type ``name``. NaN and infinity
    are refused unless ``finite=False``."""
    return complete(reg, name, parse_text(text), finite=finite)
