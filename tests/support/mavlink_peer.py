"""A stand-in flight controller for the agent: a real MAVLink peer on loopback TCP.

`ScriptedFlightController` sends an autopilot's heartbeat and a little telemetry at 5 Hz,
records every message the agent sends, and answers each command as a test scripts it
(`scripts[command]`): MAV_RESULT_IN_PROGRESS acks and then a final ACK, a STATUSTEXT, an
ACK that never ends. A command with no script gets no answer at all, as from a flight
controller that is silent. What it sends unasked is `telemetry()`, for a subclass to
narrow (a heartbeat alone, say).
"""

from __future__ import annotations

import contextlib
import socket
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from vehicle_agents.fcu.messages import MavMessage

HOME_ALT_MSL = 584.0
TELEMETRY_PERIOD_S = 0.2
_COMMANDS = ("COMMAND_LONG", "COMMAND_INT")


@dataclass(frozen=True)
class Answer:
    """A COMMAND_ACK (or STATUSTEXT) the peer sends ``after_s`` seconds after a command."""

    after_s: float
    result: int | None = None  # None: send ``text`` instead
    progress: int = 0
    text: str = ""


Script = Callable[[MavMessage], list[Answer]]


class ScriptedFlightController:
    """A real MAVLink peer on TCP: an autopilot's heartbeat and a little telemetry, and
    for each command the answers its script gives (no script: no answer)."""

    def __init__(
        self,
        *,
        system_id: int = 9,  # not 1: an agent that assumed system 1 would show it
        autopilot: int = mavlink2.MAV_AUTOPILOT_ARDUPILOTMEGA,
        mav_type: int = mavlink2.MAV_TYPE_QUADROTOR,
        armed: bool = False,
        in_air: bool = False,
    ) -> None:
        self.system_id = system_id
        self.autopilot, self.mav_type, self.armed, self.in_air = autopilot, mav_type, armed, in_air
        self.scripts: dict[int, Script] = {}
        self.received: list[MavMessage] = []  # every message from the agent, in order
        self._outgoing: list[MavMessage] = []  # pushed by the test, sent once, in order
        self._lock = threading.Lock()
        self._arrived = threading.Condition(self._lock)
        self._server = socket.create_server(("127.0.0.1", 0))
        self.port = int(self._server.getsockname()[1])
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._serve, daemon=True)

    def __enter__(self) -> ScriptedFlightController:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._server.close()
        self._thread.join(5)

    # -- what the agent sent ----------------------------------------------------------

    def commands(self, command: int) -> list[MavMessage]:
        with self._lock:
            return [m for m in self.received if _is_command(m, command)]

    def kinds(self) -> list[str]:
        with self._lock:
            return [m.get_type() for m in self.received]

    def wait_for_command(self, command: int, timeout_s: float) -> MavMessage:
        with self._arrived:
            found = self._arrived.wait_for(lambda: self._first(command), timeout_s)
            assert found, f"command {command} never reached the flight controller"
            return found

    def _first(self, command: int) -> MavMessage | None:
        return next((m for m in self.received if _is_command(m, command)), None)

    # -- what it sends unasked ----------------------------------------------------------

    def heartbeat(self) -> MavMessage:
        base = mavlink2.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
        if self.armed:
            base |= mavlink2.MAV_MODE_FLAG_SAFETY_ARMED
        return mavlink2.MAVLink_heartbeat_message(
            self.mav_type, self.autopilot, base, 4, mavlink2.MAV_STATE_STANDBY, 3
        )

    def telemetry(self) -> list[MavMessage]:
        """Sent every `TELEMETRY_PERIOD_S`: the heartbeat, the landed state and home."""
        landed = mavlink2.MAV_LANDED_STATE_IN_AIR if self.in_air else 1
        return [
            self.heartbeat(),
            mavlink2.MAVLink_extended_sys_state_message(0, landed),
            mavlink2.MAVLink_home_position_message(
                -353632620, 1491652370, round(HOME_ALT_MSL * 1000), 0, 0, 0, [1, 0, 0, 0], 0, 0, 0
            ),
        ]

    def push(self, *messages: MavMessage) -> None:
        """Send these once, in order, at the next turn of the loop (after that turn's
        telemetry, if it is due)."""
        with self._lock:
            self._outgoing.extend(messages)

    # -- the connection -------------------------------------------------------------------

    def _serve(self) -> None:
        mav = mavlink2.MAVLink(None, srcSystem=self.system_id, srcComponent=1)
        parser = mavlink2.MAVLink(None)
        parser.robust_parsing = True
        try:
            peer, _ = self._server.accept()
        except OSError:
            return  # closed before the agent came
        with peer, contextlib.suppress(ConnectionError):  # the agent went away: done
            peer.settimeout(0.02)
            self._exchange(peer, mav, parser)

    def _exchange(self, peer: socket.socket, mav: Any, parser: Any) -> None:
        pending: list[tuple[float, MavMessage]] = []
        next_beat = 0.0
        while not self._stop.is_set():
            now = time.monotonic()
            if now >= next_beat:
                for message in self.telemetry():
                    peer.sendall(message.pack(mav))
                next_beat = now + TELEMETRY_PERIOD_S
            with self._lock:
                pushed, self._outgoing = self._outgoing, []
            for message in pushed:
                peer.sendall(message.pack(mav))
            for due in [p for p in pending if p[0] <= now]:
                pending.remove(due)
                peer.sendall(due[1].pack(mav))
            try:
                data = peer.recv(4096)
            except TimeoutError:
                continue
            if not data:
                return
            for message in parser.parse_buffer(data) or []:
                pending += self._answer(message, now)

    def _answer(self, message: MavMessage, now: float) -> list[tuple[float, MavMessage]]:
        with self._arrived:
            self.received.append(message)
            self._arrived.notify_all()
        if message.get_type() not in _COMMANDS:
            return []
        script = self.scripts.get(message.command)
        if script is None:
            return []
        return [(now + answer.after_s, _reply(message, answer)) for answer in script(message)]


def _is_command(message: MavMessage, command: int) -> bool:
    return bool(message.get_type() in _COMMANDS and message.command == command)


def _reply(command: MavMessage, answer: Answer) -> MavMessage:
    if answer.result is None:
        return mavlink2.MAVLink_statustext_message(
            mavlink2.MAV_SEVERITY_CRITICAL, answer.text.encode()
        )
    return mavlink2.MAVLink_command_ack_message(
        command.command,
        answer.result,
        answer.progress,
        0,
        command.get_srcSystem(),
        command.get_srcComponent(),
    )
