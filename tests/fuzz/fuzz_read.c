/* fuzz_read.c - libFuzzer target for one reader (FUZZ_FORMAT), then the
 * quality report (adjacency, topology, measures) on whatever loads. Any
 * crash, sanitizer report, leak or hang is a finding. */
#include "femlod.h"

#include <stddef.h>
#include <stdint.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    femlod_read_options ro = FEMLOD_READ_OPTIONS_INIT;
    ro.format = FUZZ_FORMAT;
    femlod_mesh *m = NULL;
    femlod_error err;
    if (femlod_mesh_read_memory(&m, data, size, FUZZ_NAME, &ro, &err) != FEMLOD_OK) return 0;
    if (femlod_mesh_triangle_count(m) <= 100000) {
        femlod_quality q;
        (void)femlod_mesh_quality(m, &q, &err);
        femlod_mesh *s = NULL;
        if (femlod_mesh_triangle_count(m) <= 1000 &&
            femlod_mesh_subdivide(&s, m, 1, &err) == FEMLOD_OK)
            femlod_mesh_free(s);
    }
    femlod_mesh_free(m);
    return 0;
}
