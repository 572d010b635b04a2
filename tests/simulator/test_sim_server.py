"""The simulator over real sockets, seen through pymavlink's mavutil like the agent sees it."""

from __future__ import annotations

import queue
import socket
import subprocess
import sys
import time
from collections.abc import Iterator

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from simulator import ListenAddress, ManualClock, SimulatorConfig
from simulator.mavlink.peer_links import Link
from simulator.server import MIN_TICK_S, TICK_S, SimulatorServer
from tests.support.simulators import (
    REPO_ROOT,
    SYSID,
    command,
    mavlink_client,
    serving,
    simulator_process,
    wait_for,
)


def test_guided_takeoff_and_land_over_tcp() -> None:
    with (
        simulator_process("--speedup", "10") as (port, lines),
        mavlink_client(f"tcp:127.0.0.1:{port}") as gcs,
    ):
        heartbeat = wait_for(gcs, ["HEARTBEAT"], lambda m: True, 10, "a heartbeat")
        assert heartbeat.type == mavlink2.MAV_TYPE_QUADROTOR
        assert heartbeat.autopilot == mavlink2.MAV_AUTOPILOT_ARDUPILOTMEGA
        assert heartbeat.get_srcComponent() == 1
        position = wait_for(gcs, ["GLOBAL_POSITION_INT"], lambda m: True, 5, "a position")
        assert abs(position.lat - (-353632620)) <= 1
        assert abs(position.relative_alt) < 100
        gps = wait_for(gcs, ["GPS_RAW_INT"], lambda m: True, 5, "GPS")
        assert gps.fix_type == 3

        assert command(gcs, mavlink2.MAV_CMD_DO_SET_MODE, 1, 4) == mavlink2.MAV_RESULT_ACCEPTED
        wait_for(gcs, ["HEARTBEAT"], lambda m: m.custom_mode == 4, 5, "GUIDED in the heartbeat")
        assert command(gcs, mavlink2.MAV_CMD_COMPONENT_ARM_DISARM, 1) == 0
        assert command(gcs, mavlink2.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, 0, 0, 0, 10) == 0
        armed = mavlink2.MAV_MODE_FLAG_SAFETY_ARMED
        wait_for(gcs, ["HEARTBEAT"], lambda m: m.base_mode & armed, 5, "armed heartbeat")

        wait_for(
            gcs,
            ["GLOBAL_POSITION_INT"],
            lambda m: 9_000 <= m.relative_alt <= 11_000 and abs(m.vz) < 20,
            20,
            "the copter holding 10 m +- 1 m",
        )

        assert command(gcs, mavlink2.MAV_CMD_NAV_LAND) == mavlink2.MAV_RESULT_ACCEPTED
        wait_for(gcs, ["HEARTBEAT"], lambda m: m.custom_mode == 9, 5, "LAND in the heartbeat")
        disarmed = wait_for(
            gcs,
            ["HEARTBEAT"],
            lambda m: not m.base_mode & armed,
            30,
            "the copter to land and disarm",
        )
        assert disarmed.system_status == mavlink2.MAV_STATE_STANDBY
        landed = wait_for(gcs, ["GLOBAL_POSITION_INT"], lambda m: True, 5, "a position")
        assert landed.relative_alt < 500
    log = "".join(iter_queue(lines))
    assert "Disarming motors" in log
    assert "stopped" in log


def iter_queue(lines: queue.Queue[str]) -> Iterator[str]:
    while True:
        try:
            yield lines.get_nowait()
        except queue.Empty:
            return


def test_refusals_reach_the_client_with_their_reason() -> None:
    with (
        simulator_process("--speedup", "1") as (port, _lines),
        mavlink_client(f"tcp:127.0.0.1:{port}") as gcs,
    ):
        wait_for(gcs, ["HEARTBEAT"], lambda m: True, 10, "a heartbeat")
        assert command(gcs, mavlink2.MAV_CMD_DO_SET_MODE, 1, 9) == 0  # LAND, disarmed: fine
        assert command(gcs, mavlink2.MAV_CMD_COMPONENT_ARM_DISARM, 1) == 4
        # the reason was sent before the ack; mavutil keeps the last STATUSTEXT
        text = gcs.messages["STATUSTEXT"]
        assert text.text == "Arm: LAND mode not armable"
        assert text.severity == mavlink2.MAV_SEVERITY_CRITICAL


def test_tcp_clients_come_and_go() -> None:
    config = SimulatorConfig(listen=ListenAddress("tcp", "127.0.0.1", 0), system_id=SYSID)
    with serving(config) as (_server, address):
        url = f"tcp:127.0.0.1:{address.port}"
        with mavlink_client(url) as first:
            with mavlink_client(url) as second:
                for client in (first, second):
                    wait_for(client, ["HEARTBEAT"], lambda m: True, 5, "a heartbeat")
                # garbage on the link is skipped; the command after it still gets through
                second.write(b"\xfd\x09garbage\x00\xff" * 20)
                assert command(second, mavlink2.MAV_CMD_DO_SET_MODE, 1, 5) == 0
                # only the sender gets the ack; everyone sees the new mode
                wait_for(first, ["HEARTBEAT"], lambda m: m.custom_mode == 5, 5, "LOITER")
            # the first client keeps its stream after the second one left
            wait_for(first, ["ATTITUDE"], lambda m: True, 5, "attitude")
        with mavlink_client(url) as third:
            hb = wait_for(third, ["HEARTBEAT"], lambda m: True, 5, "a heartbeat")
            assert hb.custom_mode == 5


def test_udp_answers_whoever_writes() -> None:
    config = SimulatorConfig(listen=ListenAddress("udp", "127.0.0.1", 0), system_id=SYSID)
    with (
        serving(config) as (_server, address),
        mavlink_client(f"udpout:127.0.0.1:{address.port}") as gcs,
    ):
        gcs.mav.heartbeat_send(mavlink2.MAV_TYPE_GCS, mavlink2.MAV_AUTOPILOT_INVALID, 0, 0, 0)
        wait_for(gcs, ["HEARTBEAT"], lambda m: True, 5, "a heartbeat over UDP")
        assert command(gcs, mavlink2.MAV_CMD_REQUEST_MESSAGE, 242) == 0
        home = wait_for(gcs, ["HOME_POSITION"], lambda m: True, 5, "home")
        assert home.altitude == 584_000


def test_stream_rates_are_per_sim_second_so_a_speedup_multiplies_them() -> None:
    config = SimulatorConfig(
        listen=ListenAddress("tcp", "127.0.0.1", 0), system_id=SYSID, speedup=10.0
    )
    with (
        serving(config) as (_server, address),
        mavlink_client(f"tcp:127.0.0.1:{address.port}") as gcs,
    ):
        first = wait_for(gcs, ["GLOBAL_POSITION_INT"], lambda m: True, 5, "a position")
        started = time.monotonic()
        count = 0
        last = first
        while time.monotonic() - started < 1.0:
            message = gcs.recv_match(type="GLOBAL_POSITION_INT", blocking=True, timeout=0.2)
            if message is not None:
                count += 1
                last = message
        assert 70 <= count <= 130  # 10 Hz of sim time: 100 a wall second
        # ... as sim time ran 10 times faster, and by the messages' own clock, 10 Hz
        sim_s = (last.time_boot_ms - first.time_boot_ms) / 1000.0
        assert sim_s > 7.0
        assert count / sim_s == pytest.approx(10.0, rel=0.1)


class _Nowhere(Link):
    """A client that hears nothing: the schedule is what counts."""

    def _write(self, frame: bytes) -> None:
        pass

    def close(self) -> None:
        pass


def test_the_tick_comes_when_the_next_stream_is_due() -> None:
    clock, wall = ManualClock(), [0.0]
    server = SimulatorServer(SimulatorConfig(speedup=10.0), clock=clock, wall_clock=lambda: wall[0])
    assert server._until_next_tick() == TICK_S  # no client: the physics' pace
    server.links.append(_Nowhere("gcs", SYSID, clock.now()))
    assert server._until_next_tick() == MIN_TICK_S  # everything due on connect
    server.tick()
    clock.advance(0.05)
    # GLOBAL_POSITION_INT (10 Hz) next, 0.05 sim s away: 5 ms of wall time at 10x
    assert server._until_next_tick() == pytest.approx(0.005)
    clock.advance(0.5)
    assert server._until_next_tick() == MIN_TICK_S  # late: caught up at once
    server._silent_until = 4.0
    assert server._until_next_tick() == TICK_S  # a reboot's silence: nothing to send


def test_cannot_listen_exits_1(capfd: pytest.CaptureFixture[str]) -> None:
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        result = subprocess.run(
            [sys.executable, "-m", "simulator", "--listen", f"tcp:127.0.0.1:{port}"],
            cwd=REPO_ROOT,
            capture_output=True,
            text=True,
            timeout=20,
        )
    assert result.returncode == 1
    assert "cannot listen" in result.stderr
