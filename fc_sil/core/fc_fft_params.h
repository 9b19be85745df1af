/*
 * fc_fft_params.h - the in-flight FFT's configuration from the parameters (FFT_*, and
 * the harmonics of the notch it feeds). Kept apart so fc_fft itself knows no parameter
 * system.
 */
#ifndef FC_FFT_PARAMS_H
#define FC_FFT_PARAMS_H

#include "fc_fft.h"
#include "fc_params.h"

void fc_fft_config_from_params(const fc_params_t *p, fc_fft_config_t *cfg);

#endif /* FC_FFT_PARAMS_H */
