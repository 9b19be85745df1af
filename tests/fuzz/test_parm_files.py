"""`.parm` files, perturbed: each loads, or fails with a ParamFileError naming the file and
the line; a bad file given to a reload leaves the parameter set and the file itself
byte-for-byte as they were."""

from __future__ import annotations

import math
import re
import sys
import tempfile
from pathlib import Path

from hypothesis import event, given
from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.fc_sil.flight_core import FlightCore
from silbridge.fc_sil.param_store import CoreParamStore
from silbridge.mavlink.errors import ParamFileError
from silbridge.mavlink.gcs.params_file import apply_parm, format_parm, load_parm, store_entries

from fuzz_mutate import perturbed

_STORE = CoreParamStore(FlightCore())
_FULL = format_parm(store_entries(_STORE))
# What users hand us: the full set as we save it, a short tuning file with comments and
# commas (Mission Planner), and tab-separated lines (MAVProxy).
_SHORT = ("# tuning after the first flight\nATC_RAT_RLL_P,0.15\nATC_RAT_PIT_P,0.15\n"
          "DISARM_DELAY\t5\nATC_ANG_RLL_P 4.5   # roll angle\n")
VALID = (_FULL, _SHORT, "\n".join(_FULL.splitlines()[:20]))
_DIR = Path(tempfile.mkdtemp(prefix="silbridge-fuzz-parm-"))


def _check_error(exc: ParamFileError, path: Path) -> None:
    assert getattr(exc, "user_facing", False)
    msg = str(exc)
    assert re.match(re.escape(str(path)) + r":\d+: ", msg), msg


@given(perturbed(VALID, tokens=("ATC_RAT_RLL_P", "NOT_A_PARAM", "A" * 17, "SYSID_THISMAV")))
def test_a_perturbed_parm_file_loads_or_names_file_and_line(data: bytes):
    path = _DIR / "vehicle.parm"
    path.write_bytes(data)
    try:
        entries = load_parm(path)
    except ParamFileError as exc:
        _check_error(exc, path)
        event("refused")
        return
    event("loaded")
    for name, value in entries:
        assert isinstance(name, str) and 0 < len(name) <= 16
        assert isinstance(value, float)
    # Applying never raises: refused entries (unknown names, out of range, NaN) come back
    # as messages and the store keeps only finite values.
    store = CoreParamStore(FlightCore())
    apply_parm(store, entries)
    for name in store.names():
        assert math.isfinite(store.get(name)[0]), name


_RELOAD = _DIR / "reload.parm"
_SERVER = None


def _server():
    """One GcsServer (never started: no thread, no traffic) whose PREFLIGHT_STORAGE "read"
    reloads _RELOAD into the real parameter store, as a ground station's "load" does."""
    global _SERVER
    if _SERVER is None:
        sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "mavlink"))
        from mavtest_vehicle import KinematicVehicle
        from silbridge.mavlink.gcs.server import GcsServer
        _SERVER = GcsServer(KinematicVehicle(), CoreParamStore(FlightCore()),
                            ["udpin:127.0.0.1:0"], param_file=str(_RELOAD))
    return _SERVER


@given(perturbed(VALID))
def test_a_bad_parm_on_reload_leaves_store_and_file_unchanged(data: bytes):
    server = _server()
    _RELOAD.write_bytes(data)
    before = format_parm(store_entries(server.params)).encode()
    answer = server.storage(0)                  # MAV_CMD_PREFLIGHT_STORAGE, param1 = 0: read
    if answer.result != mav.MAV_RESULT_ACCEPTED:
        assert answer.result == mav.MAV_RESULT_FAILED
        assert re.match(re.escape(str(_RELOAD)) + r":\d+: ", answer.reason), answer.reason
        assert format_parm(store_entries(server.params)).encode() == before
    assert _RELOAD.read_bytes() == data         # a reload never writes the file
