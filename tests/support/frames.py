"""Hypothesis strategies for the frames the hub's decoders take."""

from __future__ import annotations

import json
from collections.abc import Iterator
from typing import Any

from hypothesis import strategies as st

from protocol.messages import (
    Ack,
    CommandRequest,
    CommandResult,
    ControlRequest,
    Event,
    LiveState,
    ManualApplied,
    ManualAxes,
    ManualFrame,
    ManualInput,
    Ping,
    Pong,
    Resend,
    ScanSourceStats,
    SubscribeMap,
    SubscribeScans,
    TakeoffCommand,
    Telemetry,
    VehicleState,
    Welcome,
    encode,
)
from protocol.messages import CommandOutcome as Outcome
from protocol.scans import (
    encode_scan,
)
from tests.support.hellos import agent_hello
from tests.support.scans import _frame

json_values = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats(allow_nan=False) | st.text(max_size=30),
    lambda children: (
        st.lists(children, max_size=4) | st.dictionaries(st.text(max_size=12), children, max_size=4)
    ),
    max_leaves=12,
)


_STATE = VehicleState(lat=-35.36, lon=149.16, alt_rel=12.5, armed=True, mode="GUIDED")


_AXES = ManualAxes(x=100, y=-200, z=600, r=5)


AGENT_FRAMES = [
    agent_hello("v1", stream_id="s1"),
    Telemetry(seq=7, time=1_760_000_000.0, state=_STATE),
    LiveState(time=1_760_000_000.0, state=_STATE),
    Event(seq=3, time=1_760_000_000.0, kind="statustext", severity=4, text="EKF ok"),
    CommandResult(request_id="r1", outcome=Outcome(status="accepted", message="ok")),
    Pong(nonce="n"),
    ManualApplied(seq=9, sent_ms=12.5),
    ScanSourceStats(source="ld06", counts={"packets": 600, "dropped_bad_crc": 2}),
]


CLIENT_FRAMES = [
    Ping(nonce="n1"),
    ControlRequest(vehicle_id="v1", action="acquire"),
    ManualInput(vehicle_id="v1", seq=4, axes=_AXES, source="gamepad", sent_ms=1.0),
    SubscribeScans(vehicle_id="v1"),
    SubscribeMap(layers=["points"]),
]


HUB_FRAMES = [
    Welcome(vehicle_id="v1"),
    CommandRequest(request_id="r1", command=TakeoffCommand(altitude=10.0), timeout_s=5.0),
    Ack(stream_id="s1", telemetry_seq=4),
    Resend(stream_id="s1", kind="telemetry", first_seq=1, last_seq=3),
    ManualFrame(seq=5, axes=_AXES),
]


TYPES = sorted(
    {m.type for m in AGENT_FRAMES + CLIENT_FRAMES + HUB_FRAMES} | {"", "error", "formation"}
)


def _paths(value: Any, prefix: tuple[Any, ...] = ()) -> Iterator[tuple[Any, ...]]:
    """Every place in a decoded JSON document a mutation may hit."""
    if isinstance(value, dict):
        for key, child in value.items():
            yield (*prefix, key)
            yield from _paths(child, (*prefix, key))
    elif isinstance(value, list):
        for index, child in enumerate(value):
            yield (*prefix, index)
            yield from _paths(child, (*prefix, index))


def _parent(document: Any, path: tuple[Any, ...]) -> Any:
    for step in path[:-1]:
        document = document[step]
    return document


def _same_kind(value: Any) -> st.SearchStrategy[Any]:
    if isinstance(value, bool):
        return st.booleans()
    if isinstance(value, int):
        return st.integers() | st.sampled_from([0, -1, 2**16, 2**31, 2**63 - 1, 2**64])
    if isinstance(value, float):
        return st.floats(allow_nan=False) | st.floats(-1e3, 1e3)
    if isinstance(value, str):
        return st.text(max_size=80) | st.just(value * 100)
    return json_values


@st.composite
def mutated_json(draw: st.DrawFn, samples: list[Any]) -> str | bytes:
    document = json.loads(encode(draw(st.sampled_from(samples))))
    for _ in range(draw(st.integers(0, 3))):
        paths = list(_paths(document))
        how = draw(st.sampled_from(["same kind", "same kind", "set", "drop", "type", "add"]))
        if how == "type" or not paths:
            document["type"] = draw(st.sampled_from(TYPES))
            continue
        path = draw(st.sampled_from(paths))
        parent = _parent(document, path)
        if how == "same kind":  # a value of the field's own JSON type: bounds, lengths
            parent[path[-1]] = draw(_same_kind(parent[path[-1]]))
        elif how == "set":
            parent[path[-1]] = draw(json_values)
        elif how == "drop":
            del parent[path[-1]]
        elif isinstance(parent, dict):
            parent[draw(st.text(max_size=8))] = draw(json_values)
    text = json.dumps(document)
    if draw(st.integers(0, 2)):
        return text
    data = bytearray(text.encode())
    return bytes(_mutate_bytes(draw, data))


def _mutate_bytes(draw: st.DrawFn, data: bytearray) -> bytearray:
    for _ in range(draw(st.integers(1, 4))):
        how = draw(st.sampled_from(["flip", "cut", "insert"]))
        if not data:
            break
        at = draw(st.integers(0, len(data) - 1))
        if how == "flip":
            data[at] ^= 1 << draw(st.integers(0, 7))
        elif how == "cut":
            del data[at:]
        else:
            data[at:at] = draw(st.binary(min_size=1, max_size=8))
    return data


def any_frames(samples: list[Any]) -> st.SearchStrategy[str | bytes]:
    # Mutations of valid frames are most of it: random text and bytes are refused at once.
    mutated = mutated_json(samples)
    return st.one_of(
        mutated,
        mutated,
        mutated,
        json_values.map(json.dumps),
        st.dictionaries(st.sampled_from(["type", "seq", "vehicle_id"]), json_values).map(
            json.dumps
        ),
        st.text(max_size=200),
        st.binary(max_size=200),
    )


def _scan(beams: int) -> bytes:
    """The scan-frame tests' own frame, as the seed the mutations start from."""
    return encode_scan(_frame(beams))


SCANS = [_scan(1), _scan(16), _scan(360)]


@st.composite
def scan_frames(draw: st.DrawFn) -> bytes:
    if draw(st.integers(0, 4)) == 0:
        return draw(st.binary(max_size=300))
    return bytes(_mutate_bytes(draw, bytearray(draw(st.sampled_from(SCANS)))))
