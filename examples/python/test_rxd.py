"""The chip's serial input from Python: Chip.drive_rxd and Chip.drive_rxd_chars refuse what a
line cannot do, as the C++ calls do (include/dpc31/chip.hpp, "the serial side"): a cycle or a start
before the chip's cycle (an edge in its past would be a glitch now) and bit_cycles 0 are a
ValueError naming the call, and nothing is driven: the chip's state, every byte of it, is as
before.

The range's edges are taken: the character 00h (chip-facts.md, "UART char: 11 bits = start,
8 data (LSB first), even parity, 1 stop") from the chip's cycle at 1 clock per bit ends 11 clocks
later.
"""

import pytest

import dpc31

STATUS = bytes([0x10, 0x05, 0x02, 0x49, 0x50, 0x16])  # FDL_Status from 2 to 5


@pytest.mark.parametrize("call, message", [
    (lambda c: c.drive_rxd(999, False), "drive_rxd: cycle 999 is before the chip's cycle 1000"),
    (lambda c: c.drive_rxd_chars(STATUS, 999, 4),
     "drive_rxd_chars: start 999 is before the chip's cycle 1000"),
    (lambda c: c.drive_rxd_chars(STATUS, 1000, 0),
     "drive_rxd_chars: bit_cycles 0: a bit lasts 1 clock or more"),
])
def test_a_time_in_the_chips_past_or_a_bit_of_no_clocks_is_a_value_error(call, message):
    chip = dpc31.Chip("dpc31")
    chip.step(1000)
    before = chip.save_state()
    with pytest.raises(ValueError) as e:
        call(chip)
    assert str(e.value) == message
    assert chip.save_state() == before

    # The range's edges are taken.
    chip.drive_rxd(1000, True)
    assert chip.drive_rxd_chars(b"\x00", 1000, 1) == 1011
