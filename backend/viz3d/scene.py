"""The fleet in the viser scene: per vehicle a model with its attitude, a label, a trail,
its home and its mission, grouped in layers that the panel toggles.

Every change of one batch is applied inside ``viser.atomic()``, so the browser shows
the whole fleet's step at once; ``backend.viz3d.mirror`` decides how often a batch comes.
viser keeps the scene's current state and replays it to a browser that connects later.
"""

from __future__ import annotations

import threading
from collections import deque
from collections.abc import Callable, Iterable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt
import viser
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from backend.viz3d.colours import rgb, vehicle_colour
from backend.viz3d.frame import SceneFrame, Vector, attitude_wxyz
from backend.viz3d.skipped_note import skipped_note
from protocol.messages import MissionItem, VehicleSummary

# A flat arrowhead, 2 m long, pointing along the body's forward (x) axis.
BODY_VERTICES = np.array(
    [[1.2, 0.0, 0.0], [-0.8, 0.7, 0.0], [-0.4, 0.0, 0.15], [-0.8, -0.7, 0.0], [-0.4, 0.0, -0.1]],
    dtype=np.float32,
)
BODY_FACES = np.array([[0, 1, 2], [0, 2, 3], [0, 4, 1], [0, 3, 4], [1, 4, 2], [2, 4, 3]])
# A trail point is kept only this far from the last one, so a hovering vehicle's trail
# does not fill with copies of one point.
TRAIL_STEP_M = 0.25
MAX_TRAIL_POINTS = 2_000
# A trail is sent whole (viser cannot append to a line), so it is redrawn at most this
# often per vehicle: 50 trails rebuilt at every 10 Hz batch were most of a batch's cost
# (bench/bench_viz.py). The model itself moves at every batch; its trail follows it.
TRAIL_REDRAW_S = 0.5
# RTL, LAND and TAKEOFF fly from where they are.
NOT_MISSION_POSITIONS = frozenset(
    {mavlink2.MAV_CMD_NAV_RETURN_TO_LAUNCH, mavlink2.MAV_CMD_NAV_LAND, mavlink2.MAV_CMD_NAV_TAKEOFF}
)


@dataclass(frozen=True)
class Layer:
    """A group of scene nodes toggled together in the panel, shown once it has data."""

    key: str
    title: str


GRID = Layer("grid", "Ground grid")
VEHICLES = Layer("vehicles", "Vehicles")
TRAILS = Layer("trails", "Trails")
HOMES = Layer("homes", "Homes")
MISSIONS = Layer("missions", "Missions")
# Layers of the sensors' and the operations' data: each appears in the panel when its
# first data is drawn (a vehicle's latest scan, the accumulated point map, the obstacles
# found in it, a survey's lanes, a formation, a mosaic), never before. They are drawn by
# their own modules (backend/scans/scene_layer, survey/viz_layer, formation/scene_layer,
# mosaic_layer) through ``show_points``, ``show_layer`` and the server's scene.
SCANS = Layer("scans", "LIDAR scans")
POINT_MAP = Layer("point_map", "Point map")
OBSTACLES = Layer("obstacles", "Obstacles")
SURVEY_LANES = Layer("survey_lanes", "Survey lanes")
FORMATIONS = Layer("formations", "Formations")
MOSAIC = Layer("mosaic", "Mosaic")
ALL_LAYERS = (
    GRID,
    VEHICLES,
    TRAILS,
    HOMES,
    MISSIONS,
    SCANS,
    POINT_MAP,
    OBSTACLES,
    SURVEY_LANES,
    FORMATIONS,
    MOSAIC,
)


@dataclass
class _Vehicle:
    frame: viser.FrameHandle
    label: viser.LabelHandle
    colour: tuple[int, int, int]
    trail: deque[tuple[float, Vector]] = field(default_factory=deque)
    trail_handle: viser.LineSegmentsHandle | None = None
    trail_drawn_at: float = float("-inf")
    home: viser.IcosphereHandle | None = None
    position: Vector | None = None


class FleetScene:
    """The scene of one viser server. Thread-safe: calls are serialised by a lock, as the
    hub applies batches from a worker thread while the panel's callbacks run in viser's."""

    def __init__(self, server: viser.ViserServer, frame: SceneFrame, trail_s: float) -> None:
        self.server = server
        self.frame = frame
        self.trail_s = trail_s
        self._lock = threading.RLock()
        self._vehicles: dict[str, _Vehicle] = {}
        self._missions: dict[str, list[Vector]] = {}
        self._layers: dict[str, viser.GuiCheckboxHandle] = {}
        # One group node per layer, made first, so the panel's checkbox hides the group.
        self._groups = {
            layer.key: server.scene.add_frame(f"/{layer.key}", show_axes=False)
            for layer in ALL_LAYERS
        }
        self._mission_paths: dict[str, viser.LineSegmentsHandle] = {}
        self._next_waypoints: dict[str, viser.IcosphereHandle] = {}
        self._follow: dict[int, str] = {}  # viser client id -> vehicle id
        # Called (on viser's thread) with the vehicle and the viewer that clicked it.
        self.on_vehicle_click: Callable[[str, viser.ClientHandle], None] | None = None
        self.batches = 0
        server.scene.set_up_direction("+z")
        server.scene.configure_environment_map(hdri=None)  # no CDN: the scene is lit plainly
        # A browser's first view: the origin (the first home) from the south-west, high
        # enough to see a fleet spread over a few hundred metres.
        server.initial_camera.position = (-60.0, -60.0, 45.0)
        server.initial_camera.look_at = (0.0, 0.0, 5.0)
        server.initial_camera.up = (0.0, 0.0, 1.0)
        self._layer_folder = server.gui.add_folder("Layers")
        self._follow_choice = server.gui.add_dropdown("Follow", ["(none)"], initial_value="(none)")
        self._follow_choice.on_update(self._on_follow)
        self._skipped = server.gui.add_markdown("")
        self.server.scene.add_grid(
            f"/{GRID.key}/plane", width=1000, height=1000, cell_size=10, section_size=100
        )
        self.show_layer(GRID)

    # -- the fleet ---------------------------------------------------------------

    def apply(self, summaries: Iterable[VehicleSummary]) -> None:
        """One batch of vehicle changes, drawn as one atomic update."""
        with self._lock, self.server.atomic():
            for summary in summaries:
                self._apply_one(summary)
            self._follow_cameras()
            self._show_skipped()
            self.batches += 1

    @contextmanager
    def batch(self) -> Iterator[None]:
        """Calls made inside reach the browser as one atomic update."""
        with self._lock, self.server.atomic():
            yield

    def vehicle_position(self, vehicle_id: str) -> Vector | None:
        vehicle = self._vehicles.get(vehicle_id)
        return None if vehicle is None else vehicle.position

    def trail_points(self, vehicle_id: str) -> list[Vector]:
        vehicle = self._vehicles.get(vehicle_id)
        return [] if vehicle is None else [point for _, point in vehicle.trail]

    def _apply_one(self, summary: VehicleSummary) -> None:
        state = summary.state
        if state is None or not self.frame.anchor(state):
            if state is not None:
                self.frame.vehicle(state)  # counted as "no origin yet" when it has a fix
            return
        position = self.frame.vehicle(state)
        vehicle = self._vehicles.get(summary.id)
        if position is None:
            if vehicle is not None:
                self._label(vehicle, summary)
            return
        if vehicle is None:
            vehicle = self._add_vehicle(summary.id, position)
        vehicle.position = position
        vehicle.frame.position = position
        vehicle.frame.wxyz = attitude_wxyz(state.roll_deg, state.pitch_deg, state.heading_deg)
        self._label(vehicle, summary)
        self._extend_trail(summary.id, vehicle, summary.last_seen, position)
        if (home := self.frame.home(state)) is not None:
            self._draw_home(summary.id, vehicle, home)
        self._draw_next_waypoint(summary.id, state.mission_current)

    def _add_vehicle(self, vehicle_id: str, position: Vector) -> _Vehicle:
        colour = rgb(vehicle_colour(vehicle_id))
        root = f"/{VEHICLES.key}/{vehicle_id}"
        frame = self.server.scene.add_frame(root, show_axes=False, position=position)
        body = self.server.scene.add_mesh_simple(
            f"{root}/body", BODY_VERTICES, BODY_FACES, color=colour, side="double"
        )
        body.on_click(lambda event: self._clicked(vehicle_id, event.client))
        # Centred above the model, not running to the right over its neighbour's.
        label = self.server.scene.add_label(
            f"{root}/label",
            vehicle_id,
            position=(0, 0, 1.5),
            anchor="bottom-center",
            font_screen_scale=0.9,
        )
        self.show_layer(VEHICLES)
        self._follow_choice.options = ("(none)", *sorted([*self._vehicles, vehicle_id]))
        vehicle = _Vehicle(frame=frame, label=label, colour=colour)
        self._vehicles[vehicle_id] = vehicle
        return vehicle

    def _label(self, vehicle: _Vehicle, summary: VehicleSummary) -> None:
        # The id alone: "sim_1 · STABILIZE · 0 m" overlapped a neighbour parked 15 m away.
        text = summary.id if summary.connected else f"{summary.id} (offline)"
        if vehicle.label.text != text:
            vehicle.label.text = text

    def _extend_trail(
        self, vehicle_id: str, vehicle: _Vehicle, when: float | None, position: Vector
    ) -> None:
        now = when if when is not None else (vehicle.trail[-1][0] if vehicle.trail else 0.0)
        trail = vehicle.trail
        if not trail or float(np.linalg.norm(trail[-1][1] - position)) >= TRAIL_STEP_M:
            trail.append((now, position))
            while trail and (trail[0][0] < now - self.trail_s or len(trail) > MAX_TRAIL_POINTS):
                trail.popleft()
        # Drawn when it has a point not drawn yet (one kept back by the pacing is drawn
        # later, even if the vehicle has stopped), at most every TRAIL_REDRAW_S.
        undrawn = bool(trail) and trail[-1][0] > vehicle.trail_drawn_at
        if len(trail) < 2 or not undrawn or now - vehicle.trail_drawn_at < TRAIL_REDRAW_S:
            return
        vehicle.trail_drawn_at = now
        points = np.array([point for _, point in trail], dtype=np.float32)
        segments = np.stack([points[:-1], points[1:]], axis=1)
        if vehicle.trail_handle is None:
            vehicle.trail_handle = self.server.scene.add_line_segments(
                f"/{TRAILS.key}/{vehicle_id}",
                segments,
                colors=vehicle.colour,
                thickness=2.0,
                thickness_units="screen",
            )
            self.show_layer(TRAILS)
        else:
            vehicle.trail_handle.points = segments  # one colour for all: (3,) stays valid

    def _draw_home(self, vehicle_id: str, vehicle: _Vehicle, home: Vector) -> None:
        if vehicle.home is None:
            vehicle.home = self.server.scene.add_icosphere(
                f"/{HOMES.key}/{vehicle_id}", radius=0.6, color=vehicle.colour, position=home
            )
            self.show_layer(HOMES)
        elif not np.allclose(vehicle.home.position, home, atol=0.01):
            vehicle.home.position = home

    # -- missions ----------------------------------------------------------------

    def show_mission(
        self, vehicle_id: str, items: Sequence[MissionItem], home_alt: float | None
    ) -> None:
        """A vehicle's mission path (items after home), as the hub last uploaded or read it.

        Heights: above home (MAV_FRAME 3) needs the home's altitude; above sea level
        (frame 0) is taken as it is; above terrain (10) has no terrain model here and is
        drawn above home. Items without a position (speed, delays) are not drawn."""
        with self._lock, self.server.atomic():
            waypoints: list[Vector] = []
            for item in items:
                if item.command in NOT_MISSION_POSITIONS or (item.lat == 0 and item.lon == 0):
                    continue
                alt = (
                    item.alt
                    if item.frame == mavlink2.MAV_FRAME_GLOBAL
                    else (home_alt or 0.0) + item.alt
                )
                point = self.frame.place(item.lat, item.lon, alt)
                if point is not None:
                    waypoints.append(point)
            self._missions[vehicle_id] = waypoints
            if (old := self._mission_paths.pop(vehicle_id, None)) is not None:
                old.remove()
            if (marker := self._next_waypoints.pop(vehicle_id, None)) is not None:
                marker.remove()
            if len(waypoints) < 2:
                return
            points = np.array(waypoints, dtype=np.float32)
            colour = rgb(vehicle_colour(vehicle_id))
            self._mission_paths[vehicle_id] = self.server.scene.add_line_segments(
                f"/{MISSIONS.key}/{vehicle_id}/path",
                np.stack([points[:-1], points[1:]], axis=1),
                colors=colour,
                thickness=1.0,
                thickness_units="screen",
            )
            self.show_layer(MISSIONS)

    def mission_path(self, vehicle_id: str) -> list[Vector]:
        return list(self._missions.get(vehicle_id, []))

    def _draw_next_waypoint(self, vehicle_id: str, current: int | None) -> None:
        waypoints = self._missions.get(vehicle_id)
        if not waypoints or current is None or not 1 <= current <= len(waypoints):
            return
        target = waypoints[current - 1]
        marker = self._next_waypoints.get(vehicle_id)
        if marker is None:
            self._next_waypoints[vehicle_id] = self.server.scene.add_icosphere(
                f"/{MISSIONS.key}/{vehicle_id}/next",
                radius=0.8,
                color=rgb(vehicle_colour(vehicle_id)),
                position=target,
            )
        elif not np.allclose(marker.position, target, atol=0.01):
            marker.position = target

    # -- later layers ------------------------------------------------------------

    def show_points(
        self,
        layer: Layer,
        key: str,
        points_enu: npt.NDArray[np.floating],
        colour: tuple[int, int, int],
        point_size: float = 0.15,
    ) -> None:
        """Points already in the scene's frame (metres east, north, up), replacing the
        layer's previous points under ``key``."""
        points = np.asarray(points_enu, dtype=np.float32).reshape(-1, 3)
        points = points[np.isfinite(points).all(axis=1)]
        with self._lock, self.server.atomic():
            self.server.scene.add_point_cloud(
                f"/{layer.key}/{key}", points, colors=colour, point_size=point_size
            )
            self.show_layer(layer)

    # -- the panel ---------------------------------------------------------------

    def show_layer(self, layer: Layer) -> None:
        """The layer's checkbox in the panel (once: call it whenever the layer draws)."""
        if layer.key in self._layers:
            return
        with self._layer_folder:
            checkbox = self.server.gui.add_checkbox(layer.title, initial_value=True)

        group = self._groups[layer.key]

        @checkbox.on_update
        def _(_: object) -> None:
            with self._lock:
                group.visible = checkbox.value

        self._layers[layer.key] = checkbox

    @property
    def layers_shown(self) -> list[str]:
        """The layers in the panel: those that have had data."""
        return list(self._layers)

    def _on_follow(self, event: viser.GuiEvent[viser.GuiDropdownHandle[str]]) -> None:
        client = event.client
        if client is None:
            return
        choice = event.target.value
        self.follow(client.client_id, None if choice == "(none)" else choice)

    def follow(self, client_id: int, vehicle_id: str | None) -> None:
        """This viewer's camera follows the vehicle from where it is now (None: stops)."""
        with self._lock:
            if vehicle_id is None:
                self._follow.pop(client_id, None)
            else:
                self._follow[client_id] = vehicle_id
            self._follow_cameras()

    def _clicked(self, vehicle_id: str, client: viser.ClientHandle) -> None:
        if self.on_vehicle_click is not None:
            self.on_vehicle_click(vehicle_id, client)

    def _follow_cameras(self) -> None:
        if not self._follow:
            return
        clients = self.server.get_clients()
        for client_id, vehicle_id in list(self._follow.items()):
            client = clients.get(client_id)
            position = self.vehicle_position(vehicle_id)
            if client is None:
                del self._follow[client_id]
                continue
            if position is None:
                continue
            offset = client.camera.position - client.camera.look_at
            # Position first: viser moves look_at along with a new position.
            with client.atomic():
                client.camera.position = position + offset
                client.camera.look_at = position

    def _show_skipped(self) -> None:
        local = self.frame.local
        text = skipped_note(
            self.frame.skipped,
            None if local is None else local.origin,
            self.frame.configured is not None,
        )
        if self._skipped.content != text:
            self._skipped.content = text
