"""The vehicle's modes as its autopilot lists them (MAVLink's standard modes protocol).

After the link comes up the agent asks for every mode at once (MAV_CMD_REQUEST_MESSAGE
for AVAILABLE_MODES, param2 0): the autopilot answers with ``number_modes`` messages,
``mode_index`` 1..N (PX4's AVAILABLE_MODES stream, ArduPilot's GCS_MAVLINK). When the
list changes (a PX4 external mode registers) the autopilot streams AVAILABLE_MODES_MONITOR
with a new ``seq``, and the agent reads the list again. A complete list replaces the
link's mode table (`FcuLink.modes`), which set_mode, hold and the manual pilot read, and is
reported to the hub; an autopilot that does not answer (older firmware) keeps the fixed
table of `vehicle_agents.fcu.modes`.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import Callable
from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from vehicle_agents.fcu.link import FcuLink
from vehicle_agents.fcu.messages import LinkChange, MavMessage, next_match
from vehicle_agents.fcu.modes import ModeTable, ReportedMode, reported_mode, reported_table

log = logging.getLogger(__name__)

AVAILABLE_MODES_ID = 435
ALL_MODES = 0  # MAV_CMD_REQUEST_MESSAGE param2: every mode


@dataclass(frozen=True)
class ModeListTimeouts:
    # From the request (or the last message of the list) to the next message. PX4 sends
    # the whole list in one go; ArduPilot one per mode from its message queue.
    between_s: float = 1.5
    attempts: int = 3


class AvailableModes:
    """Reads the autopilot's mode list into ``link.modes``; calls ``on_change`` with each
    new table."""

    def __init__(
        self,
        link: FcuLink,
        on_change: Callable[[ModeTable], None],
        timeouts: ModeListTimeouts | None = None,
    ) -> None:
        self._link = link
        self._on_change = on_change
        self.timeouts = timeouts or ModeListTimeouts()
        self._wanted = asyncio.Event()
        self._monitor_seq: int | None = None
        self.answered: bool | None = None  # None until asked; False: the fixed table stays
        link.listeners.append(self._on_message)
        link.state_listeners.append(self._on_link_change)
        if link.up:  # came up before this was listening
            self._wanted.set()

    def _on_link_change(self, change: LinkChange) -> None:
        if change.up:
            self._monitor_seq = None
            self._wanted.set()

    def _on_message(self, message: MavMessage) -> None:
        if message.get_type() != "AVAILABLE_MODES_MONITOR":
            return
        seq = int(message.seq)
        if self._monitor_seq is not None and seq != self._monitor_seq:
            log.info("the autopilot's mode list changed (monitor seq %d); reading it again", seq)
            self._wanted.set()
        self._monitor_seq = seq

    async def run(self) -> None:
        while True:
            await self._wanted.wait()
            self._wanted.clear()
            with contextlib.suppress(ConnectionError):  # down: asked again when it is up
                await self.refresh()

    async def refresh(self) -> None:
        modes = await self.read()
        link = self._link
        if modes is None:
            if self.answered is None:
                log.info("the autopilot does not list its modes; using the fixed table")
            self.answered = False
            return
        current = link.modes
        assert current is not None  # identified before the link came up
        table = reported_table(current.autopilot, self._mav_type(), modes)
        if not table.settings:
            log.warning("the autopilot listed no mode a user may select; keeping the table")
            return
        self.answered = True
        if current.reported and current.settings == table.settings:
            return
        log.info("the autopilot's modes: %s", ", ".join(table.names))
        link.modes = table
        self._on_change(table)

    def _mav_type(self) -> int:
        heartbeat = self._link.latest.get("HEARTBEAT")
        return int(heartbeat.type) if heartbeat is not None else mavlink2.MAV_TYPE_GENERIC

    async def read(self) -> list[ReportedMode] | None:
        """Every mode the autopilot lists, in its order; None if it did not list them all.

        A request for every mode brings PX4's whole list, but ArduPilot's first mode alone
        (GCS_MAVLINK::send_available_modes sends one per deferred send, the rest only at its
        PARAMS stream's rate): the modes that did not come are asked for by index."""
        link = self._link
        got: dict[int, ReportedMode] = {}
        total: int | None = None
        with link.collect(lambda m: m.get_type() == "AVAILABLE_MODES") as answers:
            for attempt in range(self.timeouts.attempts):
                link.send_command_long(
                    mavlink2.MAV_CMD_REQUEST_MESSAGE, attempt, [AVAILABLE_MODES_ID, ALL_MODES]
                )
                while (message := await next_match(answers, self.timeouts.between_s)) is not None:
                    total = int(message.number_modes)
                    got[int(message.mode_index)] = reported_mode(message)
                    if total and all(index in got for index in range(1, total + 1)):
                        return [got[index] for index in range(1, total + 1)]
                if total:
                    break
            if not total:
                return None
            for index in range(1, total + 1):
                for attempt in range(self.timeouts.attempts):
                    if index in got:
                        break
                    link.send_command_long(
                        mavlink2.MAV_CMD_REQUEST_MESSAGE, attempt, [AVAILABLE_MODES_ID, index]
                    )
                    while (
                        message := await next_match(answers, self.timeouts.between_s)
                    ) is not None:
                        got[int(message.mode_index)] = reported_mode(message)
                        if int(message.mode_index) == index:
                            break
                if index not in got:
                    log.info("AVAILABLE_MODES: mode %d of %d never came", index, total)
                    return None
        return [got[index] for index in range(1, total + 1)]
