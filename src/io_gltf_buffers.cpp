/* io_gltf_buffers.cpp - owns where a glTF buffer's bytes come from when they
 * are not in a GLB's BIN chunk: a data: URI, whose base64 text is checked
 * here (tinygltf's decoder stops quietly at the first bad character), or a
 * file beside the asset, read through the file callbacks made here.
 *
 * tinygltf 2.7.0 follows a buffer URI such as "../../../../etc/hostname" out
 * of the asset's folder (ecosystem-notes.md 2.3). The callbacks read buffers
 * only from inside the asset's own folder (no absolute path, no "..",
 * realpath stays inside, regular files, size cap) and nothing at all for
 * data in memory; they never write. Uses io_gltf_common.cpp only.
 */
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include <sys/stat.h>

#include "io_gltf.hpp"

/* {====== confined file access for external buffers */

namespace {

/* External buffer files larger than this are refused (ELIMIT). */
const size_t kMaxBufferFile = (size_t)1 << 31;

void refuse(fl_gltf_fs *c, femlod_status st, const std::string &why) {
    if (c->status != FEMLOD_OK) return;
    c->status = st;
    c->reason = why;
}

bool is_separator(char ch) { return ch == '/' || ch == '\\'; }

/* ASCII only, whatever the locale. */
bool ascii_alpha(char ch) { return (ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z'); }
bool ascii_alnum(char ch) { return ascii_alpha(ch) || (ch >= '0' && ch <= '9'); }

/* "scheme:" at the start of a URI (RFC 3986: ALPHA *( ALPHA / DIGIT / "+" / "-" / "." )). */
bool has_scheme(const std::string &u, std::string *scheme) {
    if (u.empty() || !ascii_alpha(u[0])) return false;
    for (size_t i = 1; i < u.size(); i++) {
        char ch = u[i];
        if (ch == ':') {
            *scheme = u.substr(0, i);
            return true;
        }
        if (!ascii_alnum(ch) && ch != '+' && ch != '-' && ch != '.') return false;
    }
    return false;
}

/* The real path of the buffer file at path (which tinygltf made as
 * base + "/" + decoded URI) when it is a regular file inside the asset's
 * folder; "" after recording why not. */
std::string confine(fl_gltf_fs *c, const std::string &path, size_t *size) {
    if (!c->base) {
        refuse(c, FEMLOD_EUNSUPPORTED,
               "buffer file " + fl_gltf_quote(path) +
                   " cannot be read: glTF from memory has no folder (embed the buffer or "
                   "read the file by its path)");
        return "";
    }
    /* tinygltf also tries "./" + URI: the current folder is never the asset's. */
    if (path.compare(0, c->prefix.size(), c->prefix) != 0) return "";
    std::string uri = path.substr(c->prefix.size()), scheme;
    if (uri.empty()) {
        refuse(c, FEMLOD_EPARSE, "buffer uri is empty");
        return "";
    }
    if (has_scheme(uri, &scheme)) {
        if (scheme == "data")
            refuse(c, FEMLOD_EUNSUPPORTED,
                   "data URI of an unsupported media type (base64 application/octet-stream or "
                   "application/gltf-buffer expected)");
        else
            refuse(c, FEMLOD_EUNSUPPORTED,
                   "buffer uri " + fl_gltf_quote(uri) + ": scheme '" + scheme.substr(0, 16) +
                       ":' is not supported (relative file names and data: URIs only)");
        return "";
    }
    if (is_separator(uri[0])) {
        refuse(c, FEMLOD_EPARSE,
               "buffer uri " + fl_gltf_quote(uri) +
                   " is an absolute path (buffer files must be inside the asset's folder)");
        return "";
    }
    for (size_t i = 0; i < uri.size();) {
        size_t j = i;
        while (j < uri.size() && !is_separator(uri[j])) j++;
        if (j - i == 2 && uri[i] == '.' && uri[i + 1] == '.') {
            refuse(c, FEMLOD_EPARSE,
                   "buffer uri " + fl_gltf_quote(uri) +
                       " climbs out of the asset's folder ('..' is not allowed)");
            return "";
        }
        i = j + 1;
    }
    if (c->real_base.empty()) {
        char *rb = realpath(c->base, nullptr);
        if (!rb) {
            refuse(c, FEMLOD_EIO,
                   std::string("cannot resolve the asset's folder: ") + strerror(errno));
            return "";
        }
        c->real_base = rb;
        free(rb);
        if (c->real_base.empty() || c->real_base.back() != '/') c->real_base += '/';
    }
    char *rp = realpath(path.c_str(), nullptr);
    if (!rp) {
        refuse(c, FEMLOD_EIO,
               "cannot open buffer file " + fl_gltf_quote(uri) + ": " + strerror(errno));
        return "";
    }
    std::string real = rp;
    free(rp);
    if (real.compare(0, c->real_base.size(), c->real_base) != 0) {
        refuse(c, FEMLOD_EPARSE,
               "buffer file " + fl_gltf_quote(uri) +
                   " leaves the asset's folder through a symbolic link");
        return "";
    }
    struct stat st;
    if (stat(real.c_str(), &st) != 0) {
        refuse(c, FEMLOD_EIO,
               "cannot open buffer file " + fl_gltf_quote(uri) + ": " + strerror(errno));
        return "";
    }
    if (!S_ISREG(st.st_mode)) {
        refuse(c, FEMLOD_EIO, "buffer file " + fl_gltf_quote(uri) + " is not a regular file");
        return "";
    }
    if ((uintmax_t)st.st_size > (uintmax_t)kMaxBufferFile) {
        refuse(c, FEMLOD_ELIMIT,
               "buffer file " + fl_gltf_quote(uri) + " has " +
                   std::to_string((uintmax_t)st.st_size) + " bytes (limit " +
                   std::to_string(kMaxBufferFile) + ")");
        return "";
    }
    *size = (size_t)st.st_size;
    return real;
}

bool fs_exists(const std::string &path, void *user) {
    size_t size;
    return !confine(static_cast<fl_gltf_fs *>(user), path, &size).empty();
}

std::string fs_expand(const std::string &path, void *) { return path; }

bool fs_read(std::vector<unsigned char> *out, std::string *err, const std::string &path,
             void *user) {
    fl_gltf_fs *c = static_cast<fl_gltf_fs *>(user);
    size_t size = 0;
    std::string real = confine(c, path, &size);
    if (real.empty()) {
        if (err) *err += "refused";
        return false;
    }
    FILE *fp = fopen(real.c_str(), "rb");
    if (!fp) {
        refuse(c, FEMLOD_EIO,
               "cannot open buffer file " + fl_gltf_quote(path.substr(c->prefix.size())) + ": " +
                   strerror(errno));
        return false;
    }
    out->resize(size);
    size_t got = size ? fread(out->data(), 1, size, fp) : 0;
    bool more = fgetc(fp) != EOF; /* the file grew since stat: not what was checked */
    bool bad = ferror(fp) != 0;
    fclose(fp);
    if (got != size || more || bad) {
        refuse(c, FEMLOD_EIO,
               "cannot read buffer file " + fl_gltf_quote(path.substr(c->prefix.size())) +
                   ": it changed while being read, or a read failed");
        return false;
    }
    return true;
}

bool fs_write(std::string *err, const std::string &, const std::vector<unsigned char> &, void *) {
    if (err) *err += "femlod writes no files through tinygltf";
    return false;
}

} // namespace

tinygltf::FsCallbacks fl_gltf_confine_files(fl_gltf_fs *c) {
    return {fs_exists, fs_expand, fs_read, fs_write, c};
}

/* }====== */

/* {====== data: URIs */

std::string fl_gltf_check_data_uri(const std::string &uri) {
    size_t comma = uri.find(',');
    if (comma == std::string::npos) return "data URI without ','";
    size_t n = uri.size() - comma - 1, pad = 0;
    for (size_t i = 0; i < n; i++) {
        char ch = uri[comma + 1 + i];
        if (ch == '=') {
            pad++;
            continue;
        }
        if (!ascii_alnum(ch) && ch != '+' && ch != '/')
            return "data URI is not base64: character " + fl_gltf_quote(std::string(1, ch)) +
                   " at offset " + std::to_string(i);
        if (pad)
            return "data URI is not base64: data after the '=' padding at offset " +
                   std::to_string(i);
    }
    if (pad > 2 || (pad && n % 4 != 0) || n % 4 == 1)
        return "data URI is not base64: " + std::to_string(n) + " characters, " +
               std::to_string(pad) + " of them '=' padding";
    return "";
}

/* }====== */
