/* fuzz_flh.c - libFuzzer target for the hierarchy file (.flh) reader, then
 * the operations on whatever loads: validate, refine, coarsen, extract.
 *
 * The file ends with a CRC-32 of everything before it, so almost every
 * mutation would stop at the checksum and the parser behind it would never
 * see hostile data. The target therefore rewrites the last four bytes with
 * the right CRC before loading (the checksum check itself is one line). */
#include "femlod.h"

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    if (size < 12 || size > (1u << 24)) return 0;
    uint8_t *copy = malloc(size);
    if (!copy) return 0;
    memcpy(copy, data, size);
    uLong crc = crc32(crc32(0L, Z_NULL, 0), copy, (uInt)(size - 4));
    for (int k = 0; k < 4; k++) copy[size - 4 + (size_t)k] = (uint8_t)(crc >> (8 * k));
    femlod_hierarchy *h = NULL;
    femlod_error err;
    femlod_simplify_result res;
    if (femlod_hierarchy_load_memory(&h, copy, size, "fuzz.flh", &res, &err) == FEMLOD_OK) {
        /* a loaded hierarchy must be valid, and stay valid */
        if (femlod_hierarchy_validate(h, &err) != FEMLOD_OK) abort();
        if (femlod_hierarchy_node_count(h) <= 20000) {
            size_t ops;
            femlod_mesh *m = NULL;
            (void)femlod_hierarchy_refine(h, 0.0, NULL, NULL, &ops, &err);
            if (femlod_hierarchy_validate(h, &err) != FEMLOD_OK) abort();
            (void)femlod_hierarchy_coarsen(h, INFINITY, NULL, NULL, &ops, &err);
            if (femlod_hierarchy_validate(h, &err) != FEMLOD_OK) abort();
            if (femlod_hierarchy_extract(h, &m, NULL, &err) == FEMLOD_OK) femlod_mesh_free(m);
        }
        femlod_hierarchy_free(h);
    }
    free(copy);
    return 0;
}
