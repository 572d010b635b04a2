"""The agent's mode tables: the fixed fallback, and the autopilot's own list read into one."""

from __future__ import annotations

from pymavlink.dialects.v20 import ardupilotmega as mavlink2
from pymavlink.dialects.v20 import development

from simulator.personality.available_modes import (
    ARDUCOPTER_AVAILABLE_MODES,
    PX4_AVAILABLE_MODES,
    AvailableMode,
)
from vehicle_agents.fcu.modes import (
    ModeSetting,
    mode_table_for,
    reported_mode,
    reported_table,
    shows_mode,
)


def heartbeat(autopilot: int, mav_type: int) -> mavlink2.MAVLink_heartbeat_message:
    return mavlink2.MAVLink_heartbeat_message(mav_type, autopilot, 0, 0, 0, 3)


def listed(modes: tuple[AvailableMode, ...]) -> list[object]:
    """The simulator's list as the agent decodes it off the wire."""
    return [
        reported_mode(
            development.MAVLink_available_modes_message(
                len(modes), i + 1, m.standard_mode, m.custom_mode, m.properties, m.name.encode()
            )
        )
        for i, m in enumerate(modes)
    ]


def test_the_fallback_tables_list_no_mode_the_autopilots_lack() -> None:
    px4 = mode_table_for(heartbeat(mavlink2.MAV_AUTOPILOT_PX4, mavlink2.MAV_TYPE_QUADROTOR))
    assert not {"RATTITUDE", "RTGS"} & set(px4.names)
    assert {"MISSION", "POSCTL", "LOITER", "OFFBOARD"} <= set(px4.names)
    quad = mode_table_for(
        heartbeat(mavlink2.MAV_AUTOPILOT_ARDUPILOTMEGA, mavlink2.MAV_TYPE_QUADROTOR)
    )
    lacking = {"ZIGZAG", "FOLLOW", "SYSTEMID", "TURTLE", "FLOWHOLD", "AUTOROTATE"}
    assert not (lacking | {"POSITION", "OF_LOITER"}) & set(quad.names)
    assert {"AUTO", "GUIDED", "LOITER", "BRAKE", "SMART_RTL"} <= set(quad.names)
    heli = mode_table_for(
        heartbeat(mavlink2.MAV_AUTOPILOT_ARDUPILOTMEGA, mavlink2.MAV_TYPE_HELICOPTER)
    )
    assert "AUTOROTATE" in heli.names
    assert not heli.reported


def test_px4s_list_keeps_pymavlinks_names_and_drops_what_a_user_may_not_select() -> None:
    table = reported_table(
        "px4",
        mavlink2.MAV_TYPE_QUADROTOR,
        listed(PX4_AVAILABLE_MODES),  # type: ignore[arg-type]
    )
    assert table.reported
    assert table.settings["MISSION"] == ModeSetting(29, 4, 4)  # as pymavlink encodes it
    assert table.settings["ORBIT"] == ModeSetting(1, 3, 1)  # a standard mode: no name sent
    assert table.settings["PRECISION_LANDING"] == ModeSetting(1, 4, 9)  # PX4's own name
    assert "TERMINATION" not in table.names
    assert not any(name.startswith("MODE_NOT") for name in table.names)  # unregistered
    # A HEARTBEAT in a mode pymavlink cannot name gets the listed name (it says POSCTL).
    assert table.name_of((3 << 16) | (1 << 24)) == "ORBIT"
    assert table.name_of((4 << 16) | (9 << 24)) == "PRECISION_LANDING"
    assert table.name_of((4 << 16) | (1 << 24)) is None  # AUTO.READY: not listed
    assert shows_mode("px4", (4 << 16) | (3 << 24), table.settings["LOITER"])
    assert not shows_mode("px4", (4 << 16) | (3 << 24), table.settings["OFFBOARD"])


def test_arducopters_list_names_its_modes_as_pymavlink_does() -> None:
    table = reported_table(
        "ardupilot",
        mavlink2.MAV_TYPE_QUADROTOR,
        listed(ARDUCOPTER_AVAILABLE_MODES),  # type: ignore[arg-type]
    )
    assert {"AUTO_RTL", "SMART_RTL"} <= set(table.names)  # sent as "AUTO RTL", "SMARTRTL"
    assert "ZIGZAG" not in table.names
    assert table.settings["GUIDED"] == ModeSetting(1, 4)
    assert shows_mode("ardupilot", 4, table.settings["GUIDED"])
