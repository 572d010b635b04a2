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

from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from protocol.mavftp import FtpPayload
from protocol.mavlink_extra import MAVLINK_MSG_ID_COMPONENT_METADATA
from simulator.mavconst import MavCmd, MavResult, MsgId
from simulator.mavlink.commands.arming import ArmingAndModes
from simulator.mavlink.commands.base import Command, Reply, as_int, log
from simulator.mavlink.commands.missions import MISSION_MESSAGES, Missions
from simulator.mavlink.commands.navigation import POSITION_COMMANDS, Navigation
from simulator.mavlink.commands.params import Parameters
from simulator.mavlink.commands.requests import Requests, StreamControl
from simulator.mavlink.ftp_server import FtpServer
from simulator.mavlink.message_context import MavMessage


class MessageHandler(ArmingAndModes, Navigation, Parameters, Missions, Requests):
    """Dispatches one vehicle's incoming messages."""

    _ftp_server: FtpServer | None = None  # made on the first FTP request

    def handle(self, msg: Any, streams: StreamControl, now: float) -> list[Reply]:
        """Replies to ``msg``; ``now`` is sim time, for stream scheduling."""
        kind = msg.get_type()
        if kind == "COMMAND_LONG":
            if not self._for_us(msg.target_system):
                return []
            return self._command(Command.from_long(msg), msg, streams, now)
        if kind == "COMMAND_INT":
            if not self._for_us(msg.target_system):
                return []
            command = Command.from_int(msg)
            if command.command in POSITION_COMMANDS and not self.copter.position_frame_ok(
                command.frame
            ):
                result = MavResult.COMMAND_UNSUPPORTED_MAV_FRAME
                return self._finish(command.command, result, msg)
            return self._command(command, msg, streams, now)
        if kind == "SET_MODE":
            if not self._for_us(msg.target_system):
                return []
            return self._set_mode_message(msg)
        if kind in ("PARAM_REQUEST_LIST", "PARAM_REQUEST_READ", "PARAM_SET"):
            if not self._for_us(msg.target_system):
                return []
            return self._param(kind, msg)
        if kind in MISSION_MESSAGES:
            if not self._for_us(msg.target_system):
                return []
            return self._mission(kind, msg)
        if kind == "SET_POSITION_TARGET_GLOBAL_INT":
            if self._for_us(msg.target_system):
                self._position_target(msg)
            return self._texts()
        if kind == "MANUAL_CONTROL":
            # ArduPilot takes it only from SYSID_MYGCS, PX4 as COM_RC_IN_MODE says
            sender_ok = self.copter.takes_manual_control(msg.get_srcSystem())
            if self._for_us(msg.target) and sender_ok:
                self.copter.manual_control(int(msg.x), int(msg.y), int(msg.z), int(msg.r))
            return []
        if kind == "FILE_TRANSFER_PROTOCOL":
            if not self._for_us(msg.target_system):
                return []
            return [Reply(self._ftp(msg))]
        if kind == "TIMESYNC":
            # GCS_MAVLINK::handle_timesync: a request (tc1 == 0) gets the board's
            # nanoseconds since boot in tc1, with the request's ts1
            if int(msg.tc1) == 0:
                return [Reply(self.telemetry.timesync(int(msg.ts1)))]
            return []
        # HEARTBEAT, REQUEST_DATA_STREAM (accepted and ignored: streams keep their rates),
        # and anything else the simulator does not model
        return []

    # -- component metadata over MAVLink FTP ----------------------------------

    def _metadata_uri(self) -> str | None:
        personality = getattr(self.copter, "personality", None)
        return personality.general_metadata_uri if personality is not None else None

    def _ftp(self, msg: Any) -> MavMessage:
        """MavlinkFTP's answer to the sender, from the files the autopilot keeps."""
        if self._ftp_server is None:
            personality = getattr(self.copter, "personality", None)
            files = personality.metadata_files() if personality is not None else {}
            self._ftp_server = FtpServer(files)
        answer = self._ftp_server.answer(FtpPayload.unpack(msg.payload))
        return mavlink2.MAVLink_file_transfer_protocol_message(
            0, msg.get_srcSystem(), msg.get_srcComponent(), answer.pack()
        )

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
                result = self._arm_disarm(cmd)
            case MavCmd.NAV_TAKEOFF:
                result = copter.nav_takeoff(cmd.z, cmd.frame)
            case MavCmd.NAV_LAND:
                result = copter.nav_land()
            case MavCmd.NAV_RETURN_TO_LAUNCH:
                result = copter.return_to_launch()
            case MavCmd.DO_SET_MODE:
                result = self._do_set_mode(cmd)
            case MavCmd.DO_REPOSITION:
                result = self._reposition(cmd)
            case MavCmd.DO_CHANGE_SPEED:
                result = copter.change_speed(as_int(cmd.param1), cmd.param2)
            case MavCmd.DO_DIGICAM_CONTROL:
                # GCS_MAVLINK::handle_command_do_digicam_control: param5 ("shot") 1 fires
                # the camera now (COMMAND_INT carries it in x, scaled here by 1e-7)
                if cmd.x == 1.0 or round(cmd.x * 1e7) == 1:
                    copter.take_photo()
                result = MavResult.ACCEPTED
            case MavCmd.DO_SET_HOME:
                result = self._set_home(cmd)
                if result is MavResult.ACCEPTED:
                    # Copter::set_home sends the new home to every GCS straight away
                    extra_after.append(Reply(self.telemetry.home_position(), False))
            case MavCmd.PREFLIGHT_REBOOT_SHUTDOWN:
                result = self._reboot(cmd)
            case MavCmd.REQUEST_MESSAGE if as_int(cmd.param1) == MAVLINK_MSG_ID_COMPONENT_METADATA:
                uri = self._metadata_uri()
                result = MavResult.ACCEPTED if uri is not None else MavResult.FAILED
                if uri is not None:
                    extra_after.append(Reply(self.telemetry.component_metadata(uri)))
            case MavCmd.REQUEST_MESSAGE if as_int(cmd.param1) == MsgId.AVAILABLE_MODES:
                # param2: 0 every mode, else the one at that index (GCS_MAVLINK / PX4's
                # AVAILABLE_MODES stream); one message each, after the ACK
                listed = self.telemetry.available_modes(as_int(cmd.param2))
                result = MavResult.ACCEPTED if listed is not None else MavResult.UNSUPPORTED
                extra_after.extend(Reply(message) for message in listed or ())
            case MavCmd.REQUEST_MESSAGE:
                requested = self.telemetry.build(as_int(cmd.param1))
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
                extra_after.append(self._message_interval(cmd, streams))
                result = MavResult.ACCEPTED
            case _:
                result = MavResult.UNSUPPORTED
        return extra_before + self._finish(cmd.command, result, msg) + extra_after
