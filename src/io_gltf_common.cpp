/* io_gltf_common.cpp - owns the bottom of the glTF units (io_gltf.hpp):
 * tinygltf's implementation, compiled in this unit alone with the defines
 * io_gltf.hpp sets, and the messages the reader and the writer both make.
 * It uses no other glTF unit.
 */
#include <cstdarg>
#include <cstdio>
#include <string>

#define TINYGLTF_IMPLEMENTATION
#include "io_gltf.hpp"

femlod_status fl_gltf_fail(const fl_gltf_diag &d, femlod_status st, const std::string &ptr,
                           const char *fmt, ...) {
    char msg[FEMLOD_ERROR_MESSAGE_SIZE];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    if (ptr.empty()) return fl_error(d.err, st, "%s: %s", d.name, msg);
    return fl_error(d.err, st, "%s: %s: %s", d.name, ptr.c_str(), msg);
}

std::string fl_gltf_quote(const std::string &s) {
    char q[48];
    return std::string("'") + fl_io_quote(q, sizeof q, s.data(), s.size()) + "'";
}
