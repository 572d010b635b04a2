"""The stored mission and how it is walked through: nav commands one at a time, with the
"do" commands around them (AP_Mission)."""

from __future__ import annotations

from abc import abstractmethod

from simulator.mavconst import MavCmd, MavFrame, MissionState
from simulator.vehicle.camera import Camera
from simulator.vehicle.events import ItemReached
from simulator.vehicle.gcs_interface import GcsCommands
from simulator.vehicle.state import AutoPhase
from simulator.vehicle.stored_mission import ABSOLUTE_FRAMES, MissionItem


class MissionRunner(Camera, GcsCommands):
    @property
    @abstractmethod
    def in_auto(self) -> bool:
        """In the mode that runs the stored mission."""

    @property
    def upload_keeps_current_item(self) -> bool:
        """Whether a mission upload keeps the current item's index (PX4's does)."""
        return False

    @property
    def mission_count(self) -> int:
        """Mission commands stored after item 0 (home)."""
        return max(0, len(self.mission) - 1)

    def mission_item(self, seq: int) -> MissionItem | None:
        """Item ``seq`` as a GCS downloads it: item 0 is always the current home."""
        if not 0 <= seq < len(self.mission):
            return None
        if seq == 0:
            home = self.home
            return MissionItem(
                0,
                MavFrame.GLOBAL,
                MavCmd.NAV_WAYPOINT,
                x=round(home.lat * 1e7),
                y=round(home.lon * 1e7),
                z=home.alt,
            )
        return self.mission[seq]

    def set_mission(self, items: list[MissionItem], flagged: int | None = None) -> None:
        """Replace the stored mission (a completed upload; item 0 is home). ``flagged``:
        the item the upload marked current, if any."""
        self.mission = list(items) if len(items) > 1 else []
        if self._mission_running():
            # carry on with the command in flight; the new mission follows it
            self._auto_next = min(self._auto_next, len(self.mission))
            self.mission_current = min(self.mission_current, max(0, len(self.mission) - 1))
        elif self.upload_keeps_current_item:
            # PX4 (MissionBase::updateMavlinkMission): the item flagged current, else the
            # index it had, within the new mission; the first item is "not started".
            kept = self.mission_current if flagged is None else flagged
            kept = min(kept, max(0, len(self.mission) - 1))
            self.mission_current = 0 if kept <= 1 else kept
        else:
            # Not running, or run to its end (landed, or holding after its last item):
            # the new mission starts from its first item, as ArduPilot's does (its
            # disarm resets the mission, AP_Arming_Copter::disarm; and a completed one
            # starts over when AUTO is entered, AP_Mission::resume).
            self.mission_current = 0
            if not self.armed and self._auto_phase is AutoPhase.DONE:
                self._auto_phase = AutoPhase.IDLE  # reset on disarm: not started

    def clear_mission(self) -> bool:
        """MISSION_CLEAR_ALL; refused while the mission is running (AP_Mission::clear)."""
        if self._mission_running():
            return False
        self.mission = []
        self.mission_current = 0
        return True

    def set_mission_current(self, seq: int) -> bool:
        """MISSION_SET_CURRENT: run (or, outside AUTO, resume at) command ``seq``."""
        if not 1 <= seq < len(self.mission):
            return False
        if self._mission_running():
            self._auto_run_from(seq)
        else:
            self.mission_current = seq
        return True

    def mission_state(self) -> MissionState:
        """MISSION_CURRENT.mission_state, as ArduPilot 4.5 reports it."""
        if self.mission_count == 0:
            return MissionState.NO_MISSION
        if self._auto_phase is AutoPhase.DONE:
            return MissionState.COMPLETE
        if self.in_auto and self._auto_phase is not AutoPhase.IDLE:
            return MissionState.ACTIVE
        return MissionState.NOT_STARTED if self.mission_current == 0 else MissionState.PAUSED

    def _mission_running(self) -> bool:
        return (
            self.in_auto and self.armed and self._auto_phase not in (AutoPhase.IDLE, AutoPhase.DONE)
        )

    def _first_nav_seq(self) -> int | None:
        start = self.mission_current if self.mission_current >= 1 else 1
        for seq in range(start, len(self.mission)):
            if self.mission[seq].is_nav:
                return seq
        return None

    def _item_alt(self, item: MissionItem) -> float:
        """A mission item's altitude above home."""
        if item.frame in ABSOLUTE_FRAMES:
            return item.z - self.home.alt
        return item.z

    def _item_ne(self, item: MissionItem) -> tuple[float, float]:
        """A mission item's position; none given (0, 0) means where the vehicle stops."""
        if not item.has_position:
            return self.body.stopping_point(self.params.wpnav_accel)
        return self.ne_of(item.x / 1e7, item.y / 1e7)

    def _auto_begin(self) -> None:
        """ModeAuto::run with a mission not yet started: start or resume it."""
        self._auto_run_from(self.mission_current if self.mission_current >= 1 else 1)

    def _auto_run_from(self, seq: int) -> None:
        """Run the "do" commands up to the next nav command, then start that.

        AP_Mission::advance_current_nav_cmd: the "do" commands after nav command N run
        once N completes (on the way to the next one), not while N is flown. A survey's
        DO_SET_CAM_TRIGG_DIST after a lane's entry waypoint starts the camera there, and
        the one after its exit waypoint stops it there (QGC's survey relies on this)."""
        mission = self.mission
        while seq < len(mission) and not mission[seq].is_nav:
            self._do_command(mission[seq])
            seq += 1
        if seq >= len(mission):
            self._auto_complete()
            return
        self.mission_current = seq
        self._start_nav(mission[seq])
        self._auto_next = seq + 1

    def _nav_done(self) -> None:
        item = self._auto_item
        if item is not None:
            self._events.append(ItemReached(item.seq))
        self._auto_run_from(self._auto_next)

    @abstractmethod
    def _start_nav(self, item: MissionItem) -> None:
        """Begin a navigation command."""

    @abstractmethod
    def _auto_complete(self) -> None:
        """The mission has run out of commands (ModeAuto::exit_mission)."""

    def _do_command(self, item: MissionItem) -> None:
        match item.command:
            case MavCmd.DO_CHANGE_SPEED:
                self.change_speed(int(item.param1), item.param2)
            case MavCmd.DO_SET_CAM_TRIGG_DIST:
                self._cam_trigg_dist = max(0.0, item.param1)
                self._cam_last_ne = (self.body.north, self.body.east)
                if item.param3 == 1.0:
                    self.take_photo()
            case MavCmd.DO_DIGICAM_CONTROL:
                if item.x == 1:  # param5 "shot"
                    self.take_photo()
