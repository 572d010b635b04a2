"""STATUSTEXT chunks joined on an injected clock, and reached items once per pass."""

from __future__ import annotations

from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from vehicle_agents.telemetry.mission_progress import ReachedItems
from vehicle_agents.telemetry.statustext import JoinedText, StatusTextJoiner, StatusTextTimeouts

WARNING = mavlink2.MAV_SEVERITY_WARNING


def chunk(text: str, text_id: int, seq: int) -> Any:
    """A STATUSTEXT as it comes off the wire (packed and parsed: the NUL padding goes)."""
    mav = mavlink2.MAVLink(None, 1, 1)
    frame = mavlink2.MAVLink_statustext_message(WARNING, text.encode(), text_id, seq).pack(mav)
    return mavlink2.MAVLink(None).parse_buffer(frame)[0]


def test_an_unfinished_text_is_let_out_after_its_wait() -> None:
    joiner = StatusTextJoiner(StatusTextTimeouts(flush_after_s=1.0))
    assert joiner.add(chunk("a" * 50, 3, 0), now=10.0) == []
    assert joiner.add(chunk("c" * 10, 3, 2), now=10.1) == []  # chunk 1 was lost
    assert joiner.due(10.9) == []
    assert joiner.due(11.0) == [JoinedText(WARNING, "a" * 50 + "…" + "c" * 10)]
    assert joiner.due(20.0) == []  # once


def test_an_id_that_comes_round_again_starts_a_new_text() -> None:
    joiner = StatusTextJoiner()
    assert joiner.add(chunk("x" * 50, 5, 0), now=0.0) == []
    # the same id and chunk again: the first text will never finish; it goes out as is
    assert joiner.add(chunk("y" * 50, 5, 0), now=0.1) == [JoinedText(WARNING, "x" * 50)]
    assert joiner.add(chunk("!", 5, 1), now=0.2) == [JoinedText(WARNING, "y" * 50 + "!")]


def test_a_single_text_passes_at_once() -> None:
    assert StatusTextJoiner().add(chunk("Arming", 0, 0), now=0.0) == [JoinedText(WARNING, "Arming")]


def test_the_whitespace_px4_leaves_at_a_texts_end_goes_but_not_between_chunks() -> None:
    joiner = StatusTextJoiner()
    assert joiner.add(chunk("Takeoff detected\t", 0, 0), now=0.0) == [
        JoinedText(WARNING, "Takeoff detected")
    ]
    first = "Preflight Fail: " + "x" * 33 + " "  # 50 characters, ending between two words
    assert joiner.add(chunk(first, 7, 0), now=0.0) == []
    assert joiner.add(chunk("done\t", 7, 1), now=0.1) == [JoinedText(WARNING, first + "done")]


def test_a_reached_item_is_news_once_per_pass() -> None:
    reached = ReachedItems()
    reached.current(1)
    assert reached.reached(1)
    reached.current(1)  # MISSION_CURRENT not yet moved on: no return to the item
    assert not reached.reached(1)
    reached.current(2)
    assert not reached.reached(1)  # PX4's repeats
    assert reached.reached(2)
    reached.current(3)
    reached.current(0)  # the mission restarted
    assert reached.reached(1)
    assert reached.reached(2)
    reached.current(3)
    reached.current(2)  # a DO_JUMP back to the item just reached
    assert reached.reached(2)
