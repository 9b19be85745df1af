"""The pre-flight height check (tools/autopilots/px4/rest_height.py) on PX4's own reports.

The two sequences are LOCAL_POSITION_NED (sim time s, z m, vz m/s) from two real-time boots
of PX4 v1.15.4 on our physics under one busy loop (issue 29), one report every ~0.25 s, from
the first report to the arming: a boot whose EKF2 started with a vertical velocity at rest
(it held 5 m of its own estimate at 5.83 m of truth) and a good one (5.02 m).
"""

from __future__ import annotations

import pytest

from silbridge.tools.autopilots.px4 import rest_height as rh
from silbridge.tools.autopilots.px4.rest_height import RestHeightCheck

BAD_BOOT = [(1.116, 1.194, 1.507), (1.376, 1.596, 0.701), (1.636, 1.15, 0.259),
            (1.9, 0.901, 0.089), (2.156, 0.763, 0.001), (2.416, 0.685, -0.04),
            (2.676, 0.686, -0.013), (2.936, 0.719, 0.018), (3.196, 0.749, 0.035),
            (3.456, 0.765, 0.031), (3.716, 0.762, 0.01), (3.976, 0.743, -0.021)]
GOOD_BOOT = [(1.228, -0.016, -0.011), (1.488, -0.019, -0.016), (1.748, 0.002, 0.035),
             (2.012, -0.003, -0.002), (2.268, -0.026, -0.025), (2.528, -0.034, -0.021),
             (2.788, -0.027, -0.006), (3.048, -0.019, 0.004), (3.308, -0.002, 0.024),
             (3.568, 0.011, 0.032), (3.828, 0.008, 0.022), (4.088, -0.013, -0.005)]


def _fed(reports) -> RestHeightCheck:
    check = RestHeightCheck()
    for t, z, vz in reports:
        check.feed(t, z, vz)
    return check


def test_a_good_boot_settles_after_its_settle_time_and_not_before():
    check = _fed(GOOD_BOOT)
    assert check.settled
    # settled at the first report SETTLE_S after the first one inside the bounds
    assert check.settled_s == pytest.approx(2.268)
    assert check.settled_s - GOOD_BOOT[0][0] >= rh.SETTLE_S
    assert not _fed(GOOD_BOOT[:4]).settled       # 0.78 s of reports: not yet
    assert not check.failed(GOOD_BOOT[0][0] + rh.BUDGET_S + 1.0)


def test_a_boot_that_kept_its_start_up_height_error_never_settles_and_fails_after_the_budget():
    check = _fed(BAD_BOOT)
    assert not check.settled
    assert not check.failed(BAD_BOOT[-1][0])      # within the budget: still waiting
    assert check.failed(BAD_BOOT[0][0] + rh.BUDGET_S + 0.01)
    why = check.why()
    assert "0.74 m" in why and "did not settle" in why


def test_leaving_the_bounds_restarts_the_settle_time():
    check = RestHeightCheck()
    check.feed(1.0, 0.0, 0.0)
    check.feed(1.9, 0.0, 0.0)
    check.feed(2.0, 0.0, rh.REST_VZ_M_S * 2)      # a vertical speed: not at rest
    check.feed(2.5, 0.0, 0.0)
    check.feed(3.4, 0.0, 0.0)
    assert not check.settled
    check.feed(3.5, 0.0, 0.0)
    assert check.settled_s == 3.5
    assert check.summary() == {"settled_s": 3.5, "first_report_s": 1.0, "z_m": 0.0,
                               "vz_m_s": 0.0}
