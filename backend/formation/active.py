"""A formation as the hub holds it while it flies: its request and plan, who started and
stopped it, when it formed up, each follower's slot and tracking, the scan relayed last."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

from backend.formation.metrics import TrackingMetrics
from backend.formation.planner import FormationPlan
from backend.formation.schemas import FormationRequest
from common.formation import Offset

# joining: the followers make for their slots; flying: the leader flies the route;
# route_done: it reached the route's last waypoint and the formation holds there;
# stopped: ended (by the operator, a failed join, a hub restart).
FormationState = Literal["joining", "flying", "route_done", "stopped"]


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
    # The fleet's seconds per wall second (a simulator's speed-up): the route runs in them.
    speedup: float = 1.0

    @property
    def route_done_at(self) -> float | None:
        """Unix time the leader reaches (or reached) the route's end: when it formed up
        plus the route's duration; None while joining, or when it stopped before then."""
        if self.formed_at is None:
            return None
        done_at = self.formed_at + self.plan.route.duration_s / self.speedup
        if self.stopped_at is not None and self.stopped_at < done_at:
            return None
        return done_at

    def state(self, now: float) -> FormationState:
        if self.stopped is not None:
            return "stopped"
        done_at = self.route_done_at
        if done_at is None:
            return "joining"
        return "route_done" if now >= done_at else "flying"

    @property
    def followers(self) -> list[str]:
        return list(self.offsets)

    @property
    def members(self) -> list[str]:
        leader = [self.plan.leader_id] if self.plan.leader_id else []
        return leader + self.followers
