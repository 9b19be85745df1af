/*
 * imu_noise.h - the one-sample-per-step IMU's noise rows of a block (bridge/imu.py
 * ImuModel.next_scalar_block): the bias walk accumulated, the turn-on bias and the
 * temperature drift added, the white noise on top. numpy did it in a dozen passes over the
 * block (a cumulative sum, an outer product, three sums, copies), 0.2 us a physics step;
 * one pass in C does the same additions and products in the same order, so every value is
 * numpy's to the bit (tests/bridge/test_imu_noise.py). Plain C, no allocation.
 */
#ifndef SB_IMU_NOISE_H
#define SB_IMU_NOISE_H

#include <stddef.h>

/* For each of `rows` steps i, channel j (gyro xyz, accel xyz):
 *   last[j] += inc[i][j]                                        (the walk: numpy's cumsum)
 *   slow[i][j] = (last[j] + turn_on[j]) + (temps[i] - temp_ref_c) * tempco[j]
 *   out[i][j]  = slow[i][j] + white[i][j]
 * last is the walk's value before the block and after it on return. */
void sb_imu_noise_rows(size_t rows, const double *inc, const double *white,
                       const double *temps, const double turn_on[6], const double tempco[6],
                       double temp_ref_c, double last[6], double *slow, double *out);

#endif /* SB_IMU_NOISE_H */
