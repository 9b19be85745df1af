"""Parameters at ArduCopter's scale: a 1,000-parameter table (the declared ones plus numbered
fillers) served by the real GcsServer. pymavlink's PARAM_REQUEST_LIST gets every index once
with the right count, MAVProxy's parameter fetch finishes, and a .parm file of all of them
saves and loads back bit for bit. Times are printed (-s), bounded only generously."""

from __future__ import annotations

import os
import sys
import time

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mav

HERE = os.path.dirname(__file__)
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "mavlink"))

from mavtest_client import GcsClient  # noqa: E402
from mavtest_vehicle import DeclaredParamStore, KinematicVehicle, ParamDecl  # noqa: E402
from sitl_helpers import free_udp_port  # noqa: E402

from silbridge.fc_sil import params as P  # noqa: E402
from silbridge.mavlink.gcs.params_file import apply_parm, load_parm, save_store  # noqa: E402
from silbridge.mavlink.gcs.server import GcsServer  # noqa: E402

N = 1000


def _decls():
    out = [ParamDecl(p.name, p.mav_type, p.default, p.min, p.max) for p in P.PARAMS]
    types = (mav.MAV_PARAM_TYPE_REAL32, mav.MAV_PARAM_TYPE_INT8, mav.MAV_PARAM_TYPE_INT16,
             mav.MAV_PARAM_TYPE_INT32)
    for i in range(N - len(out)):
        t = types[i % 4]
        out.append(ParamDecl(f"SCALE_TEST_{i:04d}", t,
                             (i * 0.37) if t == mav.MAV_PARAM_TYPE_REAL32 else i % 100,
                             -1e6, 1e6))
    return out


@pytest.fixture
def server_at():
    made = []

    def make(endpoint):
        store = DeclaredParamStore(_decls())
        vehicle = KinematicVehicle()
        server = GcsServer(vehicle, store, [endpoint])
        vehicle.run_loop(server)
        server.start()
        made.append((server, vehicle))
        return server, store
    yield make
    for server, vehicle in made:
        server.stop()
        vehicle.stop()


def test_param_request_list_of_1000_parameters(server_at):
    server, store = server_at("udpin:127.0.0.1:0")
    c = GcsClient(next(iter(server.local_addresses().values())))
    try:
        c.send(c.mav.heartbeat_encode(6, 8, 0, 0, 0, 3))
        t0 = time.monotonic()
        c.send(mav.MAVLink_param_request_list_message(1, 1))
        got: dict = {}
        while len(got) < N and time.monotonic() - t0 < 60:
            for m in c.pump(0.1):
                if m.get_type() == "PARAM_VALUE":
                    assert m.param_count == N
                    assert m.param_index not in got, "an index sent twice"
                    got[m.param_index] = m.param_id
        secs = time.monotonic() - t0
        print(f"\nPARAM_REQUEST_LIST: {len(got)} parameters in {secs:.2f} s")
        assert [got.get(i) for i in range(N)] == list(store.names())
        assert secs < 30.0
    finally:
        c.close()


def test_parm_file_of_1000_parameters_round_trips(server_at, tmp_path):
    _, store = server_at("udpin:127.0.0.1:0")
    for i, name in enumerate(store.names()):
        if name.startswith("SCALE_TEST_"):
            real = store.get(name)[1] == mav.MAV_PARAM_TYPE_REAL32
            assert store.set(name, (i + 0.125) if real else i % 120) is None
    path = tmp_path / "big.parm"
    t0 = time.monotonic()
    save_store(path, store)
    t_save = time.monotonic() - t0
    fresh = DeclaredParamStore(_decls())
    t0 = time.monotonic()
    problems = apply_parm(fresh, load_parm(path))
    t_load = time.monotonic() - t0
    print(f"\n.parm: {N} parameters saved in {t_save * 1e3:.1f} ms, loaded in "
          f"{t_load * 1e3:.1f} ms")
    assert not problems
    assert all(fresh.get(n) == store.get(n) for n in store.names())
    assert len(path.read_text().splitlines()) == N


def test_mavproxy_fetches_1000_parameters(server_at, tmp_path):
    from test_mavlink_mavproxy import MAVPROXY, MavProxy
    if not os.path.exists(MAVPROXY):
        pytest.skip("MAVProxy not installed")
    port = free_udp_port()
    t0 = time.monotonic()
    mp = MavProxy(port, str(tmp_path))
    try:
        server_at(f"udpout:127.0.0.1:{port}")
        mp.expect(rf"Received {N} parameters", 90.0)
        print(f"\nMAVProxy: {N} parameters received {time.monotonic() - t0:.1f} s after start")
        last = _decls()[-1].name                       # the 1000th parameter
        mp.send(f"param show {last}")
        mp.expect(rf"{last}\s+\d", 10.0)
    finally:
        mp.close()
