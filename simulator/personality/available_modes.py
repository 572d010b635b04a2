"""The modes each autopilot lists in AVAILABLE_MODES (MAVLink's standard modes protocol)."""

from __future__ import annotations

from dataclasses import dataclass

from simulator.mavconst import (
    CopterMode,
    Px4AutoMode,
    Px4MainMode,
    Px4PosctlMode,
)


@dataclass(frozen=True)
class AvailableMode:
    """One entry of the autopilot's AVAILABLE_MODES list (MAVLink standard modes)."""

    custom_mode: int  # as HEARTBEAT carries it
    name: str  # empty for PX4's standard modes, which it names by standard_mode alone
    standard_mode: int = 0  # MAV_STANDARD_MODE; 0 NON_STANDARD
    properties: int = 0  # MAV_MODE_PROPERTY: 1 ADVANCED, 2 NOT_USER_SELECTABLE


ADVANCED = 1
NOT_USER_SELECTABLE = 2
# MAV_STANDARD_MODE values PX4 reports (mode_util::getStandardModeFromNavState)
STANDARD_POSITION_HOLD, STANDARD_ORBIT, STANDARD_ALTITUDE_HOLD = 1, 2, 4
STANDARD_SAFE_RECOVERY, STANDARD_MISSION, STANDARD_LAND, STANDARD_TAKEOFF = 5, 6, 7, 8


def _px4(main: int, sub: int = 0) -> int:
    return (main << 16) | (sub << 24)


# GCS_MAVLINK_Copter::send_available_mode of ArduCopter 4.7, for a standard build (no
# FLOWHOLD, FOLLOW, ZIGZAG, SYSTEMID, AUTOROTATE, TURTLE): its order, its mode numbers, its
# modes' own names, no properties, all NON_STANDARD. AUTO RTL comes first, as there.
ARDUCOPTER_AVAILABLE_MODES: tuple[AvailableMode, ...] = tuple(
    AvailableMode(int(mode), name)
    for mode, name in (
        (CopterMode.AUTO_RTL, "AUTO RTL"),
        (CopterMode.AUTO, "AUTO"),
        (CopterMode.ACRO, "ACRO"),
        (CopterMode.STABILIZE, "STABILIZE"),
        (CopterMode.ALT_HOLD, "ALT_HOLD"),
        (CopterMode.CIRCLE, "CIRCLE"),
        (CopterMode.LOITER, "LOITER"),
        (CopterMode.GUIDED, "GUIDED"),
        (CopterMode.LAND, "LAND"),
        (CopterMode.RTL, "RTL"),
        (CopterMode.DRIFT, "DRIFT"),
        (CopterMode.SPORT, "SPORT"),
        (CopterMode.FLIP, "FLIP"),
        (CopterMode.AUTOTUNE, "AUTOTUNE"),
        (CopterMode.POSHOLD, "POSHOLD"),
        (CopterMode.BRAKE, "BRAKE"),
        (CopterMode.THROW, "THROW"),
        (CopterMode.AVOID_ADSB, "AVOID_ADSB"),
        (CopterMode.GUIDED_NOGPS, "GUIDED_NOGPS"),
        (CopterMode.SMART_RTL, "SMARTRTL"),
    )
)

_M, _A = Px4MainMode, Px4AutoMode
PX4_EXTERNAL_MODES = 8  # NAVIGATION_STATE_EXTERNAL1..8
PX4_SUB_MODE_EXTERNAL1 = 11  # PX4_CUSTOM_SUB_MODE_EXTERNAL1, after VTOL_TAKEOFF (10)
# PX4's AVAILABLE_MODES stream for a multicopter (1.16): every valid nav state in nav
# state order (mode_util::getValidNavStates), custom_mode from get_px4_custom_mode, a name
# only for non-standard modes (mode_util::nav_state_names), ADVANCED for all but Altitude,
# Position and the external modes (mode_util::isAdvanced), and NOT_USER_SELECTABLE for
# Termination and for external modes no ROS 2 component registered ("(Mode not
# available)", ModeManagement::getModeStatus). No RATTITUDE, no RTGS: PX4 has neither.
PX4_AVAILABLE_MODES: tuple[AvailableMode, ...] = (
    AvailableMode(_px4(_M.MANUAL), "Manual", properties=ADVANCED),
    AvailableMode(_px4(_M.ALTCTL), "", STANDARD_ALTITUDE_HOLD),
    AvailableMode(_px4(_M.POSCTL), "", STANDARD_POSITION_HOLD),
    AvailableMode(_px4(_M.AUTO, _A.MISSION), "", STANDARD_MISSION, ADVANCED),
    AvailableMode(_px4(_M.AUTO, _A.LOITER), "Hold", properties=ADVANCED),
    AvailableMode(_px4(_M.AUTO, _A.RTL), "", STANDARD_SAFE_RECOVERY, ADVANCED),
    AvailableMode(_px4(_M.ACRO), "Acro", properties=ADVANCED),
    AvailableMode(_px4(_M.AUTO, _A.LAND), "Descend", properties=ADVANCED),
    AvailableMode(_px4(_M.MANUAL), "Termination", properties=ADVANCED | NOT_USER_SELECTABLE),
    AvailableMode(_px4(_M.OFFBOARD), "Offboard", properties=ADVANCED),
    AvailableMode(_px4(_M.STABILIZED), "Stabilized", properties=ADVANCED),
    AvailableMode(_px4(_M.AUTO, _A.TAKEOFF), "", STANDARD_TAKEOFF, ADVANCED),
    AvailableMode(_px4(_M.AUTO, _A.LAND), "", STANDARD_LAND, ADVANCED),
    AvailableMode(_px4(_M.AUTO, _A.FOLLOW_TARGET), "Follow Target", properties=ADVANCED),
    AvailableMode(_px4(_M.AUTO, _A.PRECLAND), "Precision Landing", properties=ADVANCED),
    AvailableMode(_px4(_M.POSCTL, Px4PosctlMode.ORBIT), "", STANDARD_ORBIT, ADVANCED),
    AvailableMode(_px4(_M.AUTO, _A.VTOL_TAKEOFF), "VTOL Takeoff", properties=ADVANCED),
    *(
        AvailableMode(
            _px4(_M.AUTO, PX4_SUB_MODE_EXTERNAL1 + index),
            "(Mode not available)",
            properties=NOT_USER_SELECTABLE,
        )
        for index in range(PX4_EXTERNAL_MODES)
    ),
)
