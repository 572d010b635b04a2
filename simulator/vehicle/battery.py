"""A 4S LiPo pack: current draw in, voltage and remaining capacity out."""

from __future__ import annotations

from dataclasses import dataclass

CELL_FULL_V = 4.2
CELL_EMPTY_V = 3.5
INTERNAL_RESISTANCE_OHM = 0.02  # whole pack: the voltage sags this much per amp


@dataclass
class Battery:
    cells: int = 4
    capacity_mah: float = 5000.0
    consumed_mah: float = 0.0
    consumed_wh: float = 0.0
    current_a: float = 0.0

    @property
    def remaining_fraction(self) -> float:
        return max(0.0, 1.0 - self.consumed_mah / self.capacity_mah)

    @property
    def remaining_mah(self) -> float:
        return max(0.0, self.capacity_mah - self.consumed_mah)

    @property
    def remaining_pct(self) -> int:
        return round(100.0 * self.remaining_fraction)

    @property
    def resting_voltage(self) -> float:
        """Open-circuit voltage, linear in remaining charge between empty and full."""
        cell = CELL_EMPTY_V + (CELL_FULL_V - CELL_EMPTY_V) * self.remaining_fraction
        return self.cells * cell

    @property
    def voltage(self) -> float:
        """Terminal voltage under the present load."""
        return max(0.0, self.resting_voltage - self.current_a * INTERNAL_RESISTANCE_OHM)

    def step(self, dt: float, current_a: float, drain: float = 1.0) -> None:
        """Draw ``current_a`` amps for ``dt`` seconds; ``drain`` scales the charge used
        (SIM_BATT_DRAIN, to run a pack down quickly in tests)."""
        self.current_a = current_a
        self.consumed_mah += current_a * dt * drain * 1000.0 / 3600.0
        self.consumed_wh += current_a * drain * self.voltage * dt / 3600.0


def current_draw(armed: bool, flying: bool, throttle: float, hover_throttle: float) -> float:
    """Amps: avionics only when disarmed, motors at idle on the ground, ~15 A in a hover."""
    if not armed:
        return 0.5
    if not flying:
        return 2.0
    return 0.5 + 14.5 * float((throttle / hover_throttle) ** 1.5)
