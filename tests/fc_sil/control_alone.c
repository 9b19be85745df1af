/*
 * control_alone.c - the control law (fc_control.h) driven with no core, no
 * parameter table and no estimator: test_control_law.py compiles it with the
 * law's own files only. The configuration is written here by hand (the gains
 * are ArduCopter's defaults, as fc_params.def declares them), the vehicle state
 * is set directly, and each case prints one line "name value ..." for the test.
 */
#include <stdio.h>

#include "fc_control.h"
#include "fc_math.h"
#include "fc_mixer.h"

#define RATE_DT_S 0.001f   /* the rate loop at the 1 kHz IMU rate (SB_LOOP_HZ above it) */
#define PWM_DT_S 0.0025f   /* SB_PWM_HZ 400 */
#define TILT_RAD 0.1f      /* the roll the cases start from */
#define HOME_ALT_M 5.0f    /* where the altitude cases hover */

static fc_rate_pid_config_t rate_pid(float kp, float ki, float kd, float flte_hz)
{
    fc_rate_pid_config_t p = {0};
    p.kp = kp;
    p.ki = ki;
    p.kd = kd;
    p.kff = 0.0f;
    p.imax = 0.5f;
    p.fltt_hz = 20.0f;
    p.flte_hz = flte_hz;
    p.fltd_hz = 20.0f;
    p.out_us_per_unit = 500.0f; /* half of MOT_PWM_MIN..MAX: ArduPilot's normalisation */
    p.d_clamp_us = 12.0f;
    p.d_clamp_enable = true;
    p.d_pt2x2 = false;
    p.antiwindup = true;
    return p;
}

static fc_control_config_t config(void)
{
    fc_control_config_t c = {0};
    c.att.ang_p[0] = 4.5f;
    c.att.ang_p[1] = 4.5f;
    c.att.ang_p[2] = 0.0f;     /* yaw: rate damping only */
    c.shaper.enable = false;   /* the command is the target: the P path is plain */
    c.pid[0] = rate_pid(0.135f, 0.135f, 0.0036f, 0.0f);
    c.pid[1] = rate_pid(0.135f, 0.135f, 0.0036f, 0.0f);
    c.pid[2] = rate_pid(0.18f, 0.018f, 0.0f, 2.5f);
    c.trim.enable = false;
    c.alt.pos_p = 1.0f;
    c.alt.vel_p = 5.0f;
    c.alt.acc_p = 0.5f;
    c.alt.acc_i = 1.0f;
    c.alt.acc_imax = 800.0f;
    c.alt.acc_flte_hz = 20.0f;
    c.alt.speed_up_m_s = 2.5f;
    c.alt.speed_dn_m_s = 2.5f;
    c.alt.hover_throttle = 0.35f;
    c.sysid.axis = FC_SID_NONE;
    c.spool.liftoff_alt_m = 0.3f;
    c.spool.spin_arm = 0.1f;
    c.spool.spin_min = 0.15f;
    c.spool.land_speed_m_s = 0.5f;
    c.angle_max_rad = 30.0f * FC_DEG_TO_RAD_F;
    c.pwm_min_us = 1000.0f;
    c.pwm_max_us = 2000.0f;
    return c;
}

/* Level flight at HOME_ALT_M except a roll of roll_rad, still. */
static fc_vehicle_state_t rolled(float roll_rad)
{
    fc_vehicle_state_t vs;
    fc_vehicle_state_reset(&vs);
    fc_quat_from_euler(roll_rad, 0.0f, 0.0f, vs.q_wxyz);
    vs.euler_rad[0] = roll_rad;
    vs.alt_m = HOME_ALT_M;
    vs.cos_tilt = cosf(roll_rad);
    return vs;
}

/* Armed, a level attitude command, an altitude target; spool and airborne as given. */
static fc_control_in_t inputs(uint8_t spool, uint8_t airborne, float alt_target_m)
{
    fc_control_in_t in = {0};
    in.cmd.armed = 1;
    in.cmd.alt_mode = FC_ALT_MODE_ALTITUDE;
    in.cmd.alt_target_m = alt_target_m;
    in.spool = spool;
    in.airborne = airborne;
    return in;
}

static void tilt_case(const fc_control_config_t *cfg)
{
    fc_control_state_t s;
    fc_control_out_t out;
    fc_control_init(&s, cfg, RATE_DT_S, PWM_DT_S, &out);
    const fc_control_in_t in = inputs(FC_SPOOL_FLIGHT, 1, HOME_ALT_M);
    const fc_vehicle_state_t vs = rolled(TILT_RAD);
    fc_control_rate_step(&s, cfg, &in, &vs, RATE_DT_S, &out);
    printf("tilt %.9g %.9g %.9g %.9g %.9g %.9g\n", (double)out.att_error_frd_rad[0],
           (double)out.rate_target_frd_rad_s[0], (double)out.pid_p_us[0], (double)out.cr_us,
           (double)out.cp_us, (double)out.cy_us);
}

/* One second of a held roll error; sat_flags as the mixer would report them. */
static void integrator_case(const fc_control_config_t *cfg, const char *name, uint8_t spool,
                            uint8_t airborne, uint8_t sat_flags)
{
    fc_control_state_t s;
    fc_control_out_t out;
    fc_control_init(&s, cfg, RATE_DT_S, PWM_DT_S, &out);
    fc_control_in_t in = inputs(spool, airborne, HOME_ALT_M);
    in.sat_flags = sat_flags;
    const fc_vehicle_state_t vs = rolled(TILT_RAD);
    for (int k = 0; k < 1000; k++) {
        fc_control_rate_step(&s, cfg, &in, &vs, RATE_DT_S, &out);
    }
    printf("%s %.9g %d\n", name, (double)out.pid_i_us[0], (int)out.limited[0]);
}

static void throttle_case(const fc_control_config_t *cfg, const char *name, uint8_t spool,
                          float alt_target_m)
{
    fc_control_state_t s;
    fc_control_out_t out;
    fc_control_init(&s, cfg, RATE_DT_S, PWM_DT_S, &out);
    const fc_control_in_t in = inputs(spool, spool == FC_SPOOL_FLIGHT, alt_target_m);
    const fc_vehicle_state_t vs = rolled(0.0f);
    fc_control_throttle_step(&s, cfg, &in, &vs, PWM_DT_S, &out);
    printf("%s %.9g\n", name, (double)out.throttle_us);
}

int main(void)
{
    const fc_control_config_t cfg = config();
    tilt_case(&cfg);
    integrator_case(&cfg, "wind_flight", FC_SPOOL_FLIGHT, 1, 0);
    integrator_case(&cfg, "wind_saturated", FC_SPOOL_FLIGHT, 1, FC_SAT_ROLL);
    integrator_case(&cfg, "wind_ground", FC_SPOOL_GROUND_IDLE, 0, 0);
    throttle_case(&cfg, "shut_down", FC_SPOOL_SHUT_DOWN, HOME_ALT_M);
    throttle_case(&cfg, "ground_idle", FC_SPOOL_GROUND_IDLE, HOME_ALT_M);
    throttle_case(&cfg, "hover", FC_SPOOL_FLIGHT, HOME_ALT_M);
    throttle_case(&cfg, "climb", FC_SPOOL_FLIGHT, HOME_ALT_M + 2.0f);
    return 0;
}
