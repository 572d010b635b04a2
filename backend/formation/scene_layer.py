"""A running formation in the 3D view: where its followers are meant to be, and the room
each member keeps.

From the leader (the leader vehicle, or the virtual leader on its route) a line runs to
each follower's slot target, the point that follower steers for now (its slot turned
with the leader's heading: ``common.formation.slot_target``), in the follower's colour.
Round each member is a translucent sphere of radius ``min_separation_m / 2``: two
spheres that touch are two members at the minimum separation. A formation's heights are
above each vehicle's home. The layer follows ``FormationService.active()`` at the
mirror's pace; a stopped formation is taken out.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Awaitable, Callable, Iterable
from dataclasses import dataclass, field

import numpy as np
import viser

from backend.formation.active import ActiveFormation
from backend.formation.service import FormationService
from backend.viz3d.colours import rgb, vehicle_colour
from backend.viz3d.frame import HomeAltitude, SceneFrame, Vector
from backend.viz3d.mirror import SceneLayer
from backend.viz3d.scene import FORMATIONS, FleetScene
from common.formation import LeaderState, slot_target

SPHERE_OPACITY = 0.2
Position = Callable[[str], Vector | None]


@dataclass(frozen=True)
class FormationView:
    """One formation as drawn, in the scene's frame."""

    formation_id: str
    leader: Vector
    targets: dict[str, Vector]  # follower -> its slot target now
    members: dict[str, Vector]  # member -> where it is
    radius_m: float


def formation_view(
    formation: ActiveFormation,
    leader: LeaderState,
    frame: SceneFrame,
    home_alt: HomeAltitude,
    position: Position,
) -> FormationView | None:
    """The formation placed in the scene, given its leader's state; None while the scene
    has no origin (or the leader is not placeable)."""
    plan = formation.plan
    followers = formation.followers

    def place(vehicle_id: str | None, north: float, east: float, up: float) -> Vector | None:
        ground = frame.ground(None if vehicle_id is None else home_alt(vehicle_id))
        if ground is None:
            return None
        lat, lon = plan.frame.to_geo(east, north)
        return frame.place(lat, lon, ground + up)

    # A virtual leader's height is above the followers' home: the first one's stands in.
    leader_ref = plan.leader_id or (followers[0] if followers else None)
    where = place(leader_ref, leader.north, leader.east, leader.up)
    if where is None:
        return None
    targets: dict[str, Vector] = {}
    for follower, offset in formation.offsets.items():
        (north, east, up), _ = slot_target(leader, offset)
        if (target := place(follower, north, east, up)) is not None:
            targets[follower] = target
    members = {v: p for v in formation.members if (p := position(v)) is not None}
    return FormationView(formation.id, where, targets, members, plan.min_separation_m / 2)


@dataclass
class _Drawn:
    root: viser.FrameHandle  # removing it removes everything under it
    links: viser.LineSegmentsHandle | None = None
    spheres: dict[str, viser.IcosphereHandle] = field(default_factory=dict)


class FormationLayer:
    def __init__(self, scene: FleetScene) -> None:
        self.scene = scene
        self._drawn: dict[str, _Drawn] = {}

    @property
    def formations(self) -> list[str]:
        return list(self._drawn)

    def show(self, view: FormationView) -> None:
        with self.scene.batch():
            root = f"/{FORMATIONS.key}/{view.formation_id}"
            drawn = self._drawn.get(view.formation_id)
            if drawn is None:
                frame = self.scene.server.scene.add_frame(root, show_axes=False)
                drawn = self._drawn[view.formation_id] = _Drawn(frame)
            followers = sorted(view.targets)
            segments = np.array(
                [[view.leader, view.targets[f]] for f in followers], dtype=np.float32
            ).reshape(-1, 2, 3)
            links = drawn.links
            if links is not None and links.points.shape == segments.shape:
                links.points = segments  # the same followers: their colours stay
            else:
                if links is not None:
                    links.remove()
                drawn.links = None
                if followers:
                    colours = np.array(
                        [[rgb(vehicle_colour(f))] * 2 for f in followers], dtype=np.uint8
                    )
                    drawn.links = self.scene.server.scene.add_line_segments(
                        f"{root}/links",
                        segments,
                        colors=colours,
                        thickness=2.0,
                        thickness_units="screen",
                    )
            for gone in set(drawn.spheres) - set(view.members):
                drawn.spheres.pop(gone).remove()
            for member, here in view.members.items():
                sphere = drawn.spheres.get(member)
                if sphere is None:
                    drawn.spheres[member] = self.scene.server.scene.add_icosphere(
                        f"{root}/separation/{member}",
                        radius=view.radius_m,
                        color=rgb(vehicle_colour(member)),
                        opacity=SPHERE_OPACITY,
                        cast_shadow=False,
                        position=here,
                    )
                elif not np.allclose(sphere.position, here, atol=0.01):
                    sphere.position = here
            self.scene.show_layer(FORMATIONS)

    def keep(self, formation_ids: Iterable[str]) -> None:
        """Take out every formation drawn but not among these (stopped ones)."""
        running = set(formation_ids)
        with self.scene.batch():
            for formation_id in [f for f in self._drawn if f not in running]:
                self._drawn.pop(formation_id).root.remove()

    def sync(self, views: list[FormationView], running: list[str]) -> None:
        with self.scene.batch():
            self.keep(running)
            for view in views:
                self.show(view)

    async def follow(
        self, formations: FormationService, home_alt: HomeAltitude, interval_s: float
    ) -> None:
        """Redraw the running formations every ``interval_s``. Their state is read on the
        hub's loop (which changes it) and drawn in a worker thread."""
        position = self.scene.vehicle_position
        while True:
            now = time.time()  # the formations' own clock (FormationService's default)
            running = formations.active()
            views = []
            for formation in running:
                leader = formations.leader_state(formation, now)
                if leader is None:
                    continue  # a stale leader: the last drawing stands
                view = formation_view(formation, leader, self.scene.frame, home_alt, position)
                if view is not None:
                    views.append(view)
            await asyncio.to_thread(self.sync, views, [f.id for f in running])
            await asyncio.sleep(interval_s)


def formation_scene_layer(formations: FormationService) -> SceneLayer:
    """The running formations as a layer of the 3D view's mirror."""

    def make(
        scene: FleetScene, home_alt: HomeAltitude, interval_s: float
    ) -> Callable[[], Awaitable[None]]:
        layer = FormationLayer(scene)
        return lambda: layer.follow(formations, home_alt, interval_s)

    return make
