"""A flight as a MAVLink telemetry log (.tlog), the format QGroundControl and MAVProxy write.

Each record is the receive time as an 8-byte big-endian count of microseconds since
the Unix epoch, followed by one MAVLink 2 packet. The packets are rebuilt from the
stored samples, as if the vehicle (``flight.system_id``, component 1) had sent them:

* HEARTBEAT on the first sample, then whenever a second of log time has passed or
  the mode or arming state changed (so mode changes keep their exact time);
* GPS_RAW_INT, VFR_HUD and SYS_STATUS for every sample;
* GLOBAL_POSITION_INT for every sample with a position (:func:`sample_position`);
* STATUSTEXT for every event, merged in by time.

Unknown values use MAVLink's "unknown" encodings where the message defines one
(UINT16_MAX, -1, 255), NaN for floats, and 0 where MAVLink has no such value.
pymavlink is used only as a codec: ``mavutil`` is not imported here.
"""

from __future__ import annotations

import math
import struct
import unicodedata
from collections.abc import Iterable, Iterator
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from backend.exports.mav_modes import heartbeat_mode, mav_autopilot, mav_type
from backend.exports.samples import (
    ExportEvent,
    ExportFlight,
    ExportSample,
    finite,
    sample_position,
)
from protocol.mavlink_wire import FLOAT32_MAX

CHUNK_BYTES = 64 * 1024
HEARTBEAT_PERIOD_S = 1.0
_TIME_TOLERANCE_S = 1e-3  # unix times near 1.7e9 s carry rounding errors of ~1e-7 s
STATUSTEXT_MAX_BYTES = 50

_RECORD_TIME = struct.Struct(">Q")
_UINT16_UNKNOWN = 65535
_UINT8_UNKNOWN = 255
_NAN = math.nan


def _scaled(value: float | None, scale: float, low: int, high: int, unknown: int) -> int:
    """``round(value * scale)`` clamped into the field's range, ``unknown`` for None or NaN.

    Clamped before rounding: a stored value far out of range (an altitude of 1e308, from
    a hub that took such samples) overflows to infinity when scaled, and rounding that
    raised, ending the export with nothing written."""
    if value is None or math.isnan(value):
        return unknown
    return round(max(low, min(high, value * scale)))


def _int16(value: float) -> int:
    return _scaled(value, 1, -32768, 32767, 0)


def _int32(value: float | None, scale: float) -> int:
    return _scaled(value, scale, -(2**31), 2**31 - 1, 0)


def _float(value: float | None) -> float:
    """A float32 field's value; NaN (MAVLink's unknown) for None and for what no float32
    holds (packing 1e308 raised)."""
    if value is None or not -FLOAT32_MAX <= value <= FLOAT32_MAX:
        return _NAN
    return value


class _TlogWriter:
    """Packs messages as records with non-decreasing timestamps into a byte buffer."""

    def __init__(self, flight: ExportFlight) -> None:
        self._mav: Any = mavlink2.MAVLink(None, srcSystem=flight.system_id, srcComponent=1)
        self._last_usec = 0
        self.buffer = bytearray()

    def add(self, time: float, message: Any) -> None:
        usec = max(self._last_usec, round(time * 1e6)) if math.isfinite(time) else self._last_usec
        self._last_usec = usec
        self.buffer += _RECORD_TIME.pack(usec)
        self.buffer += message.pack(self._mav)

    def take(self) -> bytes:
        data = bytes(self.buffer)
        self.buffer.clear()
        return data


class _SampleEncoder:
    """Turns samples into the messages an autopilot would have sent."""

    def __init__(self, flight: ExportFlight) -> None:
        self._flight = flight
        self._type = mav_type(flight.vehicle_type)
        self._autopilot = mav_autopilot(flight.autopilot)
        self._last_heartbeat: tuple[float, str, bool] | None = None

    def messages(self, sample: ExportSample) -> Iterator[Any]:
        if self._heartbeat_due(sample):
            self._last_heartbeat = (sample.time, sample.mode, sample.armed)
            yield self._heartbeat(sample)
        position = sample_position(sample)
        yield self._gps_raw_int(sample, position)
        if position is not None:
            yield self._global_position_int(sample, position)
        yield self._vfr_hud(sample)
        yield self._sys_status(sample)

    def _heartbeat_due(self, sample: ExportSample) -> bool:
        if self._last_heartbeat is None:
            return True
        time, mode, armed = self._last_heartbeat
        changed = (mode, armed) != (sample.mode, sample.armed)
        return changed or abs(sample.time - time) >= HEARTBEAT_PERIOD_S - _TIME_TOLERANCE_S

    def _heartbeat(self, sample: ExportSample) -> Any:
        flight = self._flight
        base_mode, custom_mode = heartbeat_mode(flight.autopilot, flight.vehicle_type, sample.mode)
        if sample.armed:
            base_mode |= mavlink2.MAV_MODE_FLAG_SAFETY_ARMED
        status = mavlink2.MAV_STATE_ACTIVE if sample.armed else mavlink2.MAV_STATE_STANDBY
        return mavlink2.MAVLink_heartbeat_message(
            self._type, self._autopilot, base_mode, custom_mode, status, 3
        )

    def _global_position_int(self, sample: ExportSample, position: tuple[float, float]) -> Any:
        lat, lon = position
        speed, heading = finite(sample.groundspeed), finite(sample.heading_deg)
        vx = vy = 0
        if speed is not None and heading is not None:
            vx = _int16(speed * 100 * math.cos(math.radians(heading)))
            vy = _int16(speed * 100 * math.sin(math.radians(heading)))
        climb = finite(sample.climb_rate)
        return mavlink2.MAVLink_global_position_int_message(
            time_boot_ms=_scaled(sample.time - self._flight.start_time, 1000, 0, 2**32 - 1, 0),
            lat=_int32(lat, 1e7),
            lon=_int32(lon, 1e7),
            alt=_int32(finite(sample.alt_msl), 1000),
            relative_alt=_int32(finite(sample.alt_rel), 1000),
            vx=vx,
            vy=vy,
            vz=0 if climb is None else _int16(-climb * 100),  # MAVLink's z points down
            hdg=_UINT16_UNKNOWN if heading is None else round(heading % 360 * 100) % 36000,
        )

    def _gps_raw_int(self, sample: ExportSample, position: tuple[float, float] | None) -> Any:
        lat, lon = position if position is not None else (None, None)
        satellites = sample.satellites
        return mavlink2.MAVLink_gps_raw_int_message(
            time_usec=max(0, round(sample.time * 1e6)) if math.isfinite(sample.time) else 0,
            fix_type=max(0, min(255, sample.gps_fix)),
            lat=_int32(lat, 1e7),
            lon=_int32(lon, 1e7),
            alt=_int32(finite(sample.alt_msl), 1000),
            eph=_UINT16_UNKNOWN,
            epv=_UINT16_UNKNOWN,
            vel=_scaled(finite(sample.groundspeed), 100, 0, 65534, _UINT16_UNKNOWN),
            cog=_UINT16_UNKNOWN,  # course over ground is not stored, only heading
            satellites_visible=(
                _UINT8_UNKNOWN if satellites is None else max(0, min(254, satellites))
            ),
        )

    def _vfr_hud(self, sample: ExportSample) -> Any:
        heading = finite(sample.heading_deg)
        return mavlink2.MAVLink_vfr_hud_message(
            airspeed=_NAN,  # not stored
            groundspeed=_float(finite(sample.groundspeed)),
            heading=0 if heading is None else round(heading) % 360,
            throttle=0,
            alt=_float(finite(sample.alt_msl)),
            climb=_float(finite(sample.climb_rate)),
        )

    def _sys_status(self, sample: ExportSample) -> Any:
        return mavlink2.MAVLink_sys_status_message(
            onboard_control_sensors_present=0,
            onboard_control_sensors_enabled=0,
            onboard_control_sensors_health=0,
            load=0,
            voltage_battery=_scaled(
                finite(sample.battery_voltage), 1000, 0, 65534, _UINT16_UNKNOWN
            ),
            current_battery=-1,
            battery_remaining=_scaled(finite(sample.battery_remaining), 1, 0, 100, -1),
            drop_rate_comm=0,
            errors_comm=0,
            errors_count1=0,
            errors_count2=0,
            errors_count3=0,
            errors_count4=0,
        )


# What the hub's event texts use beyond ASCII, said in ASCII (the mode event's arrow):
# arrows, en and em dashes, the ellipsis and the degree sign.
_ASCII_SPELLINGS = str.maketrans(
    {
        "\u2192": "->",
        "\u2190": "<-",
        "\u2013": "-",
        "\u2014": "-",
        "\u2026": "...",
        "\u00b0": " deg",
    }
)


def mavlink_ascii(text: str) -> bytes:
    """``text`` for a MAVLink char[] field, which readers decode as ASCII (pymavlink, and
    so mavlogdump and MAVProxy, turn every other byte into U+FFFD): accents dropped
    (é -> e), a few symbols spelled out (→ -> "->"), anything else "?"."""
    spelled = unicodedata.normalize("NFKD", text.translate(_ASCII_SPELLINGS))
    bare = "".join(c for c in spelled if not unicodedata.combining(c))
    return bare.encode("ascii", errors="replace")


def _statustext(event: ExportEvent) -> Any:
    severity = mavlink2.MAV_SEVERITY_INFO if event.severity is None else event.severity
    text = mavlink_ascii(event.text or event.kind)[:STATUSTEXT_MAX_BYTES]
    return mavlink2.MAVLink_statustext_message(max(0, min(7, severity)), text)


def tlog_chunks(
    flight: ExportFlight,
    samples: Iterable[ExportSample],
    events: Iterable[ExportEvent],
    chunk_bytes: int = CHUNK_BYTES,
) -> Iterator[bytes]:
    """The .tlog bytes, in chunks of about ``chunk_bytes``.

    Samples stream through and are expected in time order, as the hub stores them;
    events (few) are read into a list and sorted. Record times never go backwards:
    a sample older than the previous record is logged at the previous record's time.
    """
    writer = _TlogWriter(flight)
    encoder = _SampleEncoder(flight)
    pending = sorted(events, key=lambda event: event.time)
    next_event = 0
    for sample in samples:
        while next_event < len(pending) and pending[next_event].time <= sample.time:
            writer.add(pending[next_event].time, _statustext(pending[next_event]))
            next_event += 1
        for message in encoder.messages(sample):
            writer.add(sample.time, message)
        if len(writer.buffer) >= chunk_bytes:
            yield writer.take()
    for event in pending[next_event:]:
        writer.add(event.time, _statustext(event))
    if writer.buffer:
        yield writer.take()
