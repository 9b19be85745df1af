/*
 * fc_fft_params.c - FFT_* parameters to fc_fft_config_t (see fc_fft_params.h).
 */
#include "fc_fft_params.h"

/* INS_HNTCH_MODE value that has a notch follow the FFT (HarmonicNotchDynamicMode). */
#define FC_FFT_NOTCH_MODE 4
/* INS_HNTCH_OPTS bit 1: one notch per tracked peak (ArduPilot: MAX_TRACKED_PEAKS of them). */
#define FC_FFT_NOTCH_OPT_PER_PEAK 0x2

/* The notch the FFT feeds: ArduPilot's init ORs the harmonics of every enabled notch and
 * takes the most dynamic notches of any; no enabled notch leaves the default (3). */
static void notch_setup(const fc_params_t *p, fc_fft_config_t *cfg)
{
    const struct { int enable, mode, hmncs, opts; } notch[2] = {
        {p->ins_hntch_enable, p->ins_hntch_mode, (int)p->ins_hntch_hmncs, p->ins_hntch_opts},
        {p->ins_hntc2_enable, p->ins_hntc2_mode, (int)p->ins_hntc2_hmncs, p->ins_hntc2_opts},
    };
    unsigned harmonics = 0;
    uint8_t notches = 1;
    for (int i = 0; i < 2; i++) {
        if (notch[i].enable == 0) {
            continue;
        }
        harmonics |= (unsigned)notch[i].hmncs;
        if (notch[i].mode == FC_FFT_NOTCH_MODE && (notch[i].opts & FC_FFT_NOTCH_OPT_PER_PEAK)) {
            notches = FC_FFT_MAX_PEAKS;
        }
    }
    cfg->harmonics = (uint16_t)harmonics;
    cfg->notches = notches;
}

void fc_fft_config_from_params(const fc_params_t *p, fc_fft_config_t *cfg)
{
    cfg->enable = p->fft_enable != 0;
    cfg->min_hz = (float)p->fft_minhz;
    cfg->max_hz = (float)p->fft_maxhz;
    cfg->sample_mode = (uint8_t)p->fft_sample_mode;
    cfg->window_size = (uint16_t)p->fft_window_size;
    cfg->window_overlap = p->fft_window_olap;
    cfg->freq_hover_hz = p->fft_freq_hover;
    cfg->thr_ref = p->fft_thr_ref;
    cfg->snr_ref_db = p->fft_snr_ref;
    cfg->att_ref_db = p->fft_att_ref;
    cfg->bw_hover_hz = p->fft_bw_hover;
    cfg->hmnc_fit_pct = (float)p->fft_hmnc_fit;
    cfg->hmnc_peak = (uint8_t)p->fft_hmnc_peak;
    cfg->num_frames = (uint8_t)p->fft_num_frames;
    cfg->options = (uint8_t)p->fft_options;
    notch_setup(p, cfg);
}
