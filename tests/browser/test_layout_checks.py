"""The layout checks the browser tests measure every screen with (tests/support/
layout_checks.py), on static pages: each finds its fault, and what a scroll brings back
is not a fault."""

from __future__ import annotations

from playwright.sync_api import Page

from tests.support.layout_checks import covered_controls, overflowing_elements


def test_a_button_past_the_right_edge_overflows(page: Page) -> None:
    page.set_content('<button style="position:absolute; left:1380px; width:60px">Far</button>')
    found = overflowing_elements(page)
    assert any('"Far"' in line for line in found), found


def test_a_button_under_a_box_is_covered(page: Page) -> None:
    page.set_content(
        '<button style="position:absolute; left:10px; top:10px">Under</button>'
        '<div style="position:absolute; left:0; top:0; width:200px; height:80px"></div>'
    )
    found = covered_controls(page)
    assert any('"Under"' in line and "is under div" in line for line in found), found


def test_a_control_half_scrolled_out_of_its_list_is_not_covered(page: Page) -> None:
    # A list that scrolls, its first input scrolled half past the top edge, a header
    # above the list: at the input's centre lies the header, and a scroll brings it back.
    page.set_content(
        '<header style="position:fixed; top:0; left:0; right:0; height:50px; z-index:2;'
        ' background:#222"></header>'
        '<div id="list" style="position:absolute; top:50px; height:200px; width:300px;'
        ' overflow-y:auto">'
        '<input value="half" style="display:block; height:40px">'
        '<div style="height:600px"></div></div>'
    )
    page.evaluate("document.getElementById('list').scrollTop = 30")
    assert covered_controls(page) == []
    assert overflowing_elements(page) == []
