"""Safety rails: the limits every command and mission is checked against before it is sent.

Each check returns every violated rule, not just the first, so an operator can fix a plan
in one go. When a rule needs something about the vehicle that is not known (its position,
home, altitude or battery level) the check fails closed with a "position_unknown"
violation instead of guessing, but only if such a rule is configured.

Altitudes are metres above home. Inputs are assumed range-checked by the caller (the API
schemas do that); the checks still refuse NaN and infinities outright, because a NaN
compares false against every limit and would otherwise pass them all.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass, field, fields
from typing import Final, Literal, TypeVar

from backend.safety.geometry import FencePolygon, InvalidGeofence
from common.geodesy import GeoPoint, haversine_m

RuleName = Literal[
    "geofence",
    "geofence_max_altitude",
    "max_altitude",
    "min_altitude",
    "max_distance_from_home",
    "min_launch_battery",
    "battery_sufficiency",
    "home_altitude",
    "position_unknown",
    "mission_item",
    "mission_unchecked",
]
GEOFENCE: Final = "geofence"
GEOFENCE_MAX_ALTITUDE: Final = "geofence_max_altitude"
MAX_ALTITUDE: Final = "max_altitude"
MIN_ALTITUDE: Final = "min_altitude"
MAX_DISTANCE_FROM_HOME: Final = "max_distance_from_home"
MIN_LAUNCH_BATTERY: Final = "min_launch_battery"
BATTERY_SUFFICIENCY: Final = "battery_sufficiency"
HOME_ALTITUDE: Final = "home_altitude"
POSITION_UNKNOWN: Final = "position_unknown"
# What an item's MAV_CMD needs (a place for a waypoint, a global frame, ...).
MISSION_ITEM: Final = "mission_item"
# A mission that would fly without having been checked: none on board, or unreadable.
MISSION_UNCHECKED: Final = "mission_unchecked"
# Every altitude a vehicle is given is measured from home's: moving home up or down
# moves them all, ceilings included. A new home may differ from the old by this much.
HOME_ALTITUDE_TOLERANCE_M: Final = 10.0
RULES: Final[tuple[RuleName, ...]] = (
    GEOFENCE,
    GEOFENCE_MAX_ALTITUDE,
    MAX_ALTITUDE,
    MIN_ALTITUDE,
    MAX_DISTANCE_FROM_HOME,
    MIN_LAUNCH_BATTERY,
    BATTERY_SUFFICIENCY,
    HOME_ALTITUDE,
    POSITION_UNKNOWN,
    MISSION_ITEM,
    MISSION_UNCHECKED,
)

DEFAULT_BATTERY_RESERVE_PCT: Final = 20.0

_T = TypeVar("_T")


@dataclass(frozen=True)
class Geofence:
    """A polygon the vehicle must stay inside, optionally with a ceiling above home.

    Validated on construction (raises InvalidGeofence). A repeated closing vertex is dropped
    from `polygon`.
    """

    polygon: tuple[GeoPoint, ...]
    max_altitude_m: float | None = None
    _shape: FencePolygon = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        shape = FencePolygon([(p.lat, p.lon) for p in self.polygon])
        alt = self.max_altitude_m
        if alt is not None and not (math.isfinite(alt) and alt >= 0):
            raise InvalidGeofence(f"max_altitude_m {alt} must be a finite number of metres ≥ 0")
        object.__setattr__(
            self, "polygon", tuple(GeoPoint(lat, lon) for lat, lon in shape.vertices)
        )
        object.__setattr__(self, "_shape", shape)

    def contains(self, point: GeoPoint) -> bool:
        return self._shape.contains(point.lat, point.lon)

    def distance_outside_m(self, point: GeoPoint) -> float:
        return self._shape.distance_outside_m(point.lat, point.lon)

    def leg_leaves(self, start: GeoPoint, end: GeoPoint) -> bool:
        return self._shape.leg_leaves(start.lat, start.lon, end.lat, end.lon)


@dataclass(frozen=True)
class SafetyRails:
    geofence: Geofence | None = None
    max_distance_from_home_m: float | None = None
    min_altitude_m: float | None = None
    max_altitude_m: float | None = None
    min_launch_battery_pct: float | None = None
    battery_reserve_pct: float = DEFAULT_BATTERY_RESERVE_PCT

    def __post_init__(self) -> None:
        # A NaN limit would let everything through, so bad limits are a hard error.
        for f in fields(self):
            value = getattr(self, f.name)
            if isinstance(value, float | int) and not (math.isfinite(value) and value >= 0):
                raise ValueError(f"{f.name} {value} must be a finite number ≥ 0")
        for name in ("min_launch_battery_pct", "battery_reserve_pct"):
            pct = getattr(self, name)
            if pct is not None and pct > 100:
                raise ValueError(f"{name} {pct} must be at most 100")

    def merged_with(self, override: SafetyRails | None) -> SafetyRails:
        """Site rails with a vehicle's own values laid over them wherever it sets one.

        The reserve has no "unset" value, so a vehicle's reserve counts as set when it
        differs from the default; a vehicle cannot override a site's reserve back to
        exactly the default.
        """
        if override is None:
            return self
        reserve = override.battery_reserve_pct
        return SafetyRails(
            geofence=_prefer(override.geofence, self.geofence),
            max_distance_from_home_m=_prefer(
                override.max_distance_from_home_m, self.max_distance_from_home_m
            ),
            min_altitude_m=_prefer(override.min_altitude_m, self.min_altitude_m),
            max_altitude_m=_prefer(override.max_altitude_m, self.max_altitude_m),
            min_launch_battery_pct=_prefer(
                override.min_launch_battery_pct, self.min_launch_battery_pct
            ),
            battery_reserve_pct=(
                self.battery_reserve_pct if reserve == DEFAULT_BATTERY_RESERVE_PCT else reserve
            ),
        )


def _prefer(own: _T | None, site: _T | None) -> _T | None:
    return site if own is None else own


@dataclass(frozen=True)
class VehicleSnapshot:
    """What the hub last heard from a vehicle; None (or NaN) means not known."""

    lat: float | None
    lon: float | None
    alt_rel: float | None
    home_lat: float | None
    home_lon: float | None
    battery_remaining_pct: float | None
    armed: bool
    landed: bool
    home_alt_msl: float | None = None


@dataclass(frozen=True)
class BatteryModel:
    capacity_mah: float = 5000
    hover_current_a: float = 15.0
    cruise_speed_m_s: float = 5.0
    climb_rate_m_s: float = 2.5
    descent_rate_m_s: float = 1.5

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{f.name} {value} must be a finite number > 0")


@dataclass(frozen=True)
class Waypoint:
    lat: float
    lon: float
    alt_rel: float
    # The mission item this place comes from (1 is the first after home), so that a
    # refusal names the item the operator wrote; None: named by its place in the list.
    item: int | None = None

    def name(self, index: int) -> str:
        """``index`` counts from 1 among the waypoints."""
        return f"item {self.item}" if self.item is not None else f"waypoint {index}"


@dataclass(frozen=True)
class Violation:
    rule: str
    message: str
    limit: float | None = None
    value: float | None = None


@dataclass(frozen=True)
class BatteryEstimate:
    """distance_m is horizontal, including the return home; percentages are of capacity."""

    distance_m: float
    flight_time_s: float
    required_pct: float
    available_pct: float | None


@dataclass(frozen=True)
class PlanCheck:
    violations: tuple[Violation, ...]
    estimate: BatteryEstimate | None

    @property
    def ok(self) -> bool:
        return not self.violations


# --- Helpers --------------------------------------------------------------------------------


def _known(value: float | None) -> float | None:
    return value if value is not None and math.isfinite(value) else None


def _point(lat: float | None, lon: float | None) -> GeoPoint | None:
    lat, lon = _known(lat), _known(lon)
    if lat is None or lon is None or (lat, lon) == (0.0, 0.0):
        # 0°N 0°E is an autopilot's "no position yet" (ArduPilot before its EKF origin),
        # from an agent that passed it on: unknown, so the rules fail closed.
        return None
    return GeoPoint(lat, lon)


def _position(vehicle: VehicleSnapshot) -> GeoPoint | None:
    return _point(vehicle.lat, vehicle.lon)


def _home(vehicle: VehicleSnapshot) -> GeoPoint | None:
    return _point(vehicle.home_lat, vehicle.home_lon)


def _altitude(vehicle: VehicleSnapshot) -> float | None:
    alt = _known(vehicle.alt_rel)
    # A landed vehicle is on the ground; its altitude reading only adds barometer drift.
    return 0.0 if alt is None and vehicle.landed else alt


def _require_target(what: str, lat: float, lon: float, alt: float) -> None:
    if not (math.isfinite(lat) and -90 <= lat <= 90 and math.isfinite(lon) and -180 <= lon <= 180):
        raise ValueError(f"{what} position ({lat}, {lon}) is not a valid latitude and longitude")
    _require_altitude(what, alt)


def _require_altitude(what: str, alt: float) -> None:
    if not math.isfinite(alt):
        raise ValueError(f"{what} altitude {alt} is not a finite number")


def _pair(value: float, limit: float, decimals: int) -> tuple[str, str]:
    """Format a value and its limit so that they never print the same when they differ."""
    while True:
        shown, bound = f"{value:.{decimals}f}", f"{limit:.{decimals}f}"
        if shown != bound or decimals >= 3:
            return shown, bound
        decimals += 1


def _others(count: int, noun: str) -> str:
    return "" if count <= 1 else f" ({count} {noun})"


class _Report:
    """Collects violations, and the unknowns that stopped rules from being checked."""

    _ITEM_ORDER = ("position", "home position", "home altitude", "altitude", "battery level")

    def __init__(self) -> None:
        self._violations: list[Violation] = []
        self._missing: dict[str, None] = {}
        self._blocked: dict[str, None] = {}

    def add(self, rule: str, message: str, limit: float | None, value: float | None) -> None:
        self._violations.append(Violation(rule, message, limit, value))

    def unknown(self, item: str, rule: str) -> None:
        self._missing[item] = None
        self._blocked[rule] = None

    def violations(self) -> list[Violation]:
        result = list(self._violations)
        if self._missing:
            items = [i for i in self._ITEM_ORDER if i in self._missing]
            verb = "is" if len(items) == 1 else "are"
            rules = [r for r in RULES if r in self._blocked]
            result.append(
                Violation(
                    POSITION_UNKNOWN,
                    f"cannot check {_and(rules)}: the vehicle's {_and(items)} {verb} not known",
                )
            )
        return result


def _and(words: Sequence[str]) -> str:
    return words[0] if len(words) == 1 else ", ".join(words[:-1]) + " and " + words[-1]


# --- Rules shared by the checks -------------------------------------------------------------


def _check_launch_battery(rails: SafetyRails, vehicle: VehicleSnapshot, report: _Report) -> None:
    limit = rails.min_launch_battery_pct
    if limit is None or not vehicle.landed:
        return
    battery = _known(vehicle.battery_remaining_pct)
    if battery is None:
        report.unknown("battery level", MIN_LAUNCH_BATTERY)
    elif battery < limit:
        shown, bound = _pair(battery, limit, 0)
        report.add(
            MIN_LAUNCH_BATTERY,
            f"battery {shown}% is below the {bound}% needed to launch",
            limit,
            battery,
        )


def _altitude_limits(rails: SafetyRails) -> list[tuple[str, float, bool, str]]:
    """(rule, limit, is a ceiling, how messages name it) for each altitude limit set."""
    limits: list[tuple[str, float, bool, str]] = []
    if rails.max_altitude_m is not None:
        limits.append((MAX_ALTITUDE, rails.max_altitude_m, True, "the {} m ceiling"))
    fence_ceiling = rails.geofence.max_altitude_m if rails.geofence else None
    if fence_ceiling is not None:
        limits.append((GEOFENCE_MAX_ALTITUDE, fence_ceiling, True, "the geofence's {} m ceiling"))
    if rails.min_altitude_m is not None:
        limits.append((MIN_ALTITUDE, rails.min_altitude_m, False, "the {} m floor"))
    return limits


def _check_altitudes(
    rails: SafetyRails, targets: Sequence[tuple[str, float]], report: _Report
) -> None:
    """Each altitude limit against (label, altitude) targets: one violation per limit,
    naming the target furthest beyond it."""
    for rule, limit, ceiling, name in _altitude_limits(rails):
        offenders = [
            (alt, label) for label, alt in targets if (alt > limit if ceiling else alt < limit)
        ]
        if not offenders:
            continue
        pick = max if ceiling else min
        alt, label = pick(offenders, key=lambda o: o[0])
        shown, bound = _pair(alt, limit, 1)
        where = "above" if ceiling else "below"
        message = f"{label} {shown} m is {where} {name.format(bound)}"
        report.add(rule, message + _others(len(offenders), f"waypoints are {where} it"), limit, alt)


def _distance_violation(
    rails: SafetyRails, label: str, distance: float, suffix: str, report: _Report
) -> None:
    limit = rails.max_distance_from_home_m
    if limit is not None and distance > limit:
        shown, bound = _pair(distance, limit, 0)
        report.add(
            MAX_DISTANCE_FROM_HOME,
            f"{label} is {shown} m from home; the limit is {bound} m{suffix}",
            limit,
            distance,
        )


def _outside_message(label: str, distance: float) -> str:
    return f"{label} is {distance:.0f} m outside the geofence"


# --- Command checks -------------------------------------------------------------------------


def check_arm(rails: SafetyRails, vehicle: VehicleSnapshot) -> list[Violation]:
    report = _Report()
    _check_launch_battery(rails, vehicle, report)
    return report.violations()


def check_takeoff(
    rails: SafetyRails, vehicle: VehicleSnapshot, altitude_m: float
) -> list[Violation]:
    _require_altitude("take-off", altitude_m)
    report = _Report()
    _check_launch_battery(rails, vehicle, report)
    _check_altitudes(rails, [("take-off altitude", altitude_m)], report)
    fence = rails.geofence
    if fence is not None:
        here = _position(vehicle)
        if here is None:
            report.unknown("position", GEOFENCE)
        elif not fence.contains(here):
            outside = fence.distance_outside_m(here)
            report.add(GEOFENCE, _outside_message("vehicle", outside), None, outside)
    return report.violations()


def check_goto(
    rails: SafetyRails, vehicle: VehicleSnapshot, lat: float, lon: float, altitude_m: float
) -> list[Violation]:
    _require_target("target", lat, lon, altitude_m)
    report = _Report()
    target = GeoPoint(lat, lon)
    _check_altitudes(rails, [("target altitude", altitude_m)], report)
    fence = rails.geofence
    if fence is not None:
        here = _position(vehicle)
        if not fence.contains(target):
            outside = fence.distance_outside_m(target)
            report.add(GEOFENCE, _outside_message("target", outside), None, outside)
        elif here is None:
            report.unknown("position", GEOFENCE)
        # A vehicle already outside is not held to the leg: refusing the way back in would
        # leave no way to recover it.
        elif fence.contains(here) and fence.leg_leaves(here, target):
            report.add(
                GEOFENCE,
                "the straight leg from the vehicle's position to the target leaves the geofence",
                None,
                None,
            )
    if rails.max_distance_from_home_m is not None:
        home = _home(vehicle)
        if home is None:
            report.unknown("home position", MAX_DISTANCE_FROM_HOME)
        else:
            distance = haversine_m(home.lat, home.lon, lat, lon)
            _distance_violation(rails, "target", distance, "", report)
    return report.violations()


def check_set_home(
    rails: SafetyRails,
    vehicle: VehicleSnapshot,
    lat: float | None,
    lon: float | None,
    alt_msl: float | None = None,
) -> list[Violation]:
    """A new home at (lat, lon, alt_msl), or where the vehicle is when those are None.

    Home is where RTL, and every failsafe that returns, flies to: a home outside the
    geofence, or one reached by a straight leg that leaves it, would send the vehicle out
    of the fence; and the range limit is measured from home, so home may not move further
    than that limit from where it is now. Every altitude is measured from home's, so its
    altitude may barely change, and home is not taken from a vehicle in the air.
    """
    report = _Report()
    if lat is None and not vehicle.landed:
        report.add(
            HOME_ALTITUDE,
            "the vehicle is in the air: home would take its altitude, and every altitude "
            "measured from home (take-off, go-to, RTL, the ceiling) would move with it",
            None,
            None,
        )
    if alt_msl is not None:
        old_alt = _known(vehicle.home_alt_msl)
        if old_alt is None:
            report.unknown("home altitude", HOME_ALTITUDE)
        elif abs(alt_msl - old_alt) > HOME_ALTITUDE_TOLERANCE_M:
            report.add(
                HOME_ALTITUDE,
                f"new home is {alt_msl - old_alt:+.1f} m from the current home's altitude "
                f"(at most ±{HOME_ALTITUDE_TOLERANCE_M:g} m): every altitude measured from "
                "home would move with it",
                HOME_ALTITUDE_TOLERANCE_M,
                alt_msl - old_alt,
            )
    here = _position(vehicle)
    if lat is None or lon is None:
        label, target = "the vehicle's position (the new home)", here
    else:
        _require_target("home", lat, lon, 0.0)
        label, target = "new home", GeoPoint(lat, lon)
    fence = rails.geofence
    if fence is not None:
        if target is None:
            report.unknown("position", GEOFENCE)
        elif not fence.contains(target):
            outside = fence.distance_outside_m(target)
            message = _outside_message(label, outside) + ": RTL would fly there"
            report.add(GEOFENCE, message, None, outside)
        elif here is None:
            report.unknown("position", GEOFENCE)
        elif fence.contains(here) and fence.leg_leaves(here, target):
            report.add(
                GEOFENCE,
                "the straight leg from the vehicle's position to the new home leaves the "
                "geofence: RTL would fly it",
                None,
                None,
            )
    if rails.max_distance_from_home_m is not None:
        home = _home(vehicle)
        if home is None or target is None:
            report.unknown("home position" if home is None else "position", MAX_DISTANCE_FROM_HOME)
        else:
            distance = haversine_m(home.lat, home.lon, target.lat, target.lon)
            _distance_violation(rails, label, distance, "", report)
    return report.violations()


# --- Mission checks -------------------------------------------------------------------------


def _plan_geofence(
    fence: Geofence, vehicle: VehicleSnapshot, waypoints: Sequence[Waypoint], report: _Report
) -> None:
    points = [GeoPoint(wp.lat, wp.lon) for wp in waypoints]
    inside = [fence.contains(p) for p in points]
    outside = [(fence.distance_outside_m(p), i) for i, p in enumerate(points) if not inside[i]]
    here = _position(vehicle)
    if here is None:
        report.unknown("position", GEOFENCE)
    # Legs with an end outside are already reported through that end; a first leg from a
    # vehicle outside the fence is allowed so that a mission can bring it back.
    stops: list[tuple[str, GeoPoint | None, bool]] = [
        ("the vehicle's position", here, here is not None and fence.contains(here))
    ]
    stops += [(waypoints[i].name(i + 1), p, inside[i]) for i, p in enumerate(points)]
    legs = [
        f"the leg from {a_label} to {b_label}"
        for (a_label, a, a_in), (b_label, b, b_in) in itertools.pairwise(stops)
        if a is not None and b is not None and a_in and b_in and fence.leg_leaves(a, b)
    ]
    if outside:
        distance, worst = max(outside)
        message = _outside_message(waypoints[worst].name(worst + 1), distance)
        message += _others(len(outside), "waypoints are outside it")
        if legs:
            verb = "leaves" if len(legs) == 1 else "leave"
            message += f"; {_count(len(legs), 'leg')} between waypoints inside it also {verb} it"
        report.add(GEOFENCE, message, None, distance)
    elif legs:
        report.add(
            GEOFENCE,
            f"{legs[0]} leaves the geofence{_others(len(legs), 'legs leave it')}",
            None,
            None,
        )


def _count(n: int, noun: str) -> str:
    return f"{n} {noun}" if n == 1 else f"{n} {noun}s"


def _plan_distance(
    rails: SafetyRails, vehicle: VehicleSnapshot, waypoints: Sequence[Waypoint], report: _Report
) -> None:
    limit = rails.max_distance_from_home_m
    if limit is None:
        return
    home = _home(vehicle)
    if home is None:
        report.unknown("home position", MAX_DISTANCE_FROM_HOME)
        return
    distances = [haversine_m(home.lat, home.lon, wp.lat, wp.lon) for wp in waypoints]
    far = max(range(len(distances)), key=distances.__getitem__)
    suffix = _others(sum(d > limit for d in distances), "waypoints are beyond it")
    _distance_violation(rails, waypoints[far].name(far + 1), distances[far], suffix, report)


def _missing_for_estimate(vehicle: VehicleSnapshot) -> list[str]:
    missing = []
    if _position(vehicle) is None:
        missing.append("position")
    if _home(vehicle) is None:
        missing.append("home position")
    if _altitude(vehicle) is None:
        missing.append("altitude")
    return missing


def estimate_plan(
    vehicle: VehicleSnapshot, waypoints: Sequence[Waypoint], model: BatteryModel = BatteryModel()
) -> BatteryEstimate:
    """Battery needed to fly the waypoints from where the vehicle is, return home and land.

    Conservative multirotor model: horizontal and vertical moves are flown one after the
    other, and the whole flight draws hover current. Raises ValueError when the vehicle's
    position, home or altitude is not known.
    """
    missing = _missing_for_estimate(vehicle)
    here, home, alt = _position(vehicle), _home(vehicle), _altitude(vehicle)
    if missing or here is None or home is None or alt is None:
        raise ValueError(f"cannot estimate the mission: the vehicle's {_and(missing)} not known")
    for i, wp in enumerate(waypoints, start=1):
        _require_target(f"waypoint {i}", wp.lat, wp.lon, wp.alt_rel)
    stops = [(here.lat, here.lon, alt)]
    stops += [(wp.lat, wp.lon, wp.alt_rel) for wp in waypoints]
    last_alt = stops[-1][2]
    stops += [(home.lat, home.lon, last_alt), (home.lat, home.lon, 0.0)]  # return, then land
    distance = time = 0.0
    for (lat1, lon1, alt1), (lat2, lon2, alt2) in itertools.pairwise(stops):
        leg = haversine_m(lat1, lon1, lat2, lon2)
        climb = alt2 - alt1
        distance += leg
        time += leg / model.cruise_speed_m_s
        time += climb / model.climb_rate_m_s if climb > 0 else -climb / model.descent_rate_m_s
    # Charge in mAh is amps * seconds / 3.6.
    required = time * model.hover_current_a / 3.6 / model.capacity_mah * 100
    return BatteryEstimate(distance, time, required, _known(vehicle.battery_remaining_pct))


def _plan_battery(
    rails: SafetyRails,
    vehicle: VehicleSnapshot,
    waypoints: Sequence[Waypoint],
    model: BatteryModel,
    report: _Report,
) -> BatteryEstimate | None:
    missing = _missing_for_estimate(vehicle)
    for item in missing:
        report.unknown(item, BATTERY_SUFFICIENCY)
    if missing:
        return None
    estimate = estimate_plan(vehicle, waypoints, model)
    available = estimate.available_pct
    needed = estimate.required_pct + rails.battery_reserve_pct
    if available is None:
        report.unknown("battery level", BATTERY_SUFFICIENCY)
    elif needed > available:
        report.add(
            BATTERY_SUFFICIENCY,
            f"mission needs about {estimate.required_pct:.0f}% of the battery plus a "
            f"{rails.battery_reserve_pct:.0f}% reserve; {available:.0f}% remains",
            available,
            needed,
        )
    return estimate


def evaluate_plan(
    rails: SafetyRails,
    vehicle: VehicleSnapshot,
    waypoints: Sequence[Waypoint],
    model: BatteryModel = BatteryModel(),
) -> PlanCheck:
    """check_plan's violations together with the battery estimate (None when the vehicle's
    position, home or altitude is not known)."""
    if not waypoints:
        raise ValueError("a mission needs at least one waypoint")
    for i, wp in enumerate(waypoints, start=1):
        _require_target(wp.name(i), wp.lat, wp.lon, wp.alt_rel)
    report = _Report()
    _check_launch_battery(rails, vehicle, report)
    _check_altitudes(
        rails, [(f"{wp.name(i)} altitude", wp.alt_rel) for i, wp in enumerate(waypoints, 1)], report
    )
    if rails.geofence is not None:
        _plan_geofence(rails.geofence, vehicle, waypoints, report)
    _plan_distance(rails, vehicle, waypoints, report)
    estimate = _plan_battery(rails, vehicle, waypoints, model, report)
    return PlanCheck(tuple(report.violations()), estimate)


def check_plan(
    rails: SafetyRails,
    vehicle: VehicleSnapshot,
    waypoints: Sequence[Waypoint],
    model: BatteryModel = BatteryModel(),
) -> list[Violation]:
    """Every waypoint and leg (from the vehicle's position) against every rule, each rule
    reported once with its worst offender."""
    return list(evaluate_plan(rails, vehicle, waypoints, model).violations)
