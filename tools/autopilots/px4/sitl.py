"""PX4 SITL as a subprocess: find it, pick a free instance, start it on our vehicle, stop it.

    binary, etc = find_px4(args.px4)            # --px4, $SILBRIDGE_PX4, `px4` on PATH
    n = pick_instance()                          # ports 4560+N, 14540+N, 14580+N, 18570+N free
    proc = start_px4(binary, etc, n, workdir, params=px4_params(sim, sc))
    ...; stop_px4(proc)                          # SIGINT, then SIGKILL after a few seconds

Instance N (`px4 -i N`): connects to the simulator on TCP 4560+N, MAV_SYS_ID N+1, its
offboard/API link listens on UDP 14580+N and sends to 127.0.0.1:14540+N, its GCS link on
18570+N sends to 14550 (QGroundControl), and it holds /tmp/px4_lock-N and /tmp/px4-sock-N.
A lock or socket left by a killed px4 is removed when no process holds it (a lock file that
another running px4 holds is never touched: that instance is not free).

Parameters: PX4's startup script sources `px4-rc.params` from PATH after the airframe's
defaults ("user defined params for instances"), so each run writes one in its working
directory and puts that directory first on PX4's PATH: PX4 boots with our vehicle's
geometry, thrust curve and hover thrust, and no RC/datalink failsafe in a headless run.
"""

from __future__ import annotations

import fcntl
import os
import signal
import socket
import subprocess

from silbridge.bridge.atmosphere import G0, R_AIR, isa_pressure_pa, isa_temperature_k
from silbridge.tools.autopilots.common.process import (STOP_GRACE_S, Autopilot, find_binary,
                                                       port_free, require_binary, spawn,
                                                       stop_process)

ENV_BINARY = "SILBRIDGE_PX4"
AIRFRAME = 10016                 # none_iris: a quad X driven by simulator_mavlink on 4560 + N
SIM_TCP_BASE = 4560
OFFBOARD_LOCAL_BASE = 14580      # PX4 listens here (API/offboard link, 'onboard' mode)
OFFBOARD_REMOTE_BASE = 14540     # ... and sends here: our driver binds it
GCS_LOCAL_BASE = 18570
ROTOR_XY_M = 0.1591             # |x| = |y| of each rotor hub (jsbsim_models/quadx/quadx.xml)
MAX_INSTANCE = 9                 # above 9 PX4 sends every offboard link to 14549
PX4_LOG = "px4.log"              # PX4's console output, in its working directory

HOW_TO_GET = (
    "no PX4 SITL binary: give --px4 PATH, set SILBRIDGE_PX4, or put `px4` on PATH. Build it "
    "(PX4 v1.15.4): git clone --recursive -b v1.15.4 "
    "https://github.com/PX4/PX4-Autopilot && cd PX4-Autopilot && "
    "bash Tools/setup/ubuntu.sh --no-nuttx --no-sim-tools && make px4_sitl_default  "
    "(binary: build/px4_sitl_default/bin/px4, etc/ beside it); see "
    "docs/tutorials/arducopter-and-px4.md")


class Px4Error(Exception):
    user_facing = True


def find_px4(explicit: str | None = None) -> tuple[str, str] | None:
    """(px4 binary, its etc/ folder) or None: --px4, then $SILBRIDGE_PX4, then PATH."""
    found = find_binary(PX4, explicit)
    return (found, _etc_for(found)) if found else None


def require_px4(explicit: str | None = None) -> tuple[str, str]:
    """find_px4, or Px4Error saying how to build one: for the commands that fly it."""
    binary = require_binary(PX4, explicit)
    return binary, _etc_for(binary)


def _etc_for(binary: str) -> str:
    etc = os.path.join(os.path.dirname(os.path.dirname(binary)), "etc")
    if not os.path.isfile(os.path.join(etc, "init.d-posix", "rcS")):
        raise Px4Error(f"no PX4 startup scripts at {etc}/init.d-posix/rcS: keep bin/ and etc/ "
                       "of the PX4 build together (build/px4_sitl_default/{bin,etc})")
    return etc


def _lock_free(n: int) -> bool:
    """/tmp/px4_lock-N held by no process (a stale one is removed with its socket)."""
    path = f"/tmp/px4_lock-{n}"
    if not os.path.exists(path):
        _remove(f"/tmp/px4-sock-{n}")
        return True
    try:
        fd = os.open(path, os.O_RDWR)
    except OSError:
        return False
    try:
        fcntl.lockf(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        return False                 # a running px4 holds it
    finally:
        os.close(fd)
    _remove(path)
    _remove(f"/tmp/px4-sock-{n}")
    return True


def _remove(path: str) -> None:
    try:
        os.unlink(path)
    except OSError:
        pass


def instance_free(n: int) -> bool:
    udp = (OFFBOARD_LOCAL_BASE + n, OFFBOARD_REMOTE_BASE + n, GCS_LOCAL_BASE + n,
           14280 + n, 13030 + n)
    return (port_free(socket.SOCK_STREAM, SIM_TCP_BASE + n)
            and all(port_free(socket.SOCK_DGRAM, p) for p in udp) and _lock_free(n))


_claims: dict[int, int] = {}


def _claim(n: int) -> bool:
    """Hold /tmp/silbridge-px4-N.claim locked for this run: parallel runs never pick the same
    instance between checking its ports and PX4 binding them."""
    fd = os.open(f"/tmp/silbridge-px4-{n}.claim", os.O_RDWR | os.O_CREAT, 0o666)
    try:
        fcntl.lockf(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        os.close(fd)
        return False
    _claims[n] = fd
    return True


def release_instance(n: int) -> None:
    fd = _claims.pop(n, None)
    if fd is not None:
        os.close(fd)


def pick_instance(start: int | None = None) -> int:
    """A free PX4 instance number in 1..9 (0 is left to a PX4 the user runs by hand),
    claimed until release_instance(n)."""
    first = (os.getpid() % MAX_INSTANCE) if start is None else start - 1
    for i in range(MAX_INSTANCE):
        n = (first + i) % MAX_INSTANCE + 1
        if n not in _claims and _claim(n):
            if instance_free(n):
                return n
            release_instance(n)
    raise Px4Error("no free PX4 instance (1..9: TCP 4560+N, UDP 14540+N/14580+N/18570+N and "
                   "/tmp/px4_lock-N all free): stop stale px4 processes")


def px4_params(sim, scenario, *, logging: bool = False, overrides: dict | None = None) -> dict:
    """PX4 parameters matching our vehicle and a headless, offboard-driven flight."""
    arm = ROTOR_XY_M
    expo = sim.fdm.model_constant("quadx/thrust-expo")
    p = {
        # Our square X (jsbsim_models/quadx: rotors at +-0.1591 m), PX4's rotor order.
        "CA_ROTOR0_PX": arm, "CA_ROTOR0_PY": arm, "CA_ROTOR0_KM": 0.05,
        "CA_ROTOR1_PX": -arm, "CA_ROTOR1_PY": -arm, "CA_ROTOR1_KM": 0.05,
        "CA_ROTOR2_PX": arm, "CA_ROTOR2_PY": -arm, "CA_ROTOR2_KM": -0.05,
        "CA_ROTOR3_PX": -arm, "CA_ROTOR3_PY": arm, "CA_ROTOR3_KM": -0.05,
        "THR_MDL_FAC": round(float(expo), 4),          # same thrust curve as MOT_THST_EXPO
        "MPC_THR_HOVER": round(min(max(1.0 / sim.thrust_to_weight, 0.1), 0.8), 4),
        "MIS_TAKEOFF_ALT": float(scenario.takeoff_alt_m),
        "EKF2_GPS_DELAY": round(scenario.gnss.latency_s * 1000.0, 1),
        "COM_RC_IN_MODE": 4,        # no RC: a companion computer flies it
        "NAV_RCL_ACT": 0, "NAV_DLL_ACT": 0, "COM_RCL_EXCEPT": 4,
        "COM_ARM_WO_GPS": 0,
        # Our GNSS error is a Gauss-Markov walk (sigma 2.1 m / 3.2 m, tau 60 s): its
        # short-term drift exceeds PX4's defaults (0.1 / 0.2 m/s) for a receiver at rest,
        # so the pre-flight drift checks use their widest settings.
        "EKF2_REQ_HDRIFT": 1.0, "EKF2_REQ_VDRIFT": 1.5,
        # Height from the barometer (1.2 Pa noise, ~0.1 m), not GNSS (3.2 m Gauss-Markov):
        # the altitude PX4 reports is what the companion computer holds.
        "EKF2_HGT_REF": 0,
        # ... weighted as the baro it gets. PX4's default (3.5 m) is for a real baro in
        # propwash; against that the EKF's height follows the IMU's vertical dead reckoning,
        # and our accelerometer's bias walk and warm-up drift pulled it 0.3-0.8 m off the
        # truth within two minutes of hover (issue 13).
        "EKF2_BARO_NOISE": baro_noise_m(scenario),
        # Our baro has no propwash ground effect: PX4 must not discard the readings that
        # say "higher" while it believes it is in ground effect (default dead zone 4 m),
        # or its height lags the climb out of ground effect.
        "EKF2_GND_EFF_DZ": 0.0,
        "EKF2_GPS_CTRL": 5,         # GNSS horizontal position and velocity, not its altitude
        "SDLOG_MODE": 1 if logging else -1,
    }
    p.update(overrides or {})
    return p


def baro_noise_m(scenario) -> float:
    """The scenario's baro white noise as height [m] at home (ISA: dh/dp = R T / (g p)),
    not below PX4's minimum for EKF2_BARO_NOISE (0.01 m)."""
    alt = scenario.home.alt_m
    m_per_pa = R_AIR * isa_temperature_k(alt) / (G0 * isa_pressure_pa(alt))
    return round(max(0.01, scenario.baro.noise_pa * m_per_pa), 3)


def write_params(workdir: str, params: dict) -> str:
    path = os.path.join(workdir, "px4-rc.params")
    with open(path, "w") as fh:
        fh.write("#!/bin/sh\n# written by silbridge: our vehicle's parameters\n")
        for name, value in params.items():
            fh.write(f"param set {name} {value:g}\n" if isinstance(value, float)
                     else f"param set {name} {value}\n")
    return path


def write_mavlink_rc(workdir: str, gcs: bool = False) -> str:
    """px4-rc.mavlink for a headless run: the offboard/API link only, in PX4's 'minimal' mode
    (heartbeat, acks, status text; the driver asks for the streams it reads), instead of
    PX4's four links streaming at up to 50 Hz each to nobody. gcs=True adds the GCS link on
    18570 + N -> 14550 for QGroundControl."""
    path = os.path.join(workdir, "px4-rc.mavlink")
    with open(path, "w") as fh:
        fh.write("#!/bin/sh\n# written by silbridge: the MAVLink links of a headless run\n"
                 f"mavlink start -x -u $(({OFFBOARD_LOCAL_BASE}+px4_instance)) -r 4000000 -f "
                 f"-m minimal -o $(({OFFBOARD_REMOTE_BASE}+px4_instance))\n")
        if gcs:
            fh.write(f"mavlink start -x -u $(({GCS_LOCAL_BASE}+px4_instance)) -r 4000000 -f\n")
    return path


def start_px4(binary: str, etc: str, instance: int, workdir: str, *, params: dict,
              speed_factor: float | None = None, autostart: int = AIRFRAME,
              extra_env: dict | None = None, headless: bool = True) -> subprocess.Popen:
    """px4 -d -i N -w workdir etc, console to workdir/px4.log; our px4-rc.params (and, when
    headless, px4-rc.mavlink) first on PATH."""
    write_params(workdir, params)
    if headless:
        write_mavlink_rc(workdir)
    exe = command_links(binary, workdir)
    env = dict(os.environ)
    env["PATH"] = os.pathsep.join((workdir, os.path.dirname(exe), env.get("PATH", "")))
    env["PX4_SYS_AUTOSTART"] = str(autostart)
    env.pop("PX4_SIM_MODEL", None)
    if speed_factor is not None:
        env["PX4_SIM_SPEED_FACTOR"] = f"{speed_factor:g}"
    env.update(extra_env or {})
    # Its own session: a Ctrl-C reaches us, and we stop PX4 in order (stop_px4). If we die
    # without that, the kernel kills it (PR_SET_PDEATHSIG): no orphan PX4 holding its
    # instance.
    return spawn([exe, "-d", "-i", str(instance), "-w", workdir, etc], workdir, PX4_LOG,
                 env=env, start_new_session=True, preexec_fn=_die_with_parent)


def command_links(binary: str, workdir: str) -> str:
    """workdir/bin/px4 and its px4-<module> links, all to the binary; returns the px4 path.

    PX4's startup script runs its modules through `px4-<module>` commands (links to px4 that
    it finds on PATH beside itself). A copy of a build that flattened those links to plain
    files cannot run them, so each run gets its own links to the one binary."""
    bindir = os.path.join(workdir, "bin")
    os.makedirs(bindir, exist_ok=True)
    src_dir = os.path.dirname(binary)
    for name in ["px4"] + sorted(os.listdir(src_dir)):
        if not name.startswith("px4"):
            continue
        target = os.path.join(src_dir, name) if name.endswith(".sh") else binary
        link = os.path.join(bindir, name)
        if not os.path.lexists(link):
            os.symlink(target, link)
    return os.path.join(bindir, "px4")


def _die_with_parent() -> None:
    try:
        import ctypes
        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL)   # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass


def stop_px4(proc: subprocess.Popen, instance: int | None = None,
             grace_s: float = STOP_GRACE_S) -> None:
    """SIGINT (PX4 shuts down its modules), then SIGKILL; its lock and socket are released."""
    stop_process(proc, signal.SIGINT, grace_s)
    if instance is not None:
        _lock_free(instance)


PX4 = Autopilot(
    name="PX4", error=Px4Error, env=ENV_BINARY, command="px4", how_to_get=HOW_TO_GET,
    build_hint="`make px4_sitl_default` in a PX4-Autopilot checkout "
               "(build/px4_sitl_default/bin/px4; docs/tutorials/arducopter-and-px4.md)",
    log_name=PX4_LOG, pick=pick_instance, stop=stop_px4, release=release_instance)
