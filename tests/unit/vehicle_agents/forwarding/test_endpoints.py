"""MAVLink forwarding's routing rules: where a frame goes by the target it names and
where each target was heard from, and the endpoint addresses a forward is given."""

from __future__ import annotations

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from tests.support.forwarding import AGENT, MAVPROXY, OTHER_GCS, QGC, VEHICLE, heartbeat
from vehicle_agents.forwarding.endpoints import NO_TARGET, EndpointAddress, Heard, targets


def heard(*ids: tuple[int, int]) -> Heard:
    side = Heard()
    for each in ids:
        side.add(each)
    return side


@pytest.mark.parametrize(
    ("side", "source", "target", "goes"),
    [
        (heard(QGC), VEHICLE, (NO_TARGET, NO_TARGET), True),  # telemetry: to every GCS
        (heard(), VEHICLE, (NO_TARGET, NO_TARGET), True),  # even one not heard from yet
        (heard(QGC), VEHICLE, (0, 0), True),  # a broadcast
        (heard(QGC), VEHICLE, QGC, True),  # QGC's answer, to QGC
        (heard(QGC), VEHICLE, (255, 0), True),  # any component of system 255
        (heard(QGC), VEHICLE, (255, NO_TARGET), True),  # a message with target_system only
        (heard(QGC), VEHICLE, MAVPROXY, False),  # another component of 255, not heard here
        (heard(QGC), VEHICLE, AGENT, False),  # the agent's own answers stay with the agent
        (heard(OTHER_GCS), VEHICLE, QGC, False),  # another GCS's answer
        (heard(QGC), QGC, (NO_TARGET, NO_TARGET), False),  # never back where it came from
    ],
)
def test_frames_go_where_their_target_was_heard_from(
    side: Heard, source: tuple[int, int], target: tuple[int, int], goes: bool
) -> None:
    assert side.wants(source, *target) is goes


def test_the_vehicle_side_takes_anything_for_its_systems() -> None:
    vehicle = heard(VEHICLE)
    assert vehicle.wants_system(QGC, 1)  # for the autopilot
    assert vehicle.wants_system(QGC, 0)
    assert vehicle.wants_system(QGC, NO_TARGET)  # a GCS heartbeat
    assert not vehicle.wants_system(QGC, 7)  # another vehicle's
    assert not vehicle.wants_system(QGC, AGENT[0])  # the agent's
    assert not vehicle.wants_system(VEHICLE, 1)  # its own frame, come back


def test_targets_are_read_from_the_message_fields() -> None:
    ack = mavlink2.MAVLink_command_ack_message(512, 0, 0, 0, 255, 190)
    assert targets(ack) == (255, 190)
    assert targets(heartbeat()) == (NO_TARGET, NO_TARGET)
    set_mode = mavlink2.MAVLink_set_mode_message(1, 1, 4)  # target_system only
    assert targets(set_mode) == (1, NO_TARGET)


@pytest.mark.parametrize(
    ("text", "listen", "host", "port"),
    [
        ("udpout:10.0.0.5:14550", False, "10.0.0.5", 14550),
        ("udpin:0.0.0.0:14551", True, "0.0.0.0", 14551),
        ("udpout:[::1]:14550", False, "::1", 14550),
        ("udpout:gcs.local:14550", False, "gcs.local", 14550),
    ],
)
def test_endpoint_addresses(text: str, listen: bool, host: str, port: int) -> None:
    address = EndpointAddress.parse(text)
    assert (address.listen, address.host, address.port) == (listen, host, port)
    assert str(address) == text


@pytest.mark.parametrize(
    "text", ["udp:10.0.0.5:14550", "tcp:10.0.0.5:5760", "udpout:10.0.0.5", "udpin::0", "x"]
)
def test_bad_endpoint_addresses_are_refused_naming_the_forms(text: str) -> None:
    with pytest.raises(ValueError, match="udpin:HOST:PORT"):
        EndpointAddress.parse(text)
