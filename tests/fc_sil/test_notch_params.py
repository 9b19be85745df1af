"""The harmonic notch's parameters in the flight core: ArduCopter 4.6's names, types,
defaults and ranges, declared once (fc_params.def); bad values refused with the old value
kept; and its cost reported by `silbridge fc-bench`."""

import json
import subprocess
import sys

import pytest

from silbridge.fc_sil import params as P
from silbridge.fc_sil.errors import ParamError
from silbridge.fc_sil.flight_core import FlightCore

# ArduCopter 4.6 (HarmonicNotchFilterParams, AP_InertialSensor's HNTCH/HNTC2 groups):
# name suffix -> (MAVLink type, default, min, max)
ARDUCOPTER = {
    "ENABLE": ("INT8", 0, 0, 1), "MODE": ("INT8", 1, 0, 5), "FREQ": ("FLOAT", 80, 10, 495),
    "BW": ("FLOAT", 40, 5, 250), "ATT": ("FLOAT", 40, 5, 50), "HMNCS": ("INT32", 3, 0, 65535),
    "REF": ("FLOAT", 0, 0, 1), "FM_RAT": ("FLOAT", 1.0, 0.1, 1.0), "OPTS": ("INT16", 0, 0, 127),
}


@pytest.mark.parametrize("prefix", ["INS_HNTCH_", "INS_HNTC2_"])
def test_declarations_are_arducopters(prefix):
    for suffix, (typ, default, lo, hi) in ARDUCOPTER.items():
        d = P.lookup(prefix + suffix)
        assert d.type == typ, d
        assert (d.default, d.min, d.max) == pytest.approx((default, lo, hi)), d.name
        assert not d.host, d.name                  # the C core's own parameters


def test_old_slots_keep_their_indices_and_new_ones_sit_in_410_439():
    assert [P.lookup(f"INS_HNTCH_{s}").index for s in ("ENABLE", "FREQ", "BW")] == [33, 34, 35]
    for prefix in ("INS_HNTCH_", "INS_HNTC2_"):
        for s in ARDUCOPTER:
            if (prefix, s) not in {("INS_HNTCH_", "ENABLE"), ("INS_HNTCH_", "FREQ"),
                                   ("INS_HNTCH_", "BW")}:
                assert 410 <= P.lookup(prefix + s).index <= 439


@pytest.mark.parametrize("name,bad", [
    ("INS_HNTCH_ATT", 60.0), ("INS_HNTCH_MODE", 6.0), ("INS_HNTCH_HMNCS", 65536.0),
    ("INS_HNTCH_OPTS", 128.0), ("INS_HNTCH_FM_RAT", 0.05), ("INS_HNTCH_REF", 1.5),
    ("INS_HNTC2_FREQ", 600.0), ("INS_HNTC2_BW", 2.0), ("INS_HNTC2_HMNCS", 1.5),
    ("INS_HNTC2_ENABLE", 2.0)])
def test_bad_values_are_refused_and_the_old_value_kept(name, bad):
    fc = FlightCore()
    old = fc.get_param(name)
    with pytest.raises(ParamError):
        fc.set_param(name, bad)
    assert fc.get_param(name) == old


def test_centre_below_half_the_bandwidth_is_refused_for_both_notches():
    fc = FlightCore()
    for prefix in ("INS_HNTCH_", "INS_HNTC2_"):
        fc.set_param(prefix + "BW", 40.0)
        with pytest.raises(ParamError):
            fc.set_param(prefix + "FREQ", 15.0)
        assert fc.get_param(prefix + "FREQ") == 80.0


def test_good_values_are_taken():
    fc = FlightCore()
    for name, v in (("INS_HNTCH_ENABLE", 1), ("INS_HNTCH_MODE", 3), ("INS_HNTCH_HMNCS", 7),
                    ("INS_HNTCH_OPTS", 18), ("INS_HNTC2_ENABLE", 1), ("INS_HNTC2_FM_RAT", 0.6)):
        assert fc.set_param(name, v) == pytest.approx(v)


def test_fc_bench_reports_the_notch_cost_per_harmonic():
    out = subprocess.run([sys.executable, "-m", "silbridge.tools", "fc-bench", "--json",
                          "--samples", "5000", "--repeat", "1"],
                         capture_output=True, text=True, check=True).stdout
    notch = json.loads(out.strip().splitlines()[-1])["notch"]
    assert notch["harmonics"] == 2
    for key in ("imu_step_off_ns", "imu_step_on_ns", "worst_ns_per_harmonic"):
        assert notch[key] > 0, key
    assert notch["ns_per_harmonic"] >= 0
    assert notch["target_ns_per_harmonic"] == 150.0
