"""The fleet's own cameras: each one offered as a survey preset named after the vehicles
that carry it, and a survey's camera checked against each chosen drone's before take-off.

An agent says its camera in its hello (``Hello.camera``, its --camera-model). The hub
refuses a photo whose image size is not the survey camera's (imagery/photos/checks.py);
this check says so when the survey is planned, not after the flight, and also refuses a
camera of the same size whose optics differ (the plan's ground resolution and overlaps
would be wrong, silently).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

from backend.fleet.registry import VehicleRecord
from backend.safety.violations import SURVEY_CAMERA, Violation
from backend.survey.planning.camera import FLEET_PREFIX, Camera, fleet_preset_id, preset
from backend.survey.planning.schemas import Camera as RequestedCamera
from backend.survey.planning.schemas import CameraModel, ManualCamera
from protocol.photos import CameraIntrinsics, describe_camera

# Sensor and focal length may differ this much (relative) between the plan and the drone:
# a maker's sheet rounds them; a different lens or sensor is far more than this.
OPTICS_TOLERANCE = 0.01
# A preset's name lists at most this many of the vehicles that carry the camera.
NAMED_VEHICLES = 3


@dataclass(frozen=True)
class FleetCamera:
    """One camera model the fleet carries: its preset name, figures and carriers."""

    preset_id: str
    camera: Camera
    vehicle_ids: tuple[str, ...]

    @property
    def name(self) -> str:
        return f"{_carriers(self.vehicle_ids)} camera ({describe_camera(self.camera)})"


def _carriers(vehicle_ids: tuple[str, ...]) -> str:
    if len(vehicle_ids) <= NAMED_VEHICLES:
        return ", ".join(vehicle_ids)
    shown = ", ".join(vehicle_ids[: NAMED_VEHICLES - 1])
    return f"{shown} and {len(vehicle_ids) - NAMED_VEHICLES + 1} more"


def fleet_cameras(records: Iterable[VehicleRecord]) -> list[FleetCamera]:
    """The cameras the vehicles' agents reported, one per model, in vehicle id order."""
    carriers: dict[str, list[str]] = {}
    for record in sorted(records, key=lambda r: r.id):
        if record.camera is not None:
            carriers.setdefault(fleet_preset_id(record.camera), []).append(record.id)
    return [
        FleetCamera(preset_id=key, camera=preset(key), vehicle_ids=tuple(ids))
        for key, ids in carriers.items()
    ]


def planned_camera(camera: RequestedCamera) -> Camera | None:
    """The figures a survey is planned with; None for a manual camera (it has none).
    A preset's name is taken as known (the planner has refused an unknown one)."""
    if isinstance(camera, ManualCamera):
        return None
    if isinstance(camera, CameraModel):
        return Camera(name="the camera's figures", **camera.model_dump())
    return preset(camera)


def _same_optics(a: CameraIntrinsics, b: CameraIntrinsics) -> bool:
    return all(
        math.isclose(x, y, rel_tol=OPTICS_TOLERANCE)
        for x, y in (
            (a.sensor_width_mm, b.sensor_width_mm),
            (a.sensor_height_mm, b.sensor_height_mm),
            (a.focal_length_mm, b.focal_length_mm),
        )
    )


def camera_violations(
    camera: RequestedCamera, carried: Mapping[str, CameraIntrinsics | None]
) -> dict[str, Violation]:
    """Each chosen drone whose camera is not the one the survey is planned for, with what
    would happen to its photos. A drone whose camera is not known (no camera on its agent,
    or an agent that does not say) is not checked: its photos reach the hub only if it has
    one, and those are checked as they arrive."""
    planned = planned_camera(camera)
    if planned is None:
        return {}
    # A catalogue preset's name says more than its figures; the others are their figures.
    named = isinstance(camera, str) and not camera.startswith(FLEET_PREFIX)
    assumed = describe_camera(planned) + (f" ({planned.name})" if named else "")
    found: dict[str, Violation] = {}
    for vehicle_id, actual in carried.items():
        if actual is None:
            continue
        size = (actual.image_width_px, actual.image_height_px)
        if size != (planned.image_width_px, planned.image_height_px):
            outcome = "its photos would be refused"
        elif not _same_optics(actual, planned):
            outcome = "its photos would not have the planned ground resolution and overlaps"
        else:
            continue
        found[vehicle_id] = Violation(
            rule=SURVEY_CAMERA,
            message=f"{vehicle_id}'s camera is {describe_camera(actual)}, the plan assumes "
            f"{assumed}: {outcome}; plan with its camera "
            f"(preset {fleet_preset_id(actual)})",
        )
    return found


def carried_cameras(records: Mapping[str, VehicleRecord]) -> dict[str, CameraIntrinsics | None]:
    return {vehicle_id: record.camera for vehicle_id, record in records.items()}
