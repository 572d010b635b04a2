"""The ArduCopter parameters a GCS can read and write, by their MAVLink names and units.

Each entry maps one parameter (as ArduPilot names, types and scales it: centimetres,
centidegrees, milliseconds) onto a `CopterParams` field in SI units. Values are kept in
the MAVLink units, so what a GCS writes is what it reads back. Pure logic, no I/O.

Validation follows the parameter's documented range: ArduPilot itself stores most values
unchecked, but a value outside the range here is refused and the stored one echoed, so a
typo cannot make the simulated vehicle do something no real copter could.
"""

from __future__ import annotations

import dataclasses
import math
import struct
from dataclasses import dataclass
from enum import IntEnum, StrEnum
from typing import Any

from simulator.params.values import CopterParams

PARAM_ID_LEN = 16  # PARAM_VALUE.param_id: 16 chars, NUL-padded when shorter


class ParamType(IntEnum):
    """MAV_PARAM_TYPE values ArduPilot reports (AP_PARAM_INT8/INT16/INT32/FLOAT)."""

    INT8 = 2
    INT16 = 4
    INT32 = 6
    REAL32 = 9


@dataclass(frozen=True)
class ParamDef:
    name: str
    type: ParamType
    low: float
    high: float
    field: str | None = None  # CopterParams attribute; None: reported but not simulated
    scale: float = 1.0  # SI value = MAVLink value * scale
    default: float | None = None  # MAVLink units; None: the CopterParams default / scale

    @property
    def is_integer(self) -> bool:
        return self.type is not ParamType.REAL32


_CM = 0.01
_CDEG = math.pi / 18000.0

PARAM_DEFS: tuple[ParamDef, ...] = (
    ParamDef("ANGLE_MAX", ParamType.INT16, 1000, 8000, "angle_max", _CDEG),
    ParamDef("ATC_SLEW_YAW", ParamType.REAL32, 500, 18000, "yaw_rate_max", _CDEG),
    ParamDef("BATT_CAPACITY", ParamType.INT32, 100, 1_000_000, "batt_capacity"),
    ParamDef("BATT_FS_LOW_ACT", ParamType.INT8, 0, 2, "batt_fs_low_act"),
    ParamDef("BATT_LOW_MAH", ParamType.REAL32, 0, 1_000_000, "batt_low_mah"),
    ParamDef("BATT_LOW_TIMER", ParamType.INT8, 0, 120, "batt_low_timer"),
    ParamDef("BATT_LOW_VOLT", ParamType.REAL32, 0, 100, "batt_low_volt"),
    ParamDef("DISARM_DELAY", ParamType.INT8, 0, 127, "disarm_delay"),
    ParamDef("GUID_TIMEOUT", ParamType.REAL32, 0.1, 5.0, "guid_timeout"),
    ParamDef("LAND_ALT_LOW", ParamType.INT16, 100, 10000, "land_alt_low", _CM),
    ParamDef("LAND_SPEED", ParamType.INT16, 30, 200, "land_speed", _CM),
    ParamDef("LAND_SPEED_HIGH", ParamType.INT16, 0, 2500, "land_speed_high", _CM),
    ParamDef("LOIT_SPEED", ParamType.REAL32, 20, 3500, "loit_speed", _CM),
    ParamDef("MOT_SPOOL_TIME", ParamType.REAL32, 0.05, 2.0, "spool_time"),
    ParamDef("MOT_THST_HOVER", ParamType.REAL32, 0.2, 0.8, "hover_throttle"),
    ParamDef("PILOT_SPEED_DN", ParamType.INT16, 0, 500, "pilot_speed_dn", _CM),
    ParamDef("PILOT_SPEED_UP", ParamType.INT16, 50, 500, "pilot_speed_up", _CM),
    ParamDef("PSC_POSXY_P", ParamType.REAL32, 0.5, 2.0, "psc_posxy_p"),
    ParamDef("PSC_POSZ_P", ParamType.REAL32, 1.0, 3.0, "psc_posz_p"),
    ParamDef("RC_OVERRIDE_TIME", ParamType.REAL32, -1.0, 120.0, "rc_override_time"),
    ParamDef("RTL_ALT", ParamType.INT32, 200, 300000, "rtl_alt", _CM),
    ParamDef("RTL_CLIMB_MIN", ParamType.INT16, 0, 3000, "rtl_climb_min", _CM),
    ParamDef("RTL_CONE_SLOPE", ParamType.REAL32, 0.0, 10.0, "rtl_cone_slope"),
    ParamDef("RTL_LOIT_TIME", ParamType.INT32, 0, 60000, "rtl_loit_time", 0.001),
    # -1 is "none": a negative integer on the wire; reported, not simulated
    ParamDef("SERIAL2_PROTOCOL", ParamType.INT8, -1, 50, default=2),
    ParamDef("SIM_BATT_DRAIN", ParamType.REAL32, 0.0, 1000.0, "sim_batt_drain"),
    ParamDef("SIM_GPS_NOISE", ParamType.REAL32, 0.0, 100.0, "sim_gps_noise"),
    ParamDef("SIM_WIND_DIR", ParamType.REAL32, 0.0, 360.0, "sim_wind_dir"),
    ParamDef("SIM_WIND_SPD", ParamType.REAL32, 0.0, 30.0, "sim_wind_spd"),
    # takes effect at the next boot, as on the real vehicle: the simulator keeps the id
    # it was started with
    ParamDef("SYSID_MYGCS", ParamType.INT16, 1, 255, "sysid_mygcs"),
    ParamDef("SYSID_THISMAV", ParamType.INT16, 1, 255),
    ParamDef("WPNAV_ACCEL", ParamType.REAL32, 50, 500, "wpnav_accel", _CM),
    ParamDef("WPNAV_ACCEL_Z", ParamType.REAL32, 50, 500, "wpnav_accel_z", _CM),
    ParamDef("WPNAV_RADIUS", ParamType.REAL32, 5, 1000, "wpnav_radius", _CM),
    ParamDef("WPNAV_SPEED", ParamType.REAL32, 20, 2000, "wpnav_speed", _CM),
    ParamDef("WPNAV_SPEED_DN", ParamType.REAL32, 10, 500, "wpnav_speed_dn", _CM),
    ParamDef("WPNAV_SPEED_UP", ParamType.REAL32, 10, 1000, "wpnav_speed_up", _CM),
    ParamDef("WP_YAW_BEHAVIOR", ParamType.INT8, 0, 3, "wp_yaw_behavior"),
)


class SetOutcome(StrEnum):
    STORED = "stored"
    UNKNOWN = "unknown"  # no such parameter: ArduPilot answers nothing
    REFUSED = "refused"  # out of range or not a number: the stored value is echoed


def wire_float(value: float) -> float:
    """``value`` as PARAM_VALUE carries it (float32)."""
    return float(struct.unpack("<f", struct.pack("<f", value))[0])


class ParamTable:
    """Parameter values in MAVLink units, in ArduPilot's (alphabetical) index order."""

    def __init__(self, params: CopterParams | None = None, system_id: int = 1) -> None:
        base = params or CopterParams()
        self._defs = {d.name: d for d in PARAM_DEFS}
        self._names = [d.name for d in PARAM_DEFS]
        self._values: dict[str, float] = {}
        for d in PARAM_DEFS:
            if d.field is not None:
                self._values[d.name] = wire_float(float(getattr(base, d.field)) / d.scale)
            elif d.name == "SYSID_THISMAV":
                self._values[d.name] = float(system_id)
            else:
                self._values[d.name] = float(d.default or 0.0)

    @property
    def count(self) -> int:
        return len(self._names)

    def names(self) -> list[str]:
        return list(self._names)

    def index(self, name: str) -> int | None:
        return self._names.index(name) if name in self._defs else None

    def name_at(self, index: int) -> str | None:
        return self._names[index] if 0 <= index < len(self._names) else None

    def definition(self, name: str) -> ParamDef:
        return self._defs[name]

    def get(self, name: str) -> float | None:
        return self._values.get(name)

    def set(self, name: str, value: float) -> SetOutcome:
        definition = self._defs.get(name)
        if definition is None:
            return SetOutcome.UNKNOWN
        if not math.isfinite(value):
            return SetOutcome.REFUSED
        if definition.is_integer:
            value = float(round(value))
        if not definition.low <= value <= definition.high:
            return SetOutcome.REFUSED
        # an integer is stored as the integer (PX4's travel bytewise, exactly)
        self._values[name] = value if definition.is_integer else wire_float(value)
        return SetOutcome.STORED

    def apply(self, name: str, params: CopterParams) -> CopterParams:
        """``params`` with the field behind ``name`` set from its stored value."""
        definition = self._defs[name]
        if definition.field is None:
            return params
        value = self._values[name]
        change: dict[str, Any] = {definition.field: value * definition.scale}
        if isinstance(getattr(params, definition.field), int):
            change[definition.field] = int(value)
        return dataclasses.replace(params, **change)
