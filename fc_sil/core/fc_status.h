/*
 * fc_status.h - status codes returned by the flight-controller core.
 *
 * The core never prints and never aborts: every function that can refuse its
 * input returns one of these codes and leaves its state as it was, so the
 * host (Python, or a real flight controller's scheduler) decides what to do.
 */
#ifndef FC_STATUS_H
#define FC_STATUS_H

typedef enum fc_status {
    FC_OK = 0,
    FC_ERR_ARG = -1,       /* argument outside what the block can use (e.g. dt <= 0) */
    FC_ERR_RANGE = -2,     /* parameter value outside its declared [min, max] */
    FC_ERR_NONFINITE = -3, /* NaN or inf input; the sample was ignored */
    FC_ERR_INDEX = -4,     /* unknown parameter index */
    FC_ERR_TYPE = -5       /* integer parameter given a non-integral value */
} fc_status_t;

#endif /* FC_STATUS_H */
