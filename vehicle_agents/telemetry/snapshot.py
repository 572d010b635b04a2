"""Assemble one telemetry snapshot from the latest MAVLink message of each type."""

from __future__ import annotations

import math
import time
from collections.abc import Mapping

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from protocol.messages import VehicleState
from vehicle_agents.fcu.link import FcuLink
from vehicle_agents.fcu.messages import MavMessage
from vehicle_agents.fcu.missions import mission_number
from vehicle_agents.fcu.modes import is_armed, mode_name
from vehicle_agents.telemetry import positioning
from vehicle_agents.telemetry.landed import landed_state
from vehicle_agents.telemetry.readiness import readiness

_UNKNOWN_INT16 = -1
_UINT16_UNKNOWN = 65535


def _system_status_name(status: int) -> str:
    entry = mavlink2.enums["MAV_STATE"].get(status)
    return entry.name.removeprefix("MAV_STATE_") if entry is not None else "UNKNOWN"


def mission_total(current: MavMessage) -> int | None:
    """The items of the mission on board, or None when there is none or it is unknown.

    MISSION_CURRENT.total is UINT16_MAX without a mission (PX4), 0 without one on
    ArduPilot (home is not counted), and 0 too from an autopilot that predates the field;
    mission_state NO_MISSION says the same. Without a known mission ``seq`` is no progress
    (PX4 reports item 0 then, which would read as "flying item 1")."""
    total = int(getattr(current, "total", 0) or 0)
    if int(getattr(current, "mission_state", 0) or 0) == mavlink2.MISSION_STATE_NO_MISSION:
        return None
    return total if 0 < total < _UINT16_UNKNOWN else None


def link_snapshot(link: FcuLink) -> VehicleState:
    """The state of the vehicle behind ``link``, with the link's own health."""
    state = snapshot(
        link.latest,
        link.connected,
        received_at=link.received_at,
        receive_errors=link.counters.receive_errors,
        autopilot=link.modes.autopilot if link.modes else "ardupilot",
        vehicle_type=link.modes.vehicle_type if link.modes else "multirotor",
    )
    ready = readiness(link.latest, link.statustexts, time.time())
    update: dict[str, object] = {"ready_to_fly": ready.ready, "not_ready_reason": ready.reason}
    heartbeat = link.latest.get("HEARTBEAT")
    if heartbeat is not None and link.modes is not None:
        listed = link.modes.name_of(int(heartbeat.custom_mode))
        if listed is not None:
            update["mode"] = listed  # the name the mode list and set_mode use
    return state.model_copy(update=update)


def snapshot(
    latest: Mapping[str, MavMessage],
    fcu_connected: bool,
    *,
    received_at: Mapping[str, float] | None = None,
    receive_errors: int = 0,
    autopilot: str = "ardupilot",
    vehicle_type: str = "multirotor",
    now: float | None = None,
) -> VehicleState:
    """A VehicleState from whatever has arrived; fields stay None until their message does.

    ``received_at`` (monotonic arrival times per message type) lets the position source
    skip receivers that went quiet; without it every message counts as fresh.
    """
    fields: dict[str, object] = {
        "fcu_connected": fcu_connected,
        "fcu_receive_errors": receive_errors,
    }
    if (heartbeat := latest.get("HEARTBEAT")) is not None:
        fields["mode"] = mode_name(heartbeat)
        fields["armed"] = is_armed(heartbeat)
        fields["system_status"] = _system_status_name(heartbeat.system_status)
    now = time.monotonic() if now is None else now
    if (position := positioning.global_position(latest, received_at, now)) is not None:
        fields["lat"] = position.lat / 1e7
        fields["lon"] = position.lon / 1e7
        fields["alt_msl"] = position.alt / 1000
        fields["alt_rel"] = position.relative_alt / 1000
        if position.hdg != _UINT16_UNKNOWN:
            fields["heading_deg"] = position.hdg / 100
        # cm/s north and east: a formation's leader is predicted forward along these
        fields["vn"] = position.vx / 100
        fields["ve"] = position.vy / 100
    if (hud := latest.get("VFR_HUD")) is not None:
        fields["groundspeed"] = float(hud.groundspeed)
        fields["climb_rate"] = float(hud.climb)
        fields.setdefault("heading_deg", float(hud.heading))
    if (attitude := latest.get("ATTITUDE")) is not None:
        fields["roll_deg"] = math.degrees(attitude.roll)
        fields["pitch_deg"] = math.degrees(attitude.pitch)
    if (status := latest.get("SYS_STATUS")) is not None:
        if status.voltage_battery != _UINT16_UNKNOWN:
            fields["battery_voltage"] = status.voltage_battery / 1000
        if status.current_battery != _UNKNOWN_INT16:
            fields["battery_current"] = status.current_battery / 100
        if status.battery_remaining != _UNKNOWN_INT16:
            fields["battery_remaining"] = float(status.battery_remaining)
    if (battery := latest.get("BATTERY_STATUS")) is not None and battery.battery_remaining >= 0:
        fields["battery_remaining"] = float(battery.battery_remaining)
    if (fix := positioning.choose(latest, received_at, now)) is not None:
        fields["position_source"] = fix.source
        fields["gps_fix"] = fix.fix_type
        fields["satellites"] = fix.satellites
    if (current := latest.get("MISSION_CURRENT")) is not None and (
        total := mission_total(current)
    ) is not None:
        fields["mission_current"] = mission_number(int(current.seq), autopilot)
        fields["mission_total"] = total
    if (home := latest.get("HOME_POSITION")) is not None:
        fields["home_lat"] = home.latitude / 1e7
        fields["home_lon"] = home.longitude / 1e7
        fields["home_alt_msl"] = home.altitude / 1000
    state = VehicleState.model_validate(fields)
    landed = landed_state(
        latest,
        received_at,
        now,
        armed=state.armed if heartbeat is not None else None,
        alt_rel=state.alt_rel,
        climb_rate=state.climb_rate,
        vehicle_type=vehicle_type,
    )
    if landed is None:
        return state
    return state.model_copy(update={"landed_state": landed[0], "landed_state_source": landed[1]})
