"""`silbridge sitl`: a vehicle QGroundControl sees, as sim_vehicle.py gives one (issue 22:
`silbridge fly` is lockstep without MAVLink, so a GCS saw nothing and nothing said why).

The default ports (14550, 14540, and 9002 for `bridge --fc ardupilot`) are fixed, so these
tests run in a private network namespace (`unshare -n`) where nothing else listens.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import textwrap

import pytest

from silbridge.tools.cli.cmd_fly import NO_MAVLINK_HINT

SB = [sys.executable, "-m", "silbridge.tools"]


def _netns_ok() -> bool:
    if shutil.which("unshare") is None:
        return False
    p = subprocess.run(["unshare", "-n", "sh", "-c", "ip link set lo up"],
                       capture_output=True, timeout=30)
    return p.returncode == 0


needs_netns = pytest.mark.skipif(not _netns_ok(),
                                 reason="needs `unshare -n` (a private network namespace)")


def _in_netns(script: str, timeout_s: float = 180.0) -> dict:
    """Run a Python script with loopback up in a fresh network namespace; its last line is
    a JSON object."""
    p = subprocess.run(["unshare", "-n", "sh", "-c",
                        f"ip link set lo up && exec {sys.executable} -c \"$0\"", script],
                       capture_output=True, text=True, timeout=timeout_s)
    assert p.returncode == 0, p.stdout[-2000:] + p.stderr[-3000:]
    return json.loads(p.stdout.strip().splitlines()[-1])


# Starts `silbridge sitl` with the given arguments, listens where the vehicle sends, and
# reports the first HEARTBEAT per port and how sitl ended after Ctrl-C.
_SITL_DRIVER = textwrap.dedent("""
    import json, select, signal, socket, subprocess, sys, time
    from pymavlink.dialects.v20 import ardupilotmega as mav
    ports = {ports!r}
    socks = {{}}
    for port in ports:
        s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        s.bind(("127.0.0.1", port))
        socks[s] = (port, mav.MAVLink(None))
    proc = subprocess.Popen({cmd!r}, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    seen = {{}}
    end = time.monotonic() + 120
    while time.monotonic() < end and proc.poll() is None and len(seen) < {want}:
        for s in select.select(list(socks), [], [], 0.5)[0]:
            port, codec = socks[s]
            for m in codec.parse_buffer(s.recv(65535)) or []:
                if m.get_type() == "HEARTBEAT" and port not in seen:
                    seen[port] = {{"autopilot": m.autopilot, "type": m.type,
                                  "sysid": m.get_srcSystem()}}
    # anything that reached the other ports meanwhile
    for s in select.select(list(socks), [], [], 1.0)[0]:
        seen.setdefault(socks[s][0], {{"other": True}})
    if proc.poll() is None:
        proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=60)
    print(json.dumps({{"seen": seen, "rc": proc.returncode, "out": out[-2000:],
                      "err": err[-3000:]}}))
""")


def _sitl(args, ports, want) -> dict:
    cmd = SB + ["sitl", *args]
    return _in_netns(_SITL_DRIVER.format(ports=ports, cmd=cmd, want=want))


@needs_netns
def test_sitl_serves_an_arducopter_like_vehicle_on_14550_and_14540():
    r = _sitl(["--speed", "2"], [14550, 14540], want=2)
    for port in (14550, 14540):
        hb = r["seen"].get(str(port))
        assert hb is not None, r["err"]
        assert hb["autopilot"] == 3 and hb["type"] == 2, hb   # ARDUPILOTMEGA, QUADROTOR
    assert r["rc"] == 130, r["err"]          # Ctrl-C is how a session ends
    assert "INTERRUPTED by SIGINT" in r["out"]


@needs_netns
def test_instance_moves_the_ports():
    """-I 1: QGroundControl's port 14550 + 10 (sim_vehicle.py), MAVSDK's 14540 + 1 (PX4 -i);
    nothing reaches instance 0's ports."""
    r = _sitl(["-I", "1", "--speed", "2", "--processes", "1"],
              [14550, 14540, 14560, 14541], want=2)
    assert set(r["seen"]) == {"14560", "14541"}, r
    assert r["seen"]["14560"]["autopilot"] == 3, r


@needs_netns
def test_ardupilot_bridge_instance_moves_the_json_port_by_ten():
    script = textwrap.dedent(f"""
        import json, signal, subprocess
        p = subprocess.Popen({SB + ["bridge", "--fc", "ardupilot", "-I", "1"]!r},
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        line = ""
        for line in p.stdout:
            if "JSON physics on udp" in line:
                break
        p.send_signal(signal.SIGINT)
        p.communicate(timeout=60)
        print(json.dumps({{"line": line}}))
    """)
    assert "udp 127.0.0.1:9012;" in _in_netns(script)["line"]


def test_fly_says_once_that_lockstep_serves_no_mavlink():
    p = subprocess.run(SB + ["fly", "--processes", "1", "--duration", "0.5"],
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    assert p.stderr.count(NO_MAVLINK_HINT) == 1
    q = subprocess.run(SB + ["fly", "--processes", "1", "--duration", "0.5", "--no-mavlink"],
                       capture_output=True, text=True, timeout=120)
    assert q.returncode == 0 and NO_MAVLINK_HINT not in q.stderr
