"""A parameter value against the parameter's metadata (`ParamMeta`): the one check the
agent makes with PX4's own metadata and the hub with ArduPilot's metadata file."""

from __future__ import annotations

import math

from protocol.messages import ParamMeta


def out_of_range(name: str, value: float, meta: ParamMeta) -> str | None:
    """Why ``value`` is not one ``name`` takes by its metadata; None if it is."""
    if meta.values:
        if any(math.isclose(value, choice.value, abs_tol=1e-6) for choice in meta.values):
            return None
        listed = ", ".join(
            f"{choice.value:g} {choice.description}".strip() for choice in meta.values
        )
        return f"{name}: {value:g} is not one of the values it takes ({listed})"
    low = -math.inf if meta.min is None else meta.min
    high = math.inf if meta.max is None else meta.max
    if low <= value <= high:
        return None
    units = f" {meta.units}" if meta.units else ""
    shown_low = "" if meta.min is None else f"{meta.min:g}"
    shown_high = "" if meta.max is None else f"{meta.max:g}"
    return f"{name}: {value:g} is outside its range {shown_low}..{shown_high}{units}"
