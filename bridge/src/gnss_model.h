/*
 * gnss_model.h - the GNSS receiver of bridge/lowrate.py (Gnss.epoch, Gnss.fix) in plain C,
 * so that a fault-free epoch needs no Python: the step that reaches an epoch makes its fix
 * here and the sensor stage holds it for its release latency_s later (sensor_stage.h
 * sb_held), as Python's hold() did. Python keeps the model while a GNSS fault is on, and
 * for the first fix (bridge/gnss_kernel.py hands the state over and back); the fixes are
 * the same bytes either way: the same operations in the same order on the same doubles,
 * the same noise rows (lowrate.py's stream, given in blocks by Python).
 */
#ifndef SB_GNSS_MODEL_H
#define SB_GNSS_MODEL_H

#include <stddef.h>
#include <stdint.h>

#include "lowrate.h"
#include "sb_records.h"

/* What a scenario's [gnss] table fixes for the run (lowrate.py Gnss; the units there;
 * its rate is the schedule's, sb_gnss_model.lr). */
typedef struct {
    int64_t latency_ns;
    double sigma_ned_m[3];     /* pos_sigma_h_m, pos_sigma_h_m, pos_sigma_v_m */
    double tau_s;              /* pos_tau_s */
    double vel_sigma_m_s;
    double m_per_rad_lat, m_per_rad_lon;
    double ground_alt_m;       /* MSL height of the ground: the fix's altitude is this + AGL */
    uint16_t eph_cm, epv_cm;   /* the stated accuracy, as the record carries it */
    uint8_t fix_type, satellites;
} sb_gnss_cfg;

typedef struct {
    int in_c;                  /* the stage makes the epochs (Python does while 0) */
    sb_gnss_cfg c;
    sb_lowrate lr;             /* on once configured; the epochs' schedule, their noise
                                * rows (rows, 6: position NED, velocity NED), seq */
    int have_err;              /* the Gauss-Markov error has been drawn (Python: not None) */
    double err_ned_m[3];
    int64_t last_epoch_ns;
} sb_gnss_model;

/* The true state of an epoch (the step's truth, as the stage leaves it in ST_*). */
typedef struct {
    double lat_rad, lon_rad, hagl_m, vel_ned_m_s[3];
} sb_gnss_truth;

/* Epoch at sim_ns: the fix into r (kind GNSS, the next seq, sim_ns 0: its release step's
 * is set then), one noise row used, the schedule advanced. 0; 1 when that was the block's
 * last row (give the next before the next epoch); -1 when no row is left (nothing done). */
int sb_gnss_epoch(sb_gnss_model *g, const sb_gnss_truth *t, int64_t sim_ns, sb_record *r);

#endif /* SB_GNSS_MODEL_H */
