"""The MAVLink parameter protocol: read all, read one, and set with confirmation.

A set counts only when the flight controller echoes the new value in PARAM_VALUE, as
QGroundControl and MAVProxy check it; a name the vehicle does not have is refused
before anything is sent (the table is read once, then kept up to date by the echoes).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from gcs.protocol import CommandOutcome
from vehicle_agents.fcu_link import FcuLink, MavMessage

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class ParamTimeouts:
    list_quiet_s: float = 1.0  # no PARAM_VALUE for this long: request what is missing
    list_rounds: int = 5
    echo_s: float = 1.0
    attempts: int = 3


def _name(message: MavMessage) -> str:
    raw = message.param_id
    text = raw.decode(errors="replace") if isinstance(raw, bytes) else str(raw)
    return text.rstrip("\x00")


class ParamClient:
    def __init__(self, link: FcuLink, timeouts: ParamTimeouts | None = None) -> None:
        self.link = link
        self.timeouts = timeouts or ParamTimeouts()
        self.values: dict[str, float] = {}
        self.types: dict[str, int] = {}
        self.count: int | None = None
        link.listeners.append(self._on_message)

    def _on_message(self, message: MavMessage) -> None:
        if message.get_type() == "PARAM_VALUE":
            self.values[_name(message)] = float(message.param_value)
            self.types[_name(message)] = int(message.param_type)
            self.count = int(message.param_count)

    @property
    def complete(self) -> bool:
        return self.count is not None and len(self.values) >= self.count

    async def read_all(self) -> CommandOutcome:
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
        got_count = len(self.values)
        return CommandOutcome(
            status="timeout",
            message=f"parameter list incomplete: {got_count} of {self.count or '?'} arrived",
        )

    async def read(self, name: str) -> CommandOutcome:
        refusal = await self._known(name)
        if refusal is not None:
            return refusal
        link = self.link
        request = mavlink2.MAVLink_param_request_read_message(
            link.target_system or 1, link.target_component, name.encode(), -1
        )
        echo = await self._exchange(name, request)
        if echo is None:
            return CommandOutcome(status="timeout", message=f"{name}: no PARAM_VALUE answer")
        value = float(echo.param_value)
        return CommandOutcome(
            status="accepted", message=f"{name} = {value:g}", values={name: value}
        )

    async def write(self, name: str, value: float) -> CommandOutcome:
        refusal = await self._known(name)
        if refusal is not None:
            return refusal
        link = self.link
        param_type = self.types.get(name, mavlink2.MAV_PARAM_TYPE_REAL32)
        request = mavlink2.MAVLink_param_set_message(
            link.target_system or 1, link.target_component, name.encode(), value, param_type
        )
        echo = await self._exchange(name, request)
        if echo is None:
            return CommandOutcome(status="timeout", message=f"{name}: no PARAM_VALUE echo")
        stored = float(echo.param_value)
        if math.isclose(stored, value, rel_tol=1e-6, abs_tol=1e-6):
            return CommandOutcome(
                status="accepted", message=f"{name} set to {stored:g}", values={name: stored}
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
        if name not in self.values:
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
