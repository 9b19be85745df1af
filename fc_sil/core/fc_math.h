/*
 * fc_math.h - small float32 helpers shared by the core blocks.
 *
 * Everything is static inline and single precision: the core is meant to run
 * on a Cortex-M4F whose FPU only does float32, so a stray double would fall
 * back to software emulation (the build uses -Wdouble-promotion to catch it).
 *
 * Quaternions are {w, x, y, z} and rotate body FRD vectors into world NED:
 * v_ned = q * v_frd * conj(q). Euler angles are ZYX (yaw, pitch, roll).
 */
#ifndef FC_MATH_H
#define FC_MATH_H

#include <math.h>
#include <stdbool.h>

#define FC_PI_F 3.14159265358979f
#define FC_TWO_PI_F 6.28318530717959f
#define FC_GRAVITY_M_S2 9.80665f
#define FC_DEG_TO_RAD_F 0.0174532925199433f

static inline float fc_constrainf(float x, float lo, float hi)
{
    return (x < lo) ? lo : ((x > hi) ? hi : x);
}

static inline bool fc_finitef(float x)
{
    return isfinite(x) != 0;
}

static inline bool fc_finite3(const float v[3])
{
    return fc_finitef(v[0]) && fc_finitef(v[1]) && fc_finitef(v[2]);
}

static inline float fc_sq(float x)
{
    return x * x;
}

/* Wrap an angle to [-pi, pi). */
static inline float fc_wrap_pi(float a)
{
    if (a >= FC_PI_F || a < -FC_PI_F) {
        a = a - FC_TWO_PI_F * floorf((a + FC_PI_F) / FC_TWO_PI_F);
    }
    return a;
}

static inline float fc_norm3(const float v[3])
{
    return sqrtf(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

static inline void fc_cross3(const float a[3], const float b[3], float out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

static inline void fc_quat_identity(float q[4])
{
    q[0] = 1.0f;
    q[1] = 0.0f;
    q[2] = 0.0f;
    q[3] = 0.0f;
}

/* Normalise in place; a degenerate quaternion becomes the identity. */
static inline void fc_quat_normalize(float q[4])
{
    float n = sqrtf(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (!(n > 1e-6f) || !fc_finitef(n)) {
        fc_quat_identity(q);
        return;
    }
    float inv = 1.0f / n;
    q[0] *= inv;
    q[1] *= inv;
    q[2] *= inv;
    q[3] *= inv;
}

/* out = a * b (Hamilton product). out may not alias a or b. */
static inline void fc_quat_mul(const float a[4], const float b[4], float out[4])
{
    out[0] = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
    out[1] = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2];
    out[2] = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1];
    out[3] = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0];
}

/* v_ned = R(q) v_frd */
static inline void fc_quat_rotate(const float q[4], const float v[3], float out[3])
{
    const float w = q[0], x = q[1], y = q[2], z = q[3];
    out[0] = (1.0f - 2.0f * (y * y + z * z)) * v[0] + 2.0f * (x * y - w * z) * v[1]
             + 2.0f * (x * z + w * y) * v[2];
    out[1] = 2.0f * (x * y + w * z) * v[0] + (1.0f - 2.0f * (x * x + z * z)) * v[1]
             + 2.0f * (y * z - w * x) * v[2];
    out[2] = 2.0f * (x * z - w * y) * v[0] + 2.0f * (y * z + w * x) * v[1]
             + (1.0f - 2.0f * (x * x + y * y)) * v[2];
}

/* v_frd = R(q)^T v_ned */
static inline void fc_quat_rotate_inv(const float q[4], const float v[3], float out[3])
{
    const float qc[4] = {q[0], -q[1], -q[2], -q[3]};
    fc_quat_rotate(qc, v, out);
}

/* ZYX Euler angles (roll, pitch, yaw) from a unit quaternion. */
static inline void fc_quat_to_euler(const float q[4], float euler_rad[3])
{
    const float w = q[0], x = q[1], y = q[2], z = q[3];
    euler_rad[0] = atan2f(2.0f * (w * x + y * z), 1.0f - 2.0f * (x * x + y * y));
    euler_rad[1] = asinf(fc_constrainf(2.0f * (w * y - z * x), -1.0f, 1.0f));
    euler_rad[2] = atan2f(2.0f * (w * z + x * y), 1.0f - 2.0f * (y * y + z * z));
}

/* Unit quaternion from ZYX Euler angles (roll, pitch, yaw). */
static inline void fc_quat_from_euler(float roll_rad, float pitch_rad, float yaw_rad, float q[4])
{
    const float cr = cosf(0.5f * roll_rad), sr = sinf(0.5f * roll_rad);
    const float cp = cosf(0.5f * pitch_rad), sp = sinf(0.5f * pitch_rad);
    const float cy = cosf(0.5f * yaw_rad), sy = sinf(0.5f * yaw_rad);
    q[0] = cr * cp * cy + sr * sp * sy;
    q[1] = sr * cp * cy - cr * sp * sy;
    q[2] = cr * sp * cy + sr * cp * sy;
    q[3] = cr * cp * sy - sr * sp * cy;
}

/* Gain 1 - exp(-dt/tau) of a first-order EMA; tau <= 0 means "follow at once". */
static inline float fc_ema_alpha(float dt_s, float tau_s)
{
    if (!(tau_s > 0.0f)) {
        return 1.0f;
    }
    return 1.0f - expf(-dt_s / tau_s);
}

/* Filters sampled at a measured period are recomputed only when the period
 * moves by more than this fraction (a 1 % error in a cutoff is below what any
 * tuning resolves, and recomputing every step would cost an exp/tan each). */
#define FC_RETUNE_TOLERANCE 0.01f

static inline bool fc_retune_needed(float current_s, float measured_s)
{
    return fabsf(measured_s - current_s) > FC_RETUNE_TOLERANCE * current_s;
}

#endif /* FC_MATH_H */
