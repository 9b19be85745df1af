/*
 * fc_notch_feed.c - the harmonic notches' inputs from the core (see
 * fc_notch_feed.h): throttle and spool (MODE 1), ESC telemetry (MODE 3), the
 * in-flight FFT (MODE 4, fc_fft.h).
 */
#include "fc_notch_feed.h"

/* ESC telemetry older than this is stale (ArduPilot's ESC_RPM_DATA_TIMEOUT_US):
 * a stale motor counts as 0 Hz, which the notch holds at its floor. */
#define FC_NOTCH_ESC_TIMEOUT_NS FC_ESC_RPM_TIMEOUT_NS

/* Rotor frequencies per motor, as ArduPilot's AP_ESC_Telem reports them to the
 * notch: every motor that ever reported keeps its place (0 Hz once stale, so
 * the bank's layout does not shuffle), and the mean is over fresh motors only. */
static void esc_inputs(const fc_esc_t *e, int64_t now_ns, fc_notch_inputs_t *in)
{
    float sum_hz = 0.0f;
    unsigned fresh = 0, n = 0;
    for (unsigned i = 0; i < FC_ESC_MAX && n < FC_NOTCH_MAX_SOURCES; i++) {
        const fc_esc_report_t *r = &e->esc[i];
        if (r->sim_ns < 0) {
            continue;
        }
        const bool is_fresh = now_ns - r->sim_ns <= FC_NOTCH_ESC_TIMEOUT_NS;
        const float hz = is_fresh ? r->rpm * (1.0f / 60.0f) : 0.0f;
        in->esc_hz[n++] = hz;
        if (is_fresh) {
            sum_hz += hz;
            fresh++;
        }
    }
    in->esc_count = (uint8_t)n;
    in->esc_mean_hz = (fresh > 0) ? sum_hz / (float)fresh : 0.0f;
}

/* The in-flight FFT's centres (MODE 4), only when a notch uses them: the FFT's own
 * fallback (FFT_MINHZ scaled by throttle while no peak is healthy) comes with them. */
static void fft_inputs(const fc_core_t *c, fc_notch_inputs_t *in)
{
    in->fft_count = 0;
    bool wanted = false;
    for (int j = 0; j < FC_INS_NOTCHES; j++) {
        const fc_notch_config_t *n = &c->ins.notch[j].cfg;
        wanted = wanted || (n->enable && n->mode == FC_NOTCH_MODE_FFT);
    }
    if (!wanted) {
        return;
    }
    float hz[FC_FFT_MAX_PEAKS];
    const unsigned count = fc_fft_notch_freqs(&c->fft, in->throttle, hz);
    for (unsigned i = 0; i < count && i < FC_FFT_MAX_PEAKS && i < FC_NOTCH_MAX_SOURCES; i++) {
        in->fft_hz[i] = hz[i];
        in->fft_count = (uint8_t)(i + 1u);
    }
}

void fc_notch_feed(fc_core_t *c)
{
    if (!fc_ins_notch_enabled(&c->ins)) {
        return;
    }
    fc_notch_inputs_t in;
    in.throttle = fc_mixer_throttle_out(&c->mixer, &c->cfg.mix);
    in.motors_stopped = c->spool == FC_SPOOL_SHUT_DOWN;
    esc_inputs(&c->esc, c->last_imu_ns, &in);
    fft_inputs(c, &in);
    fc_ins_notch_track(&c->ins, &in, (float)c->pwm_period_ns * 1e-9f);
}
