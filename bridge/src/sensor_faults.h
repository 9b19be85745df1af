/*
 * sensor_faults.h - issue 28's sensor faults in plain C: what a failing gyro, accelerometer,
 * barometer or magnetometer reports, applied by the sensor stage (sensor_stage.c) to each
 * sample after the sensor's own model (noise, bias, range). The fault engine
 * (bridge/faults/engine.py) decides when a fault is on; bridge/faults/sensors.py folds the
 * active faults of a unit into the structs below through the Kernel's set_*_fault methods.
 * The units, types and parameters are shm/fault_catalog.py's.
 *
 * Cost with no fault on: the stage tests one `on` word per sample of each sensor (a branch
 * that is always false, so always predicted); everything else runs only while a fault is on.
 */
#ifndef SB_SENSOR_FAULTS_H
#define SB_SENSOR_FAULTS_H

#include <stdint.h>

/* A gyro's or accelerometer's faults (units: rad/s or m/s^2, body FRD). */
typedef struct {
    int on;                  /* any fault below is active */
    int stuck[3];            /* per axis: repeat the held value */
    int primed;              /* held[] holds the first sample under a stuck fault */
    double held[3];
    double bias[3];          /* added (bias steps add up) */
    double sigma[3];         /* extra white noise per axis, one sigma (0: none) */
    double clip;             /* >= 0: saturate at +-clip; < 0: no clipping */
} sb_inertial_fault;

/* The barometer's faults, as altitude errors turned into pressure at the local density. */
typedef struct {
    int on;
    int stuck;               /* repeat the held pressure */
    int primed;
    double held_pa;
    double offset_m;         /* altitude error at sim time 0 of the drift line [m] */
    double drift_m_s;        /* altitude error growth (sum of active drifts) [m/s] */
} sb_baro_fault;

typedef struct {
    sb_inertial_fault gyro, accel;
    int imu_on;              /* gyro.on || accel.on: the IMU sample's one test */
    sb_baro_fault baro;
    /* The magnetometer's only C fault: silent (no record; its schedule and noise run on).
     * Motor interference is an FRD field added to the hard-iron offset by Python
     * (bridge/faults/sensors.py), whenever the battery current it follows changes. */
    int mag_off;
    uint64_t rng;            /* splitmix64 state of the noisy-axis faults (seeded by Python) */
} sb_sensor_faults;

/* The IMU sample out (accel xyz [m/s^2], gyro xyz [rad/s]) as the failing IMU reports it. */
void sb_faults_imu(sb_sensor_faults *f, double out[6]);

/* The barometer's pressure [Pa] as the failing baro reports it; temperature_k the air's. */
double sb_faults_baro_pa(sb_baro_fault *f, double pa, double temperature_k, int64_t sim_ns);

#endif /* SB_SENSOR_FAULTS_H */
