"""PX4 parameters the simulated multirotor reports when it plays PX4, by PX4's names.

PX4 has two parameter types, INT32 and FLOAT, and sends its integers bytewise (see
`wire`). The integers here are chosen to exercise that: MAV_SYS_ID (small),
COM_FLTMODE1 (-1, "unassigned", a NaN when read as a float), SDLOG_UTC_OFFSET (the
field trial's write of 60) and CAL_ACC0_ID (a device id in the millions). The floats map
onto the copter's own parameters where the meaning is the same.
"""

from __future__ import annotations

import json
import lzma
import math
import zlib

from simulator.params.table import ParamDef, ParamTable, ParamType, SetOutcome, wire_float
from simulator.params.values import CopterParams

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


# What PX4's parameter metadata (parameters.json, from each module's params.c/.yaml) says
# of the parameters above: short description, units, and the values of an enum.
PX4_PARAM_DOCS: dict[str, tuple[str, str | None, dict[int, str] | None]] = {
    "BAT1_CAPACITY": ("Battery 1 capacity", "mAh", None),
    "CAL_ACC0_ID": ("ID of the Accelerometer that the calibration is for", None, None),
    "COM_FAIL_ACT_T": (
        "Delay between failsafe condition triggered and failsafe reaction",
        "s",
        None,
    ),
    "COM_FLTMODE1": ("First flightmode slot (1000-1160)", None, None),
    "COM_LOW_BAT_ACT": ("Battery failsafe mode", None, None),
    "COM_RCL_EXCEPT": ("Manual control loss exceptions", None, None),
    "COM_RC_IN_MODE": (
        "Manual control input source configuration",
        None,
        {
            0: "RC Transmitter only",
            1: "MAVLink only",
            2: "RC and MAVLink with fallback",
            3: "RC or MAVLink keep first",
            4: "Disable manual control",
        },
    ),
    "COM_RC_LOSS_T": ("Manual control loss timeout", "s", None),
    "MAV_SYS_ID": ("MAVLink system ID", None, None),
    "MIS_TAKEOFF_ALT": ("Default take-off altitude", "m", None),
    "MPC_XY_CRUISE": ("Default horizontal velocity in autonomous modes", "m/s", None),
    "MPC_Z_VEL_MAX_DN": ("Maximum descent velocity", "m/s", None),
    "MPC_Z_VEL_MAX_UP": ("Maximum ascent velocity", "m/s", None),
    "NAV_DLL_ACT": ("Set data link loss failsafe mode", None, None),
    "NAV_RCL_ACT": (
        "Set RC loss failsafe mode",
        None,
        {
            0: "Disabled",
            1: "Hold mode",
            2: "Return mode",
            3: "Land mode",
            5: "Terminate",
            6: "Disarm",
        },
    ),
    "RTL_RETURN_ALT": ("Return mode return altitude", "m", None),
    "SDLOG_UTC_OFFSET": ("UTC offset (unit: min)", "min", None),
}


def parameters_json() -> dict[str, object]:
    """The parameter metadata document PX4 publishes, for the parameters above."""
    entries = []
    for definition in PX4_PARAM_DEFS:
        description, units, values = PX4_PARAM_DOCS[definition.name]
        entry: dict[str, object] = {
            "name": definition.name,
            "type": "Int32" if definition.is_integer else "Float",
            "default": definition.default if definition.default is not None else 0,
            "shortDesc": description,
            "min": definition.low,
            "max": definition.high,
        }
        if units is not None:
            entry["units"] = units
        if values is not None:
            entry["values"] = [{"value": v, "description": d} for v, d in values.items()]
        entries.append(entry)
    return {"version": 1, "parameters": entries}


GENERAL_METADATA_URI = "mftp://etc/extras/component_general.json.xz"
PARAMETERS_PATH = "etc/extras/parameters.json.xz"
COMP_METADATA_TYPE_PARAMETER = 1


def metadata_files() -> dict[str, bytes]:
    """The component metadata files PX4 keeps in its ROMFS (etc/extras), xz compressed as
    PX4's build makes them: the general file, naming the parameter file by its mftp://
    address and CRC32."""
    parameters = lzma.compress(json.dumps(parameters_json()).encode(), format=lzma.FORMAT_XZ)
    general = {
        "version": 1,
        "metadataTypes": [
            {
                "type": COMP_METADATA_TYPE_PARAMETER,
                "uri": f"mftp://{PARAMETERS_PATH}",
                "fileCrc": zlib.crc32(parameters),
            }
        ],
    }
    general_xz = lzma.compress(json.dumps(general).encode(), format=lzma.FORMAT_XZ)
    return {GENERAL_METADATA_URI.removeprefix("mftp://"): general_xz, PARAMETERS_PATH: parameters}


class Px4ParamTable(ParamTable):
    """The copter's parameters under PX4's names and types."""

    def __init__(self, params: CopterParams, system_id: int) -> None:
        super().__init__(params, system_id)
        self._defs = {d.name: d for d in PX4_PARAM_DEFS}
        self._names = [d.name for d in PX4_PARAM_DEFS]
        self._values = {d.name: _initial(d, params, system_id) for d in PX4_PARAM_DEFS}

    def set(self, name: str, value: float) -> SetOutcome:
        """PX4's param_set stores what it is given: no range is checked on the vehicle
        (the metadata's min, max and values are for the ground station to enforce)."""
        definition = self._defs.get(name)
        if definition is None:
            return SetOutcome.UNKNOWN
        if not math.isfinite(value):
            return SetOutcome.REFUSED
        self._values[name] = float(round(value)) if definition.is_integer else wire_float(value)
        return SetOutcome.STORED


def _initial(definition: ParamDef, params: CopterParams, system_id: int) -> float:
    if definition.field is not None:
        return float(getattr(params, definition.field)) / definition.scale
    if definition.name == "MAV_SYS_ID":
        return float(system_id)
    return float(definition.default or 0.0)
