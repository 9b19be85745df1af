/*
 * sensor_stage.h - the bridge's sensor stage in plain C: one FDM sample (what JSBSim
 * holds after a physics step) in, the step's records out (scalar IMU, GT_ATT, GT_NAV,
 * then baro and magnetometer when due, GNSS fixes held to their release (made here at
 * their epoch while the C model is on, gnss_model.h), the battery's report), with the
 * crash and contact flags Python acts on.
 *
 * No Python and no JSBSim here, as PX4 keeps RateControl free of topics: the CPython
 * shim (step_run.c) runs JSBSim, fills an sb_fdm_sample through the field table below
 * and calls sb_sensor_stage_step. The sample is the seam for whatever reads the FDM:
 * JSBSim's property nodes read from C, or their bound Python methods; the stage does not
 * change. Constants arrive by name (SB_STAGE_CONST_FIELDS), never by position.
 *
 * Same formulas, in the same operation order, as the Python oracle
 * (tests/bridge/step_kernel_oracle.py); built without FP contraction, both give the same bytes.
 */
#ifndef SB_SENSOR_STAGE_H
#define SB_SENSOR_STAGE_H

#include <stddef.h>
#include <stdint.h>

#include "battery.h"
#include "gnss_model.h"
#include "imu_chip.h"
#include "imu_raw.h"
#include "lowrate.h"
#include "sb_records.h"
#include "sensor_faults.h"
#include "step_maths.h"
#include "vibration.h"

/* One FDM sample after a physics step, in the units JSBSim reports: the stage converts
 * them (once, here). The field names are the getter names Python binds (fdm.py). */
typedef struct {
    double p_rad_s, q_rad_s, r_rad_s;        /* body rates FRD */
    double fbx_lbf, fby_lbf, fbz_lbf;        /* total non-gravity force, body FRD */
    double phi_rad, theta_rad, psi_rad;      /* ZYX Euler angles, body FRD -> NED */
    double vn_ft_s, ve_ft_s, vd_ft_s;        /* velocity NED */
    double lat_rad, lon_rad;                 /* geodetic latitude, longitude */
    double geod_alt_ft;                      /* CG geodetic altitude; minus terrain_ft: the
                                                height above ground (bridge/fdm.py says why) */
    double omega_rad_s[4];                   /* rotor speeds, motors 1..4 */
    double gear_contacts;                    /* > 0 while a leg is loaded */
    double pressure_psf;                     /* static pressure [lbf/ft^2] */
    double temperature_r;                    /* static air temperature [degR] */
} sb_fdm_sample;

/* Constants of one run (simulator.py computes them; imu.py documents the IMU ones). */
typedef struct {
    double lbf_to_m_s2;     /* specific force per body force: ft->m / mass [slug] */
    double ft_m;            /* m per ft */
    double psf_pa;          /* Pa per lbf/ft^2 */
    double lat0_rad;        /* home latitude */
    double lon0_rad;        /* home longitude */
    double m_per_rad_lat;   /* local NED north per rad of latitude [m] */
    double m_per_rad_lon;   /* east per rad of longitude [m] */
    double agl0_m;          /* CG height at rest at home (NED down 0) [m] */
    double baro_alpha;      /* per-step weight of the baro's first-order lag */
    double cos_crash_tilt;  /* on the ground, a tilt cosine below this is a tip-over */
    double strike_agl_m;    /* below this CG height a rotor strike is checked [m] */
    double terrain_ft;      /* the terrain's elevation JSBSim was given (flat ground) [ft] */
    sb_imu_consts imu;      /* the one-sample-per-step IMU model */
    /* Issue 26, all unused while vib.on and imu_rot_on are 0 (then the IMU is exactly the
     * model above): rotor vibration through frame and mount, the chip's ODR and AAF; the
     * IMU's mounting rotation R_imu_from_body (row-major, the vehicle draw's), applied to
     * the IMU's true signal when imu_rot_on is 1. */
    sb_vib_consts vib;
    sb_chip_consts chip;
    double imu_rot_on;
    double imu_rot[9];
} sb_stage_consts;

/* A struct member a name refers to: the C side of a contract by name. */
typedef struct {
    const char *name;
    size_t offset;          /* of a double in the struct */
} sb_named_double;

#define SB_FDM_SAMPLE_FIELD_COUNT 22
#define SB_STAGE_CONST_FIELD_COUNT 78
extern const sb_named_double SB_FDM_SAMPLE_FIELDS[SB_FDM_SAMPLE_FIELD_COUNT];
extern const sb_named_double SB_STAGE_CONST_FIELDS[SB_STAGE_CONST_FIELD_COUNT];

/* State slots (doubles) the stage leaves in the caller's state array for Python. */
enum {
    ST_W = 0,          /* 0..2 body rates FRD [rad/s] */
    ST_F = 3,          /* 3..5 specific force FRD [m/s^2] */
    ST_EULER = 6,      /* 6..8 phi, theta, psi [rad] */
    ST_VEL = 9,        /* 9..11 velocity NED [m/s] */
    ST_LAT = 12,       /* geodetic latitude [rad] */
    ST_LON = 13,       /* longitude [rad] */
    ST_HAGL = 14,      /* CG height above ground [m] */
    ST_OMEGA = 15,     /* 15..18 rotor speeds [rad/s] */
    ST_ON_GROUND = 19, /* 1.0 while a leg is loaded */
    ST_BARO_PA = 20,   /* lagged static pressure [Pa]; the stage's filter state too */
    ST_TEMP_C = 21,    /* IMU die temperature of the last sample [degC] */
    ST_PREV_VD = 22,   /* down velocity of the step before [m/s] */
    ST_COS_TILT = 23,  /* cosine of the tilt from level */
    ST_COUNT = 24
};

/* Returned flags: the low byte is the number of records written. */
#define F_SLOW_DUE 0x100      /* sim_ns reached next_slow_ns: setpoint, ESC, GNSS from Python */
#define F_BLOCK_DONE 0x200    /* IMU noise used up: give the next block before the next step */
#define F_GROUND_CHANGED 0x400
#define F_TIPPED 0x800        /* on the ground, tilted past the crash tilt */
#define F_FLIPPED 0x1000      /* upside down for flip_steps steps */
#define F_ROTOR_STRIKE 0x2000
#define F_BARO_BLOCK_DONE 0x4000  /* baro noise used up */
#define F_MAG_BLOCK_DONE 0x8000   /* mag noise used up */
#define F_GNSS_BLOCK_DONE 0x10000 /* the C GNSS's noise used up (gnss_model.h) */
/* The flags that end a step for Python: all but the low byte's record count. */
#define F_PYTHON_MASK (~0xFFL)

/* Negative returns of sb_sensor_stage_step (sb_sensor_stage_error words them). */
enum {
    SB_STAGE_NO_IMU_NOISE = -1,
    SB_STAGE_BUFFER_FULL = -2,
    SB_STAGE_NO_BARO_NOISE = -3,
    SB_STAGE_NO_MAG_NOISE = -4,
    SB_STAGE_NO_GNSS_NOISE = -5,
    SB_STAGE_GNSS_HELD_FULL = -6
};

/* Records Python made ahead of their release (a GNSS fix, made at its epoch and released
 * latency_s later): the stage writes each at the first step at or after its due time,
 * after the baro and mag, so that step needs no Python (simulator.py _slow_sensors). */
#define SB_HELD_MAX 8
typedef struct {
    sb_record rec[SB_HELD_MAX];   /* sim_ns and flags are the release step's */
    int64_t due_ns[SB_HELD_MAX];  /* in the order given, which is release order */
    int head, n;
} sb_held;

typedef struct {
    sb_stage_consts c;
    double *state;            /* float64[ST_COUNT], the caller's */
    int scalar_imu;           /* 1: one IMU sample per step, written here */
    const double *imu_noise;  /* (rows, 6): slow bias + white noise, gyro then accel */
    const double *imu_temp_c; /* (rows): die temperature per step [degC] */
    size_t imu_rows, imu_pos;
    double phase_rad[4];      /* rotor phases */
    double injected_rad_s[3]; /* injected gyro bias FRD */
    uint32_t seq_imu, seq_att, seq_nav;
    int was_on_ground;
    double prev_vd_m_s;
    int64_t upside_down_steps, flip_steps;
    int64_t next_slow_ns;     /* from this sim time the step flags F_SLOW_DUE */
    sb_lowrate baro, mag;
    double baro_offset_pa, baro_noise_pa;
    double mag_field_ned_gauss[3], mag_offset_gauss[3], mag_noise_gauss;
    /* With c.vib.on: the vibration model, the chip, and the rigid-body IMU signal
     * (accel xyz at the IMU, gyro xyz) of the step before, interpolated between steps. */
    sb_vibration vib;
    sb_imu_chip chip;
    int chip_n;               /* chip samples per physics step (ODR x dt) */
    int chip_primed;          /* prev6 and the filter hold a step */
    double prev6[6];
    sb_imu_raw raw;           /* the chip's ODR samples for the log, when bound (imu_raw.h) */
    sb_held held;             /* records waiting for their release step */
    sb_gnss_model gnss;       /* the GNSS's epochs, while gnss.in_c (else Python's) */
    sb_sensor_faults faults;  /* issue 28's sensor faults (all off: one test per sample) */
    sb_pack pack;             /* the physics-side battery, once configured (battery.h) */
} sb_sensor_stage;

/* A defined stage: no noise yet, sensors off, counters at 0. */
void sb_sensor_stage_init(sb_sensor_stage *s, const sb_stage_consts *c, double *state,
                          const double phase_rad[4], int64_t flip_steps, int scalar_imu,
                          int on_ground);

/* The IMU's next noise rows (a low-rate sensor's: lowrate.h sb_lowrate_set_noise). */
void sb_sensor_stage_set_imu_noise(sb_sensor_stage *s, const double *noise,
                                   const double *temp_c, size_t rows);

/* Hold r until the first step at or after due_ns; -1 when SB_HELD_MAX are held. */
int sb_sensor_stage_hold(sb_sensor_stage *s, const sb_record *r, int64_t due_ns);

/* The step's records from slots[first] for the FDM sample at sim_ns: F_* flags or'ed with
 * the number of records written, or a negative SB_STAGE_* code. */
long sb_sensor_stage_step(sb_sensor_stage *s, const sb_fdm_sample *in, int64_t sim_ns,
                          sb_record *slots, size_t n_slots, size_t first);

/* 1 when the baro's sample is due at sim_ns (sb_sensor_stage_step then writes its record). */
static inline int sb_sensor_stage_baro_due(const sb_sensor_stage *s, int64_t sim_ns)
{
    return s->baro.on && sim_ns >= s->baro.next_ns;
}

/* The offset in sb_fdm_sample of the field the step at sim_ns will not read, or
 * (size_t)-1: the air temperature is read only for a baro record (1 step in 10), so the
 * caller may leave it unread (step_run.c: one JSBSim getter call fewer on the others). */
static inline size_t sb_sensor_stage_optional(const sb_sensor_stage *s, int64_t sim_ns)
{
    return sb_sensor_stage_baro_due(s, sim_ns) ? (size_t)-1
                                                : offsetof(sb_fdm_sample, temperature_r);
}

/* 1 when the stage writes the battery's report at sim_ns: it is due and the step is not
 * one Python finishes (F_SLOW_DUE: Python writes it then, after its GNSS and setpoint
 * records, through Kernel.write_battery, so the record order is the contract's). The
 * caller sets pack.esc_w, the ESCs' power after the step, before sb_sensor_stage_step. */
static inline int sb_sensor_stage_pack_due(const sb_sensor_stage *s, int64_t sim_ns)
{
    return sb_pack_due(&s->pack, sim_ns) && sim_ns < s->next_slow_ns;
}

/* What a negative return means and what the caller must do. */
const char *sb_sensor_stage_error(long code);

#endif /* SB_SENSOR_STAGE_H */
