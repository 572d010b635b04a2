"""What each MAVLink wire type can hold: the one source of truth for field bounds.

A value the hub passes on to a flight controller ends up packed into a MAVLink field of
a fixed C type (``float``, ``int32_t`` ...). One that does not fit makes pymavlink raise
while packing (``OverflowError`` for a float32, ``struct.error`` for an integer), so the
hub refuses it at its edge, and the agent checks again before anything is sent. The
wire protocol's bounded types (`protocol.messages`) and the agent's check both read this
table; a unit test checks the protocol against pymavlink's own field types.

Standard library only: the protocol module that imports this is the leaf of the project.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Iterable

# The largest finite float32: 0x7f7fffff, about 3.4028235e38.
FLOAT32_MAX: float = struct.unpack(">f", bytes.fromhex("7f7fffff"))[0]

# Inclusive (lowest, highest) per C type, spelled as pymavlink's ``fieldtypes`` spell it.
WIRE_RANGES: dict[str, tuple[float, float]] = {
    "float": (-FLOAT32_MAX, FLOAT32_MAX),
    "double": (-math.inf, math.inf),  # any finite Python float fits a double
    "int8_t": (-(2**7), 2**7 - 1),
    "uint8_t": (0, 2**8 - 1),
    "int16_t": (-(2**15), 2**15 - 1),
    "uint16_t": (0, 2**16 - 1),
    "int32_t": (-(2**31), 2**31 - 1),
    "uint32_t": (0, 2**32 - 1),
    "int64_t": (-(2**63), 2**63 - 1),
    "uint64_t": (0, 2**64 - 1),
}

_LABELS = {"float": "float32", "double": "float64"}

# Positions travel as int32 degrees * 1e7 (MISSION_ITEM_INT.x/y, COMMAND_INT.x/y).
DEGE7 = 1e7
assert round(180 * DEGE7) <= WIRE_RANGES["int32_t"][1]  # so every longitude fits


def wire_problem(c_type: str, value: object) -> str | None:
    """Why ``value`` does not fit a field of ``c_type``, or None if it does (or the type
    has no numeric range, such as ``char``)."""
    bounds = WIRE_RANGES.get(c_type)
    if bounds is None or isinstance(value, str | bytes):
        return None
    if not isinstance(value, int | float):
        return f"{value!r} is not a number"
    if isinstance(value, float) and math.isnan(value):
        # float32 can carry NaN, and MAVLink uses it for "unset"; callers that refuse it
        # do so in the protocol, where the field's meaning is known.
        return None if c_type in ("float", "double") else "NaN is not an integer"
    low, high = bounds
    if c_type in ("float", "double"):
        # packing rounds to the nearest float32 first, so only what rounds to inf fails
        if math.isinf(value) or not low <= value <= high:
            return f"{value!r} does not fit a {_LABELS[c_type]} (at most ±{high:.7g})"
        return None
    if not low <= value <= high:
        return f"{value!r} does not fit a {c_type} ({low:.0f}..{high:.0f})"
    return None


def out_of_range(fields: Iterable[tuple[str, str, object]]) -> list[str]:
    """Each ``(name, c_type, value)`` that does not fit, as ``name: why``; array fields
    (a list or tuple of values) are checked element by element."""
    problems = []
    for name, c_type, value in fields:
        values = value if isinstance(value, list | tuple) else [value]
        for item in values:
            problem = wire_problem(c_type, item)
            if problem is not None:
                problems.append(f"{name}: {problem}")
                break
    return problems
