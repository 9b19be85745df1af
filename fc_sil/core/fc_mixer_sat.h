/*
 * fc_mixer_sat.h - where the collective sits when roll and pitch need more than the band.
 *
 * When roll + pitch ask for more than the flight band (MOT_SPIN_MIN..MAX), both are scaled
 * down until they fit around a collective. Centring them in the band (the most attitude
 * authority) pins the collective at the band's middle in PWM: the altitude loop then has
 * no say at all, and in a limit cycle that keeps the motors saturated (a 20 ms SIL link
 * each way, failure bench F9) the mean tilt eats the lift and the vehicle sinks to the
 * ground with the altitude loop asking for full throttle.
 *
 * ArduCopter (AP_MotorsMatrix::output_armed_stabilizing) keeps the collective at the
 * demanded throttle, but at most at the middle of its THRUST range, and scales roll,
 * pitch and yaw to fit around it (rpy_scale). Its thrust is linearised
 * (MOT_THST_EXPO, default 0.65: thrust = (1 - e) x + e x^2 of the band fraction x), so
 * half thrust is the band fraction x = (-(1 - e) + sqrt((1 - e)^2 + 2 e)) / (2 e) = 0.648,
 * above the PWM middle (0.5): the altitude loop keeps room to climb. Below its hover
 * throttle it goes no lower than halfway between the demand and hover (ATC_THR_MIX_MAX,
 * 0.5 in flight), so attitude keeps some authority. Ours: a demand above the band's middle
 * is kept up to ArduCopter's half-thrust point; below it, the collective is halfway
 * between the demand and the band's middle, which stands in for the hover throttle (ours
 * is not learned; the middle is within a few percent of where this vehicle hovers).
 * Only a saturated mix takes this path: an unsaturated one is unchanged.
 */
#ifndef FC_MIXER_SAT_H
#define FC_MIXER_SAT_H

/* Band fraction of half thrust for ArduCopter's default MOT_THST_EXPO 0.65 (see above). */
#define FC_MIXER_HALF_THRUST_X 0.648f

/* ArduCopter's ATC_THR_MIX_MAX default: how far toward hover a low demand is raised. */
#define FC_MIXER_THR_MIX 0.5f

/* The collective [us] a saturated roll/pitch mix fits around, in the band [lo, hi]:
 * see above; t is the demanded throttle [us]. */
static inline float fc_mixer_sat_collective(float t, float lo, float hi)
{
    const float mid = 0.5f * (lo + hi);
    const float half_thrust = lo + FC_MIXER_HALF_THRUST_X * (hi - lo);
    if (t >= mid) {
        return (t < half_thrust) ? t : half_thrust;
    }
    const float c = (t > lo ? t : lo) * (1.0f - FC_MIXER_THR_MIX) + mid * FC_MIXER_THR_MIX;
    return c;
}

/* Scale of roll/pitch parts rp_min <= 0 <= rp_max so that c + rp stays in [lo, hi]. */
static inline float fc_mixer_sat_scale(float c, float lo, float hi, float rp_min, float rp_max)
{
    float s = 1.0f;
    if (rp_max > 0.0f && (hi - c) < s * rp_max) {
        s = (hi - c) / rp_max;
    }
    if (rp_min < 0.0f && (lo - c) > s * rp_min) {
        s = (lo - c) / rp_min;
    }
    return s > 0.0f ? s : 0.0f;
}

#endif /* FC_MIXER_SAT_H */
