"""Decoding the agent's telemetry frame: the hub's path (pydantic) against msgspec.

    .venv/bin/python bench/bench_codec.py [--frames 20000]

Prints microseconds per frame; asserts nothing. The machine is shared and small (2
cores), so each figure is the best of several rounds. The rows:

- ``pydantic validate_json``: what the hub does (protocol.messages' agent_to_hub
  decoder; a valid frame takes its first pass only): pydantic-core parses and
  validates the text in one pass.
- ``json.loads + validate_python``: the path before that (and still the path that
  names the problem in a refused frame).
- ``msgspec parse + validate_python``: msgspec as the JSON parser only, pydantic still
  the one definition of the messages and their bounds.
- ``msgspec typed (no bounds)``: msgspec decoding into structs derived from the same
  pydantic models at run time (their field types and defaults, no hand-written second
  definition). They check types only: none of the protocol's bounds (string and list
  lengths, ranges, patterns, strict numbers, the validators), so this is a ceiling on
  what msgspec could buy, not a decoder the hub could use.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import msgspec
from pydantic import BaseModel

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from protocol.messages import Telemetry, VehicleState, agent_to_hub, encode

ROUNDS = 5


def telemetry_frame() -> str:
    """A full telemetry frame, every field the agent fills in flight."""
    state = VehicleState(
        mode="GUIDED",
        armed=True,
        system_status="ACTIVE",
        landed_state="in_air",
        landed_state_source="autopilot",
        lat=-35.3632621,
        lon=149.1652374,
        alt_msl=604.07,
        alt_rel=20.01,
        heading_deg=353.2,
        groundspeed=4.98,
        climb_rate=-0.02,
        vn=4.94,
        ve=-0.6,
        roll_deg=1.3,
        pitch_deg=-6.7,
        battery_voltage=12.58,
        battery_current=14.2,
        battery_remaining=81.0,
        gps_fix=6,
        satellites=18,
        ready_to_fly=True,
        home_lat=-35.3632621,
        home_lon=149.1652374,
        home_alt_msl=584.06,
        mission_current=3,
        mission_total=12,
        position_source="GPS_RAW_INT",
        outbox_pending=2,
    )
    return encode(Telemetry(seq=123_456, time=1_760_000_000.125, state=state))


def struct_of(model: type[BaseModel], structs: dict[type[BaseModel], Any]) -> Any:
    """A msgspec struct with the model's field names, types and defaults (nested models
    become structs too): derived, so there is still one definition of the message."""
    if model in structs:
        return structs[model]
    fields: list[tuple[str, Any, Any]] = []
    for name, field in model.model_fields.items():
        annotation = field.annotation
        if isinstance(annotation, type) and issubclass(annotation, BaseModel):
            annotation = struct_of(annotation, structs)
        default = field.get_default(call_default_factory=True)
        fields.append((name, annotation, msgspec.NODEFAULT if field.is_required() else default))
    # Required fields first, as a struct needs (keyword arguments make the order moot).
    fields.sort(key=lambda entry: entry[2] is not msgspec.NODEFAULT)
    structs[model] = msgspec.defstruct(model.__name__, fields, forbid_unknown_fields=True)
    return structs[model]


def best_us(decode: Callable[[str], object], frame: str, frames: int) -> float:
    best = float("inf")
    for _ in range(ROUNDS):
        started = time.perf_counter()
        for _ in range(frames):
            decode(frame)
        best = min(best, (time.perf_counter() - started) / frames * 1e6)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--frames", type=int, default=20_000)
    args = parser.parse_args()
    frame = telemetry_frame()
    telemetry_struct = struct_of(Telemetry, {})
    typed = msgspec.json.Decoder(telemetry_struct)
    parse = msgspec.json.Decoder()
    adapter = agent_to_hub.adapter
    assert adapter.validate_python(parse.decode(frame)) == agent_to_hub.decode(frame)
    assert msgspec.to_builtins(typed.decode(frame))["state"]["lat"] == -35.3632621
    rows = {
        "pydantic validate_json (the hub's)": agent_to_hub.decode,
        "json.loads + validate_python": lambda f: adapter.validate_python(json.loads(f)),
        "msgspec parse + validate_python": lambda f: adapter.validate_python(parse.decode(f)),
        "msgspec typed (no bounds)": typed.decode,
        "  json.loads alone": json.loads,
        "  msgspec parse alone": parse.decode,
    }
    print(f"telemetry frame: {len(frame)} bytes; best of {ROUNDS} rounds of {args.frames}")
    for name, decode in rows.items():
        print(f"{name:<38} {best_us(decode, frame, args.frames):7.2f} µs/frame")


if __name__ == "__main__":
    main()
