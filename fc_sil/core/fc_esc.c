/*
 * fc_esc.c - the ESC telemetry store (see fc_esc.h).
 */
#include "fc_esc.h"

#include <math.h>

void fc_esc_init(fc_esc_t *e)
{
    fc_esc_t z = {0};
    *e = z;
    for (int i = 0; i < FC_ESC_MAX; i++) {
        e->esc[i].sim_ns = -1;
    }
}

fc_status_t fc_esc_store(fc_esc_t *e, int64_t sim_ns, unsigned motor, unsigned motor_count,
                         const float values[5])
{
    if (motor >= FC_ESC_MAX) {
        e->rejected++;
        return FC_ERR_ARG;
    }
    for (int i = 0; i < 5; i++) {
        if (!isfinite(values[i])) {
            e->rejected++;
            return FC_ERR_NONFINITE;
        }
    }
    fc_esc_report_t *r = &e->esc[motor];
    r->sim_ns = sim_ns;
    r->rpm = values[0];
    r->voltage_v = values[1];
    r->current_a = values[2];
    r->temperature_c = values[3];
    r->consumption_mah = values[4];
    r->count++;
    e->motor_count = (uint8_t)(motor_count < FC_ESC_MAX ? motor_count : FC_ESC_MAX);
    e->reports++;
    return FC_OK;
}
