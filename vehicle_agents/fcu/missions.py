"""The MAVLink mission protocol: upload, download, clear and set-current.

Before anything is sent, every item is checked against what its MAV_CMD needs (the item
rules, `protocol.mission_rules`, the same the hub checks); a mission with a bad item is
refused whole, naming each item and what is wrong with it, and the vehicle never hears
of it. Upload then follows the vehicle's lead (MISSION_COUNT,
then it asks for each item), with a timeout and retries per item; a rejected item ends
the upload with the vehicle's reason, and the vehicle keeps its previous mission, as
ArduPilot and PX4 do.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from protocol.messages import CommandOutcome, MissionItem
from protocol.mission_rules import mission_problems
from vehicle_agents.fcu.link import FcuLink
from vehicle_agents.fcu.messages import MavMessage, MessagePredicate

MISSION = mavlink2.MAV_MISSION_TYPE_MISSION
# MAV_CMD_NAV_*: the commands a mission flies one at a time; the rest (DO_*, CONDITION_*)
# run on the way, and an autopilot moves on past them at once (MAV_CMD_NAV_LAST is 95).
NAV_COMMANDS = range(mavlink2.MAV_CMD_NAV_WAYPOINT, mavlink2.MAV_CMD_NAV_LAST + 1)


@dataclass(frozen=True)
class MissionTimeouts:
    item_s: float = 1.5  # the vehicle's next request, or an item it asked for
    attempts: int = 4


def _result_name(result: int) -> str:
    entry = mavlink2.enums["MAV_MISSION_RESULT"].get(result)
    return entry.name if entry is not None else f"MAV_MISSION_RESULT {result}"


class MissionClient:
    def __init__(self, link: FcuLink, timeouts: MissionTimeouts | None = None) -> None:
        self.link = link
        self.timeouts = timeouts or MissionTimeouts()
        # The MAV_CMD of each item on board by wire number, as this agent last uploaded,
        # downloaded or cleared it; None until it knows.
        self._on_board: list[int] | None = None

    def _target(self) -> tuple[int, int]:
        return self.link.target_system or 1, self.link.target_component

    def _item_message(self, seq: int, item: MissionItem) -> MavMessage:
        system, component = self._target()
        return mavlink2.MAVLink_mission_item_int_message(
            system,
            component,
            seq,
            item.frame,
            item.command,
            # The first item is flagged current: PX4 starts a changed mission there, and
            # without the flag keeps the index it had (mavlink_mission.cpp, MissionBase::
            # updateMavlinkMission), so a new survey after a finished one started at its
            # end ("Mission finished") or midway. ArduPilot reads only 2 and 3 on upload.
            1 if seq == 0 else 0,
            int(item.autocontinue),
            _wire(item.param1),
            _wire(item.param2),
            _wire(item.param3),
            _wire(item.param4),
            round(item.lat * 1e7),
            round(item.lon * 1e7),
            item.alt,
            MISSION,
        )

    def _autopilot(self) -> str:
        return self.link.modes.autopilot if self.link.modes else "ardupilot"

    def _home_item(self) -> MissionItem:
        """Home as item 0, from HOME_POSITION when the vehicle has reported it."""
        home = self.link.latest.get("HOME_POSITION")
        if home is None:
            return MissionItem(
                command=mavlink2.MAV_CMD_NAV_WAYPOINT, frame=mavlink2.MAV_FRAME_GLOBAL
            )
        return MissionItem(
            command=mavlink2.MAV_CMD_NAV_WAYPOINT,
            frame=mavlink2.MAV_FRAME_GLOBAL,
            lat=home.latitude / 1e7,
            lon=home.longitude / 1e7,
            alt=home.altitude / 1000,
        )

    async def upload(self, items: list[MissionItem]) -> CommandOutcome:
        modes = self.link.modes
        vehicle_type = modes.vehicle_type if modes else "multirotor"
        autopilot = modes.autopilot if modes else "ardupilot"
        problems = mission_problems(items, vehicle_type, autopilot)
        if problems:
            return CommandOutcome(
                status="refused",
                message=f"mission refused, nothing sent to the vehicle: {'; '.join(problems)}",
            )
        # Item 0 is home on ArduPilot; the vehicle keeps its own, so a placeholder will do.
        # PX4 has no home item: a placeholder there would be a waypoint at 0°N 0°E.
        placeholder = MissionItem(
            command=mavlink2.MAV_CMD_NAV_WAYPOINT, frame=mavlink2.MAV_FRAME_GLOBAL
        )
        sequence = [placeholder] * home_slots(autopilot) + list(items)
        system, component = self._target()
        count = mavlink2.MAVLink_mission_count_message(system, component, len(sequence), MISSION)
        last_sent: MavMessage = count
        self.link.send(count)
        for _ in range(len(sequence) * self.timeouts.attempts):
            answer = await self.link.wait_for(_upload_answer, self.timeouts.item_s)
            if answer is None:
                self.link.send(last_sent)  # lost on the way: send it again
                continue
            if answer.get_type() == "MISSION_ACK":
                if answer.type == mavlink2.MAV_MISSION_ACCEPTED:
                    self._on_board = [item.command for item in sequence]
                    return CommandOutcome(
                        status="accepted", message=f"mission of {len(items)} items uploaded"
                    )
                return CommandOutcome(
                    status="refused",
                    result=_result_name(answer.type),
                    message=f"the vehicle rejected the mission: {_result_name(answer.type)}; "
                    "it keeps its previous mission",
                )
            if not 0 <= answer.seq < len(sequence):
                continue
            last_sent = self._item_message(answer.seq, sequence[answer.seq])
            self.link.send(last_sent)
        return CommandOutcome(status="timeout", message="mission upload: the vehicle went quiet")

    async def download(self) -> CommandOutcome:
        system, component = self._target()
        count = None
        for _ in range(self.timeouts.attempts):
            self.link.send(
                mavlink2.MAVLink_mission_request_list_message(system, component, MISSION)
            )
            count = await self.link.wait_for(
                lambda m: m.get_type() == "MISSION_COUNT", self.timeouts.item_s
            )
            if count is not None:
                break
        if count is None:
            return CommandOutcome(status="timeout", message="no MISSION_COUNT from the vehicle")
        items: list[MissionItem] = []
        for seq in range(count.count):
            received = None
            for _ in range(self.timeouts.attempts):
                self.link.send(
                    mavlink2.MAVLink_mission_request_int_message(system, component, seq, MISSION)
                )
                received = await self.link.wait_for(
                    _item_number(seq),
                    self.timeouts.item_s,
                )
                if received is not None:
                    break
            if received is None:
                return CommandOutcome(status="timeout", message=f"mission item {seq} never came")
            items.append(_item_of(received))
        self._on_board = [item.command for item in items]
        if not home_slots(self._autopilot()) or not items:
            # So that item n is the hub's n everywhere. ArduPilot's item 0 is home, but a
            # cleared mission has none (AP_Mission::clear truncates to 0): count 0, no items.
            items.insert(0, self._home_item())
        self.link.send(
            mavlink2.MAVLink_mission_ack_message(
                system, component, mavlink2.MAV_MISSION_ACCEPTED, MISSION
            )
        )
        return CommandOutcome(
            status="accepted", message=f"{len(items) - 1} items (plus home)", items=items
        )

    async def clear(self) -> CommandOutcome:
        system, component = self._target()
        for _ in range(self.timeouts.attempts):
            self.link.send(mavlink2.MAVLink_mission_clear_all_message(system, component, MISSION))
            ack = await self.link.wait_for(
                lambda m: m.get_type() == "MISSION_ACK", self.timeouts.item_s
            )
            if ack is not None:
                if ack.type == mavlink2.MAV_MISSION_ACCEPTED:
                    self._on_board = []
                    return CommandOutcome(status="accepted", message="mission cleared")
                return CommandOutcome(
                    status="refused",
                    result=_result_name(ack.type),
                    message=f"clear refused: {_result_name(ack.type)}",
                )
        return CommandOutcome(status="timeout", message="no MISSION_ACK for the clear")

    async def set_current(self, seq: int) -> CommandOutcome:
        system, component = self._target()
        on_wire = wire_seq(seq, self._autopilot())
        for _ in range(self.timeouts.attempts):
            self.link.send(mavlink2.MAVLink_mission_set_current_message(system, component, on_wire))
            current = await self.link.wait_for(
                lambda m: m.get_type() == "MISSION_CURRENT" and self._went_to(on_wire, m.seq),
                self.timeouts.item_s,
            )
            if current is not None:
                if current.seq == on_wire:
                    return CommandOutcome(status="accepted", message=f"current item is {seq}")
                now = mission_number(current.seq, self._autopilot())
                return CommandOutcome(
                    status="accepted", message=f"item {seq} ran at once; current item is {now}"
                )
        return CommandOutcome(status="timeout", message=f"the vehicle did not move to item {seq}")

    def _went_to(self, asked: int, current: int) -> bool:
        """Whether MISSION_CURRENT ``current`` shows the vehicle took item ``asked``: it is
        that item, or (the asked one being a DO_ or CONDITION_ command, which a running
        mission runs at once, PX4's as ArduPilot's) the vehicle ran it and every other
        non-NAV item up to the next NAV command, and moved on there. Only a mission this
        agent knows the items of can tell the second; an unknown one waits for the first."""
        if current == asked:
            return True
        on_board = self._on_board
        if on_board is None or not asked < current <= len(on_board):
            return False
        return all(command not in NAV_COMMANDS for command in on_board[asked:current])


def home_slots(autopilot: str) -> int:
    """Wire items before the mission's first: ArduPilot keeps home as item 0; PX4 and
    the MAVLink spec start the mission itself at 0. The hub's numbering is ArduPilot's
    (1 is the first item, 0 is home) whatever flies, so only this module knows."""
    return 1 if autopilot == "ardupilot" else 0


def mission_number(wire_seq: int, autopilot: str) -> int:
    """The hub's number for a mission item the vehicle names ``wire_seq``."""
    return wire_seq + 1 - home_slots(autopilot)


def wire_seq(number: int, autopilot: str) -> int:
    return number - 1 + home_slots(autopilot)


def _upload_answer(message: MavMessage) -> bool:
    kind = message.get_type()
    if kind in ("MISSION_REQUEST_INT", "MISSION_REQUEST", "MISSION_ACK"):
        return bool(int(getattr(message, "mission_type", MISSION)) == MISSION)
    return False


def _item_number(seq: int) -> MessagePredicate:
    def matches(message: MavMessage) -> bool:
        return bool(message.get_type() == "MISSION_ITEM_INT" and message.seq == seq)

    return matches


def _wire(value: float | None) -> float:
    """An unset parameter (null) is MAVLink's NaN (e.g. a yaw that keeps the heading mode)."""
    return math.nan if value is None else value


def _unset(value: float) -> float | None:
    """Autopilots put NaN in unset parameters (e.g. 'keep yaw'): null, never 0 (north)."""
    return value if math.isfinite(value) else None


def _item_of(message: MavMessage) -> MissionItem:
    return MissionItem(
        command=message.command,
        frame=message.frame,
        param1=_unset(message.param1),
        param2=_unset(message.param2),
        param3=_unset(message.param3),
        param4=_unset(message.param4),
        lat=message.x / 1e7,
        lon=message.y / 1e7,
        alt=message.z,
        autocontinue=bool(message.autocontinue),
    )
