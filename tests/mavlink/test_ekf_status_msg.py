"""EKF_STATUS_REPORT as the FC's ground-station side fills it: EKF3's flags including
ArduPilot's gps_glitching bit (1 << 15, outside the MAVLink enum) and the four normalised
test ratios in their fields, checked through pymavlink's own encode and decode."""

from __future__ import annotations

from pymavlink.dialects.v20 import ardupilotmega as mav

from silbridge.fc_sil.innov_ratios import EKF_GPS_GLITCHING
from silbridge.mavlink.gcs.telemetry import ENCODERS
from silbridge.mavlink.gcs.vehicle_api import VehicleSnapshot

ENCODE = ENCODERS[mav.MAVLINK_MSG_ID_EKF_STATUS_REPORT]


def test_flags_and_ratios_reach_their_fields():
    flags = mav.EKF_ATTITUDE | mav.EKF_POS_HORIZ_ABS | EKF_GPS_GLITCHING
    snap = VehicleSnapshot(ekf_flags=flags, ekf_vel_var=0.25, ekf_pos_h_var=2.0,
                           ekf_pos_v_var=0.5, ekf_compass_var=0.125)
    codec = mav.MAVLink(None, srcSystem=1, srcComponent=1)
    (msg,) = [mav.MAVLink(None).decode(bytearray(m.pack(codec))) for m in ENCODE(snap, None)]
    assert msg.flags == flags and msg.flags & 32768
    assert (msg.velocity_variance, msg.pos_horiz_variance, msg.pos_vert_variance,
            msg.compass_variance) == (0.25, 2.0, 0.5, 0.125)
    assert msg.terrain_alt_variance == 0.0
