"""The scenario's setpoints, forwarded to ArduCopter in GUIDED (common/setpoints.py: profile,
clock, engagement), with ArduCopter's meaning of the thrust field.

Take-off: ArduCopter climbs in GUIDED's take-off submode (MAV_CMD_NAV_TAKEOFF from
tools/autopilots/ardupilot/driver.py). Forwarding starts once it reports (GLOBAL_POSITION_INT
relative_alt) the commanded altitude; the command is resent at RESEND_HZ because ArduCopter
drops an angle target that is GUID_TIMEOUT old (3 s by default, ArduCopter/Parameters.cpp)
back to level.

The message (ArduCopter/GCS_Mavlink.cpp, handle_message_set_attitude_target): the
quaternion must be of unit length within 1e-3 or it is refused; thrust must not be ignored
(ignoring it makes ArduCopter leave angle control). With the default GUID_OPTIONS (bit 3,
SetAttitudeTarget_ThrustAsThrust, clear) thrust is a climb-rate command: exactly 0.5 =
climb rate 0 (hold the altitude), 0.5..1 = up to WPNAV_SPEED_UP, 0..0.5 = down to
WPNAV_SPEED_DN. Altitude setpoints are flown through that field: climb = ALT_GAIN_1_S x
(commanded - reported altitude) outside a ALT_DEADBAND_M band, else exactly 0.5.
(SET_POSITION_TARGET_LOCAL_NED would switch GUIDED to its position controller and drop the
attitude target.) ArduCopter's own shaped target (ATTITUDE_TARGET) is logged next to the
command (tools/autopilots/common/log_sink.py).
"""

from __future__ import annotations

from silbridge.tools.autopilots.common.setpoints import SetpointForwarder

RESEND_HZ = 20.0            # >= 10 Hz asked; ArduCopter's GUID_TIMEOUT is 3 s by default
ALT_GAIN_1_S = 0.5          # climb-rate command per metre of altitude error [1/s]
ALT_DEADBAND_M = 0.3        # inside it thrust is exactly 0.5: ArduCopter holds its altitude
SPEED_UP_M_S = 2.5          # WPNAV_SPEED_UP default, 250 cm/s: thrust 1.0
SPEED_DN_M_S = 1.5          # WPNAV_SPEED_DN default, 150 cm/s: thrust 0.0
HOLD_THRUST = 0.5           # climb rate 0


def thrust_for_climb(climb_m_s: float) -> float:
    """ArduCopter's thrust field (GUID_OPTIONS bit 3 clear) for a climb-rate command [m/s]."""
    if climb_m_s > 0.0:
        return min(1.0, HOLD_THRUST + 0.5 * climb_m_s / SPEED_UP_M_S)
    if climb_m_s < 0.0:
        return max(0.0, HOLD_THRUST + 0.5 * climb_m_s / SPEED_DN_M_S)
    return HOLD_THRUST


class ArduCopterSetpointForwarder(SetpointForwarder):
    """send: MavlinkDriver.send_attitude_target; reported_alt_m: its relative altitude."""

    resend_hz = RESEND_HZ

    def __init__(self, scenario, dt_ns: int, heading_rad: float, *, send, reported_alt_m):
        super().__init__(scenario, dt_ns, heading_rad, send=send,
                         reported_alt_m=reported_alt_m, thrust=HOLD_THRUST)

    def thrust_for(self, alt_cmd: float, roll: float, pitch: float, flight_ns: int) -> float:
        climb = 0.0
        reported = self._reported_alt_m()
        if reported is not None and abs(alt_cmd - reported) > ALT_DEADBAND_M:
            climb = ALT_GAIN_1_S * (alt_cmd - reported)
        return thrust_for_climb(climb)
