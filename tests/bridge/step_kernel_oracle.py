"""The bridge's per-step kernel in plain Python: the oracle of the C kernel (bridge/src/).

One physics step: write the four pulse widths into JSBSim, run it, read the FDM sample
back, and write the step's IMU (when one sample per step), GT_ATT and GT_NAV records into
the step buffer, then the baro and magnetometer records when due. The C kernel
(`silbridge.bridge._step.Kernel`: the CPython shim step_run.c around the pure-C sensor
stage sensor_stage.c) does the same in the same operation order and must write the same
bytes (tests/bridge/test_step_kernel.py). Production flies only the C kernel; this one is
here to be read and to check it. The functions below mirror sensor_stage.c's.

Interface shared by both (Simulator(..., kernel_cls=Kernel) selects this one):
    k = Kernel(buffer, setters, run, getters, state, consts, phase, dt_ns, flip_steps,
               scalar_imu, on_ground)
        getters: {name in _step.SAMPLE_FIELDS: callable}; consts: {name in
        _step.CONST_FIELDS: float} (bridge/src/sensor_stage.h names and documents both)
    flags = k.step(pwm)            # scalar IMU: IMU, GT_ATT, GT_NAV in slots 0, 1, 2
    flags = k.step_gt(pwm, slot)   # oversampled IMU (written by the caller): GT at slot
    k.set_block(block, temps)      # next IMU noise rows (rows, 6) and temperatures (rows)
    k.set_injected(x, y, z)        # injected gyro bias [rad/s]
    k.set_forces(plan)             # disturbance forces written before each run()
    k.configure_baro(rate_hz, offset_pa, noise_pa)                # sample the baro (100 Hz)
    k.configure_mag(rate_hz, field_ned, offset, noise_gauss)      # and the magnetometer
    k.set_baro_block(normals (rows, 1)); k.set_mag_block(normals (rows, 3))
    k.next_slow_ns                 # from this sim time, flags carry F_SLOW_DUE (GNSS, setpoints)
    k.configure_battery(torque=..., cells=..., ...)   # the pack the step runs (battery.h);
    k.write_battery(slot), k.battery_state(), ...     # battery_reference.py KernelPack
The low byte of flags is the number of records written; the state array receives the
values in the _step.ST_* slots. Without F_SLOW_DUE the last record carries STEP_END.
"""

from __future__ import annotations

import math

from battery_reference import KernelPack

from silbridge.bridge import _step as K
from silbridge.bridge.frames import ned_to_frd, quat_from_euler
from silbridge.bridge.lowrate import due_ns
from silbridge.mavlink.hil.hil_quant import pressure_pa
from silbridge.shm.records import FLAG_STEP_END, FLAGS_OFFSET, RECORD_SIZE, Kind, record_struct

_IMU = record_struct(Kind.IMU)
_GT_ATT = record_struct(Kind.GT_ATT)
_GT_NAV = record_struct(Kind.GT_NAV)
_BARO = record_struct(Kind.BARO)
_MAG = record_struct(Kind.MAG)

_TWO_PI = 2.0 * math.pi
# Rotor hubs in body FRD [m] (quadx.xml: 0.1591 m along x and y, 0.03 m above the CG).
ROTOR_HUBS_FRD_M = ((0.1591, 0.1591, -0.03), (-0.1591, -0.1591, -0.03),
                    (0.1591, -0.1591, -0.03), (-0.1591, 0.1591, -0.03))


def quat_from_euler_w_pos(phi: float, theta: float, psi: float) -> tuple:
    """ZYX Euler -> (w, x, y, z), body FRD -> NED, in the w >= 0 hemisphere (JSBSim's psi
    is in [0, 2 pi))."""
    q = quat_from_euler(phi, theta, psi)
    return (-q[0], -q[1], -q[2], -q[3]) if q[0] < 0.0 else q


def quant_down_m(d: float) -> float:
    """Whole mm (HIL_STATE_QUATERNION.alt); NaN and infinities pass through."""
    return d if d != d or math.isinf(d) else round(d * 1000.0) / 1000.0


def quant_velocity_m_s(v: float) -> float:
    """Whole cm/s within int16 (HIL_GPS, HIL_STATE_QUATERNION)."""
    if v != v:
        return v
    cm = v if math.isinf(v) else float(round(v * 100.0))
    return max(-32767.0, min(32767.0, cm)) / 100.0


def rotor_strike(phi: float, theta: float, hagl_m: float) -> bool:
    """True when a rotor hub is at or below flat ground."""
    sth, cth = math.sin(theta), math.cos(theta)
    sph_cth, cph_cth = math.sin(phi) * cth, math.cos(phi) * cth
    for x, y, z in ROTOR_HUBS_FRD_M:
        down_m = -sth * x + sph_cth * y + cph_cth * z   # NED down offset of the hub
        if hagl_m + (-down_m) <= 0.0:
            return True
    return False


def imu_scalar(c: dict, af, w, omega, phase: list, n, j) -> tuple:
    """One IMU sample (see bridge/imu.py for the model): accel xyz, gyro xyz."""
    dt = c["dt_s"]
    p = [math.fmod(phase[i] + omega[i] * dt, _TWO_PI) for i in range(4)]
    phase[:] = p
    va, vg = c["vib_accel"], c["vib_gyro"]
    vx = vy = vz = 0.0
    if va != 0.0 or vg != 0.0:
        k = c["inv_omega_max2"]
        s = [omega[i] * omega[i] * k for i in range(4)]
        co = [math.cos(x) for x in p]
        si = [math.sin(x) for x in p]
        vx = s[0] * co[0] + s[1] * co[1] + s[2] * co[2] + s[3] * co[3]
        vy = -s[0] * si[0] - s[1] * si[1] + s[2] * si[2] + s[3] * si[3]   # motors 1, 2 CCW
        vz = (s[0] * si[0] * co[0] + s[1] * si[1] * co[1] + s[2] * si[2] * co[2]
              + s[3] * si[3] * co[3])                                      # sin(2p) / 2
    out = [af[0] + va * vx + n[3], af[1] + va * vy + n[4], af[2] + va * vz + n[5],
           w[0] + j[0] + vg * vy + n[0], w[1] + j[1] + vg * vx + n[1],
           w[2] + j[2] + vg * vz + n[2]]
    ra, rg = c["range_accel"], c["range_gyro"]
    for i in range(3):   # clip at full scale (NaN passes, as in C)
        out[i] = -ra if out[i] < -ra else (ra if out[i] > ra else out[i])
        out[i + 3] = -rg if out[i + 3] < -rg else (rg if out[i + 3] > rg else out[i + 3])
    return tuple(out)


def to_truth(c: dict, s: dict, st) -> dict:
    """JSBSim's feet, pounds and geodetic angles to SI truth in NED/FRD (and the baro lag)."""
    lbf, ft = c["lbf_to_m_s2"], c["ft_m"]
    hagl_m = (s["geod_alt_ft"] - c["terrain_ft"]) * ft
    st[K.ST_BARO_PA] += c["baro_alpha"] * (s["pressure_psf"] * c["psf_pa"] - st[K.ST_BARO_PA])
    return {
        "w": (s["p_rad_s"], s["q_rad_s"], s["r_rad_s"]),
        "af": (s["fbx_lbf"] * lbf, s["fby_lbf"] * lbf, s["fbz_lbf"] * lbf),
        "vel": (s["vn_ft_s"] * ft, s["ve_ft_s"] * ft, s["vd_ft_s"] * ft),
        "hagl_m": hagl_m,
        "on_ground": s["gear_contacts"] > 0.0,
        "q": quat_from_euler_w_pos(s["phi_rad"], s["theta_rad"], s["psi_rad"]),
        "pos": ((s["lat_rad"] - c["lat0_rad"]) * c["m_per_rad_lat"],
                (s["lon_rad"] - c["lon0_rad"]) * c["m_per_rad_lon"],
                quant_down_m(c["agl0_m"] - hagl_m)),
    }


def omega_of(s: dict) -> tuple:
    return (s["omega1_rad_s"], s["omega2_rad_s"], s["omega3_rad_s"], s["omega4_rad_s"])


class _LowRate:
    """Schedule and noise of one 100 Hz sensor."""

    def __init__(self, rate_hz: float):
        if not rate_hz > 0:
            raise ValueError("rate_hz must be > 0")
        self.rate_hz, self.m, self.next_ns = rate_hz, 1, due_ns(1, rate_hz)
        self.noise: list = []
        self.pos = 0
        self.seq = 0

    def take(self, what: str) -> list:
        if self.pos >= len(self.noise):
            raise RuntimeError(f"no {what} noise: call set_{what}_block first")
        self.m += 1
        self.next_ns = due_ns(self.m, self.rate_hz)
        row = self.noise[self.pos]
        self.pos += 1
        return row


def _by_name(d: dict, names: tuple, what: str) -> dict:
    """The C kernel's contract: exactly the names of its table."""
    if set(d) != set(names):
        raise KeyError(f"{what}: {sorted(set(d) ^ set(names))} differ from the C table")
    return dict(d)


class Kernel:
    def __init__(self, buffer, setters, run, getters, state, consts, phase, dt_ns: int,
                 flip_steps: int, scalar_imu: bool, on_ground: bool):
        if len(setters) != 4:
            raise ValueError("need 4 setters")
        self.buf = buffer
        self.setters = tuple(setters)
        self.run = run
        self.getters = _by_name(getters, K.SAMPLE_FIELDS, "getters")
        self.st = state
        self.c = {n: float(v) for n, v in _by_name(consts, K.CONST_FIELDS, "consts").items()}
        if self.c["vib_on"] or self.c["imu_rot_on"]:
            # The oracle mirrors the stage with issue 26's vibration and IMU rotation off (the byte-for-byte
            # contract of S1..S4); the vibration and chip have their own tests
            # (test_vibration.py against JSBSim, test_vibration_chip.py against scipy).
            raise NotImplementedError("the oracle has no vibration model nor IMU rotation: "
                                      "vib_on and imu_rot_on must be 0")
        self._phase = [float(x) for x in phase]
        self.dt_ns = int(dt_ns)
        self.flip_steps = int(flip_steps)
        self.scalar_imu = bool(scalar_imu)
        self.was_on_ground = bool(on_ground)
        self.prev_vd = 0.0
        self.upside_down_steps = 0
        self.step_index = 0
        self.next_slow_ns = 0
        self.injected = [0.0, 0.0, 0.0]
        self._seq = [0, 0, 0]
        self._baro = self._mag = None
        self._forces: list = []
        self._pack = None
        self._block = None
        self._temps = None
        self.pos = 0

    # --- configuration between steps (step_config.c, step_forces.c) ---------------------
    def set_block(self, block, temps) -> None:
        self._block = block.tolist()
        self._temps = temps.tolist()
        self.pos = 0

    def set_injected(self, x: float, y: float, z: float) -> None:
        self.injected = [float(x), float(y), float(z)]

    def seqs(self) -> tuple:
        return (*self._seq, self._baro.seq if self._baro else 0,
                self._mag.seq if self._mag else 0)

    def set_forces(self, plan) -> None:
        """[(direction setters (3), [(c_n, w_rad_s, t_on_s, phase_rad, periodic, axis)])]."""
        if len(plan) > 2:
            raise ValueError("set_forces: at most 2 frames (ned, frd)")
        self._forces = [(tuple(sets), [tuple(it) for it in items]) for sets, items in plan]

    def _apply_forces(self, k: int) -> None:
        # Force [N] = m g A sin(2 pi f (t - t_on) + phase) (or constant) along the axis,
        # summed per frame into the direction of that frame's 1 N external force.
        t_s = (k - 1) * self.dt_ns * 1e-9
        for (sx, sy, sz), items in self._forces:
            x = y = z = 0.0
            for c, w, t_on, phase, periodic, (ax, ay, az) in items:
                f_n = c * (math.sin(w * (t_s - t_on) + phase) if periodic else 1.0)
                x += f_n * ax
                y += f_n * ay
                z += f_n * az
            sx(x)
            sy(y)
            sz(z)

    def configure_baro(self, rate_hz, offset_pa, noise_pa) -> None:
        self._baro = _LowRate(float(rate_hz))
        self._baro_cfg = (float(offset_pa), float(noise_pa))

    def configure_mag(self, rate_hz, field_ned, offset, noise_gauss) -> None:
        self._mag = _LowRate(float(rate_hz))
        self._mag_cfg = (tuple(map(float, field_ned)), tuple(map(float, offset)),
                         float(noise_gauss))

    def set_baro_block(self, block) -> None:
        self._baro.noise, self._baro.pos = block.tolist(), 0

    def set_mag_block(self, block) -> None:
        self._mag.noise, self._mag.pos = block.tolist(), 0

    # --- the battery (step_battery.c) ----------------------------------------------------
    def configure_battery(self, **cfg) -> None:
        self._pack = KernelPack(**cfg)

    def write_battery(self, slot: int) -> int:
        sim_ns = self.step_index * self.dt_ns
        if not self._pack.due(sim_ns):
            return 0
        self._pack.report(self.buf, slot, sim_ns, self.st[K.ST_OMEGA:K.ST_OMEGA + 4].tolist())
        return 1

    def battery_state(self) -> tuple:
        return self._pack.state()

    def battery_solve(self, esc_w: float) -> tuple:
        return self._pack.solve(esc_w)

    def battery_esc_power(self, omega) -> tuple:
        return self._pack.esc_power(omega)

    def set_battery_cell(self, cell: int, offset_v: float, r_scale: float) -> None:
        self._pack.set_cell(cell, offset_v, r_scale)

    def battery_lose_charge(self, fraction: float) -> None:
        self._pack.pack.lose_charge(fraction)

    # --- the step: JSBSim (step_run.c), then the sensor stage (sensor_stage.c) -----------
    def step(self, pwm) -> int:
        if not self.scalar_imu:
            raise RuntimeError("this kernel writes no IMU: use step_gt(pwm, slot)")
        return self._step(pwm, 0)

    def step_gt(self, pwm, slot: int) -> int:
        if self.scalar_imu:
            raise RuntimeError("this kernel writes the IMU: use step(pwm)")
        return self._step(pwm, slot)

    def _step(self, pwm, first: int) -> int:
        k = self.step_index + 1
        if any(p != p for p in pwm):
            raise ValueError(f"PWM command contains NaN at step {k}: {list(pwm)}")
        for s, p in zip(self.setters, pwm):
            s(p)
        if self._forces:
            self._apply_forces(k)
        self.run()
        self.step_index = k
        sample = {name: f() for name, f in self.getters.items()}
        return self._stage(sample, k * self.dt_ns, first)

    def _stage(self, s: dict, sim_ns: int, first: int) -> int:
        t = to_truth(self.c, s, self.st)
        flags, slot = 0, first
        if self.scalar_imu:
            flags |= self._write_imu(s, t, sim_ns)
            slot += 1
        self._write_truth(t, slot, sim_ns)
        slot += 2
        self._leave_state(s, t)
        flags |= self._contact_and_crash(s, t)
        b = self._baro
        if b is not None and sim_ns >= b.next_ns:
            flags |= self._write_baro(s, slot, sim_ns)
            slot += 1
        m = self._mag
        if m is not None and sim_ns >= m.next_ns:
            flags |= self._write_mag(s, slot, sim_ns)
            slot += 1
        p = self._pack
        if p is not None and p.due(sim_ns) and sim_ns < self.next_slow_ns:
            p.report(self.buf, slot, sim_ns, omega_of(s))
            slot += 1
        if sim_ns >= self.next_slow_ns:
            flags |= K.F_SLOW_DUE
        else:
            self.buf[(slot - 1) * RECORD_SIZE + FLAGS_OFFSET] = FLAG_STEP_END
        return flags | (slot - first)

    def _write_imu(self, s: dict, t: dict, sim_ns: int) -> int:
        if self._block is None or self.pos >= len(self._block):
            raise RuntimeError("no IMU noise block: call set_block first")
        noise = self._block[self.pos]
        temp_c = self._temps[self.pos]
        self.pos += 1
        flags = K.F_BLOCK_DONE if self.pos >= len(self._block) else 0
        out = imu_scalar(self.c, t["af"], t["w"], omega_of(s), self._phase, noise,
                         self.injected)
        self.st[K.ST_TEMP_C] = temp_c
        _IMU.pack_into(self.buf, 0, Kind.IMU, 0, self._seq[0] & 0xFFFFFFFF, sim_ns, 0, *out,
                       temp_c, 0, 1, 0)
        self._seq[0] += 1
        return flags

    def _write_truth(self, t: dict, slot: int, sim_ns: int) -> None:
        seq = self._seq
        _GT_ATT.pack_into(self.buf, slot * RECORD_SIZE, Kind.GT_ATT, 0, seq[1] & 0xFFFFFFFF,
                          sim_ns, 0, *t["q"], *t["w"], *t["af"])
        _GT_NAV.pack_into(self.buf, (slot + 1) * RECORD_SIZE, Kind.GT_NAV, 0,
                          seq[2] & 0xFFFFFFFF, sim_ns, 0, *t["pos"],
                          *(quant_velocity_m_s(v) for v in t["vel"]), t["on_ground"])
        seq[1] += 1
        seq[2] += 1

    def _leave_state(self, s: dict, t: dict) -> None:
        st = self.st
        st[K.ST_W:K.ST_W + 3] = t["w"]
        st[K.ST_F:K.ST_F + 3] = t["af"]
        st[K.ST_EULER:K.ST_EULER + 3] = (s["phi_rad"], s["theta_rad"], s["psi_rad"])
        st[K.ST_VEL:K.ST_VEL + 3] = t["vel"]
        st[K.ST_LAT], st[K.ST_LON], st[K.ST_HAGL] = s["lat_rad"], s["lon_rad"], t["hagl_m"]
        st[K.ST_OMEGA:K.ST_OMEGA + 4] = omega_of(s)
        st[K.ST_ON_GROUND] = float(t["on_ground"])

    def _contact_and_crash(self, s: dict, t: dict) -> int:
        st, flags = self.st, 0
        st[K.ST_PREV_VD] = self.prev_vd
        if t["on_ground"] != self.was_on_ground:
            flags |= K.F_GROUND_CHANGED
            self.was_on_ground = t["on_ground"]
        self.prev_vd = t["vel"][2]
        q = t["q"]
        cos_tilt = 1.0 - 2.0 * (q[1] * q[1] + q[2] * q[2])
        st[K.ST_COS_TILT] = cos_tilt
        if t["on_ground"] and cos_tilt < self.c["cos_crash_tilt"]:
            flags |= K.F_TIPPED
        if cos_tilt < 0.0:
            self.upside_down_steps += 1
            if self.upside_down_steps >= self.flip_steps:
                flags |= K.F_FLIPPED
        else:
            self.upside_down_steps = 0
        hagl_m = t["hagl_m"]
        if hagl_m < self.c["strike_agl_m"] and rotor_strike(s["phi_rad"], s["theta_rad"], hagl_m):
            flags |= K.F_ROTOR_STRIKE
        return flags

    def _write_baro(self, s: dict, slot: int, sim_ns: int) -> int:
        b = self._baro
        (n,) = b.take("baro")
        offset_pa, noise_pa = self._baro_cfg
        pa = self.st[K.ST_BARO_PA] + offset_pa + noise_pa * n
        _BARO.pack_into(self.buf, slot * RECORD_SIZE, Kind.BARO, 0, b.seq & 0xFFFFFFFF, sim_ns,
                        0, pressure_pa(pa), s["temperature_r"] / 1.8 - 273.15)
        b.seq += 1
        return K.F_BARO_BLOCK_DONE if b.pos >= len(b.noise) else 0

    def _write_mag(self, s: dict, slot: int, sim_ns: int) -> int:
        m = self._mag
        n = m.take("mag")
        field, off, sd = self._mag_cfg
        bx, by, bz = ned_to_frd(s["phi_rad"], s["theta_rad"], s["psi_rad"], field)
        _MAG.pack_into(self.buf, slot * RECORD_SIZE, Kind.MAG, 0, m.seq & 0xFFFFFFFF, sim_ns,
                       0, bx + off[0] + sd * n[0], by + off[1] + sd * n[1],
                       bz + off[2] + sd * n[2])
        m.seq += 1
        return K.F_MAG_BLOCK_DONE if m.pos >= len(m.noise) else 0
