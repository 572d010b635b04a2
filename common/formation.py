"""Formation geometry, shared by the hub's planner and each follower's agent.

A follower's slot is an offset from its leader: metres forward and right in the leader's
heading frame (so the shape turns with the leader), or north and east (so it does not),
and metres up from the leader's altitude. Shape presets lay followers out at a spacing.
The leader's state is predicted forward over the link's delay at its velocity, as
ArduPilot's AP_Follow does, so that a follower flies where its slot is now, not where it
was when the leader reported it.

All positions here are local metres (north, east, up) on one tangent plane; the callers
convert to and from latitude/longitude with `common.geodesy.LocalFrame`.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from enum import StrEnum


class OffsetFrame(StrEnum):
    HEADING = "heading"  # forward, right: turns with the leader
    NORTH_EAST = "ne"  # north, east: keeps its bearing whatever the leader's heading


class Shape(StrEnum):
    LINE = "line"  # abreast: alternately right and left of the leader
    WEDGE = "wedge"  # a V behind the leader (a triangle with two followers)
    TRIANGLE = "triangle"  # the same as a wedge
    COLUMN = "column"  # one behind another
    CIRCLE = "circle"  # evenly round the leader at the spacing's radius


@dataclass(frozen=True, slots=True)
class Offset:
    """A slot relative to the leader: ``x`` forward (or north), ``y`` right (or east),
    ``up`` metres above the leader."""

    x: float
    y: float
    up: float = 0.0
    frame: OffsetFrame = OffsetFrame.HEADING

    def north_east_up(self, heading_rad: float) -> tuple[float, float, float]:
        """The offset in north, east, up metres for a leader on ``heading_rad``
        (clockwise from north)."""
        if self.frame is OffsetFrame.NORTH_EAST:
            return self.x, self.y, self.up
        c, s = math.cos(heading_rad), math.sin(heading_rad)
        return self.x * c - self.y * s, self.x * s + self.y * c, self.up


def shape_offsets(
    shape: Shape, count: int, spacing_m: float, ups: Sequence[float] = ()
) -> list[Offset]:
    """``count`` heading-frame slots of a preset, ``spacing_m`` apart along the shape;
    ``ups`` gives each follower's height above the leader (0 where not given)."""
    if count < 0:
        raise ValueError("the number of followers cannot be negative")
    if not (math.isfinite(spacing_m) and spacing_m > 0):
        raise ValueError(f"the spacing must be a positive number of metres, not {spacing_m}")

    def up(i: int) -> float:
        return ups[i] if i < len(ups) else 0.0

    out: list[Offset] = []
    for i in range(count):
        rank = i // 2 + 1  # 1, 1, 2, 2, ...
        side = 1.0 if i % 2 == 0 else -1.0  # right first, then left
        if shape is Shape.LINE:
            out.append(Offset(0.0, side * rank * spacing_m, up(i)))
        elif shape in (Shape.WEDGE, Shape.TRIANGLE):
            # 45 degrees back on either side: each rank spacing_m from the one before
            leg = rank * spacing_m / math.sqrt(2.0)
            out.append(Offset(-leg, side * leg, up(i)))
        elif shape is Shape.COLUMN:
            out.append(Offset(-(i + 1) * spacing_m, 0.0, up(i)))
        else:
            angle = math.pi + 2.0 * math.pi * i / count  # the first one behind
            out.append(Offset(spacing_m * math.cos(angle), spacing_m * math.sin(angle), up(i)))
    return out


def closest_pair(
    points: Sequence[tuple[float, float, float]],
) -> tuple[float, int, int] | None:
    """The smallest 3-D distance between two of ``points`` and their indices."""
    best: tuple[float, int, int] | None = None
    for (i, a), (j, b) in itertools.combinations(enumerate(points), 2):
        d = math.dist(a, b)
        if best is None or d < best[0]:
            best = (d, i, j)
    return best


@dataclass(frozen=True, slots=True)
class LeaderState:
    """The leader as it reported itself: local position (north, east, up), velocity
    (north, east, up m/s), heading (radians clockwise from north) and when (seconds on
    the clock the follower compares it with)."""

    north: float
    east: float
    up: float
    vn: float
    ve: float
    vu: float
    heading_rad: float
    time_s: float

    def predicted(self, now_s: float, max_lead_s: float = 1.0) -> LeaderState:
        """The state ``now_s`` if the leader kept its velocity (AP_Follow's estimate);
        the lead is bounded so a stale report is not flung far ahead."""
        lead = min(max(now_s - self.time_s, 0.0), max_lead_s)
        return LeaderState(
            self.north + self.vn * lead,
            self.east + self.ve * lead,
            self.up + self.vu * lead,
            self.vn,
            self.ve,
            self.vu,
            self.heading_rad,
            now_s,
        )


def slot_target(
    leader: LeaderState, offset: Offset
) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """A follower's target: its slot's position (north, east, up) and velocity, the
    leader's. The slot turns with the leader in the heading frame, but the turn's own
    velocity is left out: the follower's position loop takes it up."""
    dn, de, du = offset.north_east_up(leader.heading_rad)
    position = (leader.north + dn, leader.east + de, leader.up + du)
    return position, (leader.vn, leader.ve, leader.vu)


class Controller(StrEnum):
    """How a follower steers. Leader-following flies its slot around the leader's
    predicted state (position target, the leader's velocity as feed-forward); consensus
    also takes its neighbours' states, so the followers agree on where the leader is
    and close on their slots together (velocity targets)."""

    LEADER_FOLLOWER = "leader_follower"
    CONSENSUS = "consensus"


@dataclass(frozen=True, slots=True)
class ConsensusGains:
    """First-order leader-following consensus: ``k_leader`` weighs the pull to the slot
    around the leader, ``k_neighbour`` (per unit edge weight) the pull to agreement with
    the neighbours on where the leader is. Only their ratio shapes the target: the sum
    is the autopilot's position gain (see `consensus_target`)."""

    k_leader: float = 1.0
    k_neighbour: float = 0.5


@dataclass(frozen=True, slots=True)
class NeighbourState:
    """A neighbour in the communication graph: where it is (north, east, up), its slot,
    and the edge's weight a_ij."""

    position: tuple[float, float, float]
    offset: Offset
    weight: float = 1.0


def consensus_target(
    leader: LeaderState,
    offset: Offset,
    neighbours: Sequence[NeighbourState],
    gains: ConsensusGains,
) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """The consensus law as a position target and velocity feed-forward for the
    autopilot's position controller, which flies v = v_ff + K (target - p_i).

    The law: v_i = v_L + k_L (p_L + d_i - p_i) + k_n sum_j a_ij ((p_j - d_j) - (p_i - d_i)).
    Its target is the weighted mean of where the leader puts the slot (p_L + d_i) and
    where each neighbour's position puts it (p_j - d_j + d_i), weights k_L and k_n a_ij,
    and the feed-forward is v_L; the controller then flies the law with k_L + k_n
    sum_j a_ij = K. Handing the autopilot the target, not a velocity, keeps its own
    (faster, acceleration-limited) position loop the only one: a velocity target, or a
    target built from the vehicle's own sampled position, would wrap a second, slower
    loop round it that rings at every corner. Saturation is the autopilot's
    (WPNAV_SPEED / MPC_XY_VEL_MAX). p_j - d_j is neighbour j's estimate of the leader:
    the followers agree, so one that lags drags its neighbours less than the leader's
    pull brings it on. The offsets turn with the leader's heading."""
    d_i = offset.north_east_up(leader.heading_rad)
    total = gains.k_leader
    target = [
        gains.k_leader * (p + d)
        for p, d in zip((leader.north, leader.east, leader.up), d_i, strict=True)
    ]
    for n in neighbours:
        w = gains.k_neighbour * n.weight
        d_j = n.offset.north_east_up(leader.heading_rad)
        total += w
        for axis in range(3):
            target[axis] += w * (n.position[axis] - d_j[axis] + d_i[axis])
    return (target[0] / total, target[1] / total, target[2] / total), (
        leader.vn,
        leader.ve,
        leader.vu,
    )
