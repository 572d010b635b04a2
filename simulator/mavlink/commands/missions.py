"""The mission microservice as MissionItemProtocol_Waypoints answers it: uploads,
downloads, clearing and the current item."""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

from simulator.mavconst import MavFrame, MavMissionResult, Severity
from simulator.mavlink.commands.base import HandlerBase, Reply, log
from simulator.vehicle.stored_mission import (
    HOME_PLACEHOLDER,
    MAX_ITEMS,
    MissionItem,
    check_item,
    px4_download_frame,
    stored_frame,
)

MISSION_TYPE_MISSION = 0  # MAV_MISSION_TYPE_MISSION: fences and rally points are not simulated
MISSION_MESSAGES = frozenset(
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
    current: int | None = None  # the item flagged current (MISSION_ITEM_INT.current 1)


class Missions(HandlerBase):
    _upload: _Upload | None = None  # no upload in progress

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
        if int(getattr(msg, "current", 0)) == 1:
            upload.current = seq
        upload.items.append(replace(item, frame=stored_frame(item.frame)))
        if len(upload.items) < upload.count:
            return [Reply(self.telemetry.mission_request_int(len(upload.items), *peer))]
        self._upload = None
        items = upload.items
        if self.copter.mission_wire_offset:
            # PX4's item 0 is the first real one: home goes in front, as stored here.
            items = [HOME_PLACEHOLDER] + [replace(i, seq=i.seq + 1) for i in items]
        offset = self.copter.mission_wire_offset
        flagged = None if upload.current is None else upload.current + offset
        self.copter.set_mission(items, flagged)
        text = self.telemetry.statustext_of(Severity.INFO, "Flight plan received")
        return [
            self._mission_ack(MavMissionResult.ACCEPTED, peer),
            Reply(text, to_sender_only=False),
        ]


def _legacy_xy(msg: Any) -> tuple[int, int]:
    """MISSION_ITEM's float x/y as MISSION_ITEM_INT's: degrees * 1e7 for positions."""
    x, y = float(msg.x), float(msg.y)
    if int(msg.frame) == MavFrame.MISSION:
        return round(x), round(y)
    return round(x * 1e7), round(y * 1e7)
