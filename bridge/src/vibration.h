/*
 * vibration.h - rotor-synchronous vibration of the airframe, as the IMU feels it.
 *
 * Each rotor forces the frame at whole multiples of its own rotation: a static
 * imbalance U turns a force U omega^2 in the rotor plane once per revolution, and
 * the thrust ripples at blade pass and declared higher orders (a fraction of the
 * rotor's thrust kT omega^2, along the thrust axis). The forces act at the hubs, so
 * they also give moments about the CG; the rigid frame answers with a linear and an
 * angular acceleration, an optional frame mode (2nd order) shapes both, the lever arm
 * carries the angular part to the IMU (alpha x r), and the mount (hard, or 2nd order
 * per axis, translational and rotational) filters what reaches the IMU. The gyro reads
 * the angular velocity of that same motion (alpha / (j Omega)), the accelerometer its
 * acceleration: the two agree by construction.
 *
 * Why analytic: every term is a harmonic of one rotor's phase, so its response through
 * every linear stage (frame, mount, and the chip's AAF at its data rate) is a complex gain
 * at that frequency (steady state, quasi-static in omega over a step), and its value at
 * the instant the FC reads is exact without sampling it at the chip's rate: a line above
 * the FC's Nyquist frequency folds exactly as sampling folds it. Per step and term: one
 * gain and one cos/sin pair. The vibration is a small motion superposed on the FDM's: it
 * never feeds back into JSBSim.
 *
 * Prop wash (optional, off unless wash_frac > 0): broadband thrust fluctuation of each rotor,
 * white over the physics band, RMS wash_frac x the rotor's thrust (so it grows with the
 * throttle), along the thrust axis at the hub. It is not a line, so it runs in the time
 * domain: the same rigid-frame map gives the IMU's acceleration and the frame's angular
 * acceleration, the frame mode and the mount are their 2nd-order filters (bilinear), and
 * both are integrated with one leak (SB_VIB_WASH_HP_HZ) to the IMU's velocity and the
 * frame's angular velocity: the gyro reads the latter, the accelerometer the change of the
 * former over the step, so the two agree as the lines do. The draws come from a counter-
 * based generator (splitmix64) seeded from the scenario's seed: same seed, same bytes.
 * Not through the chip's AAF (its gain below the physics Nyquist frequency is near 1).
 *
 * Pure C: no heap, no globals, no OS.
 */
#ifndef SB_VIBRATION_H
#define SB_VIBRATION_H

#include <stdint.h>

#include "imu_chip.h"

#define SB_VIB_RIPPLES 5   /* blade pass + four declared orders */
/* Prop wash's lower band edge [Hz]: below it the motion is the vehicle's own (the FDM and
 * the FC's loops own it, a few Hz); above it, vibration superposed on the FDM's motion. */
#define SB_VIB_WASH_HP_HZ 10.0

/* Constants of one run (bridge/vibration_consts.py fills them from the scenario). */
typedef struct {
    double on;                       /* 1: the model runs; 0: the stage skips it */
    double hub_frd_m[4][3];          /* rotor hubs from the CG, body FRD [m] */
    double spin_cw[4];               /* +1 CW seen from above, -1 CCW */
    double imbalance_kg_m[4];        /* static imbalance per rotor [kg m] */
    double kt_n_s2;                  /* thrust per omega^2 [N s^2/rad^2] */
    double ripple_order[SB_VIB_RIPPLES];  /* x rotor frequency; 0 = unused */
    double ripple_frac[SB_VIB_RIPPLES];   /* amplitude, fraction of the rotor's thrust */
    double mass_kg;
    double inertia_kg_m2[3];         /* principal Ixx, Iyy, Izz [kg m^2] */
    double imu_lever_frd_m[3];       /* IMU from the CG, body FRD [m] */
    double frame_hz, frame_damping;  /* frame structural mode; 0 Hz = rigid frame */
    double mount_hz, mount_damping;  /* mount, translational; 0 Hz = hard */
    double mount_rot_hz, mount_rot_damping;  /* mount, rotational; 0 Hz = hard */
    double wash_frac;                /* prop wash: RMS thrust fluctuation / thrust; 0 = off */
    double wash_seed;                /* its generator's seed, a whole number below 2^53 */
} sb_vib_consts;

/* One 2nd-order low-pass per axis of a 3-vector (transposed direct form II); off: y = x. */
typedef struct {
    int on;
    double b0, b1, b2, a1, a2;
    double s1[3], s2[3];
} sb_vib_lp3;

/* Prop wash's state. */
typedef struct {
    uint64_t rng;              /* splitmix64 counter */
    double dt_s;               /* the step the filters below were made for (0: not yet) */
    double leak;               /* exp(-2 pi SB_VIB_WASH_HP_HZ dt) */
    sb_vib_lp3 frame_a, frame_al, mount_t, mount_r;
    double vel[3], rate[3];    /* IMU velocity, frame angular velocity (leaky integrals) */
    double vel_prev[3];        /* mounted IMU velocity at the previous step */
} sb_vib_wash;

/* A rotor's forcing per unit amplitude, as it reaches the IMU on a rigid frame: the
 * acceleration at the IMU's place (a + alpha x r_imu) and the angular acceleration.
 * Fixed by the geometry, so computed once (sb_vib_init). */
typedef struct {
    double p_re[3], p_im[3];   /* [m/s^2 per N] */
    double al_re[3], al_im[3]; /* [rad/s^2 per N] */
} sb_vib_unit;

typedef struct {
    sb_vib_consts c;
    double phase_rad[4];       /* rotor phases at the end of the last step [rad] */
    sb_vib_unit imbalance[4];  /* per unit of U omega^2, rotating in the rotor plane */
    sb_vib_unit ripple[4];     /* per N of thrust ripple along the thrust axis */
    sb_vib_wash wash;          /* prop wash (used when c.wash_frac > 0) */
} sb_vibration;

/* A defined model: phases as given, the geometry's unit responses. */
void sb_vib_init(sb_vibration *v, const sb_vib_consts *c, const double phase_rad[4]);

/* One physics step of dt_s at rotor speeds omega [rad/s] held over it: advances the rotor
 * phases by omega dt and adds to out (accel xyz [m/s^2], gyro xyz [rad/s], FRD) the
 * vibration the FC reads at the step's end, each line through the chip's AAF at its
 * frequency (chip: the chip whose gain applies), and the prop wash when it is on. */
void sb_vib_step(sb_vibration *v, const double omega_rad_s[4], double dt_s,
                 const sb_imu_chip *chip, double out[6]);

/* H(j w) of a unit-DC-gain 2nd-order low-pass with natural frequency f_hz and damping
 * ratio zeta (f_hz <= 0: 1): the frame mode and the mount. */
void sb_vib_second_order(double f_hz, double zeta, double w_rad_s, double *re, double *im);

#endif /* SB_VIBRATION_H */
