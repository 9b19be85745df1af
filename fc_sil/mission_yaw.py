"""The heading in AUTO: ArduCopter's auto-yaw as the mission's commands set it.

The yaw modes and the heading path are auto_yaw.py's (ArduCopter's Mode::AutoYaw and the
attitude controller's heading shaping, shared with GUIDED); this adds the two modes only a
mission sets:

  ROI     DO_SET_ROI / DO_SET_ROI_LOCATION: face the location, recomputed each step from the
          vehicle's position; DO_SET_ROI_NONE (or an ROI at 0, 0, 0) returns to the default
  CIRCLE  LOITER_TURNS: face the circle's centre

and the rules by which navigation commands choose the mode (as ModeAuto): a waypoint or spline
leg returns to the WP_YAW_BEHAVIOR default unless an ROI is active (or a CONDITION_YAW holds
and WP_YAW_BEHAVIOR is 0); take-off, landing and RTL's own legs hold; circling faces the
centre unless an ROI is active. CONDITION_YAW is auto_yaw's FIXED mode.
"""

from __future__ import annotations

import math

from .auto_yaw import AutoYaw, HeadingControl, YawConfig, YawMode

ROI, CIRCLE = "roi", "circle"


class MissionYaw:
    def __init__(self):
        self.ay = AutoYaw(0.0)
        self.heading = HeadingControl(0.0)
        self.cfg = YawConfig()
        self.extra = None             # ROI or CIRCLE (modes auto_yaw does not know), or None
        self.roi_ne = None

    def begin(self, v) -> None:
        """AUTO starts: heading shaping from where the nose points; an ROI does not carry over."""
        self.cfg = YawConfig.from_store(v.store.host)
        self.heading.reset(v.yaw_rad)
        self.ay.yaw_rad = v.yaw_rad
        if self.extra == ROI:
            self.hold(v)

    @property
    def roi_active(self) -> bool:
        return self.extra == ROI

    @property
    def fixed(self) -> bool:
        return self.extra is None and self.ay.mode == YawMode.FIXED

    def hold(self, v) -> None:
        self.extra = None
        self.ay.set_mode(YawMode.HOLD, v.yaw_rad)

    def nav_default(self, v, rtl: bool = False) -> None:
        """A waypoint or spline leg starts (ModeAuto's wp_start rule)."""
        if self.extra == ROI or (self.fixed and self.cfg.wp_yaw_behavior == 0):
            return
        self.extra = None
        self.ay.set_default(self.cfg.wp_yaw_behavior, v.yaw_rad, rtl)

    def circle(self, v) -> None:
        if self.extra != ROI:
            self.extra = CIRCLE

    def set_roi(self, v, roi_ne) -> None:
        """An ROI location, or None to end it (back to the default)."""
        if roi_ne is None:
            self.roi_ne = None
            self.extra = None
            self.ay.set_default(self.cfg.wp_yaw_behavior, v.yaw_rad)
        else:
            self.roi_ne = (float(roi_ne[0]), float(roi_ne[1]))
            self.extra = ROI

    def set_fixed(self, v, angle_deg: float, rate_deg_s: float, direction: int,
                  relative: bool) -> None:
        """CONDITION_YAW: p1 angle, p2 rate (0 = ATC_SLEW_YAW), p3 -1 ccw / +1 cw / 0 the
        short way, p4 1 = relative."""
        if self.extra is not None:       # ROI / CIRCLE held the heading: start from it
            self.ay.yaw_rad = self.heading.shaped_rad
        self.extra = None
        self.ay.set_fixed(math.radians(angle_deg), math.radians(max(0.0, rate_deg_s)),
                          direction, relative, self.cfg.slew_max_rad_s, v.yaw_rad)

    def keep_fixed(self, v) -> None:
        """CONDITION_YAW still running: it takes the heading back (ModeAuto's verify_yaw)."""
        self.extra = None
        self.ay.set_mode(YawMode.FIXED, v.yaw_rad)

    def fixed_reached(self, v) -> bool:
        return self.ay.reached_fixed(v.yaw_rad)

    def apply(self, v, dt_s: float, desired_vel_ne, speed_max_m_s: float,
              circle_yaw_rad: float | None = None) -> None:
        """This step's heading: v.yaw_target_rad and v.yaw_rate_cmd (auto_yaw.py's path)."""
        if self.extra == ROI and self.roi_ne is not None:
            dn = self.roi_ne[0] - v.est.pos_ne_m[0]
            de = self.roi_ne[1] - v.est.pos_ne_m[1]
            target = math.atan2(de, dn) if math.hypot(dn, de) > 1e-3 else self.heading.shaped_rad
            ff, angle = 0.0, True
        elif self.extra == CIRCLE and circle_yaw_rad is not None:
            target, ff, angle = circle_yaw_rad, 0.0, True
        else:
            target, ff, angle = self.ay.target(dt_s, self.heading.shaped_rad, desired_vel_ne,
                                               speed_max_m_s, v.est.vel_ne_m_s)
        v.yaw_target_rad, v.yaw_rate_cmd = self.heading.update(dt_s, self.cfg, v.yaw_rad,
                                                               target, ff, angle)
