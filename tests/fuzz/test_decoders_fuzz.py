"""Property-based fuzzing of every decoder that reads a peer's bytes: random and mutated
frames never crash a decoder nor hang it (a deadline per example), and each refusal is
the decoder's own clear error (counted by the hub: tests/integration/test_hostile_frames.py).

- the hub's agent socket and the dashboard socket (the `agent_to_hub` and `client_to_hub`
  decoders of `protocol.messages`), the manual-control frames among them;
- the agent's side of its socket (`hub_to_agent`: commands, manual frames, formation);
- the binary scan frame, as the agent sends it and as a subscriber gets it;
- the agent's MAVLink intake from the flight controller, through its real path: a real
  UDP link opened the way the agent opens it, `read_available` (pymavlink's robust
  parser), `FcuLink._on_message` and the telemetry snapshot built from it; also the
  forwarding endpoints' parser (frames from a third-party GCS).

Mutations start from valid frames: a field set to any JSON value, a field dropped, the
type swapped, bytes flipped, cut or inserted; for MAVLink, frames from pymavlink with
bytes flipped, truncated, the CRC broken, or a random payload under a valid CRC.

The number of examples each decoder took is printed at the end of the module.
"""

from __future__ import annotations

import json
import socket
import struct
from collections import Counter
from collections.abc import Callable, Iterator
from datetime import timedelta
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from protocol.messages import (
    Decoder,
    ProtocolError,
    agent_to_hub,
    client_to_hub,
    encode,
    hub_to_agent,
)
from protocol.scans import (
    ScanFrameError,
    client_scan_frame,
    decode_scan,
    encode_scan,
    split_client_scan_frame,
)
from tests.support.frames import (
    AGENT_FRAMES,
    CLIENT_FRAMES,
    HUB_FRAMES,
    _mutate_bytes,
    any_frames,
    scan_frames,
)
from vehicle_agents.fcu.link import FcuLink
from vehicle_agents.fcu.messages import read_available
from vehicle_agents.forwarding.endpoints import Endpoint, EndpointAddress
from vehicle_agents.telemetry.snapshot import link_snapshot

# About 30 s for the module on a busy 2-core machine; the deadline is per example, far
# above a decode's cost, so only a decoder that loops or blows up trips it.
DEADLINE = timedelta(milliseconds=400)
EXAMPLES = {"json": 1500, "scan": 1500, "mavlink": 1000}
EXAMPLES_TAKEN: Counter[str] = Counter()
REFUSED: Counter[str] = Counter()


def fuzz(kind: str) -> Callable[[Callable[..., None]], Callable[..., None]]:
    return settings(
        max_examples=EXAMPLES[kind],
        deadline=DEADLINE,
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
        derandomize=True,  # the suite's result does not depend on the run
    )


@pytest.fixture(scope="module", autouse=True)
def _print_counts(request: pytest.FixtureRequest) -> Iterator[None]:
    yield
    capture = request.config.pluginmanager.getplugin("capturemanager")
    with capture.global_and_fixture_disabled():
        for name, count in sorted(EXAMPLES_TAKEN.items()):
            print(f"\nfuzz examples: {name}: {count} ({REFUSED[name]} refused)", end="")
        print()


# -- JSON messages -------------------------------------------------------------------


def _check_refusal(refusal: ProtocolError) -> None:
    assert refusal.code in ("bad_frame", "invalid_message")
    assert refusal.message
    json.dumps(refusal.reply().model_dump())  # the error reply itself can be sent


def _decodes_or_refuses(name: str, decoder: Decoder[Any], frame: str | bytes) -> None:
    EXAMPLES_TAKEN[name] += 1
    try:
        message = decoder.decode(frame)
    except ProtocolError as refusal:
        REFUSED[name] += 1
        _check_refusal(refusal)
        return
    # What is taken can be sent on and read back as the same message: no NaN, no value
    # the encoder writes and the decoder refuses.
    again = encode(message)
    assert decoder.decode(again) == message


@fuzz("json")
@given(any_frames(AGENT_FRAMES))
def test_the_hubs_agent_socket_decoder(frame: str | bytes) -> None:
    _decodes_or_refuses("agent -> hub (JSON)", agent_to_hub, frame)


@fuzz("json")
@given(any_frames(CLIENT_FRAMES))
def test_the_hubs_dashboard_socket_decoder(frame: str | bytes) -> None:
    _decodes_or_refuses("browser -> hub (JSON, manual input among them)", client_to_hub, frame)


@fuzz("json")
@given(any_frames(HUB_FRAMES))
def test_the_agents_hub_socket_decoder(frame: str | bytes) -> None:
    _decodes_or_refuses("hub -> agent (JSON, manual frames among them)", hub_to_agent, frame)


# -- binary scan frames ----------------------------------------------------------------


@fuzz("scan")
@given(scan_frames())
def test_the_scan_frame_decoder(data: bytes) -> None:
    EXAMPLES_TAKEN["scan frame (binary, agent -> hub)"] += 1
    try:
        frame = decode_scan(data)
    except ScanFrameError as refusal:
        REFUSED["scan frame (binary, agent -> hub)"] += 1
        message = str(refusal)
        assert message  # names what is wrong
        return
    assert decode_scan(encode_scan(frame)) == frame


@fuzz("scan")
@given(st.binary(max_size=12), scan_frames())
def test_the_subscribers_scan_frame_decoder(name: bytes, data: bytes) -> None:
    EXAMPLES_TAKEN["scan frame (binary, hub -> browser)"] += 1
    frame = b"GSCV" + bytes([len(name)]) + name + data
    try:
        vehicle_id, scan = split_client_scan_frame(frame)
    except ScanFrameError:
        REFUSED["scan frame (binary, hub -> browser)"] += 1
        return
    assert split_client_scan_frame(client_scan_frame(vehicle_id, encode_scan(scan)))[1] == scan


# -- MAVLink from the flight controller ------------------------------------------------

_SENDER = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)


def _pack(message: Any) -> bytes:
    return bytes(message.pack(_SENDER))


VALID_MAVLINK = [
    _pack(mavlink2.MAVLink_heartbeat_message(2, 3, 81, 4, 3, 3)),
    _pack(
        mavlink2.MAVLink_global_position_int_message(
            1000, -353632620, 1491652370, 600_000, 12_000, 10, -20, 5, 9000
        )
    ),
    _pack(mavlink2.MAVLink_sys_status_message(0, 0, 0, 500, 12_600, 150, 87, 0, 0, 0, 0, 0, 0)),
    _pack(mavlink2.MAVLink_attitude_message(1000, 0.1, -0.2, 1.5, 0.0, 0.0, 0.0)),
    _pack(mavlink2.MAVLink_statustext_message(4, b"PreArm: EKF not ready")),
    _pack(mavlink2.MAVLink_command_ack_message(400, 0)),
    _pack(mavlink2.MAVLink_mission_current_message(3)),
    _pack(
        mavlink2.MAVLink_gps_raw_int_message(
            1000, 3, -353632620, 1491652370, 600_000, 80, 100, 500, 9000, 12
        )
    ),
]
HEARTBEAT = VALID_MAVLINK[0]
# A MAVLink 2 frame is at most 280 bytes: this many heartbeats end any frame a mutation
# left open, so the next one parses whatever came before.
RESYNC = HEARTBEAT * (280 // len(HEARTBEAT) + 2)
_MESSAGE_IDS = sorted(mavlink2.mavlink_map)


def _frame_with_valid_crc(msgid: int, payload: bytes, seq: int) -> bytes:
    """A MAVLink 2 frame of ``msgid`` whose payload is random but whose CRC is right:
    what a flight controller with a bug (or a forger) sends, past the CRC check."""
    header = struct.pack(
        "<BBBBBBBHB", 0xFD, len(payload), 0, 0, seq, 1, 1, msgid & 0xFFFF, msgid >> 16
    )
    crc = mavlink2.x25crc(header[1:] + payload)
    crc.accumulate(struct.pack("B", mavlink2.mavlink_map[msgid].crc_extra))
    return header + payload + struct.pack("<H", crc.crc)


@st.composite
def mavlink_bytes(draw: st.DrawFn) -> bytes:
    how = draw(st.sampled_from(["random", "flip", "truncate", "crc", "payload", "stream"]))
    frame = bytearray(draw(st.sampled_from(VALID_MAVLINK)))
    if how == "random":
        return draw(st.binary(max_size=300))
    if how == "flip":
        return bytes(_mutate_bytes(draw, frame))
    if how == "truncate":
        return bytes(frame[: draw(st.integers(0, len(frame) - 1))])
    if how == "crc":
        frame[-1 - draw(st.integers(0, 1))] ^= draw(st.integers(1, 255))
        return bytes(frame)
    if how == "payload":
        msgid = draw(st.sampled_from(_MESSAGE_IDS))
        size = mavlink2.mavlink_map[msgid].unpacker.size
        payload = draw(st.binary(min_size=1, max_size=min(size, 255)))
        return _frame_with_valid_crc(msgid, payload, draw(st.integers(0, 255)))
    # valid frames with garbage and broken frames between them, in one read
    parts = draw(
        st.lists(
            st.sampled_from(VALID_MAVLINK) | st.binary(max_size=20) | st.just(frame[:9]),
            min_size=2,
            max_size=6,
        )
    )
    return b"".join(parts)


@pytest.fixture(scope="module")
def fcu_link() -> Iterator[tuple[FcuLink, socket.socket, Any]]:
    """The agent's link, opened as the agent opens it, on a UDP port this test sends to."""
    probe = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    probe.bind(("127.0.0.1", 0))
    port = probe.getsockname()[1]
    probe.close()
    link = FcuLink(f"udpin:127.0.0.1:{port}")
    connection = link._open()
    link._connection = connection
    sender = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sender.connect(("127.0.0.1", port))
    try:
        yield link, sender, connection
    finally:
        sender.close()
        connection.close()


def _read_all(connection: Any, sent: int) -> list[Any]:
    """Every message of the datagrams just sent (each arrives whole, on loopback)."""
    messages: list[Any] = []
    for _ in range(sent):
        messages += read_available(connection, 2.0)
    return messages


@fuzz("mavlink")
@given(data=mavlink_bytes())
def test_the_agents_mavlink_intake(
    fcu_link: tuple[FcuLink, socket.socket, Any], data: bytes
) -> None:
    link, sender, connection = fcu_link
    EXAMPLES_TAKEN["MAVLink from the flight controller (agent)"] += 1
    errors_before = link.counters.receive_errors
    messages = []
    if data:
        sender.send(data)
        messages = _read_all(connection, 1)
    bad = sum(message.get_type() == "BAD_DATA" for message in messages)
    for message in messages:
        link._on_message(message)  # what _deliver_inbox does with each, on the loop
    assert link.counters.receive_errors - errors_before == bad  # each refusal counted
    if bad:
        REFUSED["MAVLink from the flight controller (agent)"] += 1
    link_snapshot(link)  # the telemetry the agent would send next is still built
    # Whatever came before, the link goes on: a heartbeat after it is read.
    sender.send(RESYNC)
    after = _read_all(connection, 1)
    assert any(m.get_type() == "HEARTBEAT" for m in after), [m.get_type() for m in after]
    for message in after:
        link._on_message(message)


@pytest.fixture(scope="module")
def forwarding_endpoint() -> Endpoint:
    return Endpoint(EndpointAddress.parse("udpin:127.0.0.1:14550"))


@fuzz("mavlink")
@given(data=mavlink_bytes())
def test_the_forwarding_endpoints_mavlink_intake(
    forwarding_endpoint: Endpoint, data: bytes
) -> None:
    EXAMPLES_TAKEN["MAVLink from a forwarded GCS (agent)"] += 1
    endpoint = forwarding_endpoint
    bad_before = endpoint.counters.bad_frames
    good = endpoint.parse(data)
    assert all(m.get_type() != "BAD_DATA" for m in good)
    # Bytes that are not the frames taken were refused, and that is counted.
    refused_some = data != b"".join(bytes(m.get_msgbuf()) for m in good)
    assert (endpoint.counters.bad_frames > bad_before) == refused_some
    if refused_some:
        REFUSED["MAVLink from a forwarded GCS (agent)"] += 1
    # a datagram holds whole frames: the next one parses on its own
    assert [m.get_type() for m in endpoint.parse(HEARTBEAT)] == ["HEARTBEAT"]
