"""A formation as the hub holds it while it flies: its request and plan, who started and
stopped it, when it formed up, each follower's slot and tracking, the scan relayed last."""

from __future__ import annotations

from dataclasses import dataclass, field

from backend.formation.metrics import TrackingMetrics
from backend.formation.planner import FormationPlan
from backend.formation.schemas import FormationRequest
from common.formation import Offset


@dataclass
class ActiveFormation:
    id: str
    request: FormationRequest
    plan: FormationPlan
    started_at: float
    started_by: str = ""
    stopped: str | None = None  # why, once stopped
    stopped_by: str | None = None
    stopped_at: float | None = None
    formed_at: float | None = None  # when every follower reached its slot: the route starts
    offsets: dict[str, Offset] = field(default_factory=dict)
    metrics: TrackingMetrics = field(default_factory=TrackingMetrics)
    scan_seq: int | None = None  # the leader's scan last relayed
    scan_relayed_at: float = 0.0

    @property
    def followers(self) -> list[str]:
        return list(self.offsets)

    @property
    def members(self) -> list[str]:
        leader = [self.plan.leader_id] if self.plan.leader_id else []
        return leader + self.followers
