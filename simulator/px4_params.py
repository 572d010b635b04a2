"""PX4 parameters the simulated multirotor reports when it plays PX4, by PX4's names.

PX4 has two parameter types, INT32 and FLOAT, and sends its integers bytewise (see
`param_wire`). The integers here are chosen to exercise that: MAV_SYS_ID (small),
COM_FLTMODE1 (-1, "unassigned", a NaN when read as a float), SDLOG_UTC_OFFSET (the
field trial's write of 60) and CAL_ACC0_ID (a device id in the millions). The floats map
onto the copter's own parameters where the meaning is the same.
"""

from __future__ import annotations

from simulator.param_table import ParamDef, ParamTable, ParamType
from simulator.params import CopterParams

INT32_MIN, INT32_MAX = -(2**31), 2**31 - 1

# Alphabetical, as PX4 indexes them.
PX4_PARAM_DEFS: tuple[ParamDef, ...] = (
    ParamDef("BAT1_CAPACITY", ParamType.REAL32, -1, 100_000, "batt_capacity"),
    ParamDef("CAL_ACC0_ID", ParamType.INT32, INT32_MIN, INT32_MAX, default=1310988),
    # The failsafe's delay in Hold before its action (the manual-control-loss one here)
    ParamDef("COM_FAIL_ACT_T", ParamType.REAL32, 0, 25, default=5.0),
    ParamDef("COM_FLTMODE1", ParamType.INT32, -1, 13, default=-1),
    ParamDef("COM_LOW_BAT_ACT", ParamType.INT32, 0, 3),  # reported, not simulated
    # Modes exempt from the manual-control-loss failsafe: bit 0 Mission, 1 Hold, 2 Offboard
    ParamDef("COM_RCL_EXCEPT", ParamType.INT32, 0, 31, default=0),
    # PX4 1.14's default: RC or MAVLink manual input, whichever comes first
    ParamDef("COM_RC_IN_MODE", ParamType.INT32, 0, 4, default=3),
    # Manual input this long silent is lost
    ParamDef("COM_RC_LOSS_T", ParamType.REAL32, 0, 35, default=0.5),
    ParamDef("MAV_SYS_ID", ParamType.INT32, 1, 250),
    ParamDef("MIS_TAKEOFF_ALT", ParamType.REAL32, 0, 80, default=2.5),
    ParamDef("MPC_XY_CRUISE", ParamType.REAL32, 3, 20, "wpnav_speed"),
    ParamDef("MPC_Z_VEL_MAX_DN", ParamType.REAL32, 0.5, 4, "wpnav_speed_dn"),
    ParamDef("MPC_Z_VEL_MAX_UP", ParamType.REAL32, 0.5, 8, "wpnav_speed_up"),
    ParamDef("NAV_DLL_ACT", ParamType.INT32, 0, 6),
    # The manual-control-loss failsafe's action: 0 none, 1 Hold, 2 Return, 3 Land
    ParamDef("NAV_RCL_ACT", ParamType.INT32, 0, 6, default=2),
    ParamDef("RTL_RETURN_ALT", ParamType.REAL32, 0, 150, "rtl_alt"),
    ParamDef("SDLOG_UTC_OFFSET", ParamType.INT32, -1000, 1000),
)


class Px4ParamTable(ParamTable):
    """The copter's parameters under PX4's names and types."""

    def __init__(self, params: CopterParams, system_id: int) -> None:
        super().__init__(params, system_id)
        self._defs = {d.name: d for d in PX4_PARAM_DEFS}
        self._names = [d.name for d in PX4_PARAM_DEFS]
        self._values = {d.name: _initial(d, params, system_id) for d in PX4_PARAM_DEFS}


def _initial(definition: ParamDef, params: CopterParams, system_id: int) -> float:
    if definition.field is not None:
        return float(getattr(params, definition.field)) / definition.scale
    if definition.name == "MAV_SYS_ID":
        return float(system_id)
    return float(definition.default or 0.0)
