"""Fixtures for the MAVLink server tests: a server on an ephemeral UDP port, the kinematic test
vehicle running its own loop thread, and a pymavlink GCS client talking to it."""

from __future__ import annotations

import os
import sys

import pytest

sys.path.insert(0, os.path.dirname(__file__))

from mavtest_client import GcsClient  # noqa: E402
from mavtest_vehicle import DeclaredParamStore, KinematicVehicle  # noqa: E402

from silbridge.mavlink.gcs.server import GcsServer, ServerTiming  # noqa: E402


class Env:
    def __init__(self, tmp_path, timing=None, param_file=None, endpoints=None):
        self.params = DeclaredParamStore()
        self.vehicle = KinematicVehicle()
        self.server = GcsServer(self.vehicle, self.params,
                                endpoints or ["udpin:127.0.0.1:0"], param_file=param_file,
                                timing=timing or ServerTiming(mission_item_resend_s=0.2,
                                                              mission_upload_timeout_s=0.8))
        self.vehicle.run_loop(self.server)
        self.server.start()
        addr = next(iter(self.server.local_addresses().values()))
        self.client = GcsClient(addr)
        self.tmp_path = tmp_path

    def new_client(self, **kw) -> GcsClient:
        addr = next(iter(self.server.local_addresses().values()))
        return GcsClient(addr, **kw)

    def close(self):
        self.client.close()
        self.server.stop()
        self.vehicle.stop()


@pytest.fixture
def env(tmp_path):
    e = Env(tmp_path)
    # the server learns our address from the first valid frame (udpin)
    e.client.send(e.client.mav.heartbeat_encode(6, 8, 0, 0, 0, 3))
    yield e
    e.close()


@pytest.fixture
def make_env(tmp_path):
    made = []

    def make(**kw):
        e = Env(tmp_path, **kw)
        e.client.send(e.client.mav.heartbeat_encode(6, 8, 0, 0, 0, 3))
        made.append(e)
        return e
    yield make
    for e in made:
        e.close()
