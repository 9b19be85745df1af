/*
 * fc_params.h - the parameter struct and table of the C core, built from
 * fc_params.def (the one declaration of every parameter; see its header).
 *
 * The algorithms never look parameters up by name: fc_core copies the values
 * they need into each block's config when a parameter changes. The table is
 * the shape Betaflight's settings table has ({name, type, min, max, offset})
 * plus the default and the permanent index.
 */
#ifndef FC_PARAMS_H
#define FC_PARAMS_H

#include <stddef.h>
#include <stdint.h>

#include "fc_status.h"

typedef enum fc_param_type {
    FC_PARAM_FLOAT = 0,
    FC_PARAM_INT8 = 1,
    FC_PARAM_INT16 = 2,
    FC_PARAM_INT32 = 3
} fc_param_type_t;

#define FC_CTYPE_FLOAT float
#define FC_CTYPE_INT8 int8_t
#define FC_CTYPE_INT16 int16_t
#define FC_CTYPE_INT32 int32_t

typedef struct fc_params {
#define FC_PARAM(idx, name, type, field, def, lo, hi, unit, text) FC_CTYPE_##type field;
#define FC_HOST(idx, name, type, def, lo, hi, unit, text)
#include "fc_params.def"
#undef FC_PARAM
#undef FC_HOST
} fc_params_t;

typedef struct fc_param_info {
    const char *name;   /* at most 16 characters */
    uint16_t index;     /* permanent slot from fc_params.def */
    uint8_t type;       /* fc_param_type_t */
    uint16_t offset;    /* offsetof(fc_params_t, field) */
    float min_value;
    float max_value;
    float default_value;
} fc_param_info_t;

extern const fc_param_info_t fc_param_table[];
extern const size_t fc_param_count;

/* Every parameter at its default. */
void fc_params_set_defaults(fc_params_t *p);

/* Table entry for a permanent index, or NULL. */
const fc_param_info_t *fc_param_find(uint16_t index);

/* Validate and store: NaN/inf, out of [min, max] or a non-integral value for
 * an integer type are refused and the old value kept. */
fc_status_t fc_param_set(fc_params_t *p, uint16_t index, float value);
fc_status_t fc_param_get(const fc_params_t *p, uint16_t index, float *value);

#endif /* FC_PARAMS_H */
