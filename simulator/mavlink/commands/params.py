"""The parameter protocol as GCS_Param.cpp answers it: PARAM_REQUEST_LIST,
PARAM_REQUEST_READ and PARAM_SET."""

from __future__ import annotations

from typing import Any

from simulator.mavconst import Severity
from simulator.mavlink.commands.base import HandlerBase, Reply, log
from simulator.params.table import SetOutcome
from simulator.params.wire import received_value


class Parameters(HandlerBase):
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


def _param_name(raw: Any) -> str:
    text = raw.decode("ascii", errors="replace") if isinstance(raw, bytes) else str(raw)
    return text.split("\x00", 1)[0]
