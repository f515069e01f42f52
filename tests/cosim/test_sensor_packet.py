"""The sensor packet made in one array step is the packet made field by field (the packet format's
``pack``), and a row the packet cannot hold is refused as the field-by-field packing refuses it."""

import numpy as np
import pytest

from robosoc.control.flight import ROW_FIELDS
from robosoc.cosim.replay import built_in_rows, packed_sensor_packet, sensor_packet
from robosoc.host import packets


def test_every_row_of_a_flight_packs_to_the_field_by_field_bytes():
    rows = built_in_rows(4.0, seed=3)  # calibration on the ground and the take-off
    for k, row in enumerate(rows):
        for low in (False, True):
            assert sensor_packet(row, k, 10_000, low) == packed_sensor_packet(row, k, 10_000, low)
    values = packets.SENSOR.unpack(sensor_packet(rows[-1], 7, 10_000))
    assert values["seq"] == 7 and values["dt_us"] == 10_000
    assert values["gyro"][0] == round(rows[-1][ROW_FIELDS.index("gyro_x")] * 65536) / 65536


def test_values_half_way_between_q16_steps_round_to_even_as_round_does():
    row = built_in_rows(0.05, seed=1)[0].copy()
    gyro = ROW_FIELDS.index("gyro_x")
    for half in (0.5, 1.5, 2.5, -0.5, -1.5, 12345.5):
        row[gyro] = half / 65536  # exact in float64: a tie
        assert sensor_packet(row, 0, 10_000) == packed_sensor_packet(row, 0, 10_000)


@pytest.mark.parametrize(
    ("column", "value"), [("gyro_x", np.nan), ("accel_z", 40_000.0), ("mag_y", -np.inf), ("t", -1.0)]
)
def test_a_value_the_packet_cannot_hold_is_refused_naming_its_field(column, value):
    row = built_in_rows(0.05, seed=1)[0].copy()
    row[ROW_FIELDS.index(column)] = value
    with pytest.raises((ValueError, OverflowError)) as fast:
        sensor_packet(row, 0, 10_000)
    with pytest.raises((ValueError, OverflowError)) as slow:
        packed_sensor_packet(row, 0, 10_000)
    assert str(fast.value) == str(slow.value)
