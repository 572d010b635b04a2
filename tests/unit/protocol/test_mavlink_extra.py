"""The messages `protocol.mavlink_extra` defines are byte for byte pymavlink's own where
pymavlink has them (its development dialect, which the agent does not import)."""

from __future__ import annotations

import pytest
from pymavlink.dialects.v20 import ardupilotmega, development

from protocol import mavlink_extra
from protocol.mavlink_extra import (
    MAVLink_available_modes_message,
    MAVLink_available_modes_monitor_message,
    MAVLink_current_mode_message,
)

OURS_AND_PYMAVLINKS = [
    (MAVLink_available_modes_message, development.MAVLink_available_modes_message),
    (MAVLink_current_mode_message, development.MAVLink_current_mode_message),
    (MAVLink_available_modes_monitor_message, development.MAVLink_available_modes_monitor_message),
]


@pytest.mark.parametrize(("ours", "theirs"), OURS_AND_PYMAVLINKS)
def test_the_definition_is_pymavlinks(ours: type, theirs: type) -> None:
    for attribute in (
        "id",
        "msgname",
        "fieldnames",
        "ordered_fieldnames",
        "fieldtypes",
        "orders",
        "array_lengths",
        "crc_extra",
    ):
        assert getattr(ours, attribute) == getattr(theirs, attribute), attribute
    assert ours.unpacker.format == theirs.unpacker.format


def test_our_bytes_decode_in_pymavlink_and_its_in_ours() -> None:
    mavlink_extra.register()
    sent = MAVLink_available_modes_message(12, 3, 5, 0x04040000, 2, b"Mission")
    wire = sent.pack(ardupilotmega.MAVLink(None, srcSystem=1, srcComponent=1))
    decoded = development.MAVLink(None).decode(bytearray(wire))
    assert (decoded.number_modes, decoded.mode_index, decoded.standard_mode) == (12, 3, 5)
    assert (decoded.custom_mode, decoded.properties, decoded.mode_name) == (
        0x04040000,
        2,
        "Mission",
    )

    theirs = development.MAVLink_current_mode_message(5, 0x04040000, 0x03040000)
    wire = theirs.pack(development.MAVLink(None, srcSystem=1, srcComponent=1))
    ours = ardupilotmega.MAVLink(None).decode(bytearray(wire))
    assert isinstance(ours, MAVLink_current_mode_message)
    assert (ours.standard_mode, ours.custom_mode, ours.intended_custom_mode) == (
        5,
        0x04040000,
        0x03040000,
    )
