"""A simulated vehicle whole: its jobs combined, what every step does, what a reboot keeps."""

from __future__ import annotations

from abc import abstractmethod
from typing import Self

from common.geodesy import GeoPoint
from simulator.vehicle.missions import MissionRunner
from simulator.vehicle.state import GPS_PERIOD_STEPS


class Vehicle(MissionRunner):
    """One simulated vehicle: sensors, home, mission and parameters, stepped in sim time.
    `Copter` and `Rover` add their autopilot's rules and their motion."""

    def _step_sensors(self) -> None:
        """The parts of a step every vehicle has: camera, GPS noise."""
        self._check_camera_distance()
        if self._steps % GPS_PERIOD_STEPS == 0:
            sigma = self.params.sim_gps_noise
            gauss = self._rng.gauss
            self.gps_error = (gauss(0.0, sigma), gauss(0.0, sigma), gauss(0.0, 1.5 * sigma))

    # -- reboot ----------------------------------------------------------------

    def rebooted(self, boot_at: float) -> Self:
        """The same vehicle after its flight controller restarts (refused while armed,
        so it is not flying): what the board stores survives (parameters, the mission),
        and so does the physical world (where it stands, its battery); everything else
        starts again: the initial mode, a new EKF origin where it is, home not yet
        locked, sim time from zero."""
        here = self.position()
        twin = self._reborn(GeoPoint(here.lat, here.lon, self.frame.origin.alt), boot_at)
        twin.params = self.params
        twin.param_table = self.param_table
        twin.battery = self.battery
        twin.mission = list(self.mission)
        twin.body.down = self.body.down
        twin.body.yaw = self.body.yaw
        twin.gps_fix_type, twin.satellites = self.gps_fix_type, self.satellites
        if self.gps_fix_type >= 3 and not self.position_ok:  # still waiting: from its boot
            twin._fix_since = twin.time_s
        elif self.gps_fix_type < 3:
            twin._fix_since = None
        return twin

    @abstractmethod
    def _reborn(self, origin: GeoPoint, boot_at: float) -> Self:
        """A freshly booted vehicle of the same kind, its EKF origin at ``origin``."""
