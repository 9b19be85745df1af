/*
 * fc_params.c - the C parameter table (from fc_params.def) and validated
 * access by permanent index. Host-side parameters (FC_HOST) are not here:
 * the Python runtime stores them.
 */
#include "fc_params.h"

#include <math.h>

const fc_param_info_t fc_param_table[] = {
#define FC_PARAM(idx, name, type, field, def, lo, hi, unit, text) \
    {#name, (uint16_t)(idx), (uint8_t)FC_PARAM_##type, (uint16_t)offsetof(fc_params_t, field), \
     (float)(lo), (float)(hi), (float)(def)},
#define FC_HOST(idx, name, type, def, lo, hi, unit, text)
#include "fc_params.def"
#undef FC_PARAM
#undef FC_HOST
};

const size_t fc_param_count = sizeof(fc_param_table) / sizeof(fc_param_table[0]);

/* Names are at most 16 characters: MAVLink's param_id is char[16]. */
#define FC_PARAM(idx, name, type, field, def, lo, hi, unit, text) \
    _Static_assert(sizeof(#name) <= 17, "parameter name longer than 16: " #name);
#define FC_HOST(idx, name, type, def, lo, hi, unit, text) \
    _Static_assert(sizeof(#name) <= 17, "parameter name longer than 16: " #name);
#include "fc_params.def"
#undef FC_PARAM
#undef FC_HOST

static void store(fc_params_t *p, const fc_param_info_t *info, float value)
{
    unsigned char *base = (unsigned char *)p + info->offset;
    switch (info->type) {
    case FC_PARAM_INT8:
        *(int8_t *)base = (int8_t)value;
        break;
    case FC_PARAM_INT16:
        *(int16_t *)base = (int16_t)value;
        break;
    case FC_PARAM_INT32:
        *(int32_t *)base = (int32_t)value;
        break;
    default:
        *(float *)base = value;
        break;
    }
}

void fc_params_set_defaults(fc_params_t *p)
{
    for (size_t i = 0; i < fc_param_count; i++) {
        store(p, &fc_param_table[i], fc_param_table[i].default_value);
    }
}

const fc_param_info_t *fc_param_find(uint16_t index)
{
    for (size_t i = 0; i < fc_param_count; i++) {
        if (fc_param_table[i].index == index) {
            return &fc_param_table[i];
        }
    }
    return NULL;
}

fc_status_t fc_param_set(fc_params_t *p, uint16_t index, float value)
{
    const fc_param_info_t *info = fc_param_find(index);
    if (info == NULL) {
        return FC_ERR_INDEX;
    }
    if (!isfinite(value)) {
        return FC_ERR_NONFINITE;
    }
    if (value < info->min_value || value > info->max_value) {
        return FC_ERR_RANGE;
    }
    if (info->type != FC_PARAM_FLOAT && value != truncf(value)) {
        return FC_ERR_TYPE;
    }
    store(p, info, value);
    return FC_OK;
}

fc_status_t fc_param_get(const fc_params_t *p, uint16_t index, float *value)
{
    const fc_param_info_t *info = fc_param_find(index);
    if (info == NULL) {
        return FC_ERR_INDEX;
    }
    const unsigned char *base = (const unsigned char *)p + info->offset;
    switch (info->type) {
    case FC_PARAM_INT8:
        *value = (float)*(const int8_t *)base;
        break;
    case FC_PARAM_INT16:
        *value = (float)*(const int16_t *)base;
        break;
    case FC_PARAM_INT32:
        *value = (float)*(const int32_t *)base;
        break;
    default:
        *value = *(const float *)base;
        break;
    }
    return FC_OK;
}
