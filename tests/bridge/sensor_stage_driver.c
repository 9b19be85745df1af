/*
 * sensor_stage_driver.c - runs the pure-C sensor stage (bridge/src/sensor_stage.c) with
 * no Python at all, for tests/bridge/test_sensor_stage.py: every input arrives on the
 * command line as name=value, sample fields and constants by the names of the stage's
 * own tables; one step is run and its result printed:
 *   line 1: the return value; line 2: the written slots in hex; line 3: the state array.
 * List values (imu_noise=a,b,...) are comma separated; doubles print with %.17g.
 */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sensor_stage.h"

static int list(const char *v, double *out, int n)
{
    char *end;
    for (int i = 0; i < n; i++) {
        out[i] = strtod(v, &end);
        if (end == v)
            return -1;
        v = *end == ',' ? end + 1 : end;
    }
    return 0;
}

/* name=value into the field of `table` with that name; 1 found, 0 not this table. */
static int named(const sb_named_double *table, int n, void *base, const char *name,
                 const char *v)
{
    for (int i = 0; i < n; i++)
        if (strcmp(table[i].name, name) == 0) {
            double d = strtod(v, NULL);
            memcpy((char *)base + table[i].offset, &d, sizeof d);
            return 1;
        }
    return 0;
}

int main(int argc, char **argv)
{
    sb_fdm_sample in;
    sb_stage_consts c;
    double state[ST_COUNT] = {0}, phase[4] = {0}, imu_noise[6] = {0}, temp = 0;
    double baro[4] = {0}, mag[8] = {0}, baro_noise = 0, mag_noise[3] = {0}, x[4] = {0};
    memset(&in, 0, sizeof in);
    memset(&c, 0, sizeof c);
    for (int a = 1; a < argc; a++) {
        char name[64];
        const char *eq = strchr(argv[a], '=');
        if (eq == NULL || (size_t)(eq - argv[a]) >= sizeof name)
            return 2;
        memcpy(name, argv[a], (size_t)(eq - argv[a]));
        name[eq - argv[a]] = '\0';
        const char *v = eq + 1;
        int ok = named(SB_FDM_SAMPLE_FIELDS, SB_FDM_SAMPLE_FIELD_COUNT, &in, name, v) ||
                 named(SB_STAGE_CONST_FIELDS, SB_STAGE_CONST_FIELD_COUNT, &c, name, v);
        if (!ok && strcmp(name, "phase") == 0) ok = !list(v, phase, 4);
        if (!ok && strcmp(name, "imu_noise") == 0) ok = !list(v, imu_noise, 6);
        if (!ok && strcmp(name, "imu_temp_c") == 0) ok = !list(v, &temp, 1);
        if (!ok && strcmp(name, "baro") == 0) ok = !list(v, baro, 3);
        if (!ok && strcmp(name, "mag") == 0) ok = !list(v, mag, 8);
        if (!ok && strcmp(name, "baro_noise") == 0) ok = !list(v, &baro_noise, 1);
        if (!ok && strcmp(name, "mag_noise") == 0) ok = !list(v, mag_noise, 3);
        /* sim_ns, next_slow_ns, flip_steps, filtered baro pressure [Pa] */
        if (!ok && strcmp(name, "step") == 0) ok = !list(v, x, 4);
        if (!ok) {
            fprintf(stderr, "unknown input %s\n", name);
            return 2;
        }
    }
    sb_sensor_stage s;
    state[ST_BARO_PA] = x[3];
    sb_sensor_stage_init(&s, &c, state, phase, (int64_t)x[2], 1, 0);
    sb_sensor_stage_set_imu_noise(&s, imu_noise, &temp, 1);
    if (sb_lowrate_start(&s.baro, baro[0]) < 0 || sb_lowrate_start(&s.mag, mag[0]) < 0)
        return 2;
    s.baro_offset_pa = baro[1];
    s.baro_noise_pa = baro[2];
    memcpy(s.mag_field_ned_gauss, &mag[1], sizeof s.mag_field_ned_gauss);
    memcpy(s.mag_offset_gauss, &mag[4], sizeof s.mag_offset_gauss);
    s.mag_noise_gauss = mag[7];
    sb_lowrate_set_noise(&s.baro, &baro_noise, 1, 0);
    sb_lowrate_set_noise(&s.mag, mag_noise, 1, 0);
    s.next_slow_ns = (int64_t)x[1];
    sb_record slots[8];
    memset(slots, 0, sizeof slots);
    const long r = sb_sensor_stage_step(&s, &in, (int64_t)x[0], slots, 8, 0);
    printf("%ld\n", r);
    const unsigned char *b = (const unsigned char *)slots;
    for (size_t i = 0; r > 0 && i < (size_t)(r & 0xFF) * sizeof(sb_record); i++)
        printf("%02x", b[i]);
    printf("\n");
    for (int i = 0; i < ST_COUNT; i++)
        printf("%.17g%c", state[i], i + 1 < ST_COUNT ? ' ' : '\n');
    return 0;
}
