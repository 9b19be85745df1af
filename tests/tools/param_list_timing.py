"""Time PARAM_REQUEST_LIST against parameter-table size, in one run (figures, not a test):

    flock /work/heavy.lock .venv/bin/python tests/tools/param_list_timing.py [--json]

Tables served by the real GcsServer (the test vehicle behind it): the parameters declared
before the ground-station block (index < 1000: the table before issue 12), every declared
parameter now, and 1,000 (padded with numbered fillers, ArduCopter's scale). Each is downloaded
by a pymavlink client over loopback UDP, REPEAT times; the median is reported, with the .parm
save and load times of the same table.
"""

from __future__ import annotations

import json
import os
import statistics
import sys
import tempfile
import time

from pymavlink.dialects.v20 import ardupilotmega as mav

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "mavlink"))

from mavtest_client import GcsClient  # noqa: E402
from mavtest_vehicle import DeclaredParamStore, KinematicVehicle, ParamDecl  # noqa: E402
from test_param_scale import _decls  # noqa: E402

from silbridge.fc_sil import params as P  # noqa: E402
from silbridge.mavlink.gcs.params_file import apply_parm, load_parm, save_store  # noqa: E402
from silbridge.mavlink.gcs.server import GcsServer  # noqa: E402

REPEAT = 5


def _download(decls) -> tuple[float, float, float]:
    store = DeclaredParamStore(decls)
    vehicle = KinematicVehicle()
    server = GcsServer(vehicle, store, ["udpin:127.0.0.1:0"])
    vehicle.run_loop(server)
    server.start()
    c = GcsClient(next(iter(server.local_addresses().values())))
    times = []
    try:
        c.send(c.mav.heartbeat_encode(6, 8, 0, 0, 0, 3))
        for _ in range(REPEAT):
            c.drain()
            t0 = time.monotonic()
            c.send(mav.MAVLink_param_request_list_message(1, 1))
            got = set()
            while len(got) < len(decls) and time.monotonic() - t0 < 60:
                got.update(m.param_index for m in c.pump(0.1) if m.get_type() == "PARAM_VALUE")
            assert len(got) == len(decls), f"{len(got)} of {len(decls)}"
            times.append(time.monotonic() - t0)
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "t.parm")
            t0 = time.monotonic()
            save_store(path, store)
            t_save = time.monotonic() - t0
            t0 = time.monotonic()
            assert not apply_parm(DeclaredParamStore(decls), load_parm(path))
            t_load = time.monotonic() - t0
    finally:
        c.close()
        server.stop()
        vehicle.stop()
    return statistics.median(times), t_save, t_load


def main() -> None:
    decl = [ParamDecl(p.name, p.mav_type, p.default, p.min, p.max) for p in P.PARAMS]
    tables = {"before (index < 1000)": [d for p, d in zip(P.PARAMS, decl) if p.index < 1000],
              "now (all declared)": decl, "1000 (padded)": _decls()}
    rows = []
    for label, decls in tables.items():
        dl, sv, ld = _download(decls)
        rows.append({"table": label, "params": len(decls), "list_s": round(dl, 3),
                     "parm_save_ms": round(sv * 1e3, 1), "parm_load_ms": round(ld * 1e3, 1)})
    if "--json" in sys.argv:
        print(json.dumps({"repeat": REPEAT, "rows": rows}))
        return
    for r in rows:
        print(f"{r['table']:<24}{r['params']:>6} params  PARAM_REQUEST_LIST {r['list_s']:.3f} s"
              f"  .parm save {r['parm_save_ms']:.1f} ms  load {r['parm_load_ms']:.1f} ms")


if __name__ == "__main__":
    main()
