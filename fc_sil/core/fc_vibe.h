/*
 * fc_vibe.h - accelerometer vibration levels and clipping, as ArduCopter computes them for
 * its VIBRATION message (AP_InertialSensor::calc_vibration_and_clipping, called per raw
 * accel sample by each IMU backend):
 *
 *   clip:  any axis |a| > clip limit -> clip_count++ (ArduPilot: the sensor's range
 *          less 0.5 g, so a 16 g accelerometer clips above 15.5 g)
 *   floor: a first-order low-pass of the accel at 5 Hz (the "vibe floor")
 *   vibe:  (a - floor)^2 per axis through a first-order low-pass at 2 Hz
 *   level: sqrt(vibe) per axis [m/s^2] (get_vibration_levels)
 *
 * Both filters are ArduPilot's DigitalLPF: alpha = dt / (dt + 1 / (2 pi fc)), and the first
 * sample initialises the output to itself (so the vibe filter starts at 0).
 * The block only reads the samples: it never touches estimation or control.
 * Pure C, float32, no heap, no globals.
 */
#ifndef FC_VIBE_H
#define FC_VIBE_H

#include <stdbool.h>
#include <stdint.h>

#define FC_VIBE_FLOOR_HZ 5.0f   /* AP_INERTIAL_SENSOR_ACCEL_VIBE_FLOOR_FILT_HZ */
#define FC_VIBE_FILT_HZ 2.0f    /* AP_INERTIAL_SENSOR_ACCEL_VIBE_FILT_HZ */
#define FC_VIBE_G_M_S2 9.80665f
/* The clip limit of a +-16 g accelerometer (the ICM-42688-P range the bridge models,
 * scenario imu.accel_range_m_s2 = 156.9): ArduPilot's (16 - 0.5) g. */
#define FC_VIBE_CLIP_16G_M_S2 (15.5f * FC_VIBE_G_M_S2)

typedef struct fc_vibe {
    float clip_m_s2;          /* |a| above this on any axis counts one clip [m/s^2] */
    float floor_m_s2[3];      /* accel low-passed at FC_VIBE_FLOOR_HZ, FRD [m/s^2] */
    float vibe_m2_s4[3];      /* (accel - floor)^2 low-passed at FC_VIBE_FILT_HZ [m^2/s^4] */
    uint32_t clip_count;      /* samples with an axis beyond clip_m_s2 (wraps, as ArduPilot's) */
    uint32_t samples;         /* samples applied */
    bool initialised;         /* the filters have their first sample */
} fc_vibe_t;

/* clip_m_s2 <= 0 or non-finite: FC_VIBE_CLIP_16G_M_S2. */
void fc_vibe_init(fc_vibe_t *v, float clip_m_s2);
/* One raw accel sample, FRD [m/s^2], dt_s since the previous one (ignored on the first
 * sample). Non-finite samples or dt_s <= 0 after the first are skipped. */
void fc_vibe_apply(fc_vibe_t *v, const float accel_frd_m_s2[3], float dt_s);
/* vibration_x/y/z of the VIBRATION message [m/s^2]. */
void fc_vibe_levels(const fc_vibe_t *v, float out_m_s2[3]);

#endif /* FC_VIBE_H */
