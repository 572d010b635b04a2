"""Which agent events end browser control: a "manual" event of WARNING or worse, EMERGENCY
(severity 0) included; a missing severity counts as DEBUG."""

from __future__ import annotations

import pytest

from backend.manual_control.service import ends_manual_control


@pytest.mark.parametrize("severity", [0, 1, 2, 3, 4])
def test_warning_or_worse_ends_it(severity: int) -> None:
    assert ends_manual_control("manual", severity)


@pytest.mark.parametrize("severity", [5, 6, 7, None])
def test_milder_or_unknown_does_not(severity: int | None) -> None:
    assert not ends_manual_control("manual", severity)


def test_only_manual_events_count() -> None:
    assert not ends_manual_control("mode", 0)
