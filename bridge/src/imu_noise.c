/*
 * imu_noise.c - a block of the IMU's noise rows (imu_noise.h), each expression in numpy's
 * operand order: (walk + turn_on) + (temp - ref) * tempco, then + white.
 */
#include "imu_noise.h"

void sb_imu_noise_rows(size_t rows, const double *inc, const double *white,
                       const double *temps, const double turn_on[6], const double tempco[6],
                       double temp_ref_c, double last[6], double *slow, double *out)
{
    for (size_t i = 0; i < rows; i++) {
        const double dtemp = temps[i] - temp_ref_c;
        for (size_t j = 0; j < 6; j++) {
            const size_t k = 6 * i + j;
            last[j] = last[j] + inc[k];
            slow[k] = (last[j] + turn_on[j]) + dtemp * tempco[j];
            out[k] = slow[k] + white[k];
        }
    }
}
