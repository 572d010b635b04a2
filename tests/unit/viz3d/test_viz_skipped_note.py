"""The 3D view's note on what it did not draw says why, where the origin is, what to do."""

from __future__ import annotations

from backend.viz3d.skipped_note import skipped_note
from common.geodesy import GeoPoint

ORIGIN = GeoPoint(-35.363262, 149.165237, 584.0)


def test_nothing_skipped_is_no_note() -> None:
    assert skipped_note({}, ORIGIN, configured=False) == ""


def test_too_far_names_the_origin_the_distance_and_the_way_to_move_it() -> None:
    note = skipped_note({"too far from the origin": 39}, ORIGIN, configured=False)
    assert "39 positions more than 200 km" in note
    assert "-35.36326, 149.16524" in note
    assert "first home position the fleet reported" in note
    assert "GCS_VIZ_ORIGIN=latitude,longitude" in note


def test_a_configured_origin_is_named_as_such() -> None:
    note = skipped_note({"too far from the origin": 1}, ORIGIN, configured=True)
    assert "1 position more than" in note
    assert "set by GCS_VIZ_ORIGIN" in note


def test_each_other_reason_is_explained_in_its_own_paragraph() -> None:
    note = skipped_note({"no origin yet": 2, "out of range": 1}, None, configured=False)
    paragraphs = note.split("\n\n")
    assert len(paragraphs) == 2
    assert "before any vehicle reported its home position" in paragraphs[0]
    assert "above 20,000 m" in paragraphs[1]
