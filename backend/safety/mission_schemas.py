"""REST bodies of missions: the mission itself (the same body for the check, the upload and
the download) and the mission check's answer.

Unknown fields, NaN and infinities are rejected, as for the rails' bodies.
"""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict, Field

from backend.safety.mission_battery import BatteryEstimate
from backend.safety.mission_rails import PlanCheck
from backend.safety.schemas import ViolationModel
from backend.safety.violations import Violation
from protocol.messages import MissionItem

MAX_WAYPOINTS = 2000


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


class Mission(_Strict):
    """One mission, the same body for the check, the upload and the download."""

    items: list[MissionItem] = Field(
        min_length=1,
        max_length=MAX_WAYPOINTS,
        description="Flown in order from the vehicle's position; item 1 is the first "
        "(home, item 0, is the vehicle's own and is not sent)",
    )


class BatteryEstimateModel(_Strict):
    distance_m: float = Field(description="Horizontal distance including the return home")
    flight_time_s: float
    required_pct: float = Field(description="Battery the flight needs, percent of capacity")
    available_pct: float | None = Field(description="Battery remaining now; null if unknown")

    @classmethod
    def from_estimate(cls, estimate: BatteryEstimate) -> BatteryEstimateModel:
        return cls(
            distance_m=estimate.distance_m,
            flight_time_s=estimate.flight_time_s,
            required_pct=estimate.required_pct,
            available_pct=estimate.available_pct,
        )


class MissionCheckResponse(_Strict):
    ok: bool = Field(description="True when no rule is violated")
    violations: list[ViolationModel]
    estimate: BatteryEstimateModel | None = Field(
        description="Null when the vehicle's position, home or altitude is not known"
    )

    @classmethod
    def build(
        cls, violations: list[Violation], estimate: BatteryEstimate | None
    ) -> MissionCheckResponse:
        return cls(
            ok=not violations,
            violations=[ViolationModel.from_violation(v) for v in violations],
            estimate=BatteryEstimateModel.from_estimate(estimate) if estimate else None,
        )

    @classmethod
    def from_plan_check(cls, check: PlanCheck) -> MissionCheckResponse:
        return cls.build(list(check.violations), check.estimate)
