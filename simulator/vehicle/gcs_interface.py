"""The commands every vehicle answers, as the MAVLink handlers call them; each vehicle
and autopilot decides what they do."""

from __future__ import annotations

from abc import abstractmethod

from simulator.mavconst import MavResult
from simulator.vehicle.state import VehicleState


class GcsCommands(VehicleState):
    @abstractmethod
    def arm(self, force: bool = False) -> MavResult:
        """MAV_CMD_COMPONENT_ARM_DISARM param1=1; ``force`` is param2=2989."""

    @abstractmethod
    def disarm(self, force: bool = False) -> MavResult:
        """MAV_CMD_COMPONENT_ARM_DISARM param1=0; ``force`` is param2=21196."""

    @abstractmethod
    def set_mode(self, number: int) -> MavResult:
        """A mode change to the autopilot's own mode number."""

    @abstractmethod
    def request_mode(self, base_mode: int, custom_mode: int, custom_sub_mode: int) -> MavResult:
        """MAV_CMD_DO_SET_MODE, in the autopilot's encoding."""

    @abstractmethod
    def request_mode_encoded(self, base_mode: int, custom_mode: int) -> MavResult:
        """SET_MODE: custom_mode as HEARTBEAT carries it."""

    @abstractmethod
    def nav_takeoff(self, altitude: float, frame: int) -> MavResult:
        """MAV_CMD_NAV_TAKEOFF from a GCS."""

    @abstractmethod
    def nav_land(self) -> MavResult:
        """MAV_CMD_NAV_LAND from a GCS."""

    @abstractmethod
    def return_to_launch(self) -> MavResult:
        """MAV_CMD_NAV_RETURN_TO_LAUNCH from a GCS."""

    @abstractmethod
    def change_speed(self, kind: int, speed: float) -> MavResult:
        """MAV_CMD_DO_CHANGE_SPEED: param1 speed type, param2 m/s."""

    @property
    @abstractmethod
    def in_guided(self) -> bool:
        """Whether position targets from a GCS are flown now."""

    @abstractmethod
    def enter_guided(self) -> MavResult:
        """Switch to the mode that flies position targets (DO_REPOSITION's change of mode)."""

    @abstractmethod
    def guided_goto(self, lat: float, lon: float, relative_alt: float) -> MavResult:
        """Go to a position while in guided."""

    def guided_posvel(
        self,
        position: tuple[float, float, float] | None,
        velocity_ned: tuple[float, float, float],
        yaw: float | None = None,
    ) -> MavResult:
        """A position-and-velocity target in guided. A vehicle without a velocity model
        (the rover) flies the position alone and refuses a velocity-only target."""
        if position is None:
            return MavResult.DENIED
        return self.guided_goto(*position)

    @abstractmethod
    def guided_hold(self) -> None:
        """Re-initialise guided to hold position (what ArduPilot does on a bad target)."""

    @property
    def reboot_declined(self) -> MavResult:
        """The answer to MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN while armed (ArduPilot's
        handle_preflight_reboot: FAILED, without a STATUSTEXT)."""
        return MavResult.FAILED

    def request_reboot(self, action: float, force: bool) -> MavResult:
        """MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN (GCS_MAVLINK::handle_preflight_reboot):
        param1 1 reboots (3, into the bootloader, is not simulated); refused while armed
        unless forced (param6 20190226). Accepted, the transport answers first and then
        restarts the vehicle (`rebooted`), as ArduPilot acknowledges before it resets."""
        if action != 1.0:
            return MavResult.UNSUPPORTED
        if self.armed and not force:
            return self.reboot_declined
        self.reboot_requested = True
        return MavResult.ACCEPTED
