/*
 * fc_ins.c - IMU front end (see fc_ins.h).
 */
#include "fc_ins.h"

#include "fc_math.h"

fc_status_t fc_ins_configure(fc_ins_t *ins, const fc_ins_config_t *cfg, float dt_s)
{
    fc_status_t first = FC_OK;
    ins->cfg = *cfg;
    ins->dt_s = dt_s;
    for (int i = 0; i < 3; i++) {
        fc_status_t st[3];
        st[0] = fc_biquad_update_lpf(&ins->gyro_lpf[i], cfg->gyro_cutoff_hz, dt_s);
        st[1] = fc_biquad_update_lpf(&ins->accel_lpf[i], cfg->accel_cutoff_hz, dt_s);
        st[2] = fc_biquad_update_notch(&ins->gyro_notch[i],
                                       cfg->notch_enable ? cfg->notch_center_hz : 0.0f,
                                       cfg->notch_bandwidth_hz, dt_s);
        for (int k = 0; k < 3; k++) {
            if (first == FC_OK && st[k] != FC_OK) {
                first = st[k];
            }
        }
    }
    return first;
}

fc_status_t fc_ins_init(fc_ins_t *ins, const fc_ins_config_t *cfg, float dt_s)
{
    fc_status_t st = fc_ins_configure(ins, cfg, dt_s);
    for (int i = 0; i < 3; i++) {
        fc_biquad_reset(&ins->gyro_lpf[i], 0.0f);
        fc_biquad_reset(&ins->accel_lpf[i], 0.0f);
        fc_biquad_reset(&ins->gyro_notch[i], 0.0f);
        ins->gyro_frd_rad_s[i] = 0.0f;
        ins->accel_frd_m_s2[i] = 0.0f;
    }
    ins->rejected = 0;
    ins->primed = false;
    return st;
}

fc_status_t fc_ins_update(fc_ins_t *ins, const float accel_frd_m_s2[3],
                          const float gyro_frd_rad_s[3])
{
    if (!fc_finite3(accel_frd_m_s2) || !fc_finite3(gyro_frd_rad_s)) {
        ins->rejected++;
        return FC_ERR_NONFINITE;
    }
    if (!ins->primed) {
        for (int i = 0; i < 3; i++) {
            fc_biquad_reset(&ins->gyro_notch[i], gyro_frd_rad_s[i]);
            fc_biquad_reset(&ins->gyro_lpf[i], gyro_frd_rad_s[i]);
            fc_biquad_reset(&ins->accel_lpf[i], accel_frd_m_s2[i]);
        }
        ins->primed = true;
    }
    for (int i = 0; i < 3; i++) {
        const float g = fc_biquad_apply(&ins->gyro_notch[i], gyro_frd_rad_s[i]);
        ins->gyro_frd_rad_s[i] = fc_biquad_apply(&ins->gyro_lpf[i], g);
        ins->accel_frd_m_s2[i] = fc_biquad_apply(&ins->accel_lpf[i], accel_frd_m_s2[i]);
    }
    return FC_OK;
}
