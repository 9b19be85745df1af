"""QGC WPL 110 files, perturbed: missions (`--mission FILE`), fences (FILE.fence) and rally
points (FILE.rally). Each loads, or fails with a MissionFileError naming the file and the
line; a list the store refuses leaves the stored one byte-for-byte as it was (compared as
the WPL text the vehicle would save)."""

from __future__ import annotations

import re
import tempfile
from pathlib import Path

from hypothesis import event, given
from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.mavlink.errors import MissionFileError
from silbridge.mavlink.gcs.geo_store import GeoStore
from silbridge.mavlink.gcs.mission_store import MissionStore
from silbridge.mavlink.gcs.vehicle_api import MissionItem
from silbridge.mavlink.gcs.wpl import format_wpl, load_wpl

from fuzz_mutate import perturbed

_REL = mav.MAV_FRAME_GLOBAL_RELATIVE_ALT
_LAT, _LON = -353632621, 1491652374      # ArduPilot's SITL home, degrees*1e7


def _item(seq, command, frame=_REL, dlat=0, dlon=0, z=0.0, p1=0.0, p2=0.0):
    return MissionItem(seq=seq, frame=frame, command=command, param1=p1, param2=p2,
                       x=_LAT + dlat, y=_LON + dlon, z=z)


MISSION = format_wpl([
    _item(0, mav.MAV_CMD_NAV_WAYPOINT, frame=mav.MAV_FRAME_GLOBAL, z=584.09),
    _item(1, mav.MAV_CMD_NAV_TAKEOFF, z=10.0),
    _item(2, mav.MAV_CMD_NAV_WAYPOINT, dlat=900, z=15.0),
    _item(3, mav.MAV_CMD_DO_CHANGE_SPEED, frame=mav.MAV_FRAME_MISSION, p2=3.0),
    _item(4, mav.MAV_CMD_NAV_LOITER_TIME, dlat=900, dlon=900, z=15.0, p1=5.0),
    _item(5, mav.MAV_CMD_NAV_RETURN_TO_LAUNCH, frame=mav.MAV_FRAME_MISSION),
])
_V = mav.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION
FENCE = format_wpl([
    _item(0, _V, p1=4, dlat=-2000, dlon=-2000), _item(1, _V, p1=4, dlat=2000, dlon=-2000),
    _item(2, _V, p1=4, dlat=2000, dlon=2000), _item(3, _V, p1=4, dlat=-2000, dlon=2000),
    _item(4, mav.MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION, p1=20.0, dlat=500),
])
RALLY = format_wpl([_item(0, mav.MAV_CMD_NAV_RALLY_POINT, dlat=300, z=20.0),
                    _item(1, mav.MAV_CMD_NAV_RALLY_POINT, dlon=-300, z=25.0)])
_TOKENS = ("QGC WPL 110", "QGC WPL 120", "16", "5001", "5100", "-35.3632621", "149.1652374",
           "91.0", "-181.0", "1e10")
_DIR = Path(tempfile.mkdtemp(prefix="silbridge-fuzz-wpl-"))


def _files(valid: str):
    return perturbed((valid,), _TOKENS, header_lines=1)     # the header kept in half of them


def _load(data: bytes, name: str):
    """The items, or None after checking the error names the file and the line."""
    path = _DIR / name
    path.write_bytes(data)
    try:
        items = load_wpl(path)
    except MissionFileError as exc:
        assert getattr(exc, "user_facing", False)
        assert re.match(re.escape(str(path)) + r":\d+: ", str(exc)), str(exc)
        event("refused")
        return None
    event("loaded")
    assert [it.seq for it in items] == list(range(len(items)))
    return items


def _keeps_or_replaces(store, items, valid_items) -> None:
    assert store.replace(valid_items) == 0
    before = format_wpl(store.items()).encode()
    if store.replace(items) != 0:
        assert format_wpl(store.items()).encode() == before


@given(_files(MISSION))
def test_a_perturbed_mission_loads_or_names_file_and_line(data: bytes):
    items = _load(data, "flight.waypoints")
    if items is not None:
        _keeps_or_replaces(MissionStore(), items, load_wpl_text(MISSION))


@given(_files(FENCE))
def test_a_perturbed_fence_loads_or_names_file_and_line(data: bytes):
    items = _load(data, "flight.waypoints.fence")
    if items is not None:
        _keeps_or_replaces(GeoStore(mav.MAV_MISSION_TYPE_FENCE), items, load_wpl_text(FENCE))


@given(_files(RALLY))
def test_a_perturbed_rally_file_loads_or_names_file_and_line(data: bytes):
    items = _load(data, "flight.waypoints.rally")
    if items is not None:
        _keeps_or_replaces(GeoStore(mav.MAV_MISSION_TYPE_RALLY), items, load_wpl_text(RALLY))


def load_wpl_text(text: str):
    from silbridge.mavlink.gcs.wpl import parse_wpl
    return parse_wpl(text, "<valid>")


@given(_files(MISSION), _files(FENCE), _files(RALLY))
def test_perturbed_files_at_vehicle_start_fly_or_name_file_and_line(mission, fence, rally):
    """`--mission FILE` with FILE.fence and FILE.rally beside it: the vehicle starts, or the
    error names the file and the line (the list's first refused item)."""
    from silbridge.fc_sil.flight_core import FlightCore
    from silbridge.fc_sil.vehicle_server import (MavlinkOptions, VehicleSetupError,
                                                 start_mavlink_vehicle)
    path = _DIR / "start.waypoints"
    path.write_bytes(mission)
    Path(f"{path}.fence").write_bytes(fence)
    Path(f"{path}.rally").write_bytes(rally)
    try:
        vehicle = start_mavlink_vehicle(FlightCore(), MavlinkOptions(mission_file=str(path),
                                                                      serve=False))
    except VehicleSetupError as exc:
        assert exc.user_facing
        names = "|".join(re.escape(f"{path}{s}") for s in (".fence", ".rally", ""))
        assert re.match(rf"({names}):\d+: |({names}): \d+ items, more than", str(exc)), str(exc)
        return
    assert vehicle.server is None
