"""Simulator: one physics step of the quad plus its sensors, as shm records.

    sim = Simulator(load_scenario("S1"))          # imu_hz=None -> the scenario's rate
    recs = sim.step(pwm_us)                       # 4 pulse widths (motors 1..4), us

`step` holds the pulse widths for one physics step (zero-order hold), advances
JSBSim, and returns that step's records (numpy RECORD_DTYPE; a view into a
preallocated buffer, valid until the next call: copy it to keep it), in the
contract's order: the step's IMU samples (oldest first), GT_ATT, GT_NAV, then
BARO, MAG, GNSS if due, then SETPOINT if the profile changed; the last record
carries FLAG_STEP_END. Step k has sim_ns = k * dt_ns; oversampled IMU sample
times are described in imu.py. Sequence numbers count per kind from 0.

Motor order is ArduCopter quad X: 1 front-right CCW, 2 back-left CCW,
3 front-left CW, 4 back-right CW; PWM 1000 us = stopped, 2000 us = full.

Randomness: only from the scenario seed (named streams, see noise.py); the same
scenario, seed and PWM sequence give identical record bytes.

The hot path keeps JSBSim property handles' bound methods in tuples and does
scalar maths in plain Python; numpy is used only for the oversampled IMU block.
"""

from __future__ import annotations

import math

import numpy as np

from silbridge.bridge import step_buffer as sb
from silbridge.bridge.disturbances import Disturbances
from silbridge.bridge.errors import SimulatorError
from silbridge.bridge.fdm import FT_M, LBF_N, PSF_PA, ROTOR_HUBS_FRD_M, SLUG_KG, Fdm
from silbridge.bridge.frames import quat_from_euler, wrap_pi
from silbridge.bridge.imu import ImuModel
from silbridge.bridge.lowrate import Baro, Gnss, Mag
from silbridge.bridge.noise import DEFAULT_BLOCK_ROWS
from silbridge.bridge.scenario import draw_rng
from silbridge.bridge.setpoints import SetpointProgram
from silbridge.mavlink.hil_quant import down_m as _q_down
from silbridge.mavlink.hil_quant import velocity_m_s as _q_vel
from silbridge.shm.records import Kind

_NS = 1_000_000_000
_FLIP_LIMIT_S = 1.0   # upside down this long in the air counts as a crash


class Simulator:
    def __init__(self, scenario, imu_hz: int | None = None, block_rows: int = DEFAULT_BLOCK_ROWS):
        sc = scenario
        self.scenario = sc
        physics_hz = int(sc.physics.rate_hz)
        if _NS % physics_hz:
            raise SimulatorError(f"physics rate {physics_hz} Hz is not a whole number of ns per step")
        imu_hz = int(sc.imu_hz if imu_hz is None else imu_hz)
        if imu_hz <= 0:
            raise SimulatorError(f"imu_hz must be > 0, got {imu_hz}")
        self.physics_hz = physics_hz
        self.imu_hz = imu_hz
        self.dt_ns = _NS // physics_hz
        self.dt_s = self.dt_ns / _NS
        self.step_index = 0
        self.sim_ns = 0
        self.crashed = False
        self.crash_reason = ""
        self.events: list[tuple[int, str]] = []
        seed = sc.seed
        home = sc.home
        jsb_seed = int(draw_rng(seed, "jsbsim").integers(1, 2**31 - 1))
        fdm = Fdm(self.dt_s, home.lat_deg, home.lon_deg, home.alt_m, home.heading_deg,
                  home.initial_agl_m, jsb_seed, sc.physics.model)
        self.fdm = fdm

        # Model constants and the open-loop hover estimate (motors.xml derivation).
        kt = fdm.model_constant("quadx/kt-n-per-rad_s2")
        self.omega_max_rad_s = fdm.model_constant("quadx/omega-max-rad_s")
        expo = fdm.model_constant("quadx/thrust-expo")
        g = fdm.fdm["accelerations/gravity-ft_sec2"] * FT_M
        self.max_thrust_n = 4.0 * kt * self.omega_max_rad_s ** 2
        self.thrust_to_weight = self.max_thrust_n / (fdm.mass_kg * g)
        f = 1.0 / self.thrust_to_weight
        throttle = ((expo - 1.0) + math.sqrt((1.0 - expo) ** 2 + 4.0 * expo * f)) / (2.0 * expo)
        self.hover_throttle = throttle
        self.hover_pwm_us = 1000.0 + 1000.0 * throttle

        ambient_c = fdm.h_temp.get_double_value() / 1.8 - 273.15
        self.imu = ImuModel(sc.imu, seed, physics_hz, imu_hz, ambient_c, self.omega_max_rad_s,
                            block_rows)
        self.baro = Baro(sc.baro, seed, self.dt_s, fdm.h_pressure.get_double_value() * PSF_PA)
        self.mag = Mag(sc.mag, seed)
        self.gnss = Gnss(sc.gnss, seed, fdm.m_per_rad_lat, fdm.m_per_rad_lon)
        self.dist = Disturbances(sc, fdm, self.imu, self.dt_ns, self._event)
        self.setpoints = SetpointProgram(sc, self.dt_ns, math.radians(home.heading_deg))
        # The scenario's current command (what the FC was told), for summaries.
        self.command = {"roll_rad": 0.0, "pitch_rad": 0.0, "alt_m": 0.0}
        self._crash_descent_m_s = sc.physics.crash_descent_m_s
        self._cos_crash_tilt = math.cos(math.radians(sc.physics.crash_tilt_deg))
        self._flip_steps = int(_FLIP_LIMIT_S * physics_hz)
        self._upside_down_steps = 0
        # Hubs are within 0.23 m of the CG: below that height a strike is possible.
        self._strike_check_agl_m = 0.25

        # IMU sampling plan.
        self._scalar_imu = imu_hz == physics_hz
        self._n_fixed = imu_hz // physics_hz if imu_hz % physics_hz == 0 else None
        if self._n_fixed:
            n = self._n_fixed
            self._offsets_ns = np.array([(j + 1) * self.dt_ns // n for j in range(n)], dtype=np.int64)
            self._frac_col = (self._offsets_ns / self.dt_ns)[:, None]
        max_imu = -(-imu_hz // physics_hz) + 1
        self.buffer = sb.StepBuffer(max_imu + 2 + 3 + 1 + 4)
        self._seq = [0] * 9   # records published per kind; the header seq is this mod 2^32

        # Hot-path handles as bound methods.
        self._set_pwm = tuple(h.set_double_value for h in fdm.h_pwm)
        self._run = fdm.fdm.run
        gd = lambda h: h.get_double_value  # noqa: E731
        self._get_gyro = tuple(gd(h) for h in (fdm.h_p, fdm.h_q, fdm.h_r))
        self._get_force = tuple(gd(h) for h in (fdm.h_fbx, fdm.h_fby, fdm.h_fbz))
        self._get_att = tuple(gd(h) for h in (fdm.h_phi, fdm.h_theta, fdm.h_psi))
        self._get_vel = tuple(gd(h) for h in (fdm.h_vn, fdm.h_ve, fdm.h_vd))
        self._get_pos = tuple(gd(h) for h in (fdm.h_lat, fdm.h_lon, fdm.h_hagl))
        self._get_omega = tuple(gd(h) for h in fdm.h_omega)
        self._get_gear = gd(fdm.h_gear)
        self._get_pressure = gd(fdm.h_pressure)
        self._get_temp = gd(fdm.h_temp)
        # specific force [m/s^2] = force [lbf] / mass [slug] * ft->m
        self._lbf_to_m_s2 = FT_M / (fdm.mass_kg / SLUG_KG)
        self._was_on_ground = self._get_gear() > 0
        self._home = (fdm.home_lat_rad, fdm.home_lon_rad, fdm.m_per_rad_lat, fdm.m_per_rad_lon,
                      fdm.home_agl_m)
        self._prev_vd = 0.0
        self._prev6 = self._true6()

    # --- helpers --------------------------------------------------------------------
    def _true6(self) -> tuple:
        """True (accel xyz, gyro xyz) now: the interpolation start of the next step."""
        k = self._lbf_to_m_s2
        g = self._get_gyro
        f = self._get_force
        return (f[0]() * k, f[1]() * k, f[2]() * k, g[0](), g[1](), g[2]())

    def _next_seq(self, kind: int) -> int:
        s = self._seq[kind]
        self._seq[kind] = s + 1
        return s & 0xFFFFFFFF

    def published_counts(self) -> dict[str, int]:
        """Records published so far per kind (not wrapped)."""
        s = self._seq
        return {"imu": s[Kind.IMU], "gt_att": s[Kind.GT_ATT], "gt_nav": s[Kind.GT_NAV],
                "baro": s[Kind.BARO], "mag": s[Kind.MAG], "gnss": s[Kind.GNSS],
                "setpoint": s[Kind.SETPOINT]}

    # --- the step ---------------------------------------------------------------------
    def step(self, pwm_us) -> np.ndarray:
        k = self.step_index + 1
        sim_ns = k * self.dt_ns
        p0, p1, p2, p3 = pwm_us
        if p0 != p0 or p1 != p1 or p2 != p2 or p3 != p3:   # NaN: a bug upstream, never fly it
            raise ValueError(f"PWM command contains NaN at step {k}: {list(pwm_us)}")
        sp = self._set_pwm
        sp[0](p0)
        sp[1](p1)
        sp[2](p2)
        sp[3](p3)
        dist = self.dist
        if k == dist.next_step:
            dist.switch(k)
        elif dist._forces or dist._ramps:
            dist.update(k)
        self._run()
        self.step_index = k
        self.sim_ns = sim_ns

        g = self._get_gyro
        wx, wy, wz = g[0](), g[1](), g[2]()
        f = self._get_force
        c = self._lbf_to_m_s2
        fx, fy, fz = f[0]() * c, f[1]() * c, f[2]() * c
        a = self._get_att
        phi, theta, psi = a[0](), a[1](), a[2]()
        v = self._get_vel
        vn, ve, vd = v[0]() * FT_M, v[1]() * FT_M, v[2]() * FT_M
        o = self._get_omega
        o1, o2, o3, o4 = o[0](), o[1](), o[2](), o[3]()
        on_ground = self._get_gear() > 0.0
        baro = self.baro
        baro.filtered_pa += baro.alpha * (self._get_pressure() * PSF_PA - baro.filtered_pa)

        buf = self.buffer
        seq = self._seq
        qw, qx, qy, qz = quat_from_euler(phi, theta, psi)
        if qw < 0.0:  # JSBSim's psi is in [0, 2 pi): keep the w >= 0 hemisphere
            qw, qx, qy, qz = -qw, -qx, -qy, -qz
        pos = self._get_pos
        lat, lon, hagl_m = pos[0](), pos[1](), pos[2]() * FT_M
        lat0, lon0, m_lat, m_lon, agl0 = self._home
        pn = (lat - lat0) * m_lat
        pe = (lon - lon0) * m_lon
        # Truth as HIL_STATE_QUATERNION carries it (whole mm down, whole cm/s), whatever the
        # transport: the FC blends truth altitude and climb, so it must read the same numbers
        # over shared memory and over MAVLink. Dynamics use JSBSim's own state, not these.
        # Inline fast path (same arithmetic as hil_quant, which handles NaN and the int16
        # range); it saves ~1 us per step, a few per cent of the whole loop.
        pd = agl0 - hagl_m
        pd = round(pd * 1000.0) / 1000.0 if -1e6 < pd < 1e6 else _q_down(pd)
        gvn = round(vn * 100.0) / 100.0 if -327.0 < vn < 327.0 else _q_vel(vn)
        gve = round(ve * 100.0) / 100.0 if -327.0 < ve < 327.0 else _q_vel(ve)
        gvd = round(vd * 100.0) / 100.0 if -327.0 < vd < 327.0 else _q_vel(vd)

        if self._scalar_imu:
            ax, ay, az, gx, gy, gz, temp_c = self.imu.step_scalar(fx, fy, fz, wx, wy, wz,
                                                                  o1, o2, o3, o4)
            sb.IMU_GT.pack_into(
                buf.buf, 0,
                1, 0, seq[1] & 0xFFFFFFFF, sim_ns, 0, ax, ay, az, gx, gy, gz, temp_c, 0, 1, 0,
                5, 0, seq[5] & 0xFFFFFFFF, sim_ns, 0, qw, qx, qy, qz, wx, wy, wz, fx, fy, fz,
                6, 0, seq[6] & 0xFFFFFFFF, sim_ns, 0, pn, pe, pd, gvn, gve, gvd, on_ground)
            seq[1] += 1
            count = 3
        else:
            count = self._imu_block(sim_ns, wx, wy, wz, fx, fy, fz, o1, o2, o3, o4)
            sb.GT.pack_into(
                buf.buf, count * 64,
                5, 0, seq[5] & 0xFFFFFFFF, sim_ns, 0, qw, qx, qy, qz, wx, wy, wz, fx, fy, fz,
                6, 0, seq[6] & 0xFFFFFFFF, sim_ns, 0, pn, pe, pd, gvn, gve, gvd, on_ground)
            count += 2
        seq[5] += 1
        seq[6] += 1

        if sim_ns >= baro.schedule.next_ns:
            baro.schedule.advance()
            sb.BARO.pack_into(buf.buf, count * 64, 2, 0, self._next_seq(2), sim_ns, 0,
                              baro.sample(), self._get_temp() / 1.8 - 273.15)
            count += 1
        mag = self.mag
        if sim_ns >= mag.schedule.next_ns:
            mag.schedule.advance()
            bx, by, bz = mag.sample(phi, theta, psi)
            sb.MAG.pack_into(buf.buf, count * 64, 3, 0, self._next_seq(3), sim_ns, 0, bx, by, bz)
            count += 1
        gnss = self.gnss
        if sim_ns >= gnss.schedule.next_ns:
            gnss.schedule.advance()
            gnss.epoch(sim_ns, lat, lon, self.fdm.ground_alt_m + hagl_m, (vn, ve, vd))
        pending = gnss.pending
        while pending and pending[0][0] <= sim_ns:
            _, _, fix = pending.popleft()
            sb.GNSS.pack_into(buf.buf, count * 64, 4, 0, self._next_seq(4), sim_ns, 0, *fix)
            count += 1
        if k == self.setpoints.next_step:
            _, s_roll, s_pitch, s_yaw, s_alt, mask = self.setpoints.pop()
            sb.SETPOINT.pack_into(buf.buf, count * 64, 8, 0, self._next_seq(8), sim_ns, 0,
                                  s_roll, s_pitch, s_yaw, s_alt, mask)
            count += 1
            cmd = self.command
            if mask & 1:
                cmd["roll_rad"], cmd["pitch_rad"] = s_roll, s_pitch
            if mask & 2:
                cmd["alt_m"] = s_alt

        # Ground contact: integrator choice and crash detection.
        if on_ground != self._was_on_ground:
            self.fdm.set_air_integrator(not on_ground)
            if on_ground and self._prev_vd > self._crash_descent_m_s:
                self._crash(f"hard touchdown at {self._prev_vd:.2f} m/s descent")
            self._was_on_ground = on_ground
        self._prev_vd = vd
        cos_tilt = 1.0 - 2.0 * (qx * qx + qy * qy)
        if on_ground and cos_tilt < self._cos_crash_tilt:
            self._crash(f"tipped over on the ground ({math.degrees(math.acos(max(-1.0, cos_tilt))):.0f} deg)")
        if cos_tilt < 0.0:
            self._upside_down_steps += 1
            if self._upside_down_steps >= self._flip_steps:
                self._crash("flipped: upside down for 1 s")
        else:
            self._upside_down_steps = 0
        if hagl_m < self._strike_check_agl_m and self._rotor_strike(phi, theta, hagl_m):
            self._crash("rotor strike: a rotor hub touched the ground")
        return buf.finish(count)

    def _imu_block(self, sim_ns, wx, wy, wz, fx, fy, fz, o1, o2, o3, o4) -> int:
        """Oversampled (or sub-sampled) IMU records of this step into slots 0..n-1."""
        cur6 = (fx, fy, fz, wx, wy, wz)
        base_ns = sim_ns - self.dt_ns
        if self._n_fixed:
            n = self._n_fixed
            times = self._offsets_ns + base_ns
            frac_col = self._frac_col
        else:
            m0 = (base_ns * self.imu_hz) // _NS + 1
            m1 = (sim_ns * self.imu_hz) // _NS
            n = max(0, m1 - m0 + 1)
            times = (np.arange(m0, m1 + 1, dtype=np.int64) * _NS) // self.imu_hz
            frac_col = ((times - base_ns) / self.dt_ns)[:, None]
        buf = self.buffer
        if n:
            buf.write_imu_headers(n, self._seq[1] & 0xFFFFFFFF, times)
            self._seq[1] += n
        self.imu.step_block(self._prev6, cur6, frac_col, o1, o2, o3, o4, buf.imu_payload(n))
        self._prev6 = cur6
        return n

    @staticmethod
    def _rotor_strike(phi: float, theta: float, hagl_m: float) -> bool:
        """True when a rotor hub is at or below the ground (flat terrain)."""
        sth, cth = math.sin(theta), math.cos(theta)
        sph_cth, cph_cth = math.sin(phi) * cth, math.cos(phi) * cth
        for x, y, z in ROTOR_HUBS_FRD_M:
            down_m = -sth * x + sph_cth * y + cph_cth * z   # NED down offset of the hub
            if hagl_m + (-down_m) <= 0.0:
                return True
        return False

    def _event(self, sim_ns: int, text: str) -> None:
        # Looked up at call time: the caller may drain or replace self.events.
        self.events.append((sim_ns, text))

    def drain_events(self) -> list[tuple[int, str]]:
        """The events since the last drain, oldest first; clears the list."""
        out, self.events = self.events, []
        return out

    def _crash(self, reason: str) -> None:
        if not self.crashed:
            self.crashed = True
            self.crash_reason = reason
            self._event(self.sim_ns, "crash: " + reason)

    # --- inspection (not on the hot path) ------------------------------------------------
    def truth(self) -> dict:
        """True state after the last step, SI units, frames in the names."""
        fdm = self.fdm
        gd = lambda h: h.get_double_value()  # noqa: E731
        phi, theta, psi = (gd(h) for h in (fdm.h_phi, fdm.h_theta, fdm.h_psi))
        c = self._lbf_to_m_s2
        hagl_m = gd(fdm.h_hagl) * FT_M
        q = quat_from_euler(phi, theta, psi)
        if q[0] < 0.0:   # the same w >= 0 hemisphere as the GT_ATT record
            q = tuple(-c for c in q)
        return {
            "sim_ns": self.sim_ns,
            "q_wxyz": q,
            "euler_rad": (phi, theta, wrap_pi(psi)),
            "rates_frd_rad_s": tuple(gd(h) for h in (fdm.h_p, fdm.h_q, fdm.h_r)),
            "specific_force_frd_m_s2": tuple(gd(h) * c for h in (fdm.h_fbx, fdm.h_fby, fdm.h_fbz)),
            "pos_ned_m": ((gd(fdm.h_lat) - fdm.home_lat_rad) * fdm.m_per_rad_lat,
                          (gd(fdm.h_lon) - fdm.home_lon_rad) * fdm.m_per_rad_lon,
                          fdm.home_agl_m - hagl_m),
            "vel_ned_m_s": tuple(gd(h) * FT_M for h in (fdm.h_vn, fdm.h_ve, fdm.h_vd)),
            "h_agl_m": hagl_m,
            "alt_msl_m": fdm.ground_alt_m + hagl_m,
            "on_ground": gd(fdm.h_gear) > 0,
            "rotor_rad_s": tuple(gd(h) for h in fdm.h_omega),
            "thrust_scale": tuple(gd(h) for h in fdm.h_scale),
            "pressure_pa": gd(fdm.h_pressure) * PSF_PA,
            "imu_bias_gyro_frd_rad_s": tuple(self.imu.bias6()[:3]),
            "imu_bias_accel_frd_m_s2": tuple(self.imu.bias6()[3:]),
            "imu_temp_c": self.imu.temp_c,
            "crashed": self.crashed,
        }

    def thrust_n(self) -> tuple:
        """Current rotor thrusts [N], motors 1..4."""
        return tuple(self.fdm.fdm[f"fcs/m{i}-thrust-lbs"] * LBF_N for i in range(1, 5))
