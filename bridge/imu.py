"""IMU model: body-FRD specific force and angular rate as an ICM-42688-class sensor reads them.

Per sample:  accel = f_true + b_a + b_a,T + vib_a + n_a,   gyro = w_true + b_g + b_g,T + b_inj + vib_g + n_g
- f_true: specific force at the CG (JSBSim forces/fb*-total / mass, lag-free);
  w_true: body rate (velocities/{p,q,r}). The Earth's rotation (7.3e-5 rad/s,
  under 1 % of the turn-on bias sigma) is left out: it saves three property
  reads per step on the hot path.
- b: turn-on bias (drawn once per run) plus a random walk (per physics step).
- b_T: temperature coefficient (drawn once, within the datasheet's +-) times
  (die temperature - 25 C); the die warms from ambient by a first-order rise.
  Turn-on, walk and temperature parts are computed per block of physics steps
  (vectorised); per step the hot path adds one precomputed row.
- b_inj: injected gyro bias (scenario [imu] gyro_bias_rad_s plus S2 disturbances).
- vib: rotor-synchronous vibration, per motor proportional to (omega/omega_max)^2:
  1/rev imbalance in the rotor plane (x, y; rotating with the spin direction)
  and 2/rev blade-pass ripple on z, at each sample's own rotor phase.
  With [vibration] enabled (issue 26) these two terms are off: the sensor stage's
  rotor-phase model, frame, mount and IMU chip (bridge/src/vibration.h, imu_chip.h;
  docs/explanation/vibrating-world.md) give the vibration, on the scalar path only.
- n: white noise of the datasheet density, one-sided: sigma = ND * sqrt(rate/2)
  (the noise of a sensor whose bandwidth is the Nyquist band of its output rate).
Outputs clip at the sensor's full scale.

Rates: ``imu_hz`` samples per second, sample m at t_m = floor(m * 1e9 / imu_hz) ns
(m = 1, 2, ...); physics step k carries the samples with (k-1) dt < t_m <= k dt.
When imu_hz is a multiple n of the physics rate that is exactly n samples per
step at (k-1) dt + (j+1) dt / n, the last coinciding with the step; otherwise
steps carry a varying count (possibly 0). Between physics steps the true signals
are interpolated linearly from the previous to the current state; noise and
vibration are generated per sample, vectorised over the step.
"""

from __future__ import annotations

import math

import numpy as np

from silbridge.bridge import _step
from silbridge.bridge.noise import DEFAULT_BLOCK_ROWS, NormalRows
from silbridge.bridge.scenario import draw_rng

TEMP_REF_C = 25.0   # datasheet reference temperature of the offset figures
_TWO_PI = 2.0 * math.pi
# Spin direction seen from above, ArduCopter quad X: motors 1, 2 CCW; 3, 4 CW.
# +1 = CW. A CCW rotor's imbalance vector turns from forward toward left (-y).
SPIN_CW = (-1.0, -1.0, 1.0, 1.0)


class BiasWalk:
    """A 6-channel random walk (gyro xyz, accel xyz) advanced once per physics step.

    Increments come from a NormalRows stream; each block is accumulated with one
    cumsum seeded by the last value, the same additions in the same order a
    scalar loop would do, so the values do not depend on the block size.
    """

    def __init__(self, seed: int, sigma_per_step6, block_rows: int = DEFAULT_BLOCK_ROWS):
        self._src = NormalRows(seed, "imu:bias_walk", 6, block_rows)
        self._sigma = np.asarray(sigma_per_step6, dtype=float)
        self._last = np.zeros((1, 6))

    def next_block(self) -> np.ndarray:
        walk = np.cumsum(np.vstack((self._last, self.next_increments())), axis=0)[1:]
        self._last = walk[-1:].copy()
        return walk

    def next_increments(self) -> np.ndarray:
        """The next block's increments, for a caller that accumulates them itself into
        `last` (_step.imu_noise_rows)."""
        return self._src.next_block() * self._sigma

    @property
    def last(self) -> np.ndarray:
        """The walk's value now (6,), a view: an accumulating caller updates it in place."""
        return self._last[0]


# From this many IMU samples per physics step on, evenly spaced samples use the rotation
# recurrence in step_block (the cosines cost ~3/4 of the step at 2 MHz).
_ROTATION_MIN_SAMPLES = 256


def _even_step(frac) -> float:
    """The common spacing d when frac[j] = (j + 1) d for every j (to 1e-12), else 0."""
    n = len(frac)
    d = frac[-1] / n
    ok = np.allclose(frac, d * np.arange(1, n + 1), rtol=0.0, atol=1e-12)
    return float(d) if ok else 0.0


class ImuModel:
    """State and maths of one IMU. With one sample per physics step (imu_hz ==
    physics_hz) the simulator's step kernel samples from `next_scalar_block` rows and
    `injected`; otherwise the simulator calls `step_block` (any count) once per step."""

    def __init__(self, cfg, seed: int, physics_hz: int, imu_hz: int, ambient_c: float,
                 omega_max_rad_s: float, block_rows: int = DEFAULT_BLOCK_ROWS):
        dt_s = 1.0 / physics_hz
        self.dt_s = dt_s
        self.physics_hz = physics_hz
        self.imu_hz = imu_hz
        self.block_rows = block_rows
        sig_g = cfg.gyro_noise_density * math.sqrt(imu_hz / 2.0)
        sig_a = cfg.accel_noise_density * math.sqrt(imu_hz / 2.0)
        self.sigma_gyro = sig_g
        self.sigma_accel = sig_a
        rng = draw_rng(seed, "imu:turn_on")
        self.turn_on = (rng.standard_normal(3) * cfg.gyro_turn_on_bias).tolist() + \
                       (rng.standard_normal(3) * cfg.accel_turn_on_bias).tolist()
        rng = draw_rng(seed, "imu:tempco")
        self.tempco = (rng.uniform(-1, 1, 3) * cfg.gyro_tempco).tolist() + \
                      (rng.uniform(-1, 1, 3) * cfg.accel_tempco).tolist()
        self.phase = draw_rng(seed, "imu:vib_phase").uniform(0, _TWO_PI, 4).tolist()
        sq = math.sqrt(dt_s)
        self.walk = BiasWalk(seed, [cfg.gyro_bias_walk * sq] * 3 + [cfg.accel_bias_walk * sq] * 3,
                             block_rows)
        # White noise, pre-scaled; scalar path order (gyro, accel), block path (accel, gyro).
        if imu_hz == physics_hz:
            self.white = NormalRows(seed, "imu:white", 6, block_rows, [sig_g] * 3 + [sig_a] * 3)
        else:
            self.white = NormalRows(seed, "imu:white", 6, block_rows, [sig_a] * 3 + [sig_g] * 3)
        self.const_gyro_bias = tuple(cfg.gyro_bias_rad_s)
        self.injected = list(self.const_gyro_bias)   # + disturbances, FRD rad/s
        # Die temperature after physics step s (closed form, so block boundaries
        # never change a value): T_s = T_ss + (T_0 - T_ss) exp(-s dt / tau).
        self.temp_c = ambient_c
        self.temp_0_c = ambient_c
        self.temp_ss_c = ambient_c + cfg.temp_rise_k
        self.temp_tau_s = cfg.temp_tau_s
        self._turn_on = np.array(self.turn_on)
        self._tempco = np.array(self.tempco)
        self._steps_done = 0    # physics steps covered by the blocks drawn so far
        self.inv_omega_max2 = 1.0 / (omega_max_rad_s * omega_max_rad_s)
        self.vib_a = cfg.vib_accel
        self.vib_g = cfg.vib_gyro
        self.range_a = cfg.accel_range_m_s2
        self.range_g = cfg.gyro_range_rad_s
        # Block path, channel order (accel xyz, gyro xyz).
        self._lim6_ag = np.array([self.range_a] * 3 + [self.range_g] * 3, dtype=np.float32)
        # Clip only when the true signal comes near full scale (vibration and noise
        # are orders of magnitude below it): the check is six Python compares.
        self._lim_true = 0.8 * self.range_a
        self._lim_true_g = 0.8 * self.range_g
        self._a_mats: dict[int, tuple] = {}
        self._b_mat = np.zeros((14, 7))
        # Vibration weights: rows cos p (4), sin p (4), sin 2p (4); columns accel
        # xyz, gyro xyz; scaled per step by (omega / omega_max)^2 of each rotor.
        vw = np.zeros((12, 7))   # column 6 (temperature) stays 0
        spin = np.array(SPIN_CW)
        vw[0:4, 0] = cfg.vib_accel          # a_x: cos p
        vw[4:8, 1] = cfg.vib_accel * spin   # a_y: spin * sin p
        vw[8:12, 2] = 0.5 * cfg.vib_accel   # a_z: blade pass, half amplitude
        vw[4:8, 3] = cfg.vib_gyro * spin    # g_x
        vw[0:4, 4] = cfg.vib_gyro           # g_y
        vw[8:12, 5] = 0.5 * cfg.vib_gyro    # g_z
        self._vib_w = vw
        # Current block: slow biases (turn-on + temperature + walk, gyro then accel)
        # and die temperature per step (the block path's; the step kernel gets its
        # own rows from next_scalar_block).
        self._slow = np.zeros((0, 6))
        self._temps: list = []
        self._pos = 0
        # The simulator's step kernel, which samples the one-per-step IMU (None: unattached).
        self.kernel = None

    def set_injected_gyro_bias(self, bias_frd_rad_s) -> None:
        """Disturbance bias on top of the scenario's constant one."""
        c = self.const_gyro_bias
        self.injected = [c[0] + bias_frd_rad_s[0], c[1] + bias_frd_rad_s[1], c[2] + bias_frd_rad_s[2]]
        if self.kernel is not None:
            self.kernel.set_injected(*self.injected)

    def bias6(self) -> list:
        """Total bias (gyro xyz rad/s, accel xyz m/s^2) of the last step, for truth."""
        scalar = self.kernel is not None and self.imu_hz == self.physics_hz
        pos = self.kernel.pos if scalar else self._pos
        if not pos:
            return list(self.injected) + [0.0] * 3
        row = self._slow[pos - 1].tolist()
        j = self.injected
        return [row[0] + j[0], row[1] + j[1], row[2] + j[2], row[3], row[4], row[5]]

    def _next_temps(self, rows: int) -> np.ndarray:
        """Die temperatures of the next `rows` physics steps."""
        s = np.arange(self._steps_done + 1, self._steps_done + rows + 1)
        self._steps_done += rows
        return self.temp_ss_c + (self.temp_0_c - self.temp_ss_c) * np.exp(
            -s * (self.dt_s / self.temp_tau_s))

    def _next_block(self) -> np.ndarray:
        """Slow biases of the next block of physics steps into _slow (the block path);
        their die temperatures are returned and kept in _temps."""
        walk = self.walk.next_block()
        temps = self._next_temps(walk.shape[0])
        self._slow = walk + self._turn_on + np.multiply.outer(temps - TEMP_REF_C, self._tempco)
        self._temps = temps.tolist()
        self._pos = 0
        return temps

    def next_scalar_block(self) -> tuple:
        """The next block for the one-sample-per-step path (the step kernel samples):
        (slow biases + white noise (rows, 6) gyro xyz then accel xyz, die temperature
        (rows)). The maths of a sample: bridge/src/step_maths.c sb_imu_scalar. The slow
        biases are _next_block's, summed in one C pass (bridge/src/imu_noise.h) where
        numpy took a dozen: the same values, to the bit."""
        inc = self.walk.next_increments()
        temps = self._next_temps(inc.shape[0])
        self._slow = np.empty_like(inc)
        out = np.empty_like(inc)
        _step.imu_noise_rows(inc, self.white.next_block(), temps, self._turn_on, self._tempco,
                             TEMP_REF_C, self.walk.last, self._slow, out)
        return out, temps

    def step_block(self, prev6, cur6, frac_col: np.ndarray, o1, o2, o3, o4,
                   out: np.ndarray) -> None:
        """Samples at fractions frac_col[:, 0] of the step (0 < frac <= 1), from the true
        (accel xyz, gyro xyz) at the previous and current step (Python sequences of 6
        floats) and the rotor speeds, written into `out` (n, 7): accel xyz, gyro xyz,
        temperature (float32 record payload view, strided).

        Numpy calls are what cost here (~1 us each on small arrays, whatever n), so a
        step is two products: the rotor phases [1, frac] @ [p0; omega dt] and one
        cos() of them give A = [1, frac, cos p, sin p, sin 2p] per sample; then
        A @ B with B = [biased start + temperature, change over the step, vibration
        weights x (omega / omega_max)^2] goes straight into `out`; the pre-scaled
        white noise is added there."""
        if self._pos >= self._slow.shape[0]:
            self._next_block()
        pos = self._pos
        self._pos = pos + 1
        self.temp_c = t = self._temps[pos]
        sl = self._slow[pos].tolist()
        j = self.injected
        dt = self.dt_s
        p1, p2, p3, p4 = self.phase
        self.phase = [(p1 + o1 * dt) % _TWO_PI, (p2 + o2 * dt) % _TWO_PI,
                      (p3 + o3 * dt) % _TWO_PI, (p4 + o4 * dt) % _TWO_PI]
        n = frac_col.shape[0]
        if n == 0:
            return
        # A's first two columns depend only on the sample fractions: cached per n
        # while the caller passes the same fraction array (fixed samples per step).
        a_mat, f_mat, src, even = self._a_mats.get(n, (None, None, None, 0.0))
        if src is not frac_col:
            a_mat = np.empty((n, 14))
            a_mat[:, 0] = 1.0
            a_mat[:, 1] = frac_col[:, 0]
            f_mat = a_mat[:, 0:2].copy()
            even = _even_step(frac_col[:, 0]) if n >= _ROTATION_MIN_SAMPLES else 0.0
            self._a_mats[n] = (a_mat, f_mat, frac_col, even)
        hp = 0.5 * math.pi
        w1, w2, w3, w4 = o1 * dt, o2 * dt, o3 * dt, o4 * dt
        if even:
            # Many evenly spaced samples (the stress test's 100 kHz .. 2 MHz): the rotor phase
            # advances by the same angle each sample, so one complex rotation per sample and
            # rotor (a cumulative product) replaces 12 cosines per sample; sin 2p = 2 sin p cos p.
            # Rounding drifts ~1e-13 rad over 2000 samples, far below the vibration model's
            # meaning; fewer samples per step keep the cosines (and their exact bits).
            z = np.cumprod(np.broadcast_to(
                np.exp(1j * even * np.array((w1, w2, w3, w4))), (n, 4)), axis=0)
            z *= np.exp(1j * np.array((p1, p2, p3, p4)))
            a_mat[:, 2:6] = z.real
            a_mat[:, 6:10] = z.imag
            np.multiply(a_mat[:, 2:6], a_mat[:, 6:10], out=a_mat[:, 10:14])
            a_mat[:, 10:14] *= 2.0
        else:
            phase_rows = np.array(((p1, p2, p3, p4, p1 - hp, p2 - hp, p3 - hp, p4 - hp,
                                    2 * p1 - hp, 2 * p2 - hp, 2 * p3 - hp, 2 * p4 - hp),
                                   (w1, w2, w3, w4, w1, w2, w3, w4,
                                    2 * w1, 2 * w2, 2 * w3, 2 * w4)))
            np.cos(f_mat @ phase_rows, out=a_mat[:, 2:])
        k = self.inv_omega_max2
        s2 = (o1 * o1 * k, o2 * o2 * k, o3 * o3 * k, o4 * o4 * k)
        b_mat = self._b_mat
        # Bias order (gyro, accel) -> sample order (accel, gyro); column 6 = temperature.
        b_mat[0:2] = ((prev6[0] + sl[3], prev6[1] + sl[4], prev6[2] + sl[5],
                       prev6[3] + sl[0] + j[0], prev6[4] + sl[1] + j[1], prev6[5] + sl[2] + j[2],
                       t),
                      (cur6[0] - prev6[0], cur6[1] - prev6[1], cur6[2] - prev6[2],
                       cur6[3] - prev6[3], cur6[4] - prev6[4], cur6[5] - prev6[5], 0.0))
        np.multiply(self._vib_w, np.array(s2 * 3)[:, None], out=b_mat[2:])
        np.matmul(a_mat, b_mat, out=out)
        six = out[:, 0:6]
        six += self.white.take(n)
        lim, lim_g = self._lim_true, self._lim_true_g
        if not (-lim < cur6[0] < lim and -lim < cur6[1] < lim and -lim < cur6[2] < lim
                and -lim_g < cur6[3] < lim_g and -lim_g < cur6[4] < lim_g
                and -lim_g < cur6[5] < lim_g):
            np.minimum(six, self._lim6_ag, out=six)
            np.maximum(six, -self._lim6_ag, out=six)
