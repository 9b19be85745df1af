/*
 * fc_fft_esc.c - FFT_OPTIONS bit 1: warn when the gyro, after the filters, still carries
 * noise at a motor's frequency as its ESC reports it (ArduCopter 4.6's
 * AP_Vehicle::check_motor_noise with AP_GyroFFT::has_noise_at_frequency_hz, rewritten).
 *
 * Why it needs bit 0 as well and no FFT-driven notch: the check asks whether the filters
 * left a motor line in the gyro the controller sees, so the FFT must analyse the filtered
 * gyro; a notch that follows the FFT already moves onto whatever the FFT finds.
 * Each check low-passes, per motor, the SNR of a tracked peak within one bin of the
 * motor's frequency (fc_fft_noise_at_hz) and names every motor above
 * FC_FFT_ESC_WARN_DB, at most once per FC_FFT_ESC_QUIET_S. The text itself
 * ("Noise %.fdB on motor %u at %.fHz") is the caller's (fc_sil/fft_notice.py).
 */
#include "fc_fft.h"

#include "fc_math.h"

#define FC_FFT_ESC_WARN_DB 40.0f    /* an SNR this high is a motor line the filters missed */
#define FC_FFT_ESC_QUIET_S 5.0f     /* at most one round of warnings per this long */
#define FC_FFT_ESC_CORNER_HZ 2.0f   /* the per-motor SNR low-pass (AP_Vehicle::setup) */

unsigned fc_fft_esc_noise_check(fc_fft_t *f, const float *motor_hz, unsigned n, bool armed,
                                bool fft_notch, float dt_s)
{
    fc_fft_esc_noise_t *e = &f->esc_noise;
    /* a clock since boot, as ArduPilot's millis(): the first warning waits 5 s of it too */
    if (dt_s > 0.0f && fc_finitef(dt_s)) {
        e->since_warning_s += dt_s;
    }
    const uint32_t both = FC_FFT_OPT_POST_FILTER | FC_FFT_OPT_ESC_CHECK;
    if (!f->active || !armed || (f->cfg.options & both) != both || fft_notch) {
        return 0u;
    }
    /* ArduPilot filters with the task's nominal period, not the measured one */
    const float rc = 1.0f / (FC_TWO_PI_F * FC_FFT_ESC_CORNER_HZ);
    const float alpha = FC_FFT_ESC_CHECK_S / (FC_FFT_ESC_CHECK_S + rc);
    const bool may_warn = e->since_warning_s > FC_FFT_ESC_QUIET_S;
    unsigned warn = 0u;
    for (unsigned i = 0; i < n && i < FC_FFT_ESC_MAX; i++) {
        if (!(motor_hz[i] != 0.0f) || !fc_finitef(motor_hz[i])) {
            continue; /* no report, or stale: the motor's filter holds */
        }
        const float snr_db = fc_fft_noise_at_hz(f, motor_hz[i]);
        if (!e->seen[i]) {
            e->energy_db[i] = snr_db;
            e->seen[i] = true;
        } else {
            e->energy_db[i] += alpha * (snr_db - e->energy_db[i]);
        }
        if (e->energy_db[i] > FC_FFT_ESC_WARN_DB && may_warn) {
            warn |= 1u << i;
        }
    }
    if (warn != 0u) {
        e->since_warning_s = 0.0f;
    }
    return warn;
}
