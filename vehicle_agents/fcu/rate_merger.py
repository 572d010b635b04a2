"""One set of stream rates for everyone on the link: the agent's and every forwarded
GCS's requests, merged, so the flight controller runs each at the highest rate anyone needs."""

from __future__ import annotations

import math
from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from vehicle_agents.fcu.stream_plan import GROUP_OF_ID, MAX_DATA_STREAM_HZ, StreamRequest

Ids = tuple[int, int]  # a GCS's (system id, component id)
# The groups MAV_DATA_STREAM_ALL sets on ArduPilot (handle_request_data_stream loops over
# every stream below STREAM_PARAMS): RAW_CONTROLLER has no messages on Copter, but is set.
ALL_GROUPS: tuple[int, ...] = (
    mavlink2.MAV_DATA_STREAM_RAW_SENSORS,
    mavlink2.MAV_DATA_STREAM_EXTENDED_STATUS,
    mavlink2.MAV_DATA_STREAM_RC_CHANNELS,
    mavlink2.MAV_DATA_STREAM_RAW_CONTROLLER,
    mavlink2.MAV_DATA_STREAM_POSITION,
    mavlink2.MAV_DATA_STREAM_EXTRA1,
    mavlink2.MAV_DATA_STREAM_EXTRA2,
    mavlink2.MAV_DATA_STREAM_EXTRA3,
)


@dataclass
class _Wants:
    groups: dict[int, int]  # REQUEST_DATA_STREAM group -> whole Hz (0: stopped)
    messages: dict[int, float]  # SET_MESSAGE_INTERVAL message id -> Hz (0: stopped)


@dataclass(frozen=True)
class IntervalAnswer:
    """What to do with a GCS's SET_MESSAGE_INTERVAL: pass its frame on (the flight
    controller answers it), or answer ACCEPTED in its place; and any rate the flight
    controller must be sent instead (the merged one), from the agent."""

    forward: bool
    send_hz: float | None = None


class RateMerger:
    """The rates the agent and every GCS sharing its link (through forwarding) ask for,
    merged, so the flight controller runs each stream at the highest rate anyone needs.

    A flight controller keeps one set of rates per link: on ArduPilot a REQUEST_DATA_STREAM
    sets the link's SRx_ rate of a group and the interval of each message in it, so a
    GCS's lower rate overrides the agent's, and the agent's higher one the GCS's, and the
    two fight (MAVProxy asks every ~15 s). Instead the forward hands every GCS's rate
    request here: a group is sent at the highest rate any party needs for it (the agent's
    need for a group is its fastest message in it), and only when that changes; a
    SET_MESSAGE_INTERVAL that asks for no more than is already set is answered by the
    forward. Used on the event loop only."""

    def __init__(self) -> None:
        self.agent: dict[int, float] = {}  # the agent's own: message id -> Hz
        self.clients: dict[Ids, _Wants] = {}
        self.sent_groups: dict[int, int] = {}  # what the flight controller was last sent
        self.sent_messages: dict[int, float] = {}
        self.absorbed = 0  # GCS requests that changed nothing and were not sent on

    def set_agent(self, plan: list[StreamRequest]) -> None:
        self.agent = {r.msg_id: r.rate_hz for r in plan}

    def reset(self) -> None:
        """The link came up again: the flight controller's rates are its defaults."""
        self.sent_groups.clear()
        self.sent_messages.clear()

    def _client(self, ids: Ids) -> _Wants:
        return self.clients.setdefault(ids, _Wants({}, {}))

    def _agent_group_hz(self, group: int) -> int:
        rates = [rate for msg_id, rate in self.agent.items() if GROUP_OF_ID.get(msg_id) == group]
        return min(math.ceil(max(rates, default=0.0)), MAX_DATA_STREAM_HZ)

    def group_hz(self, group: int) -> int:
        """The rate a group needs: the fastest any party asks for."""
        clients = (wants.groups.get(group, 0) for wants in self.clients.values())
        return max(self._agent_group_hz(group), *clients, 0)

    def message_hz(self, msg_id: int, without: Ids | None = None) -> float:
        """The rate a message needs by SET_MESSAGE_INTERVAL (leaving out one GCS)."""
        rates = [
            wants.messages.get(msg_id, 0.0) for ids, wants in self.clients.items() if ids != without
        ]
        return max(self.agent.get(msg_id, 0.0), *rates, 0.0)

    def data_stream(self, ids: Ids, group: int, rate_hz: int, start: bool) -> dict[int, int]:
        """A GCS's REQUEST_DATA_STREAM: the groups whose merged rate changed, to send."""
        wants = self._client(ids)
        groups = ALL_GROUPS if group == mavlink2.MAV_DATA_STREAM_ALL else (group,)
        for one in groups:
            wants.groups[one] = rate_hz if start else 0
        changed = self.changed_groups(groups)
        if not changed:
            self.absorbed += 1
        return changed

    def changed_groups(self, groups: tuple[int, ...] | None = None) -> dict[int, int]:
        """The merged rates of these groups (all known ones) that differ from what the
        flight controller was sent; noted as sent."""
        changed = {}
        for group in groups if groups is not None else ALL_GROUPS:
            rate = self.group_hz(group)
            if rate == 0 and group not in self.sent_groups:
                continue  # nobody wants it and it was never set: leave the default
            if self.sent_groups.get(group) != rate:
                changed[group] = rate
                self.sent_groups[group] = rate
        return changed

    def known_hz(self, msg_id: int) -> float | None:
        """The rate the flight controller was last set to send a message at, if known."""
        if msg_id in self.sent_messages:
            return self.sent_messages[msg_id]
        group = GROUP_OF_ID.get(msg_id)
        return None if group is None else self.sent_groups.get(group)

    def message_interval(self, ids: Ids, msg_id: int, interval_us: float) -> IntervalAnswer:
        """A GCS's SET_MESSAGE_INTERVAL (param2: > 0 microseconds, 0 the default, < 0 stop)."""
        wants = self._client(ids)
        if interval_us == 0:
            wants.messages.pop(msg_id, None)  # its default: no need of its own
        else:
            wants.messages[msg_id] = 1e6 / interval_us if interval_us > 0 else 0.0
        asked = wants.messages.get(msg_id)
        others = self.message_hz(msg_id, without=ids)
        if others == 0 or (asked is not None and asked > others):
            # Nobody else needs it, or the GCS needs the most: its own request, which the
            # flight controller answers, unless that rate is set already.
            if asked is not None and self.known_hz(msg_id) == asked:
                self.absorbed += 1
                return IntervalAnswer(forward=False)
            if asked is None:
                self.sent_messages.pop(msg_id, None)
            else:
                self.sent_messages[msg_id] = asked
            return IntervalAnswer(forward=True)
        # Another party needs at least as much: the GCS gets at least what it asked for.
        if self.known_hz(msg_id) == others:
            self.absorbed += 1
            return IntervalAnswer(forward=False)
        self.sent_messages[msg_id] = others
        return IntervalAnswer(forward=False, send_hz=others)

    def merged_groups(self, agent_rates: dict[int, int]) -> dict[int, int]:
        """The agent's REQUEST_DATA_STREAM rates with every GCS's merged in, noted as sent."""
        merged = {group: max(rate, self.group_hz(group)) for group, rate in agent_rates.items()}
        self.sent_groups.update(merged)
        return merged

    def note_interval(self, msg_id: int, rate_hz: float) -> None:
        """The agent set a message's interval itself (and it was accepted)."""
        self.sent_messages[msg_id] = rate_hz
