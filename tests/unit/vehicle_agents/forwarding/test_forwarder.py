"""The MAVLink forwarder on real UDP sockets with real MAVLink frames (a stand-in flight
controller link records what reaches the vehicle)."""

from __future__ import annotations

import asyncio
import contextlib
import functools
import socket
import time
from collections.abc import AsyncIterator, Callable, Coroutine, Iterator
from typing import Any, ParamSpec

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from gcs.launcher import free_port
from tests.support.forwarding import AGENT, MAVPROXY, OTHER_GCS, QGC, VEHICLE, heartbeat
from tests.support.waiting import poll_until_async
from vehicle_agents.fcu.messages import MavMessage
from vehicle_agents.forwarding.endpoints import Endpoint, EndpointAddress
from vehicle_agents.forwarding.forwarder import MavlinkForwarder

WAIT_S = 5.0
P = ParamSpec("P")


def encode(message: MavMessage, ids: tuple[int, int], seq: int = 0) -> bytes:
    encoder = mavlink2.MAVLink(None, srcSystem=ids[0], srcComponent=ids[1])
    encoder.seq = seq
    return bytes(message.pack(encoder))


def decode(frame: bytes) -> MavMessage:
    messages = mavlink2.MAVLink(None).parse_buffer(frame)
    assert messages is not None
    assert len(messages) == 1
    return messages[0]


def from_vehicle(message: MavMessage) -> MavMessage:
    """A message as the FCU reader thread hands it over: decoded from its wire bytes."""
    return decode(encode(message, VEHICLE))


class FakeVehicleLink:
    """The flight controller link, as forwarding sees it; records what it must write."""

    source_system, source_component = AGENT
    target_system, target_component = VEHICLE

    def __init__(self) -> None:
        self.taps: list[Callable[[MavMessage], None]] = []
        self.written: asyncio.Queue[bytes] = asyncio.Queue()
        self.down = False

    def write_frame(self, frame: bytes) -> None:
        if self.down:
            raise ConnectionError("flight controller link is down")
        self.written.put_nowait(bytes(frame))

    def send(self, message: MavMessage) -> None:
        """The agent's own frame (from its ids), as FcuLink.send writes it."""
        self.write_frame(encode(message, AGENT))

    def send_command_long(self, command: int, confirmation: int, params: list[float]) -> None:
        padded = [float(value) for value in params] + [0.0] * (7 - len(params))
        self.send(mavlink2.MAVLink_command_long_message(*VEHICLE, command, confirmation, *padded))

    async def tap(self, message: MavMessage) -> None:
        """Hand a vehicle frame to the taps from another thread, as the reader does."""

        def call_taps() -> None:
            for tap in self.taps:
                tap(message)

        await asyncio.to_thread(call_taps)


class Gcs:
    """A ground station's UDP socket."""

    def __init__(self) -> None:
        self.socket = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.socket.setblocking(False)
        self.socket.bind(("127.0.0.1", 0))
        self.port = self.socket.getsockname()[1]

    async def receive(self) -> MavMessage:
        loop = asyncio.get_running_loop()
        data, _ = await asyncio.wait_for(loop.sock_recvfrom(self.socket, 65535), WAIT_S)
        return decode(data)

    def send(self, frame: bytes, port: int) -> None:
        self.socket.sendto(frame, ("127.0.0.1", port))

    def close(self) -> None:
        self.socket.close()


@pytest.fixture
def make_gcs() -> Iterator[Callable[[], Gcs]]:
    made: list[Gcs] = []

    def make() -> Gcs:
        made.append(Gcs())
        return made[-1]

    yield make
    for gcs in made:
        gcs.close()


async def until(condition: Callable[[], bool], what: str) -> None:
    await poll_until_async(condition, WAIT_S, what, every_s=0.001)


@contextlib.asynccontextmanager
async def forwarding(link: FakeVehicleLink, *endpoints: str) -> AsyncIterator[MavlinkForwarder]:
    forwarder = MavlinkForwarder(link, endpoints)
    task = asyncio.create_task(forwarder.run())
    try:
        await until(lambda: bool(link.taps), "the forwarder to open its endpoints")
        yield forwarder
    finally:
        task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await task
    assert not link.taps, "the tap is removed on stop"


@contextlib.asynccontextmanager
async def forwarding_to(link: FakeVehicleLink, gcs: Gcs) -> AsyncIterator[Endpoint]:
    """A forwarder with one endpoint, udpout to ``gcs``; yields that endpoint."""
    async with forwarding(link, f"udpout:127.0.0.1:{gcs.port}") as forwarder:
        (endpoint,) = forwarder.endpoints
        yield endpoint


@pytest.fixture
def link() -> FakeVehicleLink:
    return FakeVehicleLink()


@pytest.fixture
def qgc(make_gcs: Callable[[], Gcs]) -> Gcs:
    return make_gcs()


def in_event_loop(test: Callable[P, Coroutine[Any, Any, None]]) -> Callable[P, None]:
    """Runs an async test (fixtures and all) in a fresh event loop, within 30 s."""

    @functools.wraps(test)
    def run(*args: P.args, **kwargs: P.kwargs) -> None:
        asyncio.run(asyncio.wait_for(test(*args, **kwargs), 30))

    return run


@in_event_loop
async def test_telemetry_reaches_every_gcs_and_commands_reach_the_vehicle_unchanged(
    link: FakeVehicleLink, make_gcs: Callable[[], Gcs]
) -> None:
    qgc, mavproxy = make_gcs(), make_gcs()
    listen_port = free_port()
    endpoints = (f"udpout:127.0.0.1:{qgc.port}", f"udpin:127.0.0.1:{listen_port}")
    async with forwarding(link, *endpoints) as forwarder:
        udpout, udpin = forwarder.endpoints
        # A udpin endpoint learns its GCS from the GCS's first frame.
        mavproxy.send(encode(heartbeat(mavlink2.MAV_TYPE_GCS), MAVPROXY), listen_port)
        gcs_heartbeat = decode(await link.written.get())
        assert gcs_heartbeat.get_srcSystem() == MAVPROXY[0]
        # ...and QGC hears the other GCS's heartbeat too, as through mavlink-router.
        assert (await qgc.receive()).get_srcComponent() == MAVPROXY[1]

        position = mavlink2.MAVLink_global_position_int_message(
            1000, -353632620, 1491652370, 584000, 10000, 0, 0, 0, 9000
        )
        await link.tap(from_vehicle(position))
        for gcs in (qgc, mavproxy):
            received = await gcs.receive()
            assert received.get_type() == "GLOBAL_POSITION_INT"
            assert received.get_srcSystem() == VEHICLE[0]
            assert received.lat == -353632620

        command = mavlink2.MAVLink_command_long_message(
            1, 1, mavlink2.MAV_CMD_REQUEST_MESSAGE, 0, 148, 0, 0, 0, 0, 0, 0
        )
        sent = encode(command, QGC, seq=42)
        qgc.send(sent, udpout.local_address[1])
        assert await link.written.get() == sent  # bytes unchanged, sequence number too
        assert udpout.counters.to_vehicle == 1
        assert udpin.counters.to_vehicle == 1
        assert udpout.counters.sent == 2
        assert udpin.counters.sent == 1
        assert udpout.counters.dropped == udpin.counters.dropped == 0


@in_event_loop
async def test_answers_reach_only_the_gcs_that_asked_and_the_agents_stay_private(
    link: FakeVehicleLink, make_gcs: Callable[[], Gcs]
) -> None:
    qgc, other = make_gcs(), make_gcs()
    endpoints = (f"udpout:127.0.0.1:{qgc.port}", f"udpout:127.0.0.1:{other.port}")
    async with forwarding(link, *endpoints) as forwarder:
        await link.tap(from_vehicle(heartbeat()))
        for gcs, ids, endpoint in zip(
            (qgc, other), (QGC, OTHER_GCS), forwarder.endpoints, strict=True
        ):
            assert (await gcs.receive()).get_type() == "HEARTBEAT"
            gcs.send(encode(heartbeat(mavlink2.MAV_TYPE_GCS), ids), endpoint.local_address[1])
            await link.written.get()
        assert (await qgc.receive()).get_srcSystem() == OTHER_GCS[0]  # GCS heartbeats

        ack_for = {
            name: mavlink2.MAVLink_command_ack_message(512, 0, 0, 0, *ids)
            for name, ids in (("qgc", QGC), ("agent", AGENT))
        }
        await link.tap(from_vehicle(ack_for["agent"]))
        await link.tap(from_vehicle(ack_for["qgc"]))
        await link.tap(from_vehicle(heartbeat()))
        # QGC's next frame is its own answer: the agent's went to nobody.
        answer = await qgc.receive()
        assert answer.get_type() == "COMMAND_ACK"
        assert (answer.target_system, answer.target_component) == QGC
        assert (await qgc.receive()).get_type() == "HEARTBEAT"
        # The other GCS got neither answer: its next frame is the heartbeat after them.
        assert (await other.receive()).get_type() == "HEARTBEAT"


@in_event_loop
async def test_frames_for_nobody_loops_and_garbage_are_counted_not_forwarded(
    link: FakeVehicleLink, qgc: Gcs
) -> None:
    async with forwarding_to(link, qgc) as endpoint:
        port = endpoint.local_address[1]
        await link.tap(from_vehicle(heartbeat()))
        await qgc.receive()
        for_another_vehicle = mavlink2.MAVLink_command_long_message(
            7, 1, mavlink2.MAV_CMD_NAV_LAND, 0, 0, 0, 0, 0, 0, 0, 0
        )
        qgc.send(encode(for_another_vehicle, QGC), port)
        qgc.send(encode(heartbeat(), VEHICLE), port)  # the vehicle's own frame, back
        qgc.send(b"\xfd\x09garbage that is no MAVLink", port)
        probe = encode(heartbeat(mavlink2.MAV_TYPE_GCS), QGC)
        qgc.send(probe, port)
        # Datagrams from one socket arrive in order: when the probe is written to the
        # vehicle, the three before it have been dealt with.
        assert await link.written.get() == probe
        assert link.written.empty()
        counters = endpoint.counters
        assert (counters.received, counters.to_vehicle) == (3, 1)
        assert (counters.unrouted, counters.looped) == (1, 1)
        assert counters.bad_frames >= 1


@in_event_loop
async def test_a_gcs_that_is_gone_never_blocks_the_vehicle_reader(link: FakeVehicleLink) -> None:
    nobody = free_port()  # nothing listens there
    # Sending to the broadcast address without SO_BROADCAST fails (EACCES) every time.
    refused = "udpout:255.255.255.255:14550"
    async with forwarding(link, f"udpout:127.0.0.1:{nobody}", refused) as forwarder:
        frames = [from_vehicle(heartbeat()) for _ in range(2000)]

        def read_frames() -> float:
            started = time.monotonic()
            for frame in frames:
                for tap in link.taps:
                    tap(frame)
            return time.monotonic() - started

        elapsed = await asyncio.to_thread(read_frames)
        to_nobody, to_refused = (e.counters for e in forwarder.endpoints)
        assert to_nobody.sent + to_nobody.dropped == len(frames)
        assert to_refused.dropped == len(frames)
        assert to_refused.sent == 0
        assert elapsed < 5, f"{len(frames)} frames took {elapsed:.1f} s to forward"


@in_event_loop
async def test_a_udpin_endpoint_follows_its_gcs_to_a_new_address(
    link: FakeVehicleLink, make_gcs: Callable[[], Gcs]
) -> None:
    port = free_port()
    first, restarted = make_gcs(), make_gcs()
    async with forwarding(link, f"udpin:127.0.0.1:{port}") as forwarder:
        (endpoint,) = forwarder.endpoints
        await link.tap(from_vehicle(heartbeat()))  # nobody to send it to yet: not dropped
        assert endpoint.counters.sent == endpoint.counters.dropped == 0
        first.send(encode(heartbeat(mavlink2.MAV_TYPE_GCS), QGC), port)
        await link.written.get()
        await link.tap(from_vehicle(heartbeat()))
        assert (await first.receive()).get_type() == "HEARTBEAT"
        # Stray bytes from elsewhere do not take the endpoint over; only MAVLink does.
        make_gcs().send(b"GET / HTTP/1.0\r\n\r\n", port)
        first.send(encode(heartbeat(mavlink2.MAV_TYPE_GCS), QGC), port)
        await link.written.get()  # queued behind the stray bytes: those were read
        assert endpoint.counters.bad_frames == 1
        assert endpoint.counters.peer_changes == 0
        # QGC restarted: a new source port. The endpoint follows it.
        restarted.send(encode(heartbeat(mavlink2.MAV_TYPE_GCS), QGC), port)
        await link.written.get()
        await link.tap(from_vehicle(heartbeat()))
        assert (await restarted.receive()).get_type() == "HEARTBEAT"
        assert endpoint.counters.sent == 2
        assert endpoint.counters.peer_changes == 1


@in_event_loop
async def test_frames_for_a_vehicle_link_that_is_down_are_dropped_and_counted(
    link: FakeVehicleLink, qgc: Gcs
) -> None:
    async with forwarding_to(link, qgc) as endpoint:
        link.down = True
        qgc.send(encode(heartbeat(mavlink2.MAV_TYPE_GCS), QGC), endpoint.local_address[1])
        await until(lambda: endpoint.counters.dropped == 1, "the drop to be counted")
        assert endpoint.counters.to_vehicle == 0


@in_event_loop
async def test_an_endpoint_that_cannot_open_is_left_out(
    link: FakeVehicleLink, make_gcs: Callable[[], Gcs], caplog: pytest.LogCaptureFixture
) -> None:
    taken = make_gcs()
    qgc = make_gcs()
    endpoints = (f"udpin:127.0.0.1:{taken.port}", f"udpout:127.0.0.1:{qgc.port}")
    async with forwarding(link, *endpoints):
        await link.tap(from_vehicle(heartbeat()))
        assert (await qgc.receive()).get_type() == "HEARTBEAT"
    assert "disabled" in caplog.text


@in_event_loop
async def test_a_udpout_endpoint_to_this_computer_listens_on_loopback_only() -> None:
    local = Endpoint(EndpointAddress.parse(f"udpout:127.0.0.1:{free_port()}"))
    remote = Endpoint(EndpointAddress.parse("udpout:192.0.2.1:14550"))  # TEST-NET-1
    await local.open()
    await remote.open()
    try:
        assert local.local_address[0] == "127.0.0.1"
        # A GCS elsewhere answers to the address the route gives: any interface.
        assert remote.local_address[0] == "0.0.0.0"
    finally:
        local.close()
        remote.close()
