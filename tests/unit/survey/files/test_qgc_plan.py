"""Our `.plan` export parses back to the same items and has the fields QGC requires;
QGC's own plans import, and bad ones are refused saying why."""

from __future__ import annotations

import json

import jsonschema_rs
import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from backend.survey.files.items import InteropError
from backend.survey.files.qgc_plan import read_qgc_plan_items, to_qgc_plan
from tests.support.surveys import QGC_DATA, QGC_HOME, same_items, survey_plan_items


def test_our_plan_export_has_qgcs_fields_and_parses_back_to_the_same_items() -> None:
    items = survey_plan_items()
    document = to_qgc_plan(items, QGC_HOME)
    schema = json.loads((QGC_DATA / "plan.schema.json").read_text())
    jsonschema_rs.validate(schema, document)
    commands = {item.command for item in items}
    assert mavlink2.MAV_CMD_DO_SET_CAM_TRIGG_DIST in commands
    same_items(read_qgc_plan_items(json.dumps(document)), items)


def test_qgcs_own_plan_imports() -> None:
    items = read_qgc_plan_items((QGC_DATA / "simple_square.plan").read_text())
    assert items[0].command == mavlink2.MAV_CMD_NAV_TAKEOFF
    assert items[1].lat == pytest.approx(47.398742)
    assert items[1].frame == mavlink2.MAV_FRAME_GLOBAL_RELATIVE_ALT
    # QGC's null yaw is MAVLink's NaN, "keep the heading": unset, not 0 (north on PX4).
    assert [item.param4 for item in items] == [None] * len(items)


def test_a_qgc_null_altitude_is_refused_naming_the_item_not_read_as_0() -> None:
    refusal = r"mission item 3 .*param 7 \(altitude\) is empty \(null\)"
    with pytest.raises(InteropError, match=refusal):
        read_qgc_plan_items((QGC_DATA / "null_altitude.plan").read_text())


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("{", "invalid JSON"),
        ('{"fileType": "Fence"}', '"fileType" must be "Plan"'),
        ('{"fileType": "Plan", "mission": {"items": [{"type": "SimpleItem"}]}}', "7 params"),
    ],
)
def test_bad_plan_files_are_refused_saying_why(text: str, message: str) -> None:
    with pytest.raises(InteropError, match=message):
        read_qgc_plan_items(text)
