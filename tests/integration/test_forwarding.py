"""QGroundControl and MAVProxy, played by pymavlink, reach a vehicle through its agent's
MAVLink forwarding while the hub keeps seeing it live."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest
from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from gcs.launcher import free_port
from tests.support.watcher import FleetWatcher

pytestmark = pytest.mark.integration

VEHICLE_SYSID = 3
AGENT_SYSID = 254  # the agent's default source_system
QGC_IDS = (255, 190)  # QGroundControl's defaults
MAVPROXY_IDS = (250, 230)  # a second GCS takes a system id of its own (--source-system)
AUTOPILOT_VERSION = 148
WAIT_S = 20.0
GCS_COMMAND = (sys.executable, "-m", "gcs")


@dataclass
class GroundStation:
    """A pymavlink connection playing a GCS, keeping everything it received."""

    connection: Any
    received: list[Any] = field(default_factory=list)

    def expect(self, predicate: Callable[[Any], bool], what: str) -> Any:
        deadline = time.monotonic() + WAIT_S
        while time.monotonic() < deadline:
            message = self.connection.recv_match(blocking=True, timeout=0.5)
            if message is None:
                continue
            self.received.append(message)
            if predicate(message):
                return message
        raise AssertionError(f"no {what} within {WAIT_S} s; got {self._kinds()}")

    def heartbeat(self) -> None:
        self.connection.mav.heartbeat_send(
            mavlink2.MAV_TYPE_GCS, mavlink2.MAV_AUTOPILOT_INVALID, 0, 0, 0
        )

    def _kinds(self) -> list[str]:
        return sorted({m.get_type() for m in self.received})


def from_vehicle(kind: str) -> Callable[[Any], bool]:
    return lambda m: m.get_type() == kind and m.get_srcSystem() == VEHICLE_SYSID


@dataclass
class ForwardedVehicle:
    qgc: GroundStation  # behind a udpout endpoint: the agent sends to it
    mavproxy: GroundStation  # behind a udpin endpoint: it writes to the agent first
    agent: subprocess.Popen[bytes]


@pytest.fixture
def forwarded_vehicle(
    hub: str, enrol: Callable[[str], str], tmp_path: Path
) -> Iterator[ForwardedVehicle]:
    sim_port, qgc_port, listen_port = free_port(), free_port(), free_port()
    # QGroundControl listens on its port before the vehicle appears, as it does.
    qgc = mavutil.mavlink_connection(
        f"udpin:127.0.0.1:{qgc_port}", source_system=QGC_IDS[0], source_component=QGC_IDS[1]
    )
    logs = (tmp_path / "sim.log").open("wb"), (tmp_path / "agent.log").open("wb")
    sim = subprocess.Popen(
        [
            *GCS_COMMAND,
            "sim",
            "--listen",
            f"tcp:127.0.0.1:{sim_port}",
            "--system-id",
            str(VEHICLE_SYSID),
        ],
        stdout=logs[0],
        stderr=subprocess.STDOUT,
    )
    agent = subprocess.Popen(
        [
            *GCS_COMMAND,
            "agent",
            "--fcu",
            f"tcp:127.0.0.1:{sim_port}",
            "--hub",
            hub.replace("http://", "ws://"),
            "--vehicle-id",
            "forwarded",
            "--mavlink-forward",
            f"udpout:127.0.0.1:{qgc_port}",
            "--mavlink-forward",
            f"udpin:127.0.0.1:{listen_port}",
        ],
        env={**os.environ, "GCS_AGENT_TOKEN": enrol("forwarded")},
        stdout=logs[1],
        stderr=subprocess.STDOUT,
    )
    mavproxy = mavutil.mavlink_connection(
        f"udpout:127.0.0.1:{listen_port}",
        source_system=MAVPROXY_IDS[0],
        source_component=MAVPROXY_IDS[1],
    )
    try:  # on a failure, the agent's and the simulator's logs are in tmp_path
        yield ForwardedVehicle(GroundStation(qgc), GroundStation(mavproxy), agent)
    finally:
        qgc.close()
        mavproxy.close()
        for process in (agent, sim):
            process.terminate()
            process.wait(10)
        for log in logs:
            log.close()


def test_a_third_party_gcs_flies_alongside_the_hub(
    hub: str, admin_token: str, forwarded_vehicle: ForwardedVehicle
) -> None:
    qgc, mavproxy = forwarded_vehicle.qgc, forwarded_vehicle.mavproxy

    # The vehicle's own telemetry reaches QGroundControl, unchanged.
    qgc.expect(from_vehicle("HEARTBEAT"), "HEARTBEAT from the vehicle")
    position = qgc.expect(from_vehicle("GLOBAL_POSITION_INT"), "GLOBAL_POSITION_INT")
    assert position.lat != 0

    # MAVProxy writes first (its endpoint learns its address), then hears the vehicle too.
    mavproxy.heartbeat()
    mavproxy.expect(from_vehicle("HEARTBEAT"), "HEARTBEAT through the udpin endpoint")

    # QGroundControl asks; the vehicle answers it.
    qgc.heartbeat()
    qgc.connection.mav.command_long_send(
        VEHICLE_SYSID, 1, mavlink2.MAV_CMD_REQUEST_MESSAGE, 0, AUTOPILOT_VERSION, 0, 0, 0, 0, 0, 0
    )
    ack = qgc.expect(
        lambda m: m.get_type() == "COMMAND_ACK" and m.command == mavlink2.MAV_CMD_REQUEST_MESSAGE,
        "COMMAND_ACK for REQUEST_MESSAGE",
    )
    assert ack.result == mavlink2.MAV_RESULT_ACCEPTED
    assert (ack.target_system, ack.target_component) == QGC_IDS
    qgc.expect(from_vehicle("AUTOPILOT_VERSION"), "the AUTOPILOT_VERSION asked for")
    qgc.connection.mav.param_request_read_send(VEHICLE_SYSID, 1, b"SYSID_THISMAV", -1)
    value = qgc.expect(
        lambda m: m.get_type() == "PARAM_VALUE" and m.param_id == "SYSID_THISMAV",
        "PARAM_VALUE SYSID_THISMAV",
    )
    assert value.param_value == VEHICLE_SYSID
    answered_qgc_at = time.time()

    # MAVProxy asks in turn and gets its own answer; QGroundControl's never reached it.
    mavproxy.connection.mav.command_long_send(
        VEHICLE_SYSID, 1, mavlink2.MAV_CMD_REQUEST_MESSAGE, 0, AUTOPILOT_VERSION, 0, 0, 0, 0, 0, 0
    )
    ack = mavproxy.expect(
        lambda m: m.get_type() == "COMMAND_ACK" and m.target_system == MAVPROXY_IDS[0],
        "MAVProxy's COMMAND_ACK",
    )
    assert ack.result == mavlink2.MAV_RESULT_ACCEPTED
    acks = [m for m in mavproxy.received if m.get_type() == "COMMAND_ACK"]
    assert [(m.target_system, m.target_component) for m in acks] == [MAVPROXY_IDS]

    # The agent's own exchanges with the vehicle (its stream requests, addressed to its
    # system id) were never forwarded to either GCS.
    for gcs in (qgc, mavproxy):
        assert not [m for m in gcs.received if getattr(m, "target_system", 0) == AGENT_SYSID]

    # Meanwhile the hub still has the vehicle, live.
    with FleetWatcher(hub, admin_token) as watcher:
        watcher.wait_until(
            lambda v: (
                "forwarded" in v
                and v["forwarded"]["connected"]
                and (v["forwarded"]["last_seen"] or 0) > answered_qgc_at
                and v["forwarded"]["state"]["lat"] is not None
            ),
            WAIT_S,
            "fresh telemetry from the forwarded vehicle at the hub",
        )
    assert forwarded_vehicle.agent.poll() is None
