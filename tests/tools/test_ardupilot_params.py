"""Our parameter declarations against the real ArduCopter 4.6.0 (SILBRIDGE_ARDUCOPTER): start it
with its own physics (--model quad, fresh working directory, a free instance), fetch its full
list with PARAM_REQUEST_LIST over pymavlink, and compare every parameter we declare that it has:
the MAVLink type must be ArduCopter's, and a default may differ only where a departure is
documented below. Differences are printed (run with -s to read them)."""

from __future__ import annotations

import os
import re
import tempfile
import time

import pytest

from silbridge.fc_sil import params as P
from silbridge.tools.autopilots.ardupilot.sitl import (MAVLINK_TCP_BASE, PORT_STRIDE, pick_instance,
                                                       stop_sitl)

BINARY = os.environ.get("SILBRIDGE_ARDUCOPTER")
pytestmark = pytest.mark.skipif(
    not BINARY, reason="SILBRIDGE_ARDUCOPTER is not set (path of an ArduCopter 4.6 SITL binary, "
    "`./waf copter` in an ArduPilot checkout): nothing to compare against")

# Defaults that differ from the firmware's on purpose.
DEFAULT_DEPARTURES = {
    # the paper's controller (docs/params.md) and silbridge's position loop
    "ATC_ANG_YAW_P": "paper: yaw rate damping only",
    "MOT_SLEW_UP_TIME": "paper's slew limit on", "MOT_SLEW_DN_TIME": "paper's slew limit on",
    "PSC_VELXY_D": "silbridge position loop",
    # the simulated vehicle and its battery (fc_params.def texts)
    "BATT_LOW_VOLT": "modelled 4S pack",
    "BATT_FS_LOW_ACT": "RTL on low battery", "BATT_FS_CRT_ACT": "LAND on critical battery",
    # ArduCopter SITL's copter.parm, so QGroundControl's setup pages show as done
    "FRAME_CLASS": "copter.parm (1: quad)",
    **{f"RC{c}_{k}": "copter.parm calibration" for c in range(1, 9) for k in ("MIN", "MAX")},
    **{f"INS_ACCOFFS_{a}": "copter.parm accel calibration" for a in "XYZ"},
}
# Groups whose keys ArduCopter lists only when enabled: the fetch enables them (so their defaults
# read 1 there), and every key we declare in them must then be in its list.
GROUP_ENABLES = {"INS_HNTCH_ENABLE": "INS_HNTCH_", "INS_HNTC2_ENABLE": "INS_HNTC2_",
                 "FFT_ENABLE": "FFT_"}
DEFAULT_DEPARTURES.update({name: "enabled for the fetch" for name in GROUP_ENABLES})
# AP_GyroFFT.cpp declares 80 and 200 Hz (a real board's defaults, kept here); the SITL binary
# lists 50 and 450.
DEFAULT_DEPARTURES.update({"FFT_MINHZ": "AP_GyroFFT's declared 80 Hz",
                           "FFT_MAXHZ": "AP_GyroFFT's declared 200 Hz"})
# Sensor ids ArduCopter fills in as it detects its sensors at boot (so its list can show 0 or
# the id): values, not defaults. silbridge reports one sensor of each kind.
RUNTIME_ID = re.compile(r"^(COMPASS_DEV_ID\d?|COMPASS_PRIO\d_ID|INS_(ACC|GYR)\d?_ID|BARO\d_DEVID)$")


def _fetch(binary: str, workdir: str) -> dict:
    from pymavlink import mavutil
    import subprocess
    n = pick_instance()
    with open(os.path.join(workdir, "defaults.parm"), "w") as fh:
        fh.write("BATT_MONITOR 4\n")      # as SITL's copter.parm: the BATT_* parameters exist
        for name in GROUP_ENABLES:          # ArduCopter lists a group's keys only when enabled
            fh.write(f"{name} 1\n")
    log = open(os.path.join(workdir, "sitl.log"), "w")
    proc = subprocess.Popen([binary, "--model", "quad", "--speedup", "1", "-I", str(n), "-w",
                             "--defaults", "defaults.parm"], cwd=workdir, stdout=log,
                            stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
    log.close()
    try:
        port = MAVLINK_TCP_BASE + PORT_STRIDE * n
        end = time.monotonic() + 30
        conn = None
        while conn is None:
            try:
                conn = mavutil.mavlink_connection(f"tcp:127.0.0.1:{port}", source_system=250,
                                                  retries=1)
            except OSError:
                if time.monotonic() > end:
                    raise
                time.sleep(0.3)
        assert conn.wait_heartbeat(timeout=30) is not None, "ArduCopter sent no heartbeat"
        got: dict = {}
        count = None
        for _attempt in range(3):
            conn.mav.param_request_list_send(conn.target_system, conn.target_component)
            quiet_until = time.monotonic() + 5
            while time.monotonic() < quiet_until:
                m = conn.recv_match(type="PARAM_VALUE", blocking=True, timeout=0.5)
                if m is not None:
                    got[m.param_id] = (m.param_type, m.param_value)
                    count = m.param_count
                    quiet_until = time.monotonic() + 2
                if count is not None and len(got) >= count:
                    break
            if count is not None and len(got) >= count:
                break
        conn.close()
        assert count and len(got) == count, f"got {len(got)} of {count} parameters"
        return got
    finally:
        stop_sitl(proc)


def test_declared_parameters_match_the_real_arducopter():
    with tempfile.TemporaryDirectory(prefix="silbridge-ac-params-") as wd:
        ac = _fetch(BINARY, wd)
    print(f"\nArduCopter: {len(ac)} parameters; silbridge declares {len(P.PARAMS)}")
    ours = [p for p in P.PARAMS if p.name in ac]
    absent = [p.name for p in P.PARAMS if p.name not in ac and not p.name.startswith("SB_")]
    print(f"compared: {len(ours)}; declared but not in ArduCopter: {absent}")
    type_diff, default_diff = [], []
    for p in ours:
        t, v = ac[p.name]
        if t != p.mav_type:
            type_diff.append((p.name, p.mav_type, t))
        if abs(v - p.default) > 1e-4 * max(1.0, abs(v)) and not RUNTIME_ID.match(p.name):
            default_diff.append((p.name, p.default, v))
    for name, mine, theirs in default_diff:
        why = DEFAULT_DEPARTURES.get(name, "UNDOCUMENTED")
        print(f"default {name}: silbridge {mine:g}, ArduCopter {theirs:g} ({why})")
    for name, mine, theirs in type_diff:
        print(f"type {name}: silbridge {mine}, ArduCopter {theirs}")
    assert not type_diff, type_diff      # every shared parameter has ArduCopter's MAVLink type
    undocumented = [d for d in default_diff if d[0] not in DEFAULT_DEPARTURES]
    assert not undocumented, undocumented
    grouped = [p.name for p in P.PARAMS if p.name.startswith(tuple(GROUP_ENABLES.values()))]
    assert grouped and all(n in ac for n in grouped), [n for n in grouped if n not in ac]
    gcs_block = [p for p in P.PARAMS if 1000 <= p.index <= 2999]
    assert all(p.name in ac for p in gcs_block), [p.name for p in gcs_block if p.name not in ac]
