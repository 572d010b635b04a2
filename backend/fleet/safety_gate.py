"""The safety gate between an operator's request and the vehicle: every command and
mission is checked against the effective rails (the site's, narrowed per vehicle)."""

from __future__ import annotations

from backend.auth.policy import Permission, Principal
from backend.errors import Forbidden, InvalidRequest
from backend.fleet.registry import VehicleRecord
from backend.safety import (
    PlanCheck,
    SafetyRails,
    VehicleSnapshot,
    Violation,
    Waypoint,
    check_arm,
    check_goto,
    check_set_home,
    check_takeoff,
    evaluate_plan,
)
from backend.safety.critical_params import critical_reason
from backend.safety.rails import MISSION_ITEM
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
from protocol.mission_rules import mission_problems

# Below this height a vehicle counts as on the ground for the launch rules.
LANDED_BELOW_M = 0.5
# MAV_CMD numbers of the navigation commands that fly somewhere.
NAV_WAYPOINT, NAV_LOITER_UNLIM, NAV_LOITER_TURNS, NAV_LOITER_TIME = 16, 17, 18, 19
NAV_LAND, NAV_TAKEOFF, NAV_SPLINE_WAYPOINT = 21, 22, 82
NAV_LOITER_TO_ALT, NAV_VTOL_TAKEOFF, NAV_VTOL_LAND, NAV_PAYLOAD_PLACE = 31, 84, 85, 94
DO_SET_HOME = 179  # with a position: home moves there mid-mission, so RTL goes there
POSITIONED = {
    NAV_WAYPOINT,
    NAV_LOITER_UNLIM,
    NAV_LOITER_TURNS,
    NAV_LOITER_TIME,
    NAV_LAND,
    NAV_SPLINE_WAYPOINT,
    NAV_LOITER_TO_ALT,
    NAV_VTOL_TAKEOFF,
    NAV_VTOL_LAND,
    NAV_PAYLOAD_PLACE,
    DO_SET_HOME,
}
# Frames whose altitude is above mean sea level rather than above home.
AMSL_FRAMES = {0, 5}  # MAV_FRAME_GLOBAL, MAV_FRAME_GLOBAL_INT


def mission_waypoints(items: list[MissionItem], record: VehicleRecord) -> list[Waypoint]:
    """The places a mission will take the vehicle, for the rails to check.

    A take-off climbs where the vehicle stands; a land with no position lands in place."""
    here = record.state
    home_alt = here.home_alt_msl if here else None
    points: list[Waypoint] = []
    for number, item in enumerate(items, 1):
        has_position = (item.lat, item.lon) != (0.0, 0.0)
        alt = item.alt
        if item.frame in AMSL_FRAMES:
            if home_alt is None:
                # The rails measure from home: refuse rather than guess.
                raise InvalidRequest(
                    "items",
                    f"item {number}: its altitude is above sea level, and the vehicle has "
                    "not reported home's altitude to check it against",
                )
            alt = item.alt - home_alt
        if item.command in POSITIONED and has_position:
            points.append(Waypoint(item.lat, item.lon, alt, number))
        elif item.command == NAV_TAKEOFF and here and here.lat is not None and here.lon is not None:
            points.append(Waypoint(here.lat, here.lon, item.alt, number))
    return points


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
        """The mission check, the same for a check, an upload and a switch to AUTO: what
        each item's command needs, then every rail the mission's places break, and the
        battery estimate when it can be made. Items number from 1 (home is 0)."""
        problems = tuple(
            Violation(MISSION_ITEM, problem)
            for problem in mission_problems(items, record.vehicle_type, record.autopilot)
        )
        waypoints = mission_waypoints(items, record)
        if not waypoints:
            return PlanCheck(problems, None)  # no place to go: nothing for the rails
        plan = evaluate_plan(self.effective_rails(record.id), snapshot_of(record), waypoints)
        return PlanCheck(problems + plan.violations, plan.estimate)
