"""GNSS innovation gate: which fixes the position estimator fuses, and when it resets to GNSS.

ArduCopter's EKF3 (AP_NavEKF3_PosVelFusion.cpp, AP_NavEKF3_Control.cpp) tests each GNSS fix
against its delayed state before fusing it; we apply the same rules to our complementary
filter (pos_est.py), which has no covariance matrix, so the estimate's uncertainty is modelled
(see ``GnssGate.sigmas``). Definitions, per fix, with innovations = estimate - measurement at
the fix's time:

* test ratio (EKF3's ``posTestRatio``/``velTestRatio``, the squared form):
  ``sum(innov_i^2) / (gate^2 * sum(var_i))`` with ``gate = max(EK3_*_I_GATE / 100, 1)``, summed
  over north and east for position and over north, east (and down when the fix carries it)
  for velocity. EKF_STATUS_REPORT carries its square root, so a reported 1.0 is at the gate.
* innovation variance per axis = the estimate's variance + the measurement's:
  position ``sigma_p^2 + max(eph, EK3_POSNE_M_NSE)^2`` (eph: the fix's reported horizontal
  accuracy, capped at 100 m as EKF3 does); velocity ``sigma_v^2 + EK3_VELNE_M_NSE^2 +
  (0.05 |a|)^2`` (EKF3's data-check noise: not the reported speed accuracy, plus its
  manoeuvre term, ``gpsNEVelVarAccScale`` = 0.05 per m/s^2).
* a position fix is fused when its ratio is below 1. One that is not, and every later one,
  is rejected until position has not passed for 10 s while GNSS velocity still passes
  (EKF3 ``posRetryTimeUseVel_ms``) or SB_GPS_TO (7 s, ``posRetryTimeNoVel_ms``) without it:
  then the estimate has timed out and resets to the next fix. It also resets when its own
  modelled uncertainty grows past EK3_GLITCH_RAD. EK3_GLITCH_RAD 0 never rejects: the
  correction is scaled down to what a ratio of 1 would give (EKF3's inflated variance).
* velocity: rejected fixes are not fused; velocity resets with position when neither passed
  within the retry time (EKF3 declares ``velTimeout`` only then).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

NS = 1_000_000_000
POS_RETRY_USE_VEL_S = 10.0       # EKF3 posRetryTimeUseVel_ms: GNSS velocity still fused
VEL_ACC_SCALE = 0.05             # EKF3 gpsNEVelVarAccScale [(m/s) per (m/s^2)]
MAX_POS_ACCURACY_M = 100.0       # EKF3 caps the reported accuracy at this


@dataclass(frozen=True)
class GateConfig:
    pos_gate: float = 5.0            # max(EK3_POS_I_GATE / 100, 1)
    vel_gate: float = 5.0            # max(EK3_VEL_I_GATE / 100, 1)
    posne_noise_m: float = 0.5       # EK3_POSNE_M_NSE
    velne_noise_m_s: float = 0.3     # EK3_VELNE_M_NSE
    acc_noise_m_s2: float = 0.35     # EK3_ACC_P_NSE
    glitch_radius_m: float = 25.0    # EK3_GLITCH_RAD
    pos_retry_no_vel_s: float = 7.0  # SB_GPS_TO

    @classmethod
    def from_params(cls, get) -> "GateConfig":
        return cls(pos_gate=max(get("EK3_POS_I_GATE") / 100.0, 1.0),
                   vel_gate=max(get("EK3_VEL_I_GATE") / 100.0, 1.0),
                   posne_noise_m=get("EK3_POSNE_M_NSE"), velne_noise_m_s=get("EK3_VELNE_M_NSE"),
                   acc_noise_m_s2=get("EK3_ACC_P_NSE"), glitch_radius_m=get("EK3_GLITCH_RAD"),
                   pos_retry_no_vel_s=get("SB_GPS_TO"))


@dataclass(frozen=True)
class GateDecision:
    fuse_pos: bool
    fuse_vel: bool
    reset_pos: bool          # replace the position (and its history) by the fix
    reset_vel: bool
    pos_scale: float = 1.0   # correction gain multipliers (EK3_GLITCH_RAD 0)
    vel_scale: float = 1.0


def innovation_test_ratio(innov, variances, gate: float) -> float:
    """EKF3's squared-form innovation test ratio."""
    s = sum(variances)
    return sum(i * i for i in innov) / (gate * gate * s) if s > 0 else 0.0


class GnssGate:
    """Per-fix decisions and the timers behind them; see module text."""

    def __init__(self, cfg: GateConfig | None = None):
        self.cfg = cfg or GateConfig()
        self.pos_ratio = 0.0          # sqrt of the last position test ratio (EKF_STATUS_REPORT)
        self.vel_ratio = 0.0
        self.last_pos_pass_ns: int | None = None
        self.last_vel_pass_ns: int | None = None
        self.resets = 0

    def configure(self, cfg: GateConfig) -> None:
        self.cfg = cfg

    def start(self, t_ns: int) -> None:
        """The first fix initialised the estimate: both count as passed now."""
        self.last_pos_pass_ns = self.last_vel_pass_ns = t_ns
        self.pos_ratio = self.vel_ratio = 0.0

    # ---- the estimate's modelled uncertainty ---------------------------------------------

    def sigmas(self, t_ns: int, k_pos: float, k_vel: float) -> tuple[float, float]:
        """1-sigma per-axis error of the estimate (position m, velocity m/s) at t_ns.

        Steady state: a first-order correction of gain k against white measurement noise
        leaves sigma_meas * sqrt(k / (2 - k)). Without accepted fixes the velocity error
        grows at EK3_ACC_P_NSE per second, and the position error by the velocity error
        per second (a conservative, linear dead-reckoning growth)."""
        c = self.cfg
        sv0 = c.velne_noise_m_s * math.sqrt(k_vel / (2.0 - k_vel)) if 0 < k_vel < 2 else 0.0
        sp0 = c.posne_noise_m * math.sqrt(k_pos / (2.0 - k_pos)) if 0 < k_pos < 2 else 0.0
        dv = self._since_s(t_ns, self.last_vel_pass_ns)
        dp = self._since_s(t_ns, self.last_pos_pass_ns)
        sv = sv0 + c.acc_noise_m_s2 * dv
        return sp0 + sv * dp, sv

    @staticmethod
    def _since_s(t_ns: int, then_ns: int | None) -> float:
        return 0.0 if then_ns is None else max(0.0, (t_ns - then_ns) / NS)

    # ---- timeouts (EKF3 setAidingMode) ---------------------------------------------------

    def vel_aiding(self, t_ns: int) -> bool:
        return self._since_s(t_ns, self.last_vel_pass_ns) <= self.cfg.pos_retry_no_vel_s

    def pos_timed_out(self, t_ns: int) -> bool:
        limit = POS_RETRY_USE_VEL_S if self.vel_aiding(t_ns) else self.cfg.pos_retry_no_vel_s
        return self.last_pos_pass_ns is None or self._since_s(t_ns, self.last_pos_pass_ns) > limit

    def has_position(self, t_ns: int) -> bool:
        """EKF3 horiz_pos_abs: GNSS aiding has not timed out."""
        return not self.pos_timed_out(t_ns)

    # ---- one fix -------------------------------------------------------------------------

    def test(self, t_ns: int, e_pos, e_vel, eph_m: float, acc_mag_m_s2: float,
             k_pos: float, k_vel: float) -> GateDecision:
        c = self.cfg
        sp, sv = self.sigmas(t_ns, k_pos, k_vel)
        r_pos = min(max(eph_m, c.posne_noise_m), MAX_POS_ACCURACY_M) ** 2
        r_vel = c.velne_noise_m_s ** 2 + (VEL_ACC_SCALE * acc_mag_m_s2) ** 2
        var_p = sp * sp + r_pos
        var_v = sv * sv + r_vel
        tr_p = innovation_test_ratio(e_pos, [var_p] * len(e_pos), c.pos_gate)
        tr_v = innovation_test_ratio(e_vel, [var_v] * len(e_vel), c.vel_gate)
        self.pos_ratio, self.vel_ratio = math.sqrt(tr_p), math.sqrt(tr_v)
        no_glitch_gate = c.glitch_radius_m <= 0
        pos_scale = 1.0 / tr_p if no_glitch_gate and tr_p > 1.0 else 1.0
        vel_scale = 1.0 / tr_v if no_glitch_gate and tr_v > 1.0 else 1.0
        pos_ok = tr_p < 1.0 or no_glitch_gate
        vel_ok = tr_v < 1.0 or no_glitch_gate
        timed_out = self.pos_timed_out(t_ns)
        vel_timed_out = timed_out and not self.vel_aiding(t_ns)
        too_uncertain = not no_glitch_gate and 2.0 * sp * sp > c.glitch_radius_m ** 2
        reset_pos = (pos_ok or timed_out) and (timed_out or too_uncertain)
        reset_vel = reset_pos and vel_timed_out
        if vel_ok or reset_vel:
            self.last_vel_pass_ns = t_ns
        if pos_ok or reset_pos:
            self.last_pos_pass_ns = t_ns
        if reset_pos:
            self.resets += 1
            self.pos_ratio = 0.0
            if reset_vel:
                self.vel_ratio = 0.0
        return GateDecision(fuse_pos=pos_ok and not reset_pos,
                            fuse_vel=vel_ok and not reset_vel, reset_pos=reset_pos,
                            reset_vel=reset_vel, pos_scale=pos_scale, vel_scale=vel_scale)
