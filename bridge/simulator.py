"""Simulator: one physics step of the quad plus its sensors, as shm records.

    sim = Simulator(load_scenario("S1"))          # imu_hz=None -> the scenario's rate
    recs = sim.step(pwm_us)                       # 4 pulse widths (motors 1..4), us

`step` holds the pulse widths for one physics step (zero-order hold), advances
JSBSim, and returns that step's records (numpy RECORD_DTYPE; a view into a
preallocated buffer, valid until the next call: copy it to keep it), in the
contract's order: the step's IMU samples (oldest first), GT_ATT, GT_NAV, then
BARO, MAG, GNSS if due, then SETPOINT if the profile changed, then the battery's
BATTERY (10 Hz, bridge/battery/, run by the kernel) and the ESC reports when due;
the last record carries FLAG_STEP_END. Step k has sim_ns = k * dt_ns; oversampled IMU sample
times are described in imu.py. Sequence numbers count per kind from 0.

Motor order is ArduCopter quad X: 1 front-right CCW, 2 back-left CCW,
3 front-left CW, 4 back-right CW; PWM 1000 us = stopped, 2000 us = full.

Randomness: only from the scenario seed (named streams, see noise.py); the same
scenario, seed and PWM sequence give identical record bytes.

The hot path is one call into the C step kernel (bridge/src/stepmodule.c; its
readable Python oracle is tests/bridge/step_kernel_oracle.py, passed as kernel_cls by
the tests): it sets the PWM, runs JSBSim, reads the FDM sample through the property
nodes, and its sensor stage (bridge/src/sensor_stage.c) writes the IMU, ground-truth,
baro and mag records, and from the second fix on the GNSS's (bridge/gnss_kernel.py).
Python keeps what happens at 10 Hz or less or on events (the first GNSS fix and
those under a GNSS fault, setpoints, crash messages, noise blocks) and the
oversampled IMU block (numpy, imu.py).
"""

from __future__ import annotations

import math

import numpy as np

from silbridge.bridge import _step
from silbridge.bridge.battery import Battery
from silbridge.bridge import esc_telemetry
from silbridge.bridge import step_buffer as sb
from silbridge.bridge import vibration_consts
from silbridge.bridge.disturbances import Disturbances
from silbridge.bridge.errors import SimulatorError
from silbridge.bridge.faults import appliers as fault_appliers
from silbridge.bridge.faults.engine import FaultEngine
from silbridge.bridge.fdm import FT_M, LBF_N, PSF_PA, SLUG_KG, Fdm
from silbridge.bridge.frames import quat_from_euler, wrap_pi
from silbridge.bridge.gnss_kernel import KernelGnss
from silbridge.bridge.imu import ImuModel
from silbridge.bridge.lowrate import Baro, Gnss, Mag
from silbridge.bridge.noise import DEFAULT_BLOCK_ROWS
from silbridge.bridge.scenario import draw_rng
from silbridge.bridge.setpoints import SetpointProgram
from silbridge.bridge.vehicle_draw import draw_vehicle
from silbridge.shm.records import Kind
from silbridge.shm.records import NS_PER_S as _NS

_FLIP_LIMIT_S = 1.0   # upside down this long in the air counts as a crash
_NEVER_NS = 2**63 - 1  # next_slow_ns when no slow record is due


class Simulator:
    """Parameters: ``imu_hz`` (None: the scenario's rate); ``block_rows`` rows per noise
    block; ``kernel_cls`` the step kernel's class (the C one; tests pass the Python
    oracle, tests/bridge/step_kernel_oracle.py, which has the same interface);
    ``jsbsim_native`` and ``gnss_in_c``: False keeps JSBSim's nodes, or the GNSS epochs,
    on their Python path (the same records, slower; for tests and measurements)."""

    def __init__(self, scenario, imu_hz: int | None = None, block_rows: int = DEFAULT_BLOCK_ROWS,
                 kernel_cls=_step.Kernel, jsbsim_native: bool = True, gnss_in_c: bool = True):
        sc = scenario
        self.scenario = sc
        self._set_rates(sc, imu_hz)
        self.step_index = 0
        self.sim_ns = 0
        self.crashed = False
        self.crash_reason = ""
        self.events: list[tuple[int, str]] = []
        home = sc.home
        jsb_seed = int(draw_rng(sc.seed, "jsbsim").integers(1, 2**31 - 1))
        self.vehicle = draw_vehicle(sc)    # [vehicle] imperfections (neutral unless asked)
        self.fdm = Fdm(self.dt_s, home.lat_deg, home.lon_deg, home.alt_m, home.heading_deg,
                       home.initial_agl_m, jsb_seed, sc.physics.model, vehicle=self.vehicle)
        self._estimate_hover()
        self._make_sensors(sc, block_rows)
        self._plan_imu_sampling()
        self.battery = Battery(sc.battery, self._ambient_c, sc.esc)   # run by the kernel
        self.faults.register("battery", self.battery.applier)
        max_imu = -(-self.imu_hz // self.physics_hz) + 1
        esc_slots = esc_telemetry.MOTORS if esc_telemetry.enabled(sc) else 0
        self.buffer = sb.StepBuffer(max_imu + 2 + 3 + 1 + 4 + esc_slots + 1)
        self._seq = [0] * len(Kind)   # records published per kind; the header seq is this mod 2^32
        self.kernel = self._make_kernel(kernel_cls)
        self.jsbsim_nodes = self._bind_native(jsbsim_native)
        # GNSS fixes released by the kernel at their step (kernels with hold(): the C one).
        self._hold_gnss = hasattr(self.kernel, "hold")
        self._held_rec = bytearray(64)
        self._attach_kernel()
        # The GNSS epochs in C from the second fix on, unless a fault needs Python's model.
        self._kgnss = KernelGnss(self.gnss, self.kernel, self._seq, self.dt_ns,
                                 self.fdm.ground_alt_m, gnss_in_c, moved=self._update_next_slow)
        self.esc = self._make_esc(sc)       # [esc] telemetry or None
        self._views = self.buffer._views
        self._prev6 = self._true6()
        self._update_next_slow()

    # --- construction, in order -----------------------------------------------------------
    def _set_rates(self, sc, imu_hz: int | None) -> None:
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

    def _estimate_hover(self) -> None:
        """Model constants and the open-loop hover estimate (motors.xml derivation)."""
        fdm = self.fdm
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
        # specific force [m/s^2] = force [lbf] / mass [slug] * ft->m
        self._lbf_to_m_s2 = FT_M / (fdm.mass_kg / SLUG_KG)

    def _make_sensors(self, sc, block_rows: int) -> None:
        """Sensor models, disturbances, setpoints and the crash limits of the scenario."""
        fdm, seed = self.fdm, sc.seed
        self._ambient_c = fdm.h_temp.get_double_value() / 1.8 - 273.15
        self.imu = ImuModel(sc.imu, seed, self.physics_hz, self.imu_hz, self._ambient_c,
                            self.omega_max_rad_s, block_rows)
        self.baro = Baro(sc.baro, seed, self.dt_s, fdm.h_pressure.get_double_value() * PSF_PA)
        self.mag = Mag(sc.mag, seed)
        self.gnss = Gnss(sc.gnss, seed, fdm.m_per_rad_lat, fdm.m_per_rad_lon)
        self.dist = Disturbances(sc, fdm, self.imu, self.dt_ns, self._event)
        self.faults = FaultEngine(sc.failures, self.dt_ns, sc.duration_s, self._event)
        self.setpoints = SetpointProgram(sc, self.dt_ns, math.radians(sc.home.heading_deg))
        # The scenario's current command (what the FC was told), for summaries.
        self.command = {"roll_rad": 0.0, "pitch_rad": 0.0, "alt_m": 0.0}
        if vibration_consts.enabled(sc) and self.imu_hz != self.physics_hz:
            raise SimulatorError(f"vibration.enabled reads the IMU chip once per physics step: "
                                 f"run at imu_hz = {self.physics_hz} (asked {self.imu_hz})")
        self._crash_descent_m_s = sc.physics.crash_descent_m_s
        self.end_on_crash = bool(sc.physics.end_on_crash)   # the run loops stop at a crash
        self._cos_crash_tilt = math.cos(math.radians(sc.physics.crash_tilt_deg))
        self._flip_steps = int(_FLIP_LIMIT_S * self.physics_hz)
        # Hubs are within 0.23 m of the CG: below that height a strike is possible.
        self._strike_check_agl_m = 0.25

    def _plan_imu_sampling(self) -> None:
        """One IMU sample per step (the kernel writes it) or a block per step (imu.py)."""
        imu_hz, physics_hz = self.imu_hz, self.physics_hz
        self._scalar_imu = imu_hz == physics_hz
        self._n_fixed = imu_hz // physics_hz if imu_hz % physics_hz == 0 else None
        if self._n_fixed:
            n = self._n_fixed
            self._offsets_ns = np.array([(j + 1) * self.dt_ns // n for j in range(n)], dtype=np.int64)
            self._frac_col = (self._offsets_ns / self.dt_ns)[:, None]

    def _stage_consts(self) -> dict:
        """The sensor stage's constants by name (bridge/src/sensor_stage.h sb_stage_consts)."""
        fdm, imu = self.fdm, self.imu
        c = {"lbf_to_m_s2": self._lbf_to_m_s2, "ft_m": FT_M, "psf_pa": PSF_PA,
             "lat0_rad": fdm.home_lat_rad, "lon0_rad": fdm.home_lon_rad,
             "m_per_rad_lat": fdm.m_per_rad_lat, "m_per_rad_lon": fdm.m_per_rad_lon,
             "agl0_m": fdm.home_agl_m, "baro_alpha": self.baro.alpha,
             "cos_crash_tilt": self._cos_crash_tilt,
             "strike_agl_m": self._strike_check_agl_m, "terrain_ft": fdm.terrain_ft,
             "dt_s": self.dt_s,
             "inv_omega_max2": imu.inv_omega_max2, "vib_accel": imu.vib_a,
             "vib_gyro": imu.vib_g, "range_accel": imu.range_a, "range_gyro": imu.range_g}
        vib = vibration_consts.stage_consts(self.scenario, fdm, self.vehicle)
        if vib["vib_on"]:   # the rotor-phase model replaces the per-motor 1/rev, 2/rev terms
            c["vib_accel"] = c["vib_gyro"] = 0.0
        return {**c, **vib}

    def _attach_battery(self) -> None:
        """The kernel runs the pack (bridge/battery/); its load reads the motors' torque."""
        pm = self.fdm.fdm.get_property_manager()
        torque = [pm.get_node(f"fcs/m{i}-torque-lbsft") for i in range(1, 5)]
        self.battery.attach(self.kernel, self.fdm.h_omega, torque)

    def _make_esc(self, sc):
        """The ESCs' telemetry on the kernel's pack when the scenario asks for it ([esc]
        telemetry_hz), else None."""
        if not esc_telemetry.enabled(sc):
            return None
        return esc_telemetry.EscTelemetry(sc.esc, self.physics_hz, self._ambient_c,
                                          self.battery.load, self.battery)

    def _make_kernel(self, kernel_cls):
        """The per-step kernel: it calls the bound methods of JSBSim's property nodes
        itself and leaves the state Python reads in self._state (ST_* slots)."""
        fdm = self.fdm
        self._state = np.zeros(_step.ST_COUNT)
        self._state[_step.ST_BARO_PA] = self.baro.filtered_pa
        self._state[_step.ST_TEMP_C] = self._ambient_c
        return kernel_cls(
            self.buffer.buf, [h.set_double_value for h in fdm.h_pwm], fdm.fdm.run,
            fdm.sample_getters(), self._state, self._stage_consts(), np.array(self.imu.phase),
            self.dt_ns, self._flip_steps, self._scalar_imu, fdm.h_gear.get_double_value() > 0)

    def _bind_native(self, wanted: bool) -> str:
        """"c" when the kernel reads and writes JSBSim's nodes from C, past their Python
        methods (bridge/src/jsbsim_native.h: the same values, proven at binding), else
        "python: " and why (`fly --json` says it as jsbsim_nodes)."""
        if not wanted:
            return "python: asked for"
        if not hasattr(self.kernel, "bind_native"):
            return "python: the kernel has no C path"
        why = self.kernel.bind_native()
        return "c" if why is None else f"python: {why}"

    def _attach_kernel(self) -> None:
        """Give the kernel its noise, bias, forces and low-rate sensors; bind the step."""
        kernel = self.kernel
        self.imu.kernel = kernel
        kernel.set_injected(*self.imu.injected)
        self.dist.attach_kernel(kernel)
        bc, mc = self.scenario.baro, self.scenario.mag
        kernel.configure_baro(bc.rate_hz, bc.offset_pa, bc.noise_pa)
        kernel.configure_mag(mc.rate_hz, tuple(mc.field_ned_gauss), tuple(mc.offset_gauss),
                             mc.noise_gauss)
        kernel.set_baro_block(self.baro.noise.next_block())
        kernel.set_mag_block(self.mag.noise.next_block())
        self._attach_battery()
        fault_appliers.register_all(self)    # gnss, baro, mag, gyro, accel, motor faults
        if self._scalar_imu:
            kernel.set_block(*self.imu.next_scalar_block())
            self._kstep = kernel.step
        else:
            self._kstep_gt = kernel.step_gt

    # --- helpers --------------------------------------------------------------------
    def _true6(self) -> tuple:
        """True (accel xyz, gyro xyz) now: the interpolation start of the next step."""
        k = self._lbf_to_m_s2
        f = self.fdm
        return (f.h_fbx.get_double_value() * k, f.h_fby.get_double_value() * k,
                f.h_fbz.get_double_value() * k, f.h_p.get_double_value(),
                f.h_q.get_double_value(), f.h_r.get_double_value())

    def _next_seq(self, kind: int) -> int:
        s = self._seq[kind]
        self._seq[kind] = s + 1
        return s & 0xFFFFFFFF

    def published_counts(self) -> dict[str, int]:
        """Records published so far per kind (not wrapped)."""
        s = self._seq
        imu, att, nav, baro, mag = self.kernel.seqs()
        if not self._scalar_imu:
            imu = s[Kind.IMU]
        return {"imu": imu, "gt_att": att, "gt_nav": nav,
                "baro": baro, "mag": mag,
                "gnss": self._kgnss.records() - (self.kernel.held if self._hold_gnss else 0),
                "setpoint": s[Kind.SETPOINT],
                **({"esc": s[Kind.ESC]} if self.esc else {}), "battery": self.battery.reports}

    # --- the step ---------------------------------------------------------------------
    def _disturb_before(self) -> int:
        """The disturbance's switch or ramp due at the next step; returns that step."""
        k = self.step_index + 1
        dist = self.dist
        if k == dist.next_step:
            dist.switch(k)
        elif dist.ramping:
            dist.update(k)
        if k == self.faults.next_step:
            self.faults.switch(k)
        if self.faults.pollers:                # they follow the pack's reports too
            kernel = self.kernel
            kernel.next_slow_ns = min(kernel.next_slow_ns, self.battery.next_ns)
        return k

    def step(self, pwm_us) -> np.ndarray:
        k = self._disturb_before()
        if self._scalar_imu:
            flags = self._kstep(pwm_us)        # IMU, GT_ATT, GT_NAV in slots 0..2
            count = flags & 0xFF
        else:
            n = self._imu_count(k)
            flags = self._kstep_gt(pwm_us, n)  # GT_ATT, GT_NAV after the n IMU slots
            self._imu_block(k * self.dt_ns, n)
            count = n + (flags & 0xFF)
        self.step_index = k
        self.sim_ns = k * self.dt_ns
        if flags & ~0xFF:
            count = self._after_step(flags, count)
        return self._views[count]

    # --- many steps (in-process lockstep) --------------------------------------------------
    @property
    def batches(self) -> bool:
        """True when step_batch can run: one IMU sample per step, written by the C kernel."""
        return self._scalar_imu and hasattr(self.kernel, "run_batch")

    def bind_lockstep(self, **kw) -> None:
        """Bind the kernel's batch to the bridge's segment and the in-process FC's C poll
        (bridge/src/step_batch.c bind_lockstep; BridgeLoop.bind_in_process_fc calls it).
        io: the int64 words the batch reports through (_step.IO_*); errors: the float64
        error sums (_step.ERR_*), whose home height and command are the simulator's."""
        self._batch_io = memoryview(kw["io"])
        self._batch_err = memoryview(kw["errors"])
        self._batch_err[_step.ERR_HOME_AGL] = self.fdm.home_agl_m
        self._batch_command()
        self.kernel.bind_lockstep(**kw)

    def _batch_command(self) -> None:
        """The scenario's command, which the batch's error samples are taken against."""
        e, cmd = self._batch_err, self.command
        e[_step.ERR_CMD_ROLL] = cmd["roll_rad"]
        e[_step.ERR_CMD_PITCH] = cmd["pitch_rad"]
        e[_step.ERR_CMD_ALT] = cmd["alt_m"]

    def step_batch(self, n: int) -> int:
        """Up to n lockstep steps, each published to the FC, polled and its PWM collected in
        C (bridge/src/step_batch.c); returns the steps done. A step whose kernel flags ask for
        Python ends the batch: its _after_step runs here, then the kernel finishes it.
        What Python does before a step (a disturbance switch or ramp) is done here for the
        first step only: the batch stops before the next switch, and ramps step one by one."""
        k = self._disturb_before()
        dist = self.dist
        if dist.ramping:
            n = 1
        elif dist.next_step > k:
            n = min(n, dist.next_step - k)
        if self.faults.next_step > k:          # a failure switches there: end the batch
            n = min(n, self.faults.next_step - k)
        kernel = self.kernel
        done = kernel.run_batch(n)
        flags = self._batch_io[_step.IO_PENDING]
        if flags:
            self.step_index = k + done
            self.sim_ns = self.step_index * self.dt_ns
            count = self._after_step(flags, flags & 0xFF)
            if flags & _step.F_SLOW_DUE:       # a setpoint may have changed the command
                self._batch_command()
            done = kernel.finish_step(count)
        self.step_index = k - 1 + done
        self.sim_ns = self.step_index * self.dt_ns
        return done

    def _after_step(self, flags: int, count: int) -> int:
        """What the kernel flagged: noise refill, ground contact, crashes, 100 Hz sensors."""
        st = self._state
        if flags & _step.F_BLOCK_DONE:
            self.kernel.set_block(*self.imu.next_scalar_block())
        if flags & _step.F_BARO_BLOCK_DONE:
            self.kernel.set_baro_block(self.baro.noise.next_block())
        if flags & _step.F_MAG_BLOCK_DONE:
            self.kernel.set_mag_block(self.mag.noise.next_block())
        if flags & _step.F_GNSS_BLOCK_DONE:
            self._kgnss.next_block()
        if flags & _step.F_GROUND_CHANGED:
            on_ground = st[_step.ST_ON_GROUND] > 0.0
            self.fdm.set_air_integrator(not on_ground)
            prev_vd = float(st[_step.ST_PREV_VD])
            if on_ground and prev_vd > self._crash_descent_m_s:
                self._crash(f"hard touchdown at {prev_vd:.2f} m/s descent")
        if flags & _step.F_TIPPED:
            cos_tilt = max(-1.0, float(st[_step.ST_COS_TILT]))
            self._crash(f"tipped over on the ground ({math.degrees(math.acos(cos_tilt)):.0f} deg)")
        if flags & _step.F_FLIPPED:
            self._crash("flipped: upside down for 1 s")
        if flags & _step.F_ROTOR_STRIKE:
            self._crash("rotor strike: a rotor hub touched the ground")
        if flags & _step.F_SLOW_DUE:
            count = self._slow_sensors(count)
            self.buffer.finish(count)
        return count

    def _slow_sensors(self, count: int) -> int:
        """GNSS records due at this step, a changed setpoint, the ESC reports and the battery's
        when due (the kernel wrote the baro and mag records)."""
        sim_ns = self.sim_ns
        st = self._state
        buf = self.buffer
        gnss = self.gnss
        if not self._kgnss.in_c and sim_ns >= gnss.schedule.next_ns:
            gnss.schedule.advance()
            lat, lon, hagl_m = st[_step.ST_LAT:_step.ST_HAGL + 1].tolist()
            vel = tuple(st[_step.ST_VEL:_step.ST_VEL + 3].tolist())
            gnss.epoch(sim_ns, lat, lon, self.fdm.ground_alt_m + hagl_m, vel)
        pending = gnss.pending
        while pending and pending[0][0] <= sim_ns:
            _, _, fix = pending.popleft()
            sb.GNSS.pack_into(buf.buf, count * 64, 4, 0, self._next_seq(4), sim_ns, 0, *fix)
            count += 1
        if self._hold_gnss:
            self._hold_pending()
        if self.faults.pollers:                # a fault following a slow quantity
            self.faults.poll(sim_ns)
        self._kgnss.place()
        if self.step_index == self.setpoints.next_step:
            _, s_roll, s_pitch, s_yaw, s_alt, mask = self.setpoints.pop()
            sb.SETPOINT.pack_into(buf.buf, count * 64, 8, 0, self._next_seq(8), sim_ns, 0,
                                  s_roll, s_pitch, s_yaw, s_alt, mask)
            count += 1
            cmd = self.command
            if mask & 1:
                cmd["roll_rad"], cmd["pitch_rad"] = s_roll, s_pitch
            if mask & 2:
                cmd["alt_m"] = s_alt
        count += self.kernel.write_battery(count)   # a report due here: after GNSS, setpoint
        esc = self.esc
        if esc is not None and esc.due(sim_ns):
            n = esc.write(buf.buf, count * 64, self._seq[Kind.ESC], sim_ns)
            self._seq[Kind.ESC] += n
            count += n
        self._update_next_slow()
        return count

    def _hold_pending(self) -> None:
        """The fixes due later go to the kernel, which writes each at its release step: that
        step then needs no Python (a batch runs on through it). Their sequence numbers are
        taken now, in release order, as the release would take them. The first fix is
        released here, ending its batch: the FC's supervisor looks up the declination at
        the first fix, after the batch that brought it (fc_sil/autoflight.py next_due_ns).
        Fixes beyond the kernel's room stay here, in order, for a later call or Python."""
        pending, kernel, rec = self.gnss.pending, self.kernel, self._held_rec
        while pending and self._seq[Kind.GNSS] and kernel.held < _step.HELD_MAX:
            due_ns, _, fix = pending.popleft()
            sb.GNSS.pack_into(rec, 0, 4, 0, self._next_seq(4), 0, 0, *fix)
            kernel.hold(due_ns, rec)

    def _update_next_slow(self) -> None:
        """Tell the kernel the sim time of the next GNSS, setpoint or ESC record (it writes
        the battery's itself, and the GNSS's while it makes them)."""
        due = [] if self._kgnss.in_c else [self.gnss.schedule.next_ns]
        if self.gnss.pending:
            due.append(self.gnss.pending[0][0])
        if self.setpoints.next_step > 0:
            due.append(self.setpoints.next_step * self.dt_ns)
        if self.esc is not None:
            due.append(self.esc.schedule.next_ns)
        self.kernel.next_slow_ns = min(due, default=_NEVER_NS)

    def _imu_count(self, k: int) -> int:
        """IMU samples carried by step k (imu.py: (k-1) dt < t_m <= k dt)."""
        if self._n_fixed:
            return self._n_fixed
        m0 = ((k - 1) * self.dt_ns * self.imu_hz) // _NS + 1
        m1 = (k * self.dt_ns * self.imu_hz) // _NS
        return max(0, m1 - m0 + 1)

    def _imu_block(self, sim_ns: int, n: int) -> None:
        """Oversampled (or sub-sampled) IMU records of this step into slots 0..n-1."""
        st = self._state.tolist()
        cur6 = (st[3], st[4], st[5], st[0], st[1], st[2])   # accel xyz, gyro xyz
        base_ns = sim_ns - self.dt_ns
        if self._n_fixed:
            times = self._offsets_ns + base_ns
            frac_col = self._frac_col
        else:
            m0 = (base_ns * self.imu_hz) // _NS + 1
            times = (np.arange(m0, m0 + n, dtype=np.int64) * _NS) // self.imu_hz
            frac_col = ((times - base_ns) / self.dt_ns)[:, None]
        buf = self.buffer
        if n:
            buf.write_imu_headers(n, self._seq[1] & 0xFFFFFFFF, times)
            self._seq[1] += n
        o1, o2, o3, o4 = st[_step.ST_OMEGA:_step.ST_OMEGA + 4]
        self.imu.step_block(self._prev6, cur6, frac_col, o1, o2, o3, o4, buf.imu_payload(n))
        self._prev6 = cur6

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
            "imu_temp_c": (float(self._state[_step.ST_TEMP_C]) if self._scalar_imu
                           else self.imu.temp_c),
            "crashed": self.crashed,
        }

    def roll_pitch_alt(self) -> tuple:
        """True roll, pitch [rad] and height above home [m] after the last step (cheap:
        the kernel's state, for per-step summaries; truth() has everything)."""
        st = self._state
        return (float(st[_step.ST_EULER]), float(st[_step.ST_EULER + 1]),
                float(st[_step.ST_HAGL]) - self.fdm.home_agl_m)

    def rotor_rad_s(self) -> list:
        """Rotor speeds after the last step, motors 1..4 [rad/s] (JSBSim fcs/mN-omega-rad_s,
        from the kernel's state: cheap enough for every step; the /rotor log channel)."""
        return self._state[_step.ST_OMEGA:_step.ST_OMEGA + 4].tolist()

    def thrust_n(self) -> tuple:
        """Current rotor thrusts [N], motors 1..4."""
        return tuple(self.fdm.fdm[f"fcs/m{i}-thrust-lbs"] * LBF_N for i in range(1, 5))
