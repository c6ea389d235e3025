"""Hypothesis strategies building wire-shape messages from a registry's FieldDefs (needs the test extra)."""

from __future__ import annotations

import base64

from hypothesis import strategies as st

from rcon_core.msgs.fielddefs import TIME_TYPES, is_binary, primitive


def scalar(reg, base, binary_as="base64", text=None):
    if base in TIME_TYPES:
        a, b = reg.time_fields
        secs = st.integers(0, 2**32 - 1) if base == "time" else st.integers(-(2**31), 2**31 - 1)
        return st.fixed_dictionaries({a: secs, b: st.integers(0, 999_999_999)})
    p = primitive(base, reg.ros2)
    if p is None:
        return message(reg, base, binary_as, text)
    if p.kind == "bool":
        return st.booleans()
    if p.kind == "int":
        return st.integers(p.lo, p.hi)
    if p.kind == "float":
        width = 32 if p.name == "float32" else 64
        return st.floats(allow_nan=False, allow_infinity=False, width=width)
    return text if text is not None else st.text(max_size=12)


def field(reg, f, binary_as="base64", text=None):
    if is_binary(f.base, f.array_len):
        data = st.binary(min_size=f.array_len or 0, max_size=f.array_len or 40)
        if binary_as == "base64":
            return data.map(lambda b: base64.b64encode(b).decode("ascii"))
        return data
    elem = scalar(reg, f.base, binary_as, text)
    if f.array_len is None:
        return elem
    if f.array_len:
        return st.lists(elem, min_size=f.array_len, max_size=f.array_len)
    return st.lists(elem, max_size=5)


def message(reg, name, binary_as="base64", text=None):
    """Wire-shape messages of type ``name``; ``binary_as`` "base64" (JSON) or "bytes"; ``text`` a
    strategy for string values (default: any text up to 12 characters)."""
    return st.fixed_dictionaries({f.name: field(reg, f, binary_as, text) for f in reg.fields(name)})
