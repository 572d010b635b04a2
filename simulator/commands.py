"""Incoming MAVLink to vehicle calls, and the replies the autopilot would send.

No I/O: `MessageHandler.handle` takes one decoded message and returns `Reply` objects
(a COMMAND_ACK and requested messages go back to the sender only; STATUSTEXTs go to
everyone, as ArduPilot sends them on every link). Semantics follow GCS_Common.cpp and
GCS_Mavlink.cpp of ArduPilot 4.x; COMMAND_LONG is handled as ArduPilot does, by reading
it as a COMMAND_INT in the MAV_FRAME_GLOBAL_RELATIVE_ALT frame (MAV_FRAME_GLOBAL, above
mean sea level, for DO_SET_HOME). What differs by vehicle or autopilot (modes, take-off,
which answer a refusal gets) is the vehicle's to decide.

A reboot is accepted by the vehicle and carried out by the transport, which sends the
COMMAND_ACK first, as ArduPilot acknowledges before it restarts.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, replace
from typing import Any, Protocol

from simulator.mavconst import (
    DO_REPOSITION_FLAGS_CHANGE_MODE,
    FORCE_ARM_MAGIC,
    FORCE_DISARM_MAGIC,
    FORCE_REBOOT_MAGIC,
    POSITION_TARGET_IGNORE_POSITION,
    MavCmd,
    MavFrame,
    MavMissionResult,
    MavResult,
    Severity,
)
from simulator.mission import (
    HOME_PLACEHOLDER,
    MAX_ITEMS,
    MissionItem,
    check_item,
    px4_download_frame,
    stored_frame,
)
from simulator.param_table import SetOutcome
from simulator.param_wire import received_value
from simulator.telemetry import MavMessage, TelemetryBuilder
from simulator.vehicle import Vehicle

log = logging.getLogger(__name__)

INT32_MAX = 2**31 - 1
MSG_ID_SET_MODE = 11  # ArduPilot acknowledges SET_MODE with a COMMAND_ACK for "command" 11

_GLOBAL_FRAMES = frozenset({MavFrame.GLOBAL, MavFrame.GLOBAL_INT})
_RELATIVE_FRAMES = frozenset(
    {
        MavFrame.GLOBAL_RELATIVE_ALT,
        MavFrame.GLOBAL_RELATIVE_ALT_INT,
        # flat simulated world: terrain altitude is altitude above home
        MavFrame.GLOBAL_TERRAIN_ALT,
        MavFrame.GLOBAL_TERRAIN_ALT_INT,
    }
)

# Commands whose COMMAND_INT frame says where the position is (PX4 checks it).
_POSITION_COMMANDS = frozenset({MavCmd.DO_REPOSITION, MavCmd.DO_SET_HOME})


@dataclass(frozen=True)
class Reply:
    message: MavMessage
    to_sender_only: bool = True


class StreamControl(Protocol):
    """The sending connection's telemetry schedule (for SET/GET_MESSAGE_INTERVAL)."""

    def interval(self, msg_id: int) -> float | None: ...

    def set_interval(self, msg_id: int, interval_s: float | None, now: float) -> None: ...

    def reset_interval(self, msg_id: int, now: float) -> None: ...


@dataclass(frozen=True)
class Command:
    """COMMAND_LONG or COMMAND_INT, in COMMAND_INT's terms."""

    command: int
    param1: float
    param2: float
    param3: float
    param4: float
    x: float  # latitude in degrees for global frames (COMMAND_INT's x / 1e7)
    y: float
    z: float
    frame: int
    x_unset: bool = False  # COMMAND_INT sent INT32_MAX / COMMAND_LONG sent NaN
    raw_y: float = 0.0  # param6 as sent, for commands where it is a number, not a position

    @classmethod
    def from_long(cls, msg: Any) -> Command:
        command = int(msg.command)
        # DO_SET_HOME's altitude is above mean sea level; the rest are above home
        frame = MavFrame.GLOBAL if command == MavCmd.DO_SET_HOME else MavFrame.GLOBAL_RELATIVE_ALT
        return cls(
            command,
            float(msg.param1),
            float(msg.param2),
            float(msg.param3),
            float(msg.param4),
            float(msg.param5),
            float(msg.param6),
            float(msg.param7),
            frame,
            x_unset=math.isnan(msg.param5) or math.isnan(msg.param6),
            raw_y=float(msg.param6),
        )

    @classmethod
    def from_int(cls, msg: Any) -> Command:
        return cls(
            int(msg.command),
            float(msg.param1),
            float(msg.param2),
            float(msg.param3),
            float(msg.param4),
            int(msg.x) / 1e7,
            int(msg.y) / 1e7,
            float(msg.z),
            int(msg.frame),
            x_unset=int(msg.x) == INT32_MAX or int(msg.y) == INT32_MAX,
            raw_y=float(msg.y),
        )


MISSION_TYPE_MISSION = 0  # MAV_MISSION_TYPE_MISSION: fences and rally points are not simulated
_MISSION_MESSAGES = frozenset(
    {
        "MISSION_COUNT",
        "MISSION_ITEM_INT",
        "MISSION_ITEM",
        "MISSION_REQUEST_LIST",
        "MISSION_REQUEST_INT",
        "MISSION_REQUEST",
        "MISSION_CLEAR_ALL",
        "MISSION_SET_CURRENT",
        "MISSION_ACK",
    }
)


@dataclass
class _Upload:
    """A mission upload in progress (MissionItemProtocol's receiving state)."""

    count: int
    items: list[MissionItem]
    peer: tuple[int, int]


class MessageHandler:
    """Dispatches one vehicle's incoming messages."""

    def __init__(
        self,
        copter: Vehicle,
        telemetry: TelemetryBuilder,
        system_id: int,
        component_id: int = 1,
    ) -> None:
        self.copter = copter
        self.telemetry = telemetry
        self.system_id = system_id
        self.component_id = component_id
        self._upload: _Upload | None = None

    def handle(self, msg: Any, streams: StreamControl, now: float) -> list[Reply]:
        """Replies to ``msg``; ``now`` is the wall clock, for stream scheduling."""
        kind = msg.get_type()
        if kind == "COMMAND_LONG":
            if not self._for_us(msg.target_system):
                return []
            return self._command(Command.from_long(msg), msg, streams, now)
        if kind == "COMMAND_INT":
            if not self._for_us(msg.target_system):
                return []
            command = Command.from_int(msg)
            if command.command in _POSITION_COMMANDS and not self.copter.position_frame_ok(
                command.frame
            ):
                result = MavResult.COMMAND_UNSUPPORTED_MAV_FRAME
                return self._finish(command.command, result, msg)
            return self._command(command, msg, streams, now)
        if kind == "SET_MODE":
            if not self._for_us(msg.target_system):
                return []
            result = self.copter.request_mode_encoded(int(msg.base_mode), int(msg.custom_mode))
            return self._finish(MSG_ID_SET_MODE, result, msg)
        if kind in ("PARAM_REQUEST_LIST", "PARAM_REQUEST_READ", "PARAM_SET"):
            if not self._for_us(msg.target_system):
                return []
            return self._param(kind, msg)
        if kind in _MISSION_MESSAGES:
            if not self._for_us(msg.target_system):
                return []
            return self._mission(kind, msg)
        if kind == "SET_POSITION_TARGET_GLOBAL_INT":
            if self._for_us(msg.target_system):
                self._position_target(msg)
            return self._texts()
        # HEARTBEAT, REQUEST_DATA_STREAM (accepted and ignored: streams keep their rates),
        # and anything else the simulator does not model
        return []

    def _for_us(self, target_system: int) -> bool:
        return target_system in (0, self.system_id)

    # -- commands ------------------------------------------------------------

    def _command(self, cmd: Command, msg: Any, streams: StreamControl, now: float) -> list[Reply]:
        log.debug(
            "command %d from %d/%d: %s",
            cmd.command,
            msg.get_srcSystem(),
            msg.get_srcComponent(),
            cmd,
        )
        copter = self.copter
        extra_before: list[Reply] = []
        extra_after: list[Reply] = []
        match cmd.command:
            case MavCmd.COMPONENT_ARM_DISARM:
                if cmd.param1 == 1.0:
                    result = copter.arm(force=cmd.param2 == FORCE_ARM_MAGIC)
                elif cmd.param1 == 0.0:
                    result = copter.disarm(force=cmd.param2 == FORCE_DISARM_MAGIC)
                else:
                    result = MavResult.UNSUPPORTED
            case MavCmd.NAV_TAKEOFF:
                result = copter.nav_takeoff(cmd.z, cmd.frame)
            case MavCmd.NAV_LAND:
                result = copter.nav_land()
            case MavCmd.NAV_RETURN_TO_LAUNCH:
                result = copter.return_to_launch()
            case MavCmd.DO_SET_MODE:
                result = copter.request_mode(
                    _as_int(cmd.param1), _as_int(cmd.param2), _as_int(cmd.param3)
                )
            case MavCmd.DO_REPOSITION:
                result = self._reposition(cmd)
            case MavCmd.DO_CHANGE_SPEED:
                result = copter.change_speed(_as_int(cmd.param1), cmd.param2)
            case MavCmd.DO_SET_HOME:
                result = self._set_home(cmd)
                if result is MavResult.ACCEPTED:
                    # Copter::set_home sends the new home to every GCS straight away
                    extra_after.append(Reply(self.telemetry.home_position(), False))
            case MavCmd.PREFLIGHT_REBOOT_SHUTDOWN:
                result = copter.request_reboot(cmd.param1, force=cmd.raw_y == FORCE_REBOOT_MAGIC)
            case MavCmd.REQUEST_MESSAGE:
                requested = self.telemetry.build(_as_int(cmd.param1))
                result = MavResult.ACCEPTED if requested is not None else MavResult.FAILED
                if requested is not None:
                    extra_after.append(Reply(requested))
            case MavCmd.GET_HOME_POSITION:
                extra_before.append(Reply(self.telemetry.home_position()))
                result = MavResult.ACCEPTED
            case MavCmd.REQUEST_AUTOPILOT_CAPABILITIES:
                result = MavResult.ACCEPTED if cmd.param1 == 1.0 else MavResult.FAILED
                if result is MavResult.ACCEPTED:
                    extra_after.append(Reply(self.telemetry.autopilot_version()))
            case MavCmd.SET_MESSAGE_INTERVAL:
                result = self._set_message_interval(cmd, streams, now)
            case MavCmd.GET_MESSAGE_INTERVAL:
                msg_id = _as_int(cmd.param1)
                interval = streams.interval(msg_id)
                interval_us = -1 if interval is None else round(interval * 1e6)
                if msg_id not in self.telemetry.supported:
                    interval_us = 0
                extra_after.append(Reply(self.telemetry.message_interval(msg_id, interval_us)))
                result = MavResult.ACCEPTED
            case _:
                result = MavResult.UNSUPPORTED
        return extra_before + self._finish(cmd.command, result, msg) + extra_after

    def _finish(self, command: int, result: MavResult, msg: Any) -> list[Reply]:
        """STATUSTEXTs the command caused, then its COMMAND_ACK to the sender."""
        if result is not MavResult.ACCEPTED:
            log.info("command %d from sysid %d: %s", command, msg.get_srcSystem(), result.name)
        ack = self.telemetry.command_ack(
            command, result, msg.get_srcSystem(), msg.get_srcComponent()
        )
        return [*self._texts(), Reply(ack)]

    def _texts(self) -> list[Reply]:
        replies = []
        for text in self.copter.drain_texts():
            log.info("STATUSTEXT %s: %s", text.severity.name, text.text)
            replies.append(Reply(self.telemetry.statustext(text), to_sender_only=False))
        return replies

    def _set_home(self, cmd: Command) -> MavResult:
        """GCS_MAVLINK::handle_command_do_set_home: param1=1, or no position given, is
        the current location; otherwise the point, its altitude above mean sea level."""
        if cmd.param1 == 1.0 or cmd.x_unset or (cmd.x == 0.0 and cmd.y == 0.0):
            return self.copter.set_home_here()
        if cmd.frame in _GLOBAL_FRAMES:
            alt_msl = cmd.z
        elif cmd.frame in _RELATIVE_FRAMES:
            alt_msl = cmd.z + self.copter.home.alt
        else:
            return MavResult.DENIED
        return self.copter.set_home_to(cmd.x, cmd.y, alt_msl)

    def _set_message_interval(self, cmd: Command, streams: StreamControl, now: float) -> MavResult:
        msg_id = _as_int(cmd.param1)
        if msg_id not in self.telemetry.supported:
            return MavResult.DENIED
        interval_us = cmd.param2
        if interval_us == 0.0:
            streams.reset_interval(msg_id, now)
        elif interval_us < 0.0:
            streams.set_interval(msg_id, None, now)
        else:
            streams.set_interval(msg_id, interval_us / 1e6, now)
        return MavResult.ACCEPTED

    # -- parameters ----------------------------------------------------------

    def _param(self, kind: str, msg: Any) -> list[Reply]:
        """The parameter protocol as GCS_Param.cpp answers it."""
        table = self.copter.param_table
        if kind == "PARAM_REQUEST_LIST":
            return [
                Reply(self.telemetry.param_value(name, index))
                for index, name in enumerate(table.names())
            ]
        name = _param_name(msg.param_id)
        if kind == "PARAM_REQUEST_READ":
            index = int(msg.param_index)
            if index >= 0:  # -1: by name
                found = table.name_at(index)
                if found is None:
                    return []
                name = found
            found_index = table.index(name)
            if found_index is None:
                return []  # ArduPilot stays silent about a parameter it does not have
            return [Reply(self.telemetry.param_value(name, found_index))]
        definition = table.definition(name) if table.index(name) is not None else None
        sent_type = int(definition.type) if definition is not None else int(msg.param_type)
        outcome = self.copter.set_param(
            name, received_value(msg, sent_type, self.copter.param_bytewise)
        )
        if outcome is SetOutcome.UNKNOWN:
            log.info("PARAM_SET of unknown parameter %r ignored", name)
            return []
        replies = []
        if outcome is SetOutcome.REFUSED:
            definition = table.definition(name)
            text = f"Param {name}: {msg.param_value:g} out of range"
            replies.append(
                Reply(
                    self.telemetry.statustext_of(Severity.WARNING, text),
                    to_sender_only=False,
                )
            )
            log.info("%s (%g..%g)", text, definition.low, definition.high)
        # the stored value, on every link, as ArduPilot announces a parameter change
        replies.append(Reply(self.telemetry.param_value(name), to_sender_only=False))
        return [*self._texts(), *replies]

    # -- missions ------------------------------------------------------------

    def _mission(self, kind: str, msg: Any) -> list[Reply]:
        """The mission microservice as MissionItemProtocol_Waypoints answers it."""
        peer = (msg.get_srcSystem(), msg.get_srcComponent())
        mission_type = int(getattr(msg, "mission_type", 0))
        if kind == "MISSION_ACK":
            return []  # the end of a download: nothing to answer
        offset = self.copter.mission_wire_offset
        if kind == "MISSION_SET_CURRENT":
            if self.copter.set_mission_current(int(msg.seq) + offset):
                return [*self._texts(), Reply(self.telemetry.mission_current(), False)]
            return self._texts()
        if mission_type != MISSION_TYPE_MISSION:
            return [self._mission_ack(MavMissionResult.UNSUPPORTED, peer)]
        copter = self.copter
        telemetry = self.telemetry
        if kind == "MISSION_REQUEST_LIST":
            on_wire = max(0, len(copter.mission) - offset)
            return [Reply(telemetry.mission_count(on_wire, *peer))]
        if kind in ("MISSION_REQUEST_INT", "MISSION_REQUEST"):
            item = copter.mission_item(int(msg.seq) + offset)
            if item is None:
                return [self._mission_ack(MavMissionResult.INVALID_SEQUENCE, peer)]
            frame = px4_download_frame(item.frame) if offset else item.frame
            answer = replace(item, seq=int(msg.seq), frame=frame)
            return [Reply(telemetry.mission_item_int(answer, *peer))]
        if kind == "MISSION_CLEAR_ALL":
            cleared = copter.clear_mission()
            self._upload = None
            result = MavMissionResult.ACCEPTED if cleared else MavMissionResult.ERROR
            return [self._mission_ack(result, peer)]
        if kind == "MISSION_COUNT":
            return self._mission_count(int(msg.count), peer)
        return self._mission_item(msg, kind == "MISSION_ITEM_INT", peer)

    def _mission_ack(self, result: MavMissionResult, peer: tuple[int, int]) -> Reply:
        return Reply(self.telemetry.mission_ack(int(result), *peer))

    def _mission_count(self, count: int, peer: tuple[int, int]) -> list[Reply]:
        if count == 0:
            self._upload = None
            if not self.copter.clear_mission():
                return [self._mission_ack(MavMissionResult.ERROR, peer)]
            return [self._mission_ack(MavMissionResult.ACCEPTED, peer)]
        if count > MAX_ITEMS:
            return [self._mission_ack(MavMissionResult.NO_SPACE, peer)]
        # a new MISSION_COUNT restarts any upload in progress
        self._upload = _Upload(count, [], peer)
        return [Reply(self.telemetry.mission_request_int(0, *peer))]

    def _mission_item(self, msg: Any, is_int: bool, peer: tuple[int, int]) -> list[Reply]:
        upload = self._upload
        if upload is None or upload.peer != peer:
            return [self._mission_ack(MavMissionResult.DENIED, peer)]
        seq = int(msg.seq)
        expected = len(upload.items)
        if seq != expected:
            if seq < expected:
                return []  # a repeat of an item already stored: the next request stands
            return [self._mission_ack(MavMissionResult.INVALID_SEQUENCE, peer)]
        x, y = (int(msg.x), int(msg.y)) if is_int else _legacy_xy(msg)
        item = MissionItem(
            seq,
            int(msg.frame),
            int(msg.command),
            float(msg.param1),
            float(msg.param2),
            float(msg.param3),
            float(msg.param4),
            x,
            y,
            float(msg.z),
            int(msg.autocontinue),
        )
        problem = check_item(item)
        if problem is not None:
            # the upload is abandoned; the stored mission is unchanged
            self._upload = None
            result = (
                MavMissionResult.UNSUPPORTED_FRAME
                if problem == "frame"
                else MavMissionResult.UNSUPPORTED
            )
            log.info("mission item %d (command %d) refused: %s", seq, item.command, problem)
            return [self._mission_ack(result, peer)]
        upload.items.append(replace(item, frame=stored_frame(item.frame)))
        if len(upload.items) < upload.count:
            return [Reply(self.telemetry.mission_request_int(len(upload.items), *peer))]
        self._upload = None
        items = upload.items
        if self.copter.mission_wire_offset:
            # PX4's item 0 is the first real one: home goes in front, as stored here.
            items = [HOME_PLACEHOLDER] + [replace(i, seq=i.seq + 1) for i in items]
        self.copter.set_mission(items)
        text = self.telemetry.statustext_of(Severity.INFO, "Flight plan received")
        return [
            self._mission_ack(MavMissionResult.ACCEPTED, peer),
            Reply(text, to_sender_only=False),
        ]

    # -- guided targets ------------------------------------------------------

    def _relative_alt(self, frame: int, alt: float) -> float | None:
        if frame in _RELATIVE_FRAMES:
            return alt
        if frame in _GLOBAL_FRAMES:
            return alt - self.copter.home.alt
        return None

    def _reposition(self, cmd: Command) -> MavResult:
        """GCS_MAVLINK_Copter::handle_command_int_do_reposition."""
        copter = self.copter
        change_mode = bool(_as_int(cmd.param2) & DO_REPOSITION_FLAGS_CHANGE_MODE)
        if not copter.in_guided and not change_mode:
            return MavResult.DENIED
        here = copter.position()
        lat, lon = (here.lat, here.lon) if cmd.x_unset else (cmd.x, cmd.y)
        if not (-90.0 <= lat <= 90.0 and -180.0 <= lon <= 180.0):
            return MavResult.DENIED
        alt = copter.relative_alt if math.isnan(cmd.z) else self._relative_alt(cmd.frame, cmd.z)
        if alt is None:
            return MavResult.DENIED
        if not copter.in_guided and copter.enter_guided() is not MavResult.ACCEPTED:
            return MavResult.FAILED
        if cmd.param1 > 0.0:
            copter.change_speed(0, cmd.param1)
        return copter.guided_goto(lat, lon, alt)

    def _position_target(self, msg: Any) -> None:
        """SET_POSITION_TARGET_GLOBAL_INT: position targets in GUIDED, ignored otherwise."""
        copter = self.copter
        if not copter.in_guided:
            return
        if int(msg.type_mask) & POSITION_TARGET_IGNORE_POSITION == POSITION_TARGET_IGNORE_POSITION:
            log.debug("velocity/acceleration-only position targets are not simulated")
            return
        lat, lon = int(msg.lat_int) / 1e7, int(msg.lon_int) / 1e7
        alt = self._relative_alt(int(msg.coordinate_frame), float(msg.alt))
        if alt is None or not (-90.0 <= lat <= 90.0 and -180.0 <= lon <= 180.0):
            copter.guided_hold()  # ArduCopter re-initialises guided on a bad target
            return
        copter.guided_goto(lat, lon, alt)


def _param_name(raw: Any) -> str:
    text = raw.decode("ascii", errors="replace") if isinstance(raw, bytes) else str(raw)
    return text.split("\x00", 1)[0]


def _legacy_xy(msg: Any) -> tuple[int, int]:
    """MISSION_ITEM's float x/y as MISSION_ITEM_INT's: degrees * 1e7 for positions."""
    x, y = float(msg.x), float(msg.y)
    if int(msg.frame) == MavFrame.MISSION:
        return round(x), round(y)
    return round(x * 1e7), round(y * 1e7)


def _as_int(value: float) -> int:
    return int(value) if math.isfinite(value) else -1
