"""The safety gate between an operator's request and the vehicle: every command and
mission is checked against the effective rails (the site's, narrowed per vehicle)."""

from __future__ import annotations

from backend.auth.policy import Permission, Principal
from backend.errors import Forbidden
from backend.fleet.registry import VehicleRecord
from backend.missions import PlanCheck, check_mission
from backend.safety import (
    SafetyRails,
    VehicleSnapshot,
    Violation,
    check_arm,
    check_goto,
    check_set_home,
    check_takeoff,
)
from backend.safety.critical_params import critical_reason
from backend.safety.schemas import SafetyRailsModel
from backend.settings import HubSettings
from backend.storage.rails import SITE, RailsRepository, vehicle_scope
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

# Below this height a vehicle counts as on the ground for the launch rules.
LANDED_BELOW_M = 0.5


def snapshot_of(record: VehicleRecord) -> VehicleSnapshot:
    state = record.state
    if state is None:
        return VehicleSnapshot(None, None, None, None, None, None, armed=False, landed=True)
    landed = not state.armed or (state.alt_rel is not None and state.alt_rel < LANDED_BELOW_M)
    return VehicleSnapshot(
        lat=state.lat,
        lon=state.lon,
        alt_rel=state.alt_rel,
        home_lat=state.home_lat,
        home_lon=state.home_lon,
        battery_remaining_pct=state.battery_remaining,
        armed=state.armed,
        landed=landed,
        home_alt_msl=state.home_alt_msl,
    )


class SafetyGate:
    def __init__(self, repository: RailsRepository, settings: HubSettings) -> None:
        self.repository = repository
        self.settings = settings

    def site_rails(self) -> SafetyRails:
        stored = self.repository.get(SITE)
        if stored is not None:
            return SafetyRailsModel.model_validate_json(stored).to_rails()
        settings = self.settings
        return SafetyRails(
            max_altitude_m=settings.max_altitude_m,
            min_altitude_m=settings.min_altitude_m,
            max_distance_from_home_m=settings.max_distance_from_home_m,
            min_launch_battery_pct=settings.min_launch_battery_pct,
            battery_reserve_pct=settings.battery_reserve_pct,
            min_height_above_home_m=settings.min_height_above_home_m,
        )

    def vehicle_rails(self, vehicle_id: str) -> SafetyRails | None:
        stored = self.repository.get(vehicle_scope(vehicle_id))
        return SafetyRailsModel.model_validate_json(stored).to_rails() if stored else None

    def effective_rails(self, vehicle_id: str) -> SafetyRails:
        return self.site_rails().merged_with(self.vehicle_rails(vehicle_id))

    def check_authority(
        self, principal: Principal, record: VehicleRecord, command: Command
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

    def check_command(self, record: VehicleRecord, command: Command) -> list[Violation]:
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

    def check_mission(self, record: VehicleRecord, items: list[MissionItem]) -> PlanCheck:
        """The mission check (`backend.missions.check`) for this vehicle, against its
        effective rails."""
        return check_mission(
            items,
            snapshot_of(record),
            lambda: self.effective_rails(record.id),
            record.vehicle_type,
            record.autopilot,
        )
