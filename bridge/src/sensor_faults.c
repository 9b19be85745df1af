/*
 * sensor_faults.c - see sensor_faults.h. Order within a sensor: bias, extra noise, clip,
 * then stuck (a frozen output hides everything before it), as a chip whose output register
 * stops updating would.
 */
#include "sensor_faults.h"

#include <math.h>

#define TWO_PI 6.283185307179586

/* Dry air's gas constant [J/(kg K)] and standard gravity [m/s^2] (ISA, as JSBSim's). */
#define R_AIR 287.05287
#define G0 9.80665

/* splitmix64 (Steele, Lea, Flood 2014): a tiny generator whose whole state is one word,
 * so a run's noisy-axis samples depend only on the seed and the faults' history. */
static uint64_t next_u64(uint64_t *state)
{
    uint64_t z = (*state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

/* One standard normal (Box-Muller; the second of the pair is dropped: a noisy axis is a
 * rare fault, not a hot path). */
static double normal(uint64_t *state)
{
    const double u1 = ((double)(next_u64(state) >> 11) + 1.0) * 0x1.0p-53;   /* (0, 1] */
    const double u2 = (double)(next_u64(state) >> 11) * 0x1.0p-53;           /* [0, 1) */
    return sqrt(-2.0 * log(u1)) * cos(TWO_PI * u2);
}

static void inertial(sb_inertial_fault *f, uint64_t *rng, double v[3])
{
    if (!f->on)
        return;
    for (int i = 0; i < 3; i++) {
        v[i] += f->bias[i];
        if (f->sigma[i] > 0.0)
            v[i] += f->sigma[i] * normal(rng);
        if (f->clip >= 0.0)
            v[i] = v[i] > f->clip ? f->clip : (v[i] < -f->clip ? -f->clip : v[i]);
    }
    if (!f->primed) {   /* the first sample under a stuck fault is the one it repeats */
        for (int i = 0; i < 3; i++)
            f->held[i] = v[i];
        f->primed = 1;
    }
    for (int i = 0; i < 3; i++)
        if (f->stuck[i])
            v[i] = f->held[i];
}

void sb_faults_imu(sb_sensor_faults *f, double out[6])
{
    inertial(&f->accel, &f->rng, out);
    inertial(&f->gyro, &f->rng, out + 3);
}

double sb_faults_baro_pa(sb_baro_fault *f, double pa, double temperature_k, int64_t sim_ns)
{
    /* An altitude error dh reads as the pressure dh lower in the local air column:
     * dp = -rho g dh, rho = p / (R T) (hydrostatics, the air's density at the vehicle). */
    const double dh_m = f->offset_m + f->drift_m_s * ((double)sim_ns * 1e-9);
    const double rho = pa / (R_AIR * temperature_k);
    pa -= rho * G0 * dh_m;
    if (!f->primed) {
        f->held_pa = pa;
        f->primed = 1;
    }
    return f->stuck ? f->held_pa : pa;
}
