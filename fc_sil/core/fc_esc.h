/*
 * fc_esc.h - the latest telemetry report of each ESC, as the FC receives it (shared-memory
 * ESC records or the HIL link's ESC_TELEMETRY_1_TO_4), for ground stations
 * (ESC_TELEMETRY_1_TO_4, as ArduPilot's AP_ESC_Telem keeps per-ESC data) and, later,
 * for filters that track rotor speed. A store only: nothing here acts on control.
 * Pure C, no heap, no globals.
 */
#ifndef FC_ESC_H
#define FC_ESC_H

#include <stdint.h>

#include "fc_status.h"

#define FC_ESC_MAX 8
/* A report older than this is stale: its motor counts as 0 Hz (ArduPilot's ESC_RPM_DATA_TIMEOUT_US) */
#define FC_ESC_RPM_TIMEOUT_NS 1000000000LL

typedef struct fc_esc_report {
    int64_t sim_ns;          /* time of the report [ns]; -1: never reported */
    float rpm;               /* mechanical rotor speed [rev/min] */
    float voltage_v;         /* [V] */
    float current_a;         /* [A] */
    float temperature_c;     /* [degC] */
    float consumption_mah;   /* [mAh] */
    uint32_t count;          /* reports received from this ESC (wraps) */
} fc_esc_report_t;

typedef struct fc_esc {
    fc_esc_report_t esc[FC_ESC_MAX];
    uint8_t motor_count;     /* ESCs the latest report said are reporting */
    uint32_t reports;        /* reports stored */
    uint32_t rejected;       /* reports refused (motor index, non-finite value) */
} fc_esc_t;

void fc_esc_init(fc_esc_t *e);
/* Store one report; values[5] = rpm, voltage_v, current_a, temperature_c, consumption_mah.
 * FC_ERR_ARG for a motor index >= FC_ESC_MAX, FC_ERR_NONFINITE for NaN/inf (not stored). */
fc_status_t fc_esc_store(fc_esc_t *e, int64_t sim_ns, unsigned motor, unsigned motor_count,
                         const float values[5]);

#endif /* FC_ESC_H */
