"""The bridge's per-step kernel in plain Python: the readable reference of bridge/src/stepmodule.c.

One physics step: write the four pulse widths into JSBSim, run it, read the state back,
and write the step's IMU (when one sample per step), GT_ATT and GT_NAV records into the
step buffer, then the baro and magnetometer records when due. The C kernel
(`silbridge.bridge._step.Kernel`) does the same with the same operation order and gives
byte-identical records (tests/bridge/test_step_kernel.py); it runs in production because
this version costs ~4 us more per step. Read this one.

Interface shared by both (the simulator is the only caller):
    k = Kernel(buffer, setters, run, getters, state, consts, phase, dt_ns, flip_steps,
               scalar_imu, on_ground)
    flags = k.step(pwm)            # scalar IMU: IMU, GT_ATT, GT_NAV in slots 0, 1, 2
    flags = k.step_gt(pwm, slot)   # oversampled IMU (written by the caller): GT at slot
    k.set_block(block, temps)      # next IMU noise rows (rows, 6) and temperatures (rows)
    k.set_injected(x, y, z)        # injected gyro bias [rad/s]
    k.set_forces(plan)             # disturbance forces written before each run()
    k.configure_baro(rate_hz, offset_pa, noise_pa, get_temp)      # sample the baro (100 Hz)
    k.configure_mag(rate_hz, field_ned, offset, noise_gauss)      # and the magnetometer
    k.set_baro_block(normals (rows, 1)); k.set_mag_block(normals (rows, 3))
    k.next_slow_ns                 # from this sim time, flags carry F_SLOW_DUE (GNSS, setpoints)
The low byte of flags is the number of records written; the state array receives the
values in the ST_* slots below. Without F_SLOW_DUE the last record carries STEP_END.
"""

from __future__ import annotations

import math

from silbridge.bridge import step_buffer as sb
from silbridge.bridge.frames import ned_to_frd, quat_from_euler
from silbridge.bridge.lowrate import due_ns
from silbridge.mavlink.hil.hil_quant import pressure_pa
from silbridge.shm.records import FLAG_STEP_END

# Getter order (JSBSim property nodes' get_double_value): rates, forces, Euler, velocity
# NED, lat, lon, height AGL, rotor speeds, gear contacts, static pressure.
GETTERS = ("p", "q", "r", "fbx", "fby", "fbz", "phi", "theta", "psi", "vn", "ve", "vd",
           "lat", "lon", "hagl", "o1", "o2", "o3", "o4", "gear", "pressure")
KERNEL_CONSTS = ("lbf_to_m_s2", "ft_m", "psf_pa", "lat0", "lon0", "m_lat", "m_lon", "agl0",
                 "dt_s", "inv_omega_max2", "vib_a", "vib_g", "range_a", "range_g",
                 "baro_alpha", "cos_crash_tilt", "strike_agl")
# State slots.
ST_W, ST_F, ST_EULER, ST_VEL = 0, 3, 6, 9
ST_LAT, ST_LON, ST_HAGL, ST_OMEGA = 12, 13, 14, 15
ST_ON_GROUND, ST_BARO_PA, ST_TEMP_C, ST_PREV_VD, ST_COS_TILT, ST_COUNT = 19, 20, 21, 22, 23, 24
# Flags.
F_SLOW_DUE, F_BLOCK_DONE, F_GROUND_CHANGED = 0x100, 0x200, 0x400
F_TIPPED, F_FLIPPED, F_ROTOR_STRIKE = 0x800, 0x1000, 0x2000
F_BARO_BLOCK_DONE, F_MAG_BLOCK_DONE = 0x4000, 0x8000

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


class _LowRate:
    """Schedule and noise of one 100 Hz sensor."""

    def __init__(self, rate_hz: float):
        if not rate_hz > 0:
            raise ValueError("rate_hz must be > 0")
        self.rate_hz, self.m, self.next_ns = rate_hz, 1, due_ns(1, rate_hz)
        self.noise: list = []
        self.pos = 0
        self.seq = 0

    def take(self) -> list:
        if self.pos >= len(self.noise):
            raise RuntimeError("no noise: call set_*_block first")
        self.m += 1
        self.next_ns = due_ns(self.m, self.rate_hz)
        row = self.noise[self.pos]
        self.pos += 1
        return row


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
    va, vg = c["vib_a"], c["vib_g"]
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
    ra, rg = c["range_a"], c["range_g"]
    for i in range(3):   # clip at full scale (NaN passes, as in C)
        out[i] = -ra if out[i] < -ra else (ra if out[i] > ra else out[i])
        out[i + 3] = -rg if out[i + 3] < -rg else (rg if out[i + 3] > rg else out[i + 3])
    return tuple(out)


class Kernel:
    def __init__(self, buffer, setters, run, getters, state, consts, phase, dt_ns: int,
                 flip_steps: int, scalar_imu: bool, on_ground: bool):
        if len(setters) != 4 or len(getters) != len(GETTERS):
            raise ValueError("need 4 setters and one getter per GETTERS entry")
        self.buf = buffer
        self.setters = tuple(setters)
        self.run = run
        self.getters = tuple(getters)
        self.st = state
        self.c = dict(zip(KERNEL_CONSTS, (float(x) for x in consts)))
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
        self._block = None
        self._temps = None
        self.pos = 0

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

    def configure_baro(self, rate_hz, offset_pa, noise_pa, get_temp) -> None:
        self._baro = _LowRate(float(rate_hz))
        self._baro_cfg = (float(offset_pa), float(noise_pa), get_temp)

    def configure_mag(self, rate_hz, field_ned, offset, noise_gauss) -> None:
        self._mag = _LowRate(float(rate_hz))
        self._mag_cfg = (tuple(map(float, field_ned)), tuple(map(float, offset)),
                         float(noise_gauss))

    def set_baro_block(self, block) -> None:
        self._baro.noise, self._baro.pos = block.tolist(), 0

    def set_mag_block(self, block) -> None:
        self._mag.noise, self._mag.pos = block.tolist(), 0

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
        sim_ns = k * self.dt_ns
        g = dict(zip(GETTERS, (f() for f in self.getters)))
        c, st = self.c, self.st
        w = (g["p"], g["q"], g["r"])
        lbf = c["lbf_to_m_s2"]
        af = (g["fbx"] * lbf, g["fby"] * lbf, g["fbz"] * lbf)
        ft = c["ft_m"]
        vn, ve, vd = g["vn"] * ft, g["ve"] * ft, g["vd"] * ft
        hagl_m = g["hagl"] * ft
        on_ground = g["gear"] > 0.0
        omega = (g["o1"], g["o2"], g["o3"], g["o4"])
        st[ST_BARO_PA] += c["baro_alpha"] * (g["pressure"] * c["psf_pa"] - st[ST_BARO_PA])
        q = quat_from_euler_w_pos(g["phi"], g["theta"], g["psi"])
        pn = (g["lat"] - c["lat0"]) * c["m_lat"]
        pe = (g["lon"] - c["lon0"]) * c["m_lon"]
        pd = quant_down_m(c["agl0"] - hagl_m)
        flags = 0
        slot = first
        seq = self._seq
        if self.scalar_imu:
            if self._block is None or self.pos >= len(self._block):
                raise RuntimeError("no IMU noise block: call set_block first")
            noise = self._block[self.pos]
            temp_c = self._temps[self.pos]
            self.pos += 1
            if self.pos >= len(self._block):
                flags |= F_BLOCK_DONE
            out = imu_scalar(c, af, w, omega, self._phase, noise, self.injected)
            st[ST_TEMP_C] = temp_c
            sb.IMU.pack_into(self.buf, 0, 1, 0, seq[0] & 0xFFFFFFFF, sim_ns, 0, *out,
                             temp_c, 0, 1, 0)
            seq[0] += 1
            slot += 1
        sb.GT.pack_into(self.buf, slot * 64,
                        5, 0, seq[1] & 0xFFFFFFFF, sim_ns, 0, *q, *w, *af,
                        6, 0, seq[2] & 0xFFFFFFFF, sim_ns, 0, pn, pe, pd,
                        quant_velocity_m_s(vn), quant_velocity_m_s(ve), quant_velocity_m_s(vd),
                        on_ground)
        seq[1] += 1
        seq[2] += 1
        slot += 2
        st[ST_W:ST_W + 3] = w
        st[ST_F:ST_F + 3] = af
        st[ST_EULER:ST_EULER + 3] = (g["phi"], g["theta"], g["psi"])
        st[ST_VEL:ST_VEL + 3] = (vn, ve, vd)
        st[ST_LAT], st[ST_LON], st[ST_HAGL] = g["lat"], g["lon"], hagl_m
        st[ST_OMEGA:ST_OMEGA + 4] = omega
        st[ST_ON_GROUND] = float(on_ground)
        st[ST_PREV_VD] = self.prev_vd
        if on_ground != self.was_on_ground:
            flags |= F_GROUND_CHANGED
            self.was_on_ground = on_ground
        self.prev_vd = vd
        cos_tilt = 1.0 - 2.0 * (q[1] * q[1] + q[2] * q[2])
        st[ST_COS_TILT] = cos_tilt
        if on_ground and cos_tilt < c["cos_crash_tilt"]:
            flags |= F_TIPPED
        if cos_tilt < 0.0:
            self.upside_down_steps += 1
            if self.upside_down_steps >= self.flip_steps:
                flags |= F_FLIPPED
        else:
            self.upside_down_steps = 0
        if hagl_m < c["strike_agl"] and rotor_strike(g["phi"], g["theta"], hagl_m):
            flags |= F_ROTOR_STRIKE
        b = self._baro
        if b is not None and sim_ns >= b.next_ns:
            temp_r = self._baro_cfg[2]()
            (n,) = b.take()
            if b.pos >= len(b.noise):
                flags |= F_BARO_BLOCK_DONE
            offset_pa, noise_pa, _ = self._baro_cfg
            pa = st[ST_BARO_PA] + offset_pa + noise_pa * n
            sb.BARO.pack_into(self.buf, slot * 64, 2, 0, b.seq & 0xFFFFFFFF, sim_ns, 0,
                              pressure_pa(pa), temp_r / 1.8 - 273.15)
            b.seq += 1
            slot += 1
        m = self._mag
        if m is not None and sim_ns >= m.next_ns:
            n = m.take()
            if m.pos >= len(m.noise):
                flags |= F_MAG_BLOCK_DONE
            field, off, s = self._mag_cfg
            bx, by, bz = ned_to_frd(g["phi"], g["theta"], g["psi"], field)
            sb.MAG.pack_into(self.buf, slot * 64, 3, 0, m.seq & 0xFFFFFFFF, sim_ns, 0,
                             bx + off[0] + s * n[0], by + off[1] + s * n[1],
                             bz + off[2] + s * n[2])
            m.seq += 1
            slot += 1
        if sim_ns >= self.next_slow_ns:
            flags |= F_SLOW_DUE
        else:
            self.buf[(slot - 1) * 64 + 2] = FLAG_STEP_END
        return flags | (slot - first)
