"""What a vehicle reports as it goes: STATUSTEXTs, mission items reached, photos taken."""

from __future__ import annotations

from dataclasses import dataclass

from simulator.mavconst import Severity


@dataclass(frozen=True)
class StatusText:
    severity: Severity
    text: str


@dataclass(frozen=True)
class ItemReached:
    """MISSION_ITEM_REACHED: mission command ``seq`` is complete."""

    seq: int


@dataclass(frozen=True)
class PhotoTaken:
    """CAMERA_FEEDBACK: the camera fired (``index`` counts from 1)."""

    index: int
    time_s: float
    lat: float
    lon: float
    alt_msl: float
    alt_rel: float
    roll: float
    pitch: float
    yaw: float


Event = ItemReached | PhotoTaken
