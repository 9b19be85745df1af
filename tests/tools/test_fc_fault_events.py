"""A scenario's [[failure]] entries of the FC-side units become the FC's timed switches."""

from __future__ import annotations

from silbridge.fc_sil.params import lookup
from silbridge.tools.loop.fc_param_events import load_flight_scenario, param_events

BODY = 'name = "F"\nseed = 5\nduration_s = 60.0\n'


def test_rc_and_gcs_failures_become_switches_others_stay_with_the_bridge(tmp_path):
    path = tmp_path / "f.toml"
    path.write_text(BODY
                    + '[[failure]]\nunit = "rc"\ntype = "lost"\nat_s = 10.0\nduration_s = 5.0\n'
                    + '[[failure]]\nunit = "gcs"\ntype = "lost"\nat_s = 20.0\n'
                    + '[[failure]]\nunit = "gnss"\ntype = "off"\nat_s = 30.0\n')
    events = param_events(load_flight_scenario(str(path)))
    got = sorted((e.at_ns, e.name, e.value) for e in events)
    assert got == [(10_000_000_000, "SIM_RC_FAIL", 1.0), (15_000_000_000, "SIM_RC_FAIL", 0.0),
                   (20_000_000_000, "SB_SIM_GCS_FAIL", 1.0)]     # no duration: to the end
    for _, name, value in got:
        assert lookup(name).validate(value) == value
