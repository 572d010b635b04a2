"""The fleet's cameras as survey presets (one per model, named after its vehicles, its
name alone enough to plan with) and a survey's camera checked against each drone's."""

from __future__ import annotations

import pytest

from backend.fleet.registry import FleetRegistry
from backend.survey.fleet_cameras import camera_violations, fleet_cameras
from backend.survey.planning.camera import CameraError, calculate, preset
from backend.survey.planning.schemas import CameraModel, ManualCamera
from protocol.photos import CameraIntrinsics, parse_camera_model
from tests.support.hellos import agent_hello

SIM_CAMERA = parse_camera_model("6.3,4.7,1600,1200,4.5")
SMALL_CAMERA = parse_camera_model("6.4,4.8,640,480,4.8")


def _registry(cameras: dict[str, CameraIntrinsics | None]) -> FleetRegistry:
    registry = FleetRegistry()
    for vehicle_id, camera in cameras.items():
        hello = agent_hello(vehicle_id).model_copy(update={"camera": camera})
        registry.connect(hello, channel=object())  # type: ignore[arg-type]
    return registry


def test_each_camera_model_is_one_preset_named_after_its_vehicles() -> None:
    registry = _registry(
        {"sim_3": SIM_CAMERA, "sim_1": SIM_CAMERA, "sim_2": SMALL_CAMERA, "sim_4": None}
    )
    presets = fleet_cameras(registry.all())
    assert [(p.preset_id, p.vehicle_ids) for p in presets] == [
        ("fleet:6.3,4.7,1600,1200,4.5", ("sim_1", "sim_3")),
        ("fleet:6.4,4.8,640,480,4.8", ("sim_2",)),
    ]
    assert presets[0].name == "sim_1, sim_3 camera (6.3x4.7 mm, 1600x1200 px, 4.5 mm)"
    assert presets[0].camera.image_width_px == 1600


def test_a_camera_many_vehicles_carry_names_a_few_and_counts_the_rest() -> None:
    registry = _registry({f"sim_{i}": SIM_CAMERA for i in range(1, 6)})
    (only,) = fleet_cameras(registry.all())
    assert only.name.startswith("sim_1, sim_2 and 3 more camera (")


def test_a_fleet_preset_plans_by_its_name_alone() -> None:
    camera = preset("fleet:6.3,4.7,1600,1200,4.5")
    assert camera.model_dump(exclude={"name", "landscape", "distance_trigger"}) == (
        SIM_CAMERA.model_dump()
    )
    # GSD = 40 m * 6.3 mm * 100 / (1600 px * 4.5 mm) = 3.5 cm/px
    assert calculate(camera, altitude_m=40).gsd_cm == pytest.approx(3.5)
    with pytest.raises(CameraError, match=r"fleet:6\.3,4\.7"):
        preset("fleet:6.3,4.7")


def test_the_plans_own_camera_passes() -> None:
    carried = {"sim_1": SIM_CAMERA, "sim_2": SIM_CAMERA}
    assert camera_violations("fleet:6.3,4.7,1600,1200,4.5", carried) == {}
    figures = CameraModel(**SIM_CAMERA.model_dump())
    assert camera_violations(figures, carried) == {}


def test_another_image_size_is_explained_as_photos_that_would_be_refused() -> None:
    found = camera_violations("dji_phantom4_pro", {"sim_1": None, "sim_2": SIM_CAMERA})
    assert list(found) == ["sim_2"]  # sim_1 says no camera: nothing to compare
    assert found["sim_2"].rule == "survey_camera"
    assert found["sim_2"].message == (
        "sim_2's camera is 6.3x4.7 mm, 1600x1200 px, 4.5 mm, the plan assumes "
        "13.2x8.8 mm, 5472x3648 px, 8.8 mm (DJI Phantom 4 Pro): its photos would be "
        "refused; plan with its camera (preset fleet:6.3,4.7,1600,1200,4.5)"
    )


def test_other_optics_of_the_same_size_are_refused_too() -> None:
    other_lens = CameraModel(**{**SIM_CAMERA.model_dump(), "focal_length_mm": 6.0})
    found = camera_violations(other_lens, {"sim_1": SIM_CAMERA})
    assert "would not have the planned ground resolution" in found["sim_1"].message
    # A maker's rounding is not another camera.
    rounded = CameraModel(**{**SIM_CAMERA.model_dump(), "sensor_width_mm": 6.31})
    assert camera_violations(rounded, {"sim_1": SIM_CAMERA}) == {}


def test_a_manual_camera_has_no_figures_to_compare() -> None:
    manual = ManualCamera(lane_spacing_m=20, trigger_distance_m=10)
    assert camera_violations(manual, {"sim_1": SIM_CAMERA}) == {}


def test_an_agent_that_reconnects_with_another_camera_replaces_it() -> None:
    registry = _registry({"sim_1": SIM_CAMERA})
    registry.connect(
        agent_hello("sim_1").model_copy(update={"camera": SMALL_CAMERA}),
        channel=object(),  # type: ignore[arg-type]
    )
    assert registry.get("sim_1").camera == SMALL_CAMERA
