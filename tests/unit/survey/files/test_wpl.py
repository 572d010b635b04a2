"""Our `QGC WPL 110` export reads back, with pymavlink's own reader, to the same items."""

from __future__ import annotations

import pytest

from backend.survey.files.wpl import to_wpl
from tests.support.surveys import QGC_HOME, read_wpl, same_items, survey_plan_items


def test_wpl_round_trip() -> None:
    items = survey_plan_items()
    text = to_wpl(items, QGC_HOME)
    assert text.startswith("QGC WPL 110\n0\t1\t0\t16\t")
    home, back = read_wpl(text)
    assert home == pytest.approx(QGC_HOME)
    same_items(back, items)
