"""`gcs demo`'s options: cameras by default (a model the hub offers as a survey preset),
`--no-cameras`, `--lidar` with or without a format, and a help whose example camera is a
survey preset's."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from backend.survey.planning.camera import PRESETS, fleet_preset_id, preset
from gcs.cli import build_parser, demo_plan
from gcs.demo_camera import DEMO_CAMERA_MODEL
from gcs.launcher import FleetPlan
from protocol.photos import parse_camera_model


def _plan(tmp_path: Path, *options: str) -> FleetPlan:
    args = build_parser().parse_args(["demo", "--data-dir", str(tmp_path), *options])
    return demo_plan(args)


def test_the_demo_fits_cameras_and_no_lidar_by_default(tmp_path: Path) -> None:
    plan = _plan(tmp_path)
    assert plan.camera_model == DEMO_CAMERA_MODEL
    assert plan.lidars is False
    # The hub offers the demo's camera as a preset that plans (fleet_cameras.py).
    camera = preset(fleet_preset_id(parse_camera_model(DEMO_CAMERA_MODEL)))
    assert (camera.image_width_px, camera.image_height_px) == (1280, 960)


def test_no_cameras_leaves_them_off(tmp_path: Path) -> None:
    assert _plan(tmp_path, "--no-cameras").camera_model is None
    assert _plan(tmp_path, "--camera-model", "13.2,8.8,5472,3648,8.8").camera_model == (
        "13.2,8.8,5472,3648,8.8"
    )


@pytest.mark.parametrize(
    ("options", "lidar"),
    [
        (["--lidar"], "ydlidar"),
        (["--lidar", "ld06"], "ld06"),
        (["--lidar", "--vehicles", "4"], "ydlidar"),
    ],
)
def test_lidar_with_or_without_a_format(tmp_path: Path, options: list[str], lidar: str) -> None:
    plan = _plan(tmp_path, *options)
    assert plan.lidars is True
    assert plan.lidar == lidar


def test_a_camera_model_that_is_not_one_stops_the_demo_at_once(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit):
        _plan(tmp_path, "--camera-model", "6.3,4.7,1600")
    assert "sensor width,height" in capsys.readouterr().err


def test_the_helps_example_camera_is_the_preset_it_names(
    capsys: pytest.CaptureFixture[str],
) -> None:
    with pytest.raises(SystemExit):
        build_parser().parse_args(["demo", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    example = re.search(r"(\d[\d.]*,[\d.]+,\d+,\d+,[\d.]+) is a DJI Phantom 4 Pro", text)
    assert example is not None, text
    figures = parse_camera_model(example.group(1))
    assert figures.model_dump() == PRESETS["dji_phantom4_pro"].model_dump(
        exclude={"name", "landscape", "distance_trigger"}
    )
    assert DEMO_CAMERA_MODEL in text
