"""Sending one command to one vehicle, the whole way: the safety service, the dispatch to
its agent, the audit log and the command log. The REST routes for one vehicle and for a
group both go through here, so every command is checked and recorded the same way."""

from __future__ import annotations

import asyncio
import logging
from dataclasses import asdict

from sqlalchemy.exc import SQLAlchemyError

from backend.audit import AuditAction, principal_audit_entry
from backend.auth.policy import Permission, Principal, authorize
from backend.errors import (
    CommandTimedOut,
    Forbidden,
    GcsError,
    InvalidRequest,
    SafetyViolation,
    VehicleOffline,
    VehicleRefused,
)
from backend.fleet.collaborators import CommandServices
from backend.fleet.commands import Sender
from backend.safety.mission_on_board import MissionReader, starts_mission
from backend.storage.logbook import command_row
from backend.storage.models import CommandRow
from protocol.messages import (
    Command,
    CommandOutcome,
    ManualStartCommand,
    ManualStopCommand,
    MissionDownloadCommand,
    MissionItem,
    ParamGetCommand,
    ParamSetCommand,
    lease_only,
)
from protocol.param_checks import out_of_range
from protocol.routing import RoutedCommand

log = logging.getLogger(__name__)


async def execute_command(
    hub: CommandServices,
    principal: Principal,
    source: str,
    vehicle_id: str,
    command: Command,
    override_reason: str | None = None,
) -> CommandOutcome:
    """The flight controller's answer; raises GcsError for a refusal before the vehicle."""
    details: dict[str, object] = {"command": command.model_dump()}

    async def audit(outcome: str) -> None:
        await _audit(hub, principal, source, vehicle_id, outcome, details)

    try:
        if isinstance(command, ManualStartCommand | ManualStopCommand):
            # Browser control opens and closes with the lease, whose holder the hub
            # tracks; a bare command would leave the vehicle in a pilot mode nobody flies.
            raise InvalidRequest("name", lease_only(command.name))
        record = hub.registry.get(vehicle_id)
        read_on_board = _mission_reader(hub, vehicle_id, principal)
        critical = hub.safety.check_param_write(principal, record, command)
        if critical is not None:
            details["safety_critical"] = critical
        file_meta = None
        if isinstance(command, ParamGetCommand | ParamSetCommand):
            # Off the event loop: the first use of a family reads its file (a few MB).
            file_meta = await asyncio.to_thread(
                hub.param_catalog.meta, record.autopilot, record.vehicle_type, command.param
            )
        if isinstance(command, ParamSetCommand) and file_meta is not None:
            problem = out_of_range(command.param, command.value, file_meta)
            if problem is not None:
                raise VehicleRefused(problem)
        try:
            violations = await asyncio.to_thread(hub.safety.check_command, record, command)
        except SQLAlchemyError:
            # The rails live in the database: a command they govern is refused, never
            # sent unchecked (land, RTL and hold need no rails and go through). The
            # refusal is audited through the spool; the API answers 503.
            details["error"] = "the database is unavailable: the safety rails cannot be read"
            await audit("refused")
            raise
        if starts_mission(command):
            # AUTO flies whatever is on board, perhaps loaded by another GCS: it flies
            # only after the same check as an upload (or an admin's audited override).
            found, count = await hub.safety.check_mission_on_board(record, read_on_board)
            details["mission_checked"] = {"items": count, "ok": not found}
            violations += found
        if violations:
            if override_reason is None:
                raise SafetyViolation([asdict(violation) for violation in violations])
            if Permission.ADMIN not in principal.permissions:
                raise Forbidden("only an admin may override safety rules")
            details["override"] = {
                "reason": override_reason,
                "violations": [violation.rule for violation in violations],
            }
        await hub.safety.check_current_item(record, command, read_on_board)
        # An agent on another hub: that hub checks the principal again and records the
        # command itself (carry_out_routed); this one records only what never got there.
        elsewhere = record.channel is not None and record.channel.remote
        sender = Sender(principal, source, {k: v for k, v in details.items() if k != "command"})
        outcome = await hub.dispatcher.execute(vehicle_id, command, sender)
    except GcsError as error:
        if error.recorded_elsewhere:
            raise
        details["error"] = error.message
        await audit("refused")
        if isinstance(error, CommandTimedOut | SafetyViolation | VehicleOffline):
            status = "timeout" if isinstance(error, CommandTimedOut) else "refused"
            await _log(hub, principal, vehicle_id, command, status, None, error.message)
        raise
    if file_meta is not None and outcome.param_meta is None:
        outcome = outcome.model_copy(update={"param_meta": file_meta})
    if elsewhere:
        return outcome
    details["answer"] = outcome.model_dump()
    try:
        await audit("ok" if outcome.status == "accepted" else "failed")
        await _log(
            hub, principal, vehicle_id, command, outcome.status, outcome.result, outcome.message
        )
    except (SQLAlchemyError, OSError) as error:
        # The vehicle has acted: the operator must see its answer, not an error that
        # invites a second takeoff. The lost record goes to the hub's log instead.
        log.error(
            "could not record %s to %s (%s): %s", command.name, vehicle_id, outcome.message, error
        )
    return outcome


def _mission_reader(hub: CommandServices, vehicle_id: str, principal: Principal) -> MissionReader:
    """The vehicle's own mission for the AUTO gate, read (downloaded) for ``principal``:
    another GCS may have loaded one the hub never sent."""

    async def read() -> list[MissionItem]:
        sender = Sender(principal, "mission_check")
        outcome = await hub.dispatcher.execute(vehicle_id, MissionDownloadCommand(), sender)
        if outcome.status != "accepted" or outcome.items is None:
            raise VehicleRefused(f"mission download: {outcome.message}")
        return list(outcome.items[1:])  # without home: item 1 first

    return read


async def carry_out_routed(
    hub: CommandServices, principal: Principal, vehicle_id: str, routed: RoutedCommand
) -> CommandOutcome:
    """A command another hub routed here for an agent this hub holds, from ``principal``
    (checked against the database by the caller): the permission is checked again, and
    the audit row and command log are written here, where the vehicle is commanded. The
    asking hub ran the safety checks; what they found comes in ``routed.checks``."""
    command = routed.command
    details: dict[str, object] = {
        "command": command.model_dump(),
        **routed.checks,
        "routed_from": routed.asked_by,
    }
    try:
        authorize(principal, Permission.COMMAND, vehicle_id)
        channel = hub.registry.get(vehicle_id).channel
        if channel is None or channel.remote:
            # Never passed on again: two hubs must not bounce a command between them.
            raise VehicleOffline(f"{vehicle_id} just left this hub")
        outcome = await channel.request(command, routed.timeout_s)
    except GcsError as error:
        details["error"] = error.message
        await _audit(hub, principal, routed.source, vehicle_id, "refused", details)
        if isinstance(error, CommandTimedOut | VehicleOffline):
            status = "timeout" if isinstance(error, CommandTimedOut) else "refused"
            await _log(hub, principal, vehicle_id, command, status, None, error.message)
        raise
    details["answer"] = outcome.model_dump()
    try:
        result = "ok" if outcome.status == "accepted" else "failed"
        await _audit(hub, principal, routed.source, vehicle_id, result, details)
        await _log(
            hub, principal, vehicle_id, command, outcome.status, outcome.result, outcome.message
        )
    except (SQLAlchemyError, OSError) as error:
        log.error(
            "could not record %s to %s (%s): %s", command.name, vehicle_id, outcome.message, error
        )
    return outcome


async def execute_expecting_acceptance(
    hub: CommandServices,
    principal: Principal,
    source: str,
    vehicle_id: str,
    command: Command,
    override_reason: str | None = None,
) -> CommandOutcome:
    """For routes that return what the vehicle gave back (parameters, a mission): an
    answer other than "accepted" becomes VehicleRefused (409) with its reason."""
    outcome = await execute_command(hub, principal, source, vehicle_id, command, override_reason)
    if outcome.status != "accepted":
        raise VehicleRefused(outcome.message)
    return outcome


async def _audit(
    hub: CommandServices,
    principal: Principal,
    source: str,
    vehicle_id: str,
    outcome: str,
    details: dict[str, object],
) -> None:
    await hub.record(
        principal_audit_entry(principal, source, AuditAction.COMMAND, vehicle_id, outcome, details)
    )


async def _log(
    hub: CommandServices,
    principal: Principal,
    vehicle_id: str,
    command: Command,
    status: str,
    result: str | None,
    message: str,
) -> None:
    row = command_row(vehicle_id, principal.name, command.model_dump(), status, result, message)
    # Through the spool: a database outage delays the row, never loses it or the answer.
    await asyncio.to_thread(hub.spool.write, CommandRow.__tablename__, row)
    # And to the operators' event feed (and the flight log, for the replay's feed).
    await hub.store_event(
        vehicle_id,
        "command",
        command_event_text(command, status, message),
        _INFO if status == "accepted" else _WARNING,
    )


_WARNING = 4  # MAV_SEVERITY_WARNING
_INFO = 6  # MAV_SEVERITY_INFO


def command_event_text(command: Command, status: str, message: str) -> str:
    """E.g. "set_mode AUTO: refused — mission not checked"; at most an event's 500 chars."""
    mode = getattr(command, "mode", None)
    what = f"{command.name} {mode}" if isinstance(mode, str) else command.name
    text = f"{what}: {status}"
    if message and message != status:
        text += f" — {message}"
    return text[:500]
