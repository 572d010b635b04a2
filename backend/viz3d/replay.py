"""A stored flight replayed in 3D: each viewer gets its own controls and its own ghost.

A viewer picks one of the newest flights in the panel and scrubs its time slider, or
plays it; a ghost in the vehicle's colour stands where the flight log puts the vehicle
at that moment, over the flight's whole track. Both live in that viewer's own scene and
panel (viser's per-client API), so one operator's scrubbing never moves another's view,
and the live fleet stays drawn beside the replay.
"""

from __future__ import annotations

import bisect
import logging
import threading
import time
from dataclasses import dataclass

import numpy as np
import viser
from viser import GuiApi, SceneApi

from backend.storage.logbook import Logbook
from backend.storage.models import FlightRow
from backend.viz3d.colours import rgb, vehicle_colour
from backend.viz3d.frame import SceneFrame, Vector, attitude_wxyz
from backend.viz3d.scene import BODY_FACES, BODY_VERTICES

log = logging.getLogger(__name__)

FLIGHTS_LISTED = 20  # the newest flights offered in the panel
MAX_TRACK_POINTS = 5_000  # a long flight's track is thinned to this many samples
PLAY_STEP_S = 0.1  # the ghost moves this often while playing
PLAY_SPEEDS = ("1x", "5x", "10x", "30x")
# VIEWER_VALUE_SETTER: viser's GUI values are settable, and a new value calls the input's
# on_update (here: the ghost moves); mypy cannot see the setter, which viser defines
# after another method.
NONE = "(none)"
REPLAY_ROOT = "/replay"


@dataclass(frozen=True)
class ReplayTrack:
    """A flight's positions in the scene's frame, in time order."""

    flight_id: int
    vehicle_id: str
    times: list[float]  # seconds since the flight's start
    points: Vector  # (n, 3) east, north, up
    headings: list[float | None]

    @property
    def duration_s(self) -> float:
        return self.times[-1] if self.times else 0.0

    def index_at(self, seconds: float) -> int:
        """The newest sample at or before ``seconds`` into the flight (the first before it
        starts): the ghost shows only what the log recorded, never an invented point."""
        return max(0, bisect.bisect_right(self.times, seconds) - 1)


def load_track(logbook: Logbook, frame: SceneFrame, flight: FlightRow) -> ReplayTrack:
    """The flight's samples placed in the scene (those the frame cannot place are left
    out, and counted by it), thinned evenly to MAX_TRACK_POINTS."""
    end = flight.end_time if flight.end_time is not None else time.time()
    times: list[float] = []
    points: list[Vector] = []
    headings: list[float | None] = []
    for sample in logbook.iter_series(flight.vehicle_id, flight.start_time, end):
        lat, lon, alt = sample["lat"], sample["lon"], sample["alt_msl"]
        if lat is None or lon is None or alt is None:
            continue
        point = frame.place(lat, lon, alt)
        if point is None:
            continue
        times.append(sample["time"] - flight.start_time)
        points.append(point)
        headings.append(sample["heading_deg"])
    stride = max(1, -(-len(times) // MAX_TRACK_POINTS))
    return ReplayTrack(
        flight_id=flight.id,
        vehicle_id=flight.vehicle_id,
        times=times[::stride],
        points=np.array(points[::stride], dtype=np.float64).reshape(-1, 3),
        headings=headings[::stride],
    )


def flight_label(flight: FlightRow) -> str:
    started = time.strftime("%Y-%m-%d %H:%M", time.gmtime(flight.start_time))
    duration = f"{flight.duration_s:.0f} s" if flight.duration_s is not None else "in progress"
    return f"#{flight.id} {flight.vehicle_id} {started} UTC ({duration})"


class FlightReplay:
    """One viewer's replay panel and ghost. viser calls the callbacks on its own threads,
    so the state they share is guarded by a lock."""

    def __init__(self, scene: SceneApi, gui: GuiApi, frame: SceneFrame, logbook: Logbook) -> None:
        self._scene = scene
        self._frame = frame
        self._logbook = logbook
        self._lock = threading.Lock()
        self._flights: dict[str, FlightRow] = {}
        self.track: ReplayTrack | None = None
        self._ghost: viser.FrameHandle | None = None
        self._path: viser.LineSegmentsHandle | None = None
        self._playing = threading.Event()
        self._closed = threading.Event()
        with gui.add_folder("Replay a flight", expand_by_default=False):
            self.flight_choice = gui.add_dropdown("Flight", [NONE], initial_value=NONE)
            self.newest = gui.add_button("List the newest flights")
            self.time_slider = gui.add_slider(
                "Time (s)", min=0.0, max=1.0, step=0.1, initial_value=0.0, disabled=True
            )
            self.speed = gui.add_dropdown("Speed", PLAY_SPEEDS, initial_value="10x")
            self.play_button = gui.add_button("Play", disabled=True)
            self.status = gui.add_markdown("")
        self.flight_choice.on_update(lambda _: self.choose(self.flight_choice.value))
        self.newest.on_click(lambda _: self.list_flights())
        self.time_slider.on_update(lambda _: self._at_slider())
        self.play_button.on_click(lambda _: self.toggle_play())
        self.list_flights()

    def list_flights(self) -> None:
        flights = self._logbook.flights(None, None, FLIGHTS_LISTED)
        with self._lock:
            self._flights = {flight_label(flight): flight for flight in flights}
            self.flight_choice.options = (NONE, *self._flights)
        self.status.content = "" if flights else "No stored flight yet."

    def choose(self, label: str) -> None:
        """Show this flight's track and put its ghost at its start."""
        self._playing.clear()
        with self._lock:
            flight = self._flights.get(label)
            self._clear()
            if flight is None:
                self.track = None
                self.time_slider.disabled = self.play_button.disabled = True
                self.status.content = ""
                return
            track = load_track(self._logbook, self._frame, flight)
            self.track = track
            if len(track.times) < 2:
                self.status.content = f"Flight #{flight.id} has no position to replay."
                return
            colour = rgb(vehicle_colour(track.vehicle_id))
            segments = np.stack([track.points[:-1], track.points[1:]], axis=1).astype(np.float32)
            self._path = self._scene.add_line_segments(
                f"{REPLAY_ROOT}/track",
                segments,
                colors=colour,
                thickness=3.0,
                thickness_units="screen",
            )
            self._ghost = self._scene.add_frame(f"{REPLAY_ROOT}/ghost", show_axes=False)
            body = f"{REPLAY_ROOT}/ghost/body"
            self._scene.add_mesh_simple(
                body, BODY_VERTICES, BODY_FACES, color=colour, opacity=0.6, side="double"
            )
            label = f"replay #{flight.id}"
            self._scene.add_label(f"{REPLAY_ROOT}/ghost/label", label, position=(0, 0, 1.5))
            self.time_slider.max = max(track.duration_s, 0.1)
            self.time_slider.disabled = self.play_button.disabled = False
            self.status.content = (
                f"{track.vehicle_id}: {len(track.times)} positions over {track.duration_s:.0f} s"
            )
        # Setting a value calls its on_update, unless the value is already the same.
        self.time_slider.value = 0.0  # type: ignore[misc]  # VIEWER_VALUE_SETTER
        self.seek(0.0)

    def _at_slider(self) -> None:
        self.seek(self.time_slider.value)

    def seek(self, seconds: float) -> Vector | None:
        """Put the ghost where the log had the vehicle at ``seconds`` into the flight."""
        with self._lock:
            track, ghost = self.track, self._ghost
            if track is None or ghost is None or not track.times:
                return None
            index = track.index_at(seconds)
            position: Vector = track.points[index]
            ghost.position = position
            ghost.wxyz = attitude_wxyz(0.0, 0.0, track.headings[index])
            return position

    def toggle_play(self) -> None:
        if self._playing.is_set():
            self._playing.clear()
            return
        if self.track is None:
            return
        self._playing.set()
        self.play_button.label = "Pause"
        threading.Thread(target=self._play, name="viz-replay", daemon=True).start()

    def _play(self) -> None:
        """Moves the slider (and the ghost with it) at the chosen speed until the flight's
        end, a pause, another flight, or the viewer leaving."""
        last = time.monotonic()
        while self._playing.is_set() and not self._closed.wait(PLAY_STEP_S):
            now = time.monotonic()
            speed = float(self.speed.value.rstrip("x"))
            track = self.track
            if track is None:
                break
            at = min(self.time_slider.value + (now - last) * speed, track.duration_s)
            last = now
            self.time_slider.value = at  # type: ignore[misc]  # VIEWER_VALUE_SETTER
            if at >= track.duration_s:
                break
        self._playing.clear()
        self.play_button.label = "Play"

    def close(self) -> None:
        self._closed.set()
        self._playing.clear()

    def _clear(self) -> None:
        for handle in (self._path, self._ghost):
            if handle is not None:
                handle.remove()
        self._path = self._ghost = None


class ReplayPanels:
    """Gives each viewer that connects a replay panel, and drops it when they leave."""

    def __init__(self, server: viser.ViserServer, frame: SceneFrame, logbook: Logbook) -> None:
        self._frame = frame
        self._logbook = logbook
        self.by_client: dict[int, FlightReplay] = {}
        server.on_client_connect(self._connected)
        server.on_client_disconnect(self._disconnected)

    def _connected(self, client: viser.ClientHandle) -> None:
        try:
            replay = FlightReplay(client.scene, client.gui, self._frame, self._logbook)
        except Exception:  # the live view must not fail for a replay panel
            log.exception("could not give viewer %s a replay panel", client.client_id)
            return
        self.by_client[client.client_id] = replay

    def _disconnected(self, client: viser.ClientHandle) -> None:
        replay = self.by_client.pop(client.client_id, None)
        if replay is not None:
            replay.close()
