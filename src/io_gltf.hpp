/* io_gltf.hpp - what femlod's glTF units share: tinygltf 2.7.0 (Debian
 * libtinygltf-dev) with femlod's defines, the messages, and the buffer
 * access the reader hands to tinygltf. Internal to src/, never installed.
 *
 * The glTF units, bottom up (a unit uses only those above it in this list):
 *   io_gltf_common.cpp   tinygltf's implementation, compiled once; messages
 *   io_gltf_buffers.cpp  buffer bytes from outside the JSON: data: URIs
 *                        checked, files confined to the asset's folder
 *   io_gltf_read.cpp     fl_read_gltf: GLB header, node matrices, geometry
 *   io_gltf_write.cpp    fl_write_gltf: geometry, normals, colour maps
 * The reader and the writer never use each other.
 *
 * Every unit includes tinygltf through this header only: its defines change
 * inline members of tinygltf's classes, so all units must see the same
 * ones. No image decoder, no image writer, no external images;
 * TINYGLTF_IMPLEMENTATION is defined in io_gltf_common.cpp alone.
 *
 * No exception leaves the glTF units: fl_read_gltf and fl_write_gltf (C
 * functions, declared in core.h) catch everything (the JSON parser and
 * allocation throw) and return a femlod status. No Lua is involved, so no
 * longjmp crosses these frames. Cross-file functions are fl_gltf_<verb>,
 * hidden like the rest of the library's internals.
 */
#ifndef FEMLOD_IO_GLTF_HPP
#define FEMLOD_IO_GLTF_HPP

#include <string>

#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <nlohmann/json.hpp>
#include <tiny_gltf.h>

extern "C" {
#include "io_util.h"
}

/* {====== messages (io_gltf_common.cpp) */

/* Where messages go: "NAME: POINTER: message" (or "NAME: message"). */
struct fl_gltf_diag {
    const char *name;
    femlod_error *err;
};

/* Fills d.err with st and the message, after d.name and the JSON pointer
 * ptr when it is not empty; returns st. */
FL_INTERNAL femlod_status fl_gltf_fail(const fl_gltf_diag &d, femlod_status st,
                                       const std::string &ptr, const char *fmt, ...)
    FL_PRINTF(4, 5);

/* A string from the file, fit for a message: quoted, cut, printable. */
FL_INTERNAL std::string fl_gltf_quote(const std::string &s);

/* }====== */

/* {====== buffers outside the JSON (io_gltf_buffers.cpp) */

/* The confinement of one load: which folder external buffers may come from,
 * and the first refusal, which explains tinygltf's failure. */
struct fl_gltf_fs {
    const char *base = nullptr; /* the asset's folder, as handed to tinygltf; nullptr: memory */
    std::string prefix;         /* what tinygltf puts before a URI: base + "/" */
    std::string real_base;      /* realpath(base) + "/", made on first use */
    femlod_status status = FEMLOD_OK;
    std::string reason; /* the first refusal, for the message */
};

/* File callbacks for tinygltf that read buffers only from inside c's folder
 * (no absolute path, no "..", realpath stays inside, regular files, size
 * cap), nothing at all when c->base is nullptr, and never write. c must
 * outlive the load. */
FL_INTERNAL tinygltf::FsCallbacks fl_gltf_confine_files(fl_gltf_fs *c);

/* The first problem with a data: URI's base64 text, or "" when it has none
 * (tinygltf's decoder stops quietly at the first bad character). */
FL_INTERNAL std::string fl_gltf_check_data_uri(const std::string &uri);

/* }====== */

#endif
