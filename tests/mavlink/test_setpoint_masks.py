"""SET_POSITION_TARGET_* and SET_ATTITUDE_TARGET type_masks read as ArduCopter 4.6 reads them
(mavlink/gcs/setpoints.py): which are flown, which stop the vehicle, which are dropped."""

from __future__ import annotations

import math

import pytest

from silbridge.mavlink.gcs import setpoints as S

POS, VEL, ACC = 0x007, 0x038, 0x1C0
YAW, RATE, FORCE = 0x400, 0x800, 0x200


@pytest.mark.parametrize("mask, kind, accel", [
    (VEL | ACC | YAW | RATE, "pos", False),              # position only
    (POS | ACC | RATE, "velaccel", False),               # MAVSDK VelocityNedYaw (0x9C7)
    (POS | ACC | YAW | RATE, "velaccel", False),         # velocity only (0xDC7)
    (POS | YAW | RATE, "velaccel", True),                # velocity + acceleration
    (POS | VEL | YAW | RATE, "accel", True),             # acceleration only
    (ACC | YAW | RATE, "posvelaccel", False),            # position + velocity
    (RATE, "posvelaccel", True),                         # all three (MAVSDK's pos-vel-acc)
    (0x001 | ACC | YAW | RATE, "velaccel", False),       # x ignored: no position at all
])
def test_accepted_masks(mask, kind, accel):
    use = S.position_mask_use(mask)
    assert (use.kind, use.use_accel) == (kind, accel)


def test_a_group_with_any_ignore_bit_counts_as_ignored():
    # ignoring only z leaves no position: with velocity and acceleration ignored too, nothing
    use = S.position_mask_use(0x004 | VEL | ACC)
    assert use.kind is None and use.stop


@pytest.mark.parametrize("mask", [
    POS | VEL | ACC | RATE,          # a yaw alone
    POS | VEL | ACC | YAW,           # a yaw rate alone
    POS | VEL | ACC | YAW | RATE,    # nothing
    VEL | YAW | RATE,                # position + acceleration without velocity
])
def test_refused_masks_stop(mask):
    use = S.position_mask_use(mask)
    assert use.kind is None and use.stop and use.why


def test_force_set_acceleration_is_dropped_without_stopping():
    use = S.position_mask_use(POS | VEL | FORCE | YAW | RATE)
    assert use.kind is None and not use.stop
    # FORCE_SET with the acceleration ignored is an ordinary target
    assert S.position_mask_use(POS | ACC | FORCE | RATE).kind == "velaccel"


def test_yaw_and_yaw_rate_flags():
    use = S.position_mask_use(POS | ACC)
    assert use.use_yaw and use.use_yaw_rate
    use = S.position_mask_use(POS | ACC | YAW | RATE)
    assert not use.use_yaw and not use.use_yaw_rate


UNIT = (1.0, 0.0, 0.0, 0.0)


@pytest.mark.parametrize("mask, q, ok, att, rates", [
    (0x07, UNIT, True, True, False),                     # attitude, rates ignored (MAVSDK)
    (0x00, UNIT, True, True, True),                      # attitude + body-rate feed-forward
    (0x80, (0.0, 0.0, 0.0, 0.0), True, False, True),     # body rates only
    (0x87, (0.0, 0.0, 0.0, 0.0), True, False, False),    # nothing but thrust: rates 0
    (0x47, UNIT, False, False, False),                   # thrust ignored
    (0x03, UNIT, False, False, False),                   # yaw rate alone of the three
    (0x07, (0.9, 0.0, 0.0, 0.0), False, False, False),   # not unit length
    (0x07, (math.nan, 0.0, 0.0, 0.0), False, False, False),
])
def test_attitude_masks(mask, q, ok, att, rates):
    use = S.attitude_mask_use(mask, q)
    assert use.ok == ok
    if ok:
        assert (use.use_attitude, use.use_rates) == (att, rates)
    else:
        assert use.why
