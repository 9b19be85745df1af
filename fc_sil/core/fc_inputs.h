/*
 * fc_inputs.h - the targets a host sets between steps (fc_core_set_* in
 * fc_core.h validate them): arming, attitude, yaw and the vertical target in
 * one of three modes. The controllers and the spool logic read them here.
 */
#ifndef FC_INPUTS_H
#define FC_INPUTS_H

#include <stdint.h>

typedef struct fc_core_inputs {
    uint8_t armed;
    uint8_t yaw_hold;        /* 1: yaw angle target; 0: yaw rate target */
    uint8_t alt_mode;        /* fc_alt_mode_t */
    uint8_t vibe_comp;       /* 1: the altitude loop's vibration-resistant law (FS_VIBE_ENABLE) */
    float roll_target_rad;
    float pitch_target_rad;
    float yaw_target_rad;
    float yaw_rate_target_rad_s;
    float alt_target_m;      /* above home, up */
    float climb_target_m_s;  /* up */
    float throttle;          /* 0..1, direct-throttle mode */
} fc_core_inputs_t;

#endif /* FC_INPUTS_H */
