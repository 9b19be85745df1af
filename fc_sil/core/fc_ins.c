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
        fc_status_t st[2];
        st[0] = fc_biquad_update_lpf(&ins->gyro_lpf[i], cfg->gyro_cutoff_hz, dt_s);
        st[1] = fc_biquad_update_lpf(&ins->accel_lpf[i], cfg->accel_cutoff_hz, dt_s);
        for (int k = 0; k < 2; k++) {
            if (first == FC_OK && st[k] != FC_OK) {
                first = st[k];
            }
        }
    }
    for (int j = 0; j < FC_INS_NOTCHES; j++) {
        if (!cfg->notch[j].enable) {
            ins->notch[j].cfg.enable = false; /* never called: the plain gyro path */
            continue;
        }
        /* Switched on: from a clean start (its first output is its input), never
         * from states left over from an earlier flight of the notch. */
        const fc_status_t st = ins->notch[j].cfg.enable
                                   ? fc_notch_configure(&ins->notch[j], &cfg->notch[j], dt_s)
                                   : fc_notch_init(&ins->notch[j], &cfg->notch[j], dt_s);
        if (first == FC_OK && st != FC_OK) {
            first = st;
        }
    }
    return first;
}

fc_status_t fc_ins_init(fc_ins_t *ins, const fc_ins_config_t *cfg, float dt_s)
{
    for (int j = 0; j < FC_INS_NOTCHES; j++) {
        ins->notch[j].cfg.enable = false; /* so configure starts each enabled one afresh */
    }
    fc_status_t st = fc_ins_configure(ins, cfg, dt_s);
    for (int i = 0; i < 3; i++) {
        fc_biquad_reset(&ins->gyro_lpf[i], 0.0f);
        fc_biquad_reset(&ins->accel_lpf[i], 0.0f);
        ins->gyro_frd_rad_s[i] = 0.0f;
        ins->accel_frd_m_s2[i] = 0.0f;
    }
    ins->rejected = 0;
    ins->primed = false;
    return st;
}

bool fc_ins_notch_enabled(const fc_ins_t *ins)
{
    return ins->notch[0].cfg.enable || ins->notch[1].cfg.enable;
}

void fc_ins_notch_track(fc_ins_t *ins, const fc_notch_inputs_t *in, float tick_s)
{
    for (int j = 0; j < FC_INS_NOTCHES; j++) {
        fc_notch_track(&ins->notch[j], in, tick_s); /* a disabled notch returns at once */
    }
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
            fc_biquad_reset(&ins->gyro_lpf[i], gyro_frd_rad_s[i]);
            fc_biquad_reset(&ins->accel_lpf[i], accel_frd_m_s2[i]);
        }
        ins->primed = true; /* the notches prime themselves from their first input */
    }
    float g[3] = {gyro_frd_rad_s[0], gyro_frd_rad_s[1], gyro_frd_rad_s[2]};
    for (int j = 0; j < FC_INS_NOTCHES; j++) {
        if (ins->notch[j].cfg.enable) {
            fc_notch_apply(&ins->notch[j], g);
        }
    }
    for (int i = 0; i < 3; i++) {
        ins->gyro_frd_rad_s[i] = fc_biquad_apply(&ins->gyro_lpf[i], g[i]);
        ins->accel_frd_m_s2[i] = fc_biquad_apply(&ins->accel_lpf[i], accel_frd_m_s2[i]);
    }
    return FC_OK;
}
