"""Parameter and mission protocols over a real TCP socket, through pymavlink's mavutil."""

from __future__ import annotations

from typing import Any

from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from simulator import ListenAddress, SimulatorConfig
from simulator.params.table import PARAM_DEFS
from tests.support.simulators import SYSID, mavlink_client, serving, wait_for


def _config() -> SimulatorConfig:
    return SimulatorConfig(listen=ListenAddress("tcp", "127.0.0.1", 0), system_id=SYSID)


def _param(gcs: Any, name: str) -> Any:
    return wait_for(gcs, ["PARAM_VALUE"], lambda m: m.param_id == name, 5, f"{name}")


def test_parameter_protocol() -> None:
    with (
        serving(_config()) as (server, address),
        mavlink_client(f"tcp:127.0.0.1:{address.port}") as gcs,
    ):
        wait_for(gcs, ["HEARTBEAT"], lambda m: True, 5, "a heartbeat")
        gcs.mav.param_request_list_send(SYSID, 1)
        seen: dict[int, Any] = {}
        while len(seen) < len(PARAM_DEFS):
            value = wait_for(gcs, ["PARAM_VALUE"], lambda m: True, 5, "the parameter list")
            assert value.param_count == len(PARAM_DEFS)
            seen[value.param_index] = value
        assert sorted(seen) == list(range(len(PARAM_DEFS)))
        by_name = {v.param_id: v for v in seen.values()}
        assert by_name["WPNAV_SPEED"].param_value == 500.0
        assert by_name["RTL_ALT"].param_type == mavlink2.MAV_PARAM_TYPE_INT32
        assert by_name["SYSID_THISMAV"].param_value == SYSID

        gcs.mav.param_request_read_send(SYSID, 1, b"RTL_ALT", -1)
        assert _param(gcs, "RTL_ALT").param_value == 1500.0
        index = by_name["LAND_SPEED"].param_index
        gcs.mav.param_request_read_send(SYSID, 1, b"", index)
        assert _param(gcs, "LAND_SPEED").param_index == index

        gcs.mav.param_set_send(SYSID, 1, b"WPNAV_SPEED", 300.0, mavlink2.MAV_PARAM_TYPE_REAL32)
        echo = _param(gcs, "WPNAV_SPEED")
        assert (echo.param_value, echo.param_index) == (300.0, 65535)
        assert server.copter.params.wpnav_speed == 3.0

        # out of range: refused with a reason, the stored value echoed
        gcs.mav.param_set_send(SYSID, 1, b"WPNAV_SPEED", 99999.0, mavlink2.MAV_PARAM_TYPE_REAL32)
        text = wait_for(gcs, ["STATUSTEXT"], lambda m: "WPNAV_SPEED" in m.text, 5, "refusal")
        assert "out of range" in text.text
        assert _param(gcs, "WPNAV_SPEED").param_value == 300.0

        # an unknown name gets no answer; the next request is still answered
        gcs.mav.param_set_send(SYSID, 1, b"NO_SUCH_PARAM", 1.0, mavlink2.MAV_PARAM_TYPE_REAL32)
        gcs.mav.param_request_read_send(SYSID, 1, b"DISARM_DELAY", -1)
        first = wait_for(gcs, ["PARAM_VALUE"], lambda m: True, 5, "next PARAM_VALUE")
        assert first.param_id == "DISARM_DELAY"


def _item(seq: int, command: int, x: float = 0, y: float = 0, z: float = 0, **params: float) -> Any:
    frame = mavlink2.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT
    return mavutil.mavlink.MAVLink_mission_item_int_message(
        SYSID,
        1,
        seq,
        frame,
        command,
        0,
        1,
        params.get("p1", 0.0),
        params.get("p2", 0.0),
        params.get("p3", 0.0),
        params.get("p4", 0.0),
        int(x),
        int(y),
        z,
        0,
    )


def _upload(gcs: Any, items: list[Any]) -> int:
    gcs.mav.mission_count_send(SYSID, 1, len(items), 0)
    while True:
        message = wait_for(gcs, ["MISSION_REQUEST_INT", "MISSION_ACK"], lambda m: True, 5, "upload")
        if message.get_type() == "MISSION_ACK":
            return int(message.type)
        gcs.mav.send(items[message.seq])


def test_mission_protocol() -> None:
    with (
        serving(_config()) as (server, address),
        mavlink_client(f"tcp:127.0.0.1:{address.port}") as gcs,
    ):
        wait_for(gcs, ["HEARTBEAT"], lambda m: True, 5, "a heartbeat")
        lat, lon = -353632620, 1491652370
        items = [
            _item(0, mavlink2.MAV_CMD_NAV_WAYPOINT),
            _item(1, mavlink2.MAV_CMD_NAV_TAKEOFF, z=10),
            _item(2, mavlink2.MAV_CMD_NAV_WAYPOINT, lat + 1000, lon, 10),
            _item(3, mavlink2.MAV_CMD_NAV_RETURN_TO_LAUNCH),
        ]
        assert _upload(gcs, items) == mavlink2.MAV_MISSION_ACCEPTED
        assert server.copter.mission_count == 3
        current = wait_for(gcs, ["MISSION_CURRENT"], lambda m: True, 5, "MISSION_CURRENT")
        assert current.total == 3

        # download: item 0 is home
        gcs.mav.mission_request_list_send(SYSID, 1)
        count = wait_for(gcs, ["MISSION_COUNT"], lambda m: True, 5, "count")
        assert count.count == 4
        downloaded = []
        for seq in range(4):
            gcs.mav.mission_request_int_send(SYSID, 1, seq)
            downloaded.append(
                wait_for(gcs, ["MISSION_ITEM_INT"], lambda m, s=seq: m.seq == s, 5, "item")
            )
        gcs.mav.mission_ack_send(SYSID, 1, 0)
        assert (downloaded[0].x, downloaded[0].y, downloaded[0].z) == (lat, lon, 584.0)
        assert downloaded[2].command == mavlink2.MAV_CMD_NAV_WAYPOINT
        assert (downloaded[2].x, downloaded[2].z) == (lat + 1000, 10.0)

        # an unsupported command refuses the upload and keeps the mission
        bad = [items[0], _item(1, mavlink2.MAV_CMD_DO_SET_SERVO, p1=5, p2=1500)]
        assert _upload(gcs, bad) == mavlink2.MAV_MISSION_UNSUPPORTED
        assert server.copter.mission_count == 3

        gcs.mav.mission_set_current_send(SYSID, 1, 2)
        wait_for(gcs, ["MISSION_CURRENT"], lambda m: m.seq == 2, 5, "current 2")

        gcs.mav.mission_clear_all_send(SYSID, 1, 0)
        ack = wait_for(gcs, ["MISSION_ACK"], lambda m: True, 5, "clear ack")
        assert ack.type == mavlink2.MAV_MISSION_ACCEPTED
        assert server.copter.mission_count == 0
        gcs.mav.mission_request_list_send(SYSID, 1)
        assert wait_for(gcs, ["MISSION_COUNT"], lambda m: True, 5, "count").count == 0
