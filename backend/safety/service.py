"""The safety service: the one place the hub asks whether a command, a mission or a
parameter write may go to a vehicle. It reads the effective rails (the site's, narrowed
per vehicle) from the rails store and runs the pure rules of this package against them.

Its entry points, one per caller: `check_command` (every command, an upload included),
`check_mission` (a mission check, a survey's parts), `check_mission_on_board` and
`check_current_item` (the AUTO gate), `check_param_write` (safety-critical parameters),
and `site_rails` (a formation's plan is checked against the site's rails).
"""

from __future__ import annotations

from typing import Protocol

from backend.auth.policy import Permission, Principal
from backend.errors import Forbidden
from backend.safety.commands import check_arm, check_goto, check_set_home, check_takeoff
from backend.safety.critical_params import critical_reason
from backend.safety.mission_check import check_mission
from backend.safety.mission_on_board import MissionReader, check_current_item, unchecked_mission
from backend.safety.mission_rails import PlanCheck
from backend.safety.rails import SafetyRails
from backend.safety.rails_store import SITE, RailsRepository, vehicle_scope
from backend.safety.schemas import SafetyRailsModel
from backend.safety.snapshot import ReportedVehicle, snapshot_of
from backend.safety.violations import Violation
from protocol.messages import (
    ArmCommand,
    Command,
    GotoCommand,
    MissionItem,
    MissionUploadCommand,
    ParamSetCommand,
    SetHomeCommand,
    TakeoffCommand,
)


class RailsDefaults(Protocol):
    """The site's rails until an admin stores some (the hub's settings provide them)."""

    @property
    def max_altitude_m(self) -> float | None: ...
    @property
    def min_altitude_m(self) -> float | None: ...
    @property
    def max_distance_from_home_m(self) -> float | None: ...
    @property
    def min_launch_battery_pct(self) -> float | None: ...
    @property
    def battery_reserve_pct(self) -> float: ...
    @property
    def min_height_above_home_m(self) -> float | None: ...


class SafetyService:
    def __init__(self, repository: RailsRepository, defaults: RailsDefaults) -> None:
        self.repository = repository
        self.defaults = defaults

    # --- The rails --------------------------------------------------------------------------

    def site_rails(self) -> SafetyRails:
        stored = self.repository.get(SITE)
        if stored is not None:
            return SafetyRailsModel.model_validate_json(stored).to_rails()
        defaults = self.defaults
        return SafetyRails(
            max_altitude_m=defaults.max_altitude_m,
            min_altitude_m=defaults.min_altitude_m,
            max_distance_from_home_m=defaults.max_distance_from_home_m,
            min_launch_battery_pct=defaults.min_launch_battery_pct,
            battery_reserve_pct=defaults.battery_reserve_pct,
            min_height_above_home_m=defaults.min_height_above_home_m,
        )

    def vehicle_rails(self, vehicle_id: str) -> SafetyRails | None:
        stored = self.repository.get(vehicle_scope(vehicle_id))
        return SafetyRailsModel.model_validate_json(stored).to_rails() if stored else None

    def effective_rails(self, vehicle_id: str) -> SafetyRails:
        return self.site_rails().merged_with(self.vehicle_rails(vehicle_id))

    def store_site_rails(self, rails: SafetyRailsModel, updated_by: str) -> None:
        self.repository.put(SITE, rails.model_dump_json(), updated_by)

    def store_vehicle_rails(
        self, vehicle_id: str, rails: SafetyRailsModel, updated_by: str
    ) -> None:
        self.repository.put(vehicle_scope(vehicle_id), rails.model_dump_json(), updated_by)

    def clear_vehicle_rails(self, vehicle_id: str) -> bool:
        return self.repository.delete(vehicle_scope(vehicle_id))

    # --- The checks -------------------------------------------------------------------------

    def check_param_write(
        self, principal: Principal, record: ReportedVehicle, command: Command
    ) -> str | None:
        """Raise Forbidden if ``command`` needs more authority than ``principal`` has: a
        safety-critical parameter (failsafes, fence, arming checks) is an admin's to
        change. Returns why the command was critical, for the audit log, if it was."""
        if not isinstance(command, ParamSetCommand):
            return None
        reason = critical_reason(record.autopilot, command.param)
        if reason is not None and Permission.ADMIN not in principal.permissions:
            raise Forbidden(
                f"{command.param} is safety-critical on {record.autopilot} ({reason}): "
                "only an admin may change it"
            )
        return reason

    def check_command(self, record: ReportedVehicle, command: Command) -> list[Violation]:
        """Violations of the rails; landing, RTL, hold, mode changes and disarming are never
        blocked, because they are how an operator gets out of trouble. A new home is
        checked because RTL and the failsafes fly to it."""
        if isinstance(command, MissionUploadCommand):
            return list(self.check_mission(record, command.items).violations)
        if not isinstance(command, ArmCommand | TakeoffCommand | GotoCommand | SetHomeCommand):
            return []  # decided before any rails are read: no database needed
        rails = self.effective_rails(record.id)
        vehicle = snapshot_of(record)
        match command:
            case ArmCommand():
                return check_arm(rails, vehicle)
            case TakeoffCommand(altitude=altitude):
                return check_takeoff(rails, vehicle, altitude)
            case GotoCommand(lat=lat, lon=lon, altitude=altitude):
                return check_goto(rails, vehicle, lat, lon, altitude)
            case SetHomeCommand(use_current=True):
                return check_set_home(rails, vehicle, None, None)
            case SetHomeCommand(lat=lat, lon=lon, alt_msl=alt_msl):
                return check_set_home(rails, vehicle, lat, lon, alt_msl)

    def check_mission(self, record: ReportedVehicle, items: list[MissionItem]) -> PlanCheck:
        """The mission check (`mission_check`) for this vehicle, against its effective
        rails."""
        return check_mission(
            items,
            snapshot_of(record),
            lambda: self.effective_rails(record.id),
            record.vehicle_type,
            record.autopilot,
        )

    async def check_mission_on_board(
        self, record: ReportedVehicle, read: MissionReader
    ) -> tuple[list[Violation], int]:
        """Before a switch to AUTO: every problem of the mission ``read`` from the vehicle,
        and its number of items (`mission_on_board`)."""
        return await unchecked_mission(read, lambda items: self.check_mission(record, items))

    async def check_current_item(
        self, record: ReportedVehicle, command: Command, read: MissionReader
    ) -> None:
        """Raise InvalidRequest for a new current item beyond the mission on board."""
        total = record.state.mission_total if record.state else None
        await check_current_item(read, total, command)
