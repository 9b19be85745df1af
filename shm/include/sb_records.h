/*
 * sb_records.h - the records that cross the bridge <-> FC boundary.
 *
 * Defined once here; the Python view (silbridge.shm.records) is checked
 * against sizeof/offsetof in tests/shm/test_layout.py. Every record is one
 * 64-byte slot (one cache line): a 24-byte header and a 40-byte payload.
 * 64 bytes keeps the ring streaming at tens of millions of records/s across
 * cores; ground truth therefore spans two kinds (GT_ATT and GT_NAV) published
 * back to back with the same sim time.
 *
 * Byte order is little-endian (x86-64, AArch64, Cortex-M all are); there is
 * no implicit padding: every field sits at its natural alignment and the
 * static_asserts below pin the layout.
 *
 * Frames: body FRD, world NED (README "Layout" and docs/hil_transport.md).
 * Time:   sim_ns  = simulation time since run start, int64 ns.
 *         wall_ns = CLOCK_MONOTONIC at publish, int64 ns.
 */
#ifndef SB_RECORDS_H
#define SB_RECORDS_H

#include <stdint.h>

#define SB_RECORDS_VERSION 1u
#define SB_RECORD_SIZE 64u
#define SB_PWM_MAX_CHANNELS 8u

/* Record kinds. Values are permanent: a retired kind keeps its number. */
enum sb_kind {
    SB_KIND_NONE = 0,
    SB_KIND_IMU = 1,      /* bridge -> FC */
    SB_KIND_BARO = 2,     /* bridge -> FC */
    SB_KIND_MAG = 3,      /* bridge -> FC */
    SB_KIND_GNSS = 4,     /* bridge -> FC */
    SB_KIND_GT_ATT = 5,   /* bridge -> FC, ground truth: attitude part */
    SB_KIND_GT_NAV = 6,   /* bridge -> FC, ground truth: navigation part */
    SB_KIND_PWM = 7,      /* FC -> bridge */
    SB_KIND_SETPOINT = 8, /* bridge -> FC, scripted scenario setpoint */
    SB_KIND_ESC = 9,      /* bridge -> FC, one ESC's telemetry report (off unless asked) */
    SB_KIND_BATTERY = 10, /* bridge -> FC, the physics-side battery pack (10 Hz) */
    SB_KIND_FAULT = 11,   /* FC -> bridge, a fault switched on or off (shm/fault_catalog.py) */
    SB_KIND_COUNT = 12
};

/* Header flags. */
#define SB_FLAG_STEP_END 0x0001u /* last record the bridge publishes for a physics step */

typedef struct sb_header {
    uint16_t kind;    /* enum sb_kind */
    uint16_t flags;   /* SB_FLAG_* */
    uint32_t seq;     /* per-kind sequence number, starts at 0, wraps at 2^32 */
    int64_t sim_ns;   /* simulation time of the sample [ns] */
    int64_t wall_ns;  /* monotonic wall clock at publish [ns] */
} sb_header;          /* 24 bytes */

typedef struct sb_imu {
    float accel_frd_m_s2[3]; /* specific force, body FRD [m/s^2]; z = -9.81 at rest */
    float gyro_frd_rad_s[3]; /* angular rate, body FRD [rad/s] */
    float temperature_c;     /* sensor die temperature [degC] */
    uint32_t sample_index;   /* index within the physics step when oversampled (0..n-1) */
    uint32_t samples_per_step; /* IMU samples per physics step (1 at 1 kHz / 1 ms physics) */
    uint32_t reserved;
} sb_imu;                    /* 40 bytes */

typedef struct sb_baro {
    float pressure_pa;      /* static pressure [Pa] */
    float temperature_c;    /* [degC] */
    uint8_t reserved[32];
} sb_baro;

typedef struct sb_mag {
    float field_frd_gauss[3]; /* Earth field in body FRD [gauss] */
    uint8_t reserved[28];
} sb_mag;

typedef struct sb_gnss {
    int32_t lat_e7;          /* latitude [deg * 1e7] */
    int32_t lon_e7;          /* longitude [deg * 1e7] */
    int32_t alt_mm;          /* altitude above mean sea level [mm] */
    float vel_ned_m_s[3];    /* velocity NED [m/s] */
    uint16_t eph_cm;         /* horizontal dilution / accuracy [cm] */
    uint16_t epv_cm;         /* vertical accuracy [cm] */
    uint8_t fix_type;        /* 0 none, 2 2D, 3 3D (MAVLink GPS_FIX_TYPE) */
    uint8_t satellites;      /* satellites visible */
    uint8_t reserved[10];
} sb_gnss;

typedef struct sb_gt_att {
    float q_wxyz[4];          /* attitude, rotates body FRD to world NED */
    float rates_frd_rad_s[3]; /* true body rates, FRD [rad/s] */
    float specific_force_frd_m_s2[3]; /* true specific force, FRD [m/s^2] */
} sb_gt_att;                  /* 40 bytes */

typedef struct sb_gt_nav {
    double pos_ned_m[3];      /* position relative to home, NED [m] */
    float vel_ned_m_s[3];     /* velocity NED [m/s] */
    uint8_t on_ground;        /* 1 while any landing-gear contact is loaded */
    uint8_t reserved[3];
} sb_gt_nav;                  /* 40 bytes */

typedef struct sb_pwm {
    uint16_t pwm_us[SB_PWM_MAX_CHANNELS]; /* ESC pulse width [us], 1000..2000 */
    uint8_t channel_count;   /* channels in use (4 for quad X) */
    uint8_t armed;           /* 1 when the FC is armed */
    uint16_t reserved0;
    uint32_t fc_step_seq;    /* seq of the last sensor record the FC had consumed */
    int64_t imu_sim_ns;      /* sim time of the IMU sample this PWM was computed from */
    uint8_t reserved[8];
} sb_pwm;                    /* 40 bytes */

typedef struct sb_setpoint {
    float roll_rad;          /* attitude setpoint [rad] */
    float pitch_rad;
    float yaw_rad;
    float altitude_m;        /* altitude setpoint above home [m], NaN = keep */
    uint32_t mask;           /* bit 0 attitude valid, bit 1 altitude valid, bit 2 yaw valid */
    uint8_t reserved[20];
} sb_setpoint;

/* One ESC's telemetry report, as BLHeli_32 serial telemetry / bidirectional DShot give it
 * per ESC: one record per motor per report epoch, all of an epoch at the same sim_ns.
 * Values are quantised at the source to what the ESC reports (bridge/esc_telemetry.py). */
typedef struct sb_esc {
    uint8_t motor;           /* 0-based motor index (ArduCopter quad X order) */
    uint8_t motor_count;     /* ESCs reporting */
    uint16_t reserved0;
    float rpm;               /* mechanical rotor speed [rev/min], whole rpm */
    float voltage_v;         /* pack voltage at the ESC [V], 0.01 V steps */
    float current_a;         /* battery-side ESC current [A], 0.01 A steps */
    float temperature_c;     /* ESC temperature [degC], whole degrees */
    float consumption_mah;   /* charge this ESC drew since start [mAh], whole mAh */
    uint8_t reserved[16];
} sb_esc;                    /* 40 bytes */

/* The physics-side battery pack (bridge/battery/), as a smart battery reports it: pack
 * terminal voltage and current, the charge drawn, the state of charge and the weakest cell.
 * One record per report ([battery] rate_hz, 10 Hz). Quantised at the source to what
 * BATTERY_STATUS carries (whole mV per cell, cA, whole mAh, whole %, cdegC), so the FC
 * reads the same numbers over shared memory and over MAVLink HIL. */
typedef struct sb_battery {
    float voltage_v;         /* pack terminal voltage under load [V] */
    float current_a;         /* pack current, ESCs plus avionics [A] */
    float consumed_mah;      /* charge drawn since start [mAh] */
    float remaining;         /* charge left over the nominal capacity, 0..1 */
    float temperature_c;     /* pack temperature [degC] */
    float lowest_cell_v;     /* terminal voltage of the lowest cell [V] */
    uint8_t cell_count;      /* cells in series */
    uint8_t reserved[15];
} sb_battery;                /* 40 bytes */

/* A fault the FC switches on or off (MAV_CMD_INJECT_FAILURE, a SIM_* parameter), forwarded
 * beside the PWM for the bridge's fault engine to apply. Units, types and the meaning of the
 * parameter slots are numbered in shm/fault_catalog.py (pack_params: catalog order, a vec3
 * in three slots, unused slots 0). */
typedef struct sb_fault {
    uint8_t action;          /* 1 on, 0 off */
    uint8_t unit;            /* catalog unit code (gnss 1, baro 2, ...) */
    uint8_t type;            /* catalog type code within the unit */
    uint8_t instance;        /* 1-based instance; 0 all where the unit allows it */
    float params[9];         /* the type's parameters in catalog units, MAX_PARAM_SLOTS */
} sb_fault;                  /* 40 bytes */

typedef struct sb_record {
    sb_header h;
    union {
        sb_imu imu;
        sb_baro baro;
        sb_mag mag;
        sb_gnss gnss;
        sb_gt_att gt_att;
        sb_gt_nav gt_nav;
        sb_pwm pwm;
        sb_setpoint setpoint;
        sb_esc esc;
        sb_battery battery;
        sb_fault fault;
        uint8_t raw[40];
    } u;
} sb_record;

#if defined(__cplusplus)
#define SB_STATIC_ASSERT static_assert
#else
#define SB_STATIC_ASSERT _Static_assert
#endif
SB_STATIC_ASSERT(sizeof(sb_header) == 24, "sb_header must be 24 bytes");
SB_STATIC_ASSERT(sizeof(sb_imu) == 40, "payload must be 40 bytes");
SB_STATIC_ASSERT(sizeof(sb_baro) == 40, "payload must be 40 bytes");
SB_STATIC_ASSERT(sizeof(sb_mag) == 40, "payload must be 40 bytes");
SB_STATIC_ASSERT(sizeof(sb_gnss) == 40, "payload must be 40 bytes");
SB_STATIC_ASSERT(sizeof(sb_gt_att) == 40, "payload must be 40 bytes");
SB_STATIC_ASSERT(sizeof(sb_gt_nav) == 40, "payload must be 40 bytes");
SB_STATIC_ASSERT(sizeof(sb_pwm) == 40, "payload must be 40 bytes");
SB_STATIC_ASSERT(sizeof(sb_setpoint) == 40, "payload must be 40 bytes");
SB_STATIC_ASSERT(sizeof(sb_esc) == 40, "payload must be 40 bytes");
SB_STATIC_ASSERT(sizeof(sb_battery) == 40, "payload must be 40 bytes");
SB_STATIC_ASSERT(sizeof(sb_fault) == 40, "payload must be 40 bytes");
SB_STATIC_ASSERT(sizeof(sb_record) == SB_RECORD_SIZE, "a record is one 64-byte slot");

/* Does one of the n records have a kind in mask (bit k: kind k)? The lockstep's hand-on
 * kinds (shm/lockstep.py HAND_ON_KINDS), checked by the bridge, the FC's poll and its serve
 * loop. */
static inline int sb_records_any_kind(const sb_record *r, uint64_t n, uint64_t mask)
{
    for (uint64_t i = 0; i < n; i++) {
        if (r[i].h.kind < 64u && ((mask >> r[i].h.kind) & 1u))
            return 1;
    }
    return 0;
}

#endif /* SB_RECORDS_H */
