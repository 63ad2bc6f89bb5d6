/* error.c - status names, error records and checked allocation. */
#include "core.h"

#include <stdlib.h>
#include <string.h>

const char *femlod_status_name(femlod_status status) {
    switch (status) {
    case FEMLOD_OK: return "ok";
    case FEMLOD_ENOMEM: return "nomem";
    case FEMLOD_EIO: return "io";
    case FEMLOD_EPARSE: return "parse";
    case FEMLOD_EINPUT: return "input";
    case FEMLOD_ETOPOLOGY: return "topology";
    case FEMLOD_ECANCELLED: return "cancelled";
    case FEMLOD_EUNSUPPORTED: return "unsupported";
    case FEMLOD_ELIMIT: return "limit";
    }
    return "unknown";
}

femlod_status fl_error(femlod_error *err, femlod_status status, const char *fmt, ...) {
    if (err) {
        va_list ap;
        err->status = status;
        va_start(ap, fmt);
        vsnprintf(err->message, sizeof err->message, fmt, ap);
        va_end(ap);
    }
    return status;
}

void *fl_alloc(size_t count, size_t size) {
    size_t bytes;
    if (__builtin_mul_overflow(count, size, &bytes)) return NULL;
    return malloc(bytes ? bytes : 1);
}

void *fl_calloc(size_t count, size_t size) {
    if (count == 0 || size == 0) return calloc(1, 1);
    return calloc(count, size);
}

void *fl_realloc(void *p, size_t count, size_t size) {
    size_t bytes;
    if (__builtin_mul_overflow(count, size, &bytes)) return NULL;
    return realloc(p, bytes ? bytes : 1);
}
