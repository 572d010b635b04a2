"""The camera maths against values worked by hand with QGC's definitions
(src/MissionManager/CameraCalc.cc, CameraCalc::_recalcTriggerDistance)."""

from __future__ import annotations

import pytest

from backend.survey.planning.camera import CameraError, calculate, preset

SONY = preset("sony_a6000_16mm")


def test_altitude_gives_qgc_gsd_footprint_spacing_and_trigger() -> None:
    calc = calculate(SONY, altitude_m=100, side_overlap_pct=70, front_overlap_pct=80)
    # GSD = alt * sensorW * 100 / (imageW * focal) = 100 * 23.5 * 100 / (6000 * 16)
    #     = 235000 / 96000 = 2.447916... cm/px
    assert calc.gsd_cm == pytest.approx(2.4479166667)
    # landscape: side = imageW * GSD / 100 = 6000 * 0.024479166 = 146.875 m
    #            frontal = imageH * GSD / 100 = 4000 * 0.024479166 = 97.91666 m
    assert calc.footprint_side_m == pytest.approx(146.875)
    assert calc.footprint_frontal_m == pytest.approx(97.9166667)
    # lane spacing = 146.875 * (100 - 70) / 100 = 44.0625 m
    # trigger distance = 97.91666 * (100 - 80) / 100 = 19.58333 m
    assert calc.lane_spacing_m == pytest.approx(44.0625)
    assert calc.trigger_distance_m == pytest.approx(19.5833333)


def test_gsd_gives_qgc_altitude() -> None:
    calc = calculate(
        preset("dji_phantom4_pro"), gsd_cm=2.0, side_overlap_pct=60, front_overlap_pct=75
    )
    # alt = imageW * GSD * focal / (sensorW * 100) = 5472 * 2 * 8.8 / (13.2 * 100)
    #     = 96307.2 / 1320 = 72.96 m
    assert calc.altitude_m == pytest.approx(72.96)
    # side = 5472 * 0.02 = 109.44 m, spacing = 109.44 * 0.4 = 43.776 m
    # frontal = 3648 * 0.02 = 72.96 m, trigger = 72.96 * 0.25 = 18.24 m
    assert calc.lane_spacing_m == pytest.approx(43.776)
    assert calc.trigger_distance_m == pytest.approx(18.24)


def test_portrait_swaps_side_and_frontal() -> None:
    portrait = SONY.model_copy(update={"landscape": False})
    calc = calculate(portrait, altitude_m=100, side_overlap_pct=0, front_overlap_pct=0)
    # portrait: side = imageH * GSD = 97.91666 m, frontal = imageW * GSD = 146.875 m
    assert calc.footprint_side_m == pytest.approx(97.9166667)
    assert calc.footprint_frontal_m == pytest.approx(146.875)
    assert calc.lane_spacing_m == pytest.approx(97.9166667)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        (
            {"altitude_m": 100, "side_overlap_pct": 100},
            "side_overlap_pct must be at least 0 and below 100",
        ),
        (
            {"altitude_m": 100, "front_overlap_pct": -1},
            "front_overlap_pct must be at least 0 and below 100",
        ),
        ({"altitude_m": 100, "gsd_cm": 2}, "exactly one of altitude_m and gsd_cm"),
        ({}, "exactly one of altitude_m and gsd_cm"),
        ({"altitude_m": 0}, "altitude_m must be greater than 0"),
        ({"gsd_cm": -2}, "gsd_cm must be greater than 0"),
    ],
)
def test_bad_settings_are_refused_saying_what_to_change(
    kwargs: dict[str, float], message: str
) -> None:
    with pytest.raises(CameraError, match=message):
        calculate(SONY, **kwargs)


def test_unknown_preset_names_the_known_ones() -> None:
    with pytest.raises(CameraError, match=r"unknown camera preset 'gopro'.*sony_a6000_16mm"):
        preset("gopro")


def test_a_camera_without_a_sensor_is_refused() -> None:
    with pytest.raises(CameraError, match="sensor_width_mm must be greater than 0"):
        SONY.with_figures(sensor_width_mm=0)
