"""The MAVLink parameter protocol: read all, read one, and set with confirmation.

A set counts only when the flight controller echoes the new value in PARAM_VALUE, as
QGroundControl and MAVProxy check it; a name the vehicle does not have is refused
before anything is sent (the table is read once, then kept up to date by the echoes).
Values are decoded and encoded as the autopilot advertises in AUTOPILOT_VERSION
(`param_encoding`: PX4 copies integers bytewise, ArduPilot casts them to float), by
each parameter's type; the echo that confirms a set is decoded the same way.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from protocol.messages import CommandOutcome
from protocol.param_checks import out_of_range
from vehicle_agents.fcu import param_encoding
from vehicle_agents.fcu.link import FcuLink
from vehicle_agents.fcu.messages import MavMessage, next_match
from vehicle_agents.fcu.param_encoding import ParamEncoding, ParamSetBytes
from vehicle_agents.fcu.param_metadata import ParamMetadata

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class ParamTimeouts:
    list_quiet_s: float = 1.0  # no PARAM_VALUE for this long: request what is missing
    list_rounds: int = 5
    echo_s: float = 1.0
    attempts: int = 3
    capabilities_s: float = 1.0  # one wait for AUTOPILOT_VERSION


def _name(message: MavMessage) -> str:
    raw = message.param_id
    text = raw.decode(errors="replace") if isinstance(raw, bytes) else str(raw)
    return text.rstrip("\x00")


class ParamClient:
    def __init__(self, link: FcuLink, timeouts: ParamTimeouts | None = None) -> None:
        self.link = link
        self.timeouts = timeouts or ParamTimeouts()
        # The autopilot's own metadata (PX4), when the agent reads it: checks writes.
        self.metadata: ParamMetadata | None = None
        # each parameter's four wire bytes and MAV_PARAM_TYPE, decoded when reported: the
        # encoding may be learnt after the values arrived
        self._raw: dict[str, tuple[bytes, int]] = {}
        self.count: int | None = None
        self.encoding: ParamEncoding | None = None
        link.listeners.append(self._on_message)

    def _on_message(self, message: MavMessage) -> None:
        if message.get_type() == "PARAM_VALUE":
            self._raw[_name(message)] = (
                param_encoding.wire_bytes(message),
                int(message.param_type),
            )
            self.count = int(message.param_count)

    @property
    def values(self) -> dict[str, float]:
        encoding = self.encoding or "c_cast"
        return {
            name: param_encoding.decode(raw, param_type, encoding)
            for name, (raw, param_type) in self._raw.items()
        }

    def _value(self, message: MavMessage) -> float:
        encoding = self.encoding or "c_cast"
        raw = param_encoding.wire_bytes(message)
        return param_encoding.decode(raw, int(message.param_type), encoding)

    async def _learn_encoding(self) -> ParamEncoding:
        """The encoding the autopilot advertises in AUTOPILOT_VERSION (asked for with
        MAV_CMD_REQUEST_MESSAGE, then the older REQUEST_AUTOPILOT_CAPABILITIES); an
        autopilot that does not answer gets its kind's (PX4 bytewise, others C cast)."""
        if self.encoding is not None:
            return self.encoding
        link = self.link
        version = link.latest.get("AUTOPILOT_VERSION")
        requests: tuple[tuple[int, list[float]], ...] = (
            (mavlink2.MAV_CMD_REQUEST_MESSAGE, [float(mavlink2.MAVLINK_MSG_ID_AUTOPILOT_VERSION)]),
            (mavlink2.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES, [1.0]),
        )
        for command, params in requests:
            if version is not None:
                break
            with link.collect(lambda m: m.get_type() == "AUTOPILOT_VERSION") as answers:
                link.send_command_long(command, 0, params)
                version = await next_match(answers, self.timeouts.capabilities_s)
        found = (
            None
            if version is None
            else (param_encoding.encoding_from_capabilities(int(version.capabilities)))
        )
        autopilot = link.modes.autopilot if link.modes else "generic"
        if found is None:
            found = param_encoding.default_encoding(autopilot)
            log.warning(
                "the autopilot (%s) did not advertise its parameter encoding; assuming %s",
                autopilot,
                found,
            )
        else:
            log.info("parameter encoding: %s (AUTOPILOT_VERSION)", found)
        self.encoding = found
        return found

    @property
    def complete(self) -> bool:
        return self.count is not None and len(self._raw) >= self.count

    async def read_all(self) -> CommandOutcome:
        await self._learn_encoding()
        link = self.link
        link.send(
            mavlink2.MAVLink_param_request_list_message(
                link.target_system or 1, link.target_component
            )
        )
        for _ in range(self.timeouts.list_rounds):
            # Wait until the stream goes quiet, then ask for what did not arrive.
            while not self.complete:
                got = await link.wait_for(
                    lambda m: m.get_type() == "PARAM_VALUE", self.timeouts.list_quiet_s
                )
                if got is None:
                    break
            if self.complete:
                return CommandOutcome(
                    status="accepted",
                    message=f"{len(self.values)} parameters",
                    values=dict(sorted(self.values.items())),
                )
            if self.count is None:
                link.send(
                    mavlink2.MAVLink_param_request_list_message(
                        link.target_system or 1, link.target_component
                    )
                )
        got_count = len(self._raw)
        return CommandOutcome(
            status="timeout",
            message=f"parameter list incomplete: {got_count} of {self.count or '?'} arrived",
        )

    async def read(self, name: str) -> CommandOutcome:
        refusal = await self._known(name)
        if refusal is not None:
            return refusal
        await self._learn_encoding()
        link = self.link
        request = mavlink2.MAVLink_param_request_read_message(
            link.target_system or 1, link.target_component, name.encode(), -1
        )
        echo = await self._exchange(name, request)
        if echo is None:
            return CommandOutcome(status="timeout", message=f"{name}: no PARAM_VALUE answer")
        value = self._value(echo)
        meta = self.metadata.of(name) if self.metadata is not None else None
        return CommandOutcome(
            status="accepted", message=f"{name} = {value:g}", values={name: value}, param_meta=meta
        )

    async def write(self, name: str, value: float) -> CommandOutcome:
        refusal = await self._known(name)
        if refusal is not None:
            return refusal
        meta = self.metadata.of(name) if self.metadata is not None else None
        if meta is not None and (problem := out_of_range(name, value, meta)) is not None:
            return CommandOutcome(status="refused", message=problem, param_meta=meta)
        encoding = await self._learn_encoding()
        link = self.link
        param_type = self._raw[name][1]
        try:
            raw = param_encoding.encode(value, param_type, encoding)
        except ValueError as error:
            return CommandOutcome(status="refused", message=f"{name}: {error}")
        request = ParamSetBytes(
            link.target_system or 1, link.target_component, name.encode(), raw, param_type
        )
        echo = await self._exchange(name, request)
        if echo is None:
            return CommandOutcome(status="timeout", message=f"{name}: no PARAM_VALUE echo")
        stored = self._value(echo)
        # what the wire can carry of the value asked for (a float32, or the integer)
        wanted = param_encoding.decode(raw, param_type, encoding)
        if stored == wanted or math.isclose(stored, wanted, rel_tol=1e-6, abs_tol=1e-6):
            return CommandOutcome(
                status="accepted",
                message=f"{name} set to {stored:g}",
                values={name: stored},
                param_meta=meta,
            )
        reasons = [entry.text for entry in link.statustexts][-1:]
        return CommandOutcome(
            status="refused",
            message=f"{name} kept at {stored:g}" + (f" ({reasons[0]})" if reasons else ""),
            values={name: stored},
        )

    async def _known(self, name: str) -> CommandOutcome | None:
        """None if the vehicle has ``name``; otherwise why the request goes no further."""
        if not self.complete:
            listing = await self.read_all()
            if listing.status != "accepted":
                return listing
        if name not in self._raw:
            return CommandOutcome(
                status="refused", message=f"no parameter {name!r} on this vehicle"
            )
        return None

    async def _exchange(self, name: str, request: MavMessage) -> MavMessage | None:
        """Send ``request`` until the vehicle answers with ``name``'s PARAM_VALUE."""
        for _ in range(self.timeouts.attempts):
            self.link.send(request)
            echo = await self.link.wait_for(
                lambda m: m.get_type() == "PARAM_VALUE" and _name(m) == name,
                self.timeouts.echo_s,
            )
            if echo is not None:
                return echo
        return None
