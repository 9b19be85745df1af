"""FlightCore: the whole C flight-controller chain behind one Python object.

The hot loop stays in C: `step_batch(records)` hands a numpy array of 64-byte
shared-memory records of mixed kinds (silbridge.shm.records) to the extension
in one call and gets back the PWM records and one STATUS_DTYPE row per PWM
tick. Between batches the host sets parameters (by name; validated, effective
at once), feature switches, arming and targets.

Host-side parameters (FC_HOST in fc_params.def) are validated and kept here
too, so one object answers for every parameter the FC declares.

Not thread-safe by itself: the extension holds the GIL during every call, so
calls from two threads never interleave inside C, but a caller that needs a
consistent group of changes (several parameters at once) must serialise them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from . import params as P
from .errors import CoreBuildError, InputError, ParamError
from .status import STATUS_DTYPE

try:
    from . import _core
except ImportError as exc:  # pragma: no cover - only without a build
    raise CoreBuildError(
        "the compiled flight-controller core is missing; build it with "
        "`SILBRIDGE_EXT=core python setup.py build_ext --inplace` (or `make setup`)") from exc

from silbridge.shm.records import PWM_DTYPE, RECORD_SIZE

_STATUS_TEXT = {
    _core.FC_ERR_ARG: "invalid argument",
    _core.FC_ERR_RANGE: "out of range",
    _core.FC_ERR_NONFINITE: "not finite",
    _core.FC_ERR_INDEX: "unknown parameter",
    _core.FC_ERR_TYPE: "not an integer",
}


def _check(code: int, what: str) -> None:
    if code != _core.FC_OK:
        raise InputError(f"{what}: {_STATUS_TEXT.get(code, code)}; the previous value is kept")


@dataclass(frozen=True)
class EscReport:
    """One ESC's latest telemetry as the FC holds it."""

    motor: int                # 0-based motor index
    sim_ns: int               # time of the report [ns]
    rpm: float
    voltage_v: float
    current_a: float
    temperature_c: float
    consumption_mah: float
    count: int                # reports received from this ESC (wraps at 2^32)


class FlightCore:
    """One flight controller: parameters, inputs, and the C chain."""

    def __init__(self, params: dict | None = None):
        self._c = _core.Core()
        self._host = {p.name: p.default for p in P.PARAMS if p.host}
        for name, value in (params or {}).items():
            self.set_param(name, value)

    # ---- parameters ------------------------------------------------------

    def set_param(self, name: str, value) -> float:
        """Validate and store; returns the value as stored. ParamError keeps the old value."""
        d = P.lookup(name)
        v = d.validate(value)
        if d.host:
            self._host[d.name] = v
            return v
        code = self._c.set_param(d.index, v)
        if code == _core.FC_ERR_RANGE:
            raise ParamError(f"{d.name}={v:g} is refused: it contradicts another parameter "
                             "(MOT_PWM_MIN + 100 <= MOT_PWM_MAX, MOT_SPIN_ARM <= MOT_SPIN_MIN < "
                             "MOT_SPIN_MAX, INS_HNTCH/HNTC2_FREQ > _BW / 2); value kept")
        if code != _core.FC_OK:
            raise ParamError(f"{d.name}={value!r} refused by the core: "
                             f"{_STATUS_TEXT.get(code, code)}; value kept")
        return self._c.get_param(d.index)

    def get_param(self, name: str) -> float:
        d = P.lookup(name)
        return self._host[d.name] if d.host else self._c.get_param(d.index)

    def params(self) -> dict[str, float]:
        """name -> current value of every declared parameter, in index order."""
        return {p.name: (self._host[p.name] if p.host else self._c.get_param(p.index))
                for p in P.PARAMS}

    def set_feature(self, feature: str, enabled: bool) -> None:
        """Switch a stabilisation feature (params.FEATURES) on or off at run time."""
        self.set_param(P.feature_param(feature), 1 if enabled else 0)

    def feature_enabled(self, feature: str) -> bool:
        return self.get_param(P.feature_param(feature)) != 0

    # ---- inputs ----------------------------------------------------------

    def arm(self) -> None:
        self._c.set_armed(True)

    def disarm(self) -> None:
        self._c.set_armed(False)

    @property
    def armed(self) -> bool:
        return bool(self._c.inputs()["armed"])

    def set_attitude_target(self, roll_rad: float, pitch_rad: float, *,
                            yaw_rad: float | None = None,
                            yaw_rate_rad_s: float | None = None) -> None:
        """Roll and pitch [rad]; yaw either as an angle (held when ATC_ANG_YAW_P > 0)
        or as a rate. Leaving both out keeps the present yaw mode."""
        if yaw_rad is not None and yaw_rate_rad_s is not None:
            raise InputError("give either yaw_rad or yaw_rate_rad_s, not both")
        _check(self._c.set_attitude_target(roll_rad, pitch_rad), "attitude target")
        if yaw_rad is not None:
            _check(self._c.set_yaw_target(yaw_rad), "yaw target")
        if yaw_rate_rad_s is not None:
            _check(self._c.set_yaw_rate_target(yaw_rate_rad_s), "yaw rate target")

    def set_altitude_target(self, alt_m: float) -> None:
        """Hold an altitude above home [m, up]; above SB_LIFTOFF_ALT this takes off."""
        _check(self._c.set_altitude_target(alt_m), "altitude target")

    def set_climb_rate(self, climb_m_s: float) -> None:
        """Follow a climb rate [m/s, up] (limited by PILOT_SPEED_UP/DN)."""
        _check(self._c.set_climb_target(climb_m_s), "climb-rate target")

    def set_throttle(self, throttle: float) -> None:
        """Direct throttle 0..1 of the PWM range (STABILIZE-style manual)."""
        _check(self._c.set_throttle(throttle), "throttle")

    def set_accel_reference(self, accel_ned_m_s2) -> None:
        """Optional kinematic acceleration of the vehicle, NED [m/s^2] (e.g. from GNSS
        velocity), so the estimator's accelerometer correction holds through sustained
        accelerations (see fc_mahony.h). Ignored 0.5 s after the last call."""
        _check(self._c.set_accel_ref(tuple(float(v) for v in accel_ned_m_s2)),
               "acceleration reference")

    def inputs(self) -> dict:
        return self._c.inputs()

    def set_scenario_setpoints(self, enabled: bool) -> None:
        """Consume (default) or skip the scenario's SETPOINT records in step_batch;
        the MAVLink vehicle switches them off so only the GCS commands the vehicle."""
        self._c.set_setpoint_input(bool(enabled))

    def last_seen_ns(self) -> tuple[int, ...]:
        """Sim time [ns] of the last record of each kind (index = shm Kind; -1 never)."""
        return self._c.last_seen()

    def take_accel_mean(self) -> tuple[float, float, float] | None:
        """Mean raw IMU specific force (FRD, m/s^2) since the last call, or None."""
        return self._c.take_accel_mean()

    # ---- stepping ----------------------------------------------------------

    def step_batch(self, records: np.ndarray, pwm_out: np.ndarray | None = None,
                   status_out: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Consume a batch of records of mixed kinds; returns (pwm, status).

        pwm is a PWM_DTYPE array (one record per PWM tick now due), status the
        matching STATUS_DTYPE rows. Give preallocated pwm_out/status_out
        (at least `pwm_bound(records)` rows) to avoid the two allocations; the
        results are then views into them.
        """
        recs = np.ascontiguousarray(records)
        if recs.dtype.itemsize != RECORD_SIZE:
            raise InputError(f"records must be {RECORD_SIZE}-byte slots (shm.records dtypes), "
                             f"got itemsize {recs.dtype.itemsize}")
        if pwm_out is None or status_out is None:
            n = self._c.pwm_bound(recs)
            if pwm_out is None:
                pwm_out = np.zeros(n, dtype=PWM_DTYPE)
            if status_out is None:
                status_out = np.zeros(n, dtype=STATUS_DTYPE)
        if pwm_out.dtype.itemsize != RECORD_SIZE or status_out.dtype != STATUS_DTYPE:
            raise InputError("pwm_out must be PWM_DTYPE and status_out STATUS_DTYPE")
        k = self._c.step_batch(recs, pwm_out, status_out)
        return pwm_out[:k], status_out[:k]

    # ---- the FC loop's surface (fc_sil/fc_loop.py) --------------------------

    def bind_batch(self, records: np.ndarray, pwm_out: np.ndarray,
                   status_out: np.ndarray) -> Callable[[int], int]:
        """Bind the loop's record, PWM and status arrays once; returns step(n) -> PWM
        records written: step_batch over the first n bound records, nothing parsed or
        allocated per call (the C method itself, so a poll pays no Python frame here)."""
        self._c.bind_batch(records, pwm_out, status_out)
        return self._c.step_bound

    def attach_router(self, capsule, *, fc_sim_word: int, latency_ns: np.ndarray,
                      period_ns: np.ndarray, e2e_ns: np.ndarray,
                      words: np.ndarray) -> Callable[[], int] | None:
        """Hand the segment (FcTransport.c_capsule()) to the C record router
        (fc_sil/ext/record_router.c); returns poll() -> records consumed, which pops, steps
        over the bound arrays (bind_batch first), pushes, acknowledges fc_sim_word and keeps
        the loop's statistics rings and counters. A core that must see records in Python
        returns None and the loop polls in Python."""
        self._c.attach_io(capsule, fc_sim_word=fc_sim_word, latency_ns=latency_ns,
                          period_ns=period_ns, e2e_ns=e2e_ns, words=words)
        return self._c.poll_io

    def detach_router(self) -> None:
        """Let go of the segment (before it closes); the router's poll then raises."""
        self._c.attach_io(None)

    def bind_log(self, queues, **targets) -> None:
        """Have the C core append what it consumes to a log's queues (Core.bind_log,
        fc_sil/ext/core_log.c; tools/loop/run_log.py capture_fc); bind_log(None) stops."""
        self._c.bind_log(queues, **targets)

    def pwm_bound(self, records: np.ndarray) -> int:
        """Most PWM ticks step_batch(records) can emit (to size preallocated outputs)."""
        return self._c.pwm_bound(np.ascontiguousarray(records))

    def step_imu(self, sim_ns: int, accel_frd_m_s2, gyro_frd_rad_s) -> int:
        """One IMU sample outside a batch; returns the C status code (0 ok)."""
        return self._c.imu(int(sim_ns), tuple(map(float, accel_frd_m_s2)),
                           tuple(map(float, gyro_frd_rad_s)))

    def step_baro(self, sim_ns: int, pressure_pa: float) -> int:
        return self._c.baro(int(sim_ns), float(pressure_pa))

    def step_mag(self, sim_ns: int, field_frd_gauss) -> int:
        return self._c.mag(int(sim_ns), tuple(map(float, field_frd_gauss)))

    def step_gt_att(self, sim_ns: int, q_wxyz) -> int:
        return self._c.gt_att(int(sim_ns), tuple(map(float, q_wxyz)))

    def step_gt_nav(self, sim_ns: int, pos_ned_m, vel_ned_m_s) -> int:
        return self._c.gt_nav(int(sim_ns), tuple(map(float, pos_ned_m)),
                              tuple(map(float, vel_ned_m_s)))

    def pwm_due(self) -> int | None:
        """Sim time [ns] of the next PWM tick if it is due, else None."""
        return self._c.pwm_due()

    def step_pwm(self, tick_ns: int) -> tuple[int, int, int, int]:
        """Step one PWM tick (see pwm_due); returns the four outputs [us]."""
        return self._c.pwm_step(int(tick_ns))

    def status(self) -> np.void:
        """The status snapshot of the last PWM tick (one STATUS_DTYPE row)."""
        return np.frombuffer(self._c.status_bytes(), dtype=STATUS_DTYPE)[0]

    def counters(self) -> dict:
        return self._c.counters()

    def gnss(self) -> dict | None:
        """The last GNSS fix routed to the FC, or None."""
        return self._c.gnss()

    def innovations(self) -> dict:
        """The estimators' latest innovations (read-only): baro_innov_m (baro - vertical
        estimate, in flight), baro_alt_m, have_baro, last_baro_ns, heading_err_rad (attitude
        yaw - magnetometer heading), heading_age_s, heading_valid."""
        return self._c.innovations()

    def set_vibe_comp(self, on: bool) -> None:
        """The altitude loop's vibration-resistant law (the vibration failsafe's action)."""
        self._c.set_vibe_comp(bool(on))

    def reset(self) -> None:
        """Back to power-on state (disarmed, targets cleared); parameters kept."""
        self._c.reset()

    # ---- what VIBRATION and ESC_TELEMETRY_1_TO_4 report (core_telem.c) ------

    def vibration(self) -> tuple[float, float, float, int]:
        """ArduPilot's vibration levels x, y, z [m/s^2] of the accel samples consumed so far
        and the accelerometer's clip count (fc_sil/core/fc_vibe.h)."""
        x, y, z, clips, _samples = self._c.vibration()
        return x, y, z, clips

    def battery(self) -> tuple:
        """The latest BATTERY record the router kept (the bridge's pack): (count, sim_ns or -1,
        voltage_v, current_a, consumed_mah, remaining, temperature_c, lowest_cell_v,
        cell_count); fc_sil/battery.py reads it."""
        return self._c.battery()

    def esc_reports(self) -> list[EscReport]:
        """The latest telemetry of each reporting ESC, motor order (fc_sil/core/fc_esc.h);
        empty while no ESC has reported."""
        _reports, _rejected, count, rows = self._c.esc_reports()
        return [EscReport(m, *row) for m, row in enumerate(rows[:count]) if row[0] >= 0]


    # ---- the in-flight FFT (FFT_* parameters, fc_fft.h; fc_sil/ext/core_fft.c) ----

    def bind_fft_log(self, ftn1, ftn2) -> None:
        """FTN1/FTN2 rows at 10 Hz into these bytearrays while the FFT runs
        (tools/logs/ftn_log.py); None, None: off."""
        self._c.bind_fft_log(ftn1, ftn2)

    def fft_ftn(self) -> tuple[np.ndarray, np.ndarray]:
        """The FTN1 row and FTN2 rows as they would be logged now."""
        from .ftn_rows import FTN1_DTYPE, FTN2_DTYPE
        r1, r2 = self._c.fft_ftn()
        return np.frombuffer(r1, FTN1_DTYPE), np.frombuffer(r2, FTN2_DTYPE)

    def fft_calibrating(self) -> bool:
        """FFT_ENABLE is set and the FFT still learns its noise reference (pre-arm)."""
        return self._c.fft_calibrating()

    def fft_notch_freqs(self, throttle_out: float) -> tuple[float, ...]:
        """The frequencies [Hz] the harmonic notch's MODE 4 reads now, fundamental first."""
        return self._c.fft_notch_freqs(float(throttle_out))

    def fft_calibration(self) -> tuple[float, float, float] | None:
        """(sample kHz, half bin Hz, output Hz) of ArduCopter's "FFT: calibrated" text once
        the noise reference is learned; None while the FFT is off or still learning."""
        return self._c.fft_calibration()

    def fft_esc_noise(self, dt_s: float) -> list[tuple[int, float, float]]:
        """One FFT_OPTIONS bit 1 check (every 0.2 s, dt_s since the last): (motor 1.., SNR dB,
        motor Hz) of each motor to warn about now (fc_fft_esc.c)."""
        return self._c.fft_esc_noise(float(dt_s))

    # ---- system identification (SID_* parameters, fc_sysid.h) --------------

    def sysid_start(self) -> None:
        """Start the SID_* frequency sweep now (as entering ArduCopter's SYSTEMID mode)."""
        if self._c.sysid_start() != _core.FC_OK:
            raise InputError("the sweep cannot start: set SID_AXIS (1-13) and SID_F_START_HZ, "
                             "SID_F_STOP_HZ > 0, SID_T_REC longer than 2 / SID_F_START_HZ")

    def sysid_stop(self) -> None:
        self._c.sysid_stop()

    def sysid_sample(self) -> tuple:
        """(sim_ns, active, axis, t_s, sample, freq_hz, runs, rate_target x3 [rad/s],
        rate x3 [rad/s], pid_out x3 [us], mixer_in x3 [us]) of the latest step."""
        return self._c.sysid_sample()
