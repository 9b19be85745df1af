"""Build a MAVLink-served Vehicle: parameter store, .parm file, mission file, GcsServer.

``start_mavlink_vehicle(core, MavlinkOptions(...))`` is what `silbridge fc`, `fly --realtime`
and `sitl` call: parameters come from ``load_start_params`` (the declaration defaults, then
the `--params` file, then `--param NAME=VALUE` overrides; the scripted, non-MAVLink FC loads
them the same way); the server opens every endpoint at once (a busy port fails here, with a
clear message) and serves on its own thread; the vehicle is returned ready to be the FcLoop's
supervisor. Call ``vehicle_close(vehicle)`` at the end (writes pending parameter changes,
closes sockets).

The `--params` file is read-only: PARAM_SET changes are written back to it only with
``save_params`` (`--save-params`), which also creates a missing file at start. A mistyped
path must never turn into a new file, nor a tuned file into the GCS's scratch pad.
"""

from __future__ import annotations

import logging
import os
import sys
from dataclasses import dataclass, field

from .errors import ParamError
from .param_store import CoreParamStore
from .vehicle import Vehicle

log = logging.getLogger(__name__)


class VehicleSetupError(Exception):
    user_facing = True


@dataclass
class MavlinkOptions:
    endpoints: list = field(default_factory=list)   # mavlink.endpoints.Endpoint or URL strings
    param_file: str | None = None                   # --params FILE (.parm, read at start)
    save_params: bool = False                       # --save-params: PARAM_SETs saved to it
    mission_file: str | None = None                 # --mission FILE (QGC WPL 110; fence and
                                                    # rally in FILE.fence / FILE.rally)
    serve: bool = True                              # False: the vehicle without a server
    tlog: str | None = None                         # --tlog FILE: the GCS traffic (mavlink/gcs/tlog.py)


def load_start_params(core, param_file: str | None, overrides: dict | None = None, *,
                      create: bool = False) -> tuple[CoreParamStore, list[str]]:
    """Apply the --params file, then the --param overrides, to core; return the store and
    one message per file entry it refused. A missing file is an error unless create is set
    (--save-params): then the full parameter set is written there now, and said on stderr."""
    from silbridge.mavlink.errors import ParamFileError
    from silbridge.mavlink.gcs.params_file import apply_parm, load_parm, save_store

    store = CoreParamStore(core)
    problems: list[str] = []
    created = False
    if param_file and not os.path.exists(param_file):
        if not create:
            raise VehicleSetupError(f"--params {param_file}: no such file; check the path "
                                    f"(with --save-params a missing file is created)")
        created = True
    elif param_file:
        try:
            problems += apply_parm(store, load_parm(param_file))
        except ParamFileError as exc:
            raise VehicleSetupError(str(exc)) from None
    for name, value in (overrides or {}).items():
        err = store.set(name, value)
        if err:
            raise ParamError(f"--param {name}={value:g}: {err}")
    store.apply()
    if created:
        try:
            save_store(param_file, store)
        except ParamFileError as exc:
            raise VehicleSetupError(str(exc)) from None
        print(f"silbridge: created {param_file} with the full parameter set "
              f"(--save-params writes PARAM_SET changes there)", file=sys.stderr)
    return store, problems


def _mission_result(code: int) -> str:
    """MAV_MISSION_INVALID_PARAM1 and the like, for an error message."""
    from pymavlink.dialects.v20 import ardupilotmega as mav
    entry = mav.enums["MAV_MISSION_RESULT"].get(code)
    return entry.name if entry is not None else f"MAV_MISSION_RESULT {code}"


def start_mavlink_vehicle(core, opts: MavlinkOptions, *, overrides: dict | None = None,
                          sink=None, out=None) -> Vehicle:
    from silbridge.mavlink.errors import MissionFileError
    from silbridge.mavlink.gcs.mission_store import MissionStore, check_mission, home_item
    from silbridge.mavlink.gcs.server import GcsServer
    from silbridge.mavlink.gcs.geo_store import GeoStore, check_list
    from silbridge.mavlink.gcs.wpl import geo_file, item_line, load_wpl

    store, problems = load_start_params(core, opts.param_file, overrides,
                                        create=opts.save_params)
    missions = MissionStore()
    if opts.mission_file and os.path.exists(opts.mission_file):
        try:
            items = load_wpl(opts.mission_file)
        except MissionFileError as exc:
            raise VehicleSetupError(str(exc)) from None
        if items and missions.replace(items) != 0:
            result, bad = check_mission(items)
            if bad < 0:      # every item is fine: there are too many
                raise VehicleSetupError(f"{opts.mission_file}: {len(items)} items, more than "
                                        f"the {missions.capacity} a mission holds; shorten it")
            raise VehicleSetupError(f"{opts.mission_file}:{item_line(opts.mission_file, bad)}: "
                                    f"item {bad} refused ({_mission_result(result)}); fix the "
                                    f"file or remove --mission")
    geo = {t: GeoStore(t) for t in (1, 2)}     # MAV_MISSION_TYPE_FENCE, _RALLY
    for t, gs in geo.items():
        path = geo_file(opts.mission_file, t) if opts.mission_file else None
        if path and os.path.exists(path):
            try:
                items = load_wpl(path)
            except MissionFileError as exc:
                raise VehicleSetupError(str(exc)) from None
            if gs.replace(items) != 0:
                result, bad = check_list(t, items)    # bad is -1 for too many items
                where = f"{path}:{item_line(path, bad)}: item {bad}" if bad >= 0 else path
                raise VehicleSetupError(f"{where}: not a valid {gs.what.lower()} list "
                                        f"({_mission_result(result)}; see docs: fence polygons "
                                        f"need all their vertices); fix or remove the file")
    vehicle = Vehicle(core, store, sink=sink, mission_file=opts.mission_file)
    vehicle.fence.set_items(geo[1].items())
    vehicle.rally.set_items(geo[2].items())
    if geo[2].count():
        store.set("RALLY_TOTAL", float(geo[2].count()))
    vehicle.mission.set_items(missions.items() if missions.count() > 1 else (home_item(),),
                              vehicle)
    for p in problems:
        log.warning("parameter file: %s", p)
        if out is not None:
            out(f"parameter file: {p}")
    if opts.serve:
        sysid = int(store.get("SYSID_THISMAV")[0])
        tlog = None
        if opts.tlog:       # opened first: a bad path fails before any socket is open
            from silbridge.mavlink.gcs.tlog import TlogWriter
            tlog = TlogWriter(opts.tlog)
        try:
            server = GcsServer(vehicle, store, opts.endpoints or None, sysid=sysid, compid=1,
                               param_file=opts.param_file, save_params=opts.save_params,
                               missions=missions, fence=geo[1], rally=geo[2])
        except Exception:
            if tlog is not None:
                tlog.close()
            raise
        server.tlog = tlog
        vehicle.attach_server(server)
        server.start()
        for p in problems[:10]:
            server.send_statustext(4, p[:150])
    return vehicle


def vehicle_close(vehicle: Vehicle) -> None:
    if vehicle.server is not None:
        vehicle.server.stop()
