"""The pre-flight height check a ground station makes before it lets PX4 take off.

PX4 v1.15's EKF2 sometimes starts with a vertical velocity while the vehicle stands still
(issue 29: 1.5-2.5 m/s in its state by 0.2 s of sim time, before its gravity-vector fusion is on),
integrates it into its height, and keeps that height as the barometer's offset once baro
fusion starts (~1.2 s). From then on its height at rest reads 0.7-1.2 m off the ground it
booted on, and it holds every altitude about that far off (5.8-6.1 m of truth for 5 m).
Nothing in PX4's own arming checks catches it: the baro innovations agree with the offset.
In the five PX4 logs that caught it (SDLOG_MODE 2), the velocity grows in 13-15 equal steps
of g x 10 to g x 20 ms (one size per boot), as if EKF2 predicted that often from one IMU
sample with no delta velocity (its oldest, while its IMU buffer fills); what in PX4's
start-up under load gives it that sample is not known. Lockstep boots have not shown it, and
the real-time ones stopped showing it once the server freewheeled PX4's boot at lockstep's
pace rather than at the step period (bridge/autopilots/px4/server.py: 16 of 16 good boots,
against 7 of 24, on an idle machine that day); the check stays, for a PX4 that still does.

A vehicle standing where it booted must read a local height (LOCAL_POSITION_NED z) near 0
and a vertical speed near 0. This check watches both before arming: `settled` once both have
stayed within bounds for SETTLE_S of sim time, `failed` if that has not happened within
BUDGET_S of the first report. A failed check means "power-cycle the vehicle", which is what
fly_px4 does (a fresh PX4): the offset does not go away by waiting (0.9-1.1 m still at
6 s), and the v1.15.4 binary has no EKF2 height reset or GNSS-referenced baro calibration to
ask for (`strings bin/px4 | grep -iE 'baro.*calib|reset.*height|hgt.*reset'` finds only the
temperature calibration).

Bounds, from PX4's own reports at rest (issue 29: real-time boots under load): good boots read
|z| <= 0.06 m and |vz| <= 0.07 m/s from the first report (~1.1 s) on; bad ones read z 1.2-1.8 m
with vz 1.5-2.2 m/s at the first report, and still 0.7-1.2 m at 4-6 s.
"""

from __future__ import annotations

REST_Z_M = 0.3          # |LOCAL_POSITION_NED z| at rest: good <= 0.06 m, bad >= 0.7 m
REST_VZ_M_S = 0.15      # |vz| at rest: good <= 0.07 m/s
SETTLE_S = 1.0          # both within bounds this long (sim time) before arming
BUDGET_S = 5.0          # from the first report: a height not settled by then stays off


class RestHeightCheck:
    """Fed LOCAL_POSITION_NED (sim time, z, vz) while disarmed; says settled / failed."""

    def __init__(self):
        self.first_s: float | None = None
        self.inside_since_s: float | None = None
        self.settled_s: float | None = None      # sim time it passed
        self.last: tuple[float, float] | None = None   # newest (z, vz)

    def feed(self, t_s: float, z_m: float, vz_m_s: float) -> None:
        if self.settled_s is not None:
            return
        self.last = (z_m, vz_m_s)
        if self.first_s is None:
            self.first_s = t_s
        if abs(z_m) <= REST_Z_M and abs(vz_m_s) <= REST_VZ_M_S:
            if self.inside_since_s is None:
                self.inside_since_s = t_s
            if t_s - self.inside_since_s >= SETTLE_S:
                self.settled_s = t_s
        else:
            self.inside_since_s = None

    @property
    def settled(self) -> bool:
        return self.settled_s is not None

    def failed(self, t_s: float) -> bool:
        return (self.settled_s is None and self.first_s is not None
                and t_s - self.first_s > BUDGET_S)

    def why(self) -> str:
        z, vz = self.last if self.last is not None else (float("nan"), float("nan"))
        return (f"PX4's height at rest did not settle within {BUDGET_S:g} s: local z {z:.2f} m, "
                f"vz {vz:.2f} m/s (want |z| <= {REST_Z_M} m and |vz| <= {REST_VZ_M_S} m/s "
                f"for {SETTLE_S:g} s)")

    def summary(self) -> dict:
        return {"settled_s": self.settled_s, "first_report_s": self.first_s,
                "z_m": None if self.last is None else round(self.last[0], 3),
                "vz_m_s": None if self.last is None else round(self.last[1], 3)}
