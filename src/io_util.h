/*
 * io_util.h - what the format readers and writers (io_*.c, io_gltf_*.cpp)
 * share, in io_util.c: token quoting and number checks for messages, the
 * line-counting token reader, "FILE:LINE:" and "FILE: byte N:" errors, fan
 * triangulation of polygons, a reader's hand-over of its arrays, and the
 * text output of coordinates. It sits below the readers and io.c, which
 * dispatches to them, and uses only core.h's units (never io.c).
 */
#ifndef FEMLOD_IO_UTIL_H
#define FEMLOD_IO_UTIL_H

#include "core.h"

#include <stdarg.h>

/* {====== tokens and numbers in messages */

/* Copies token s[0..n) into buf for a message: at most 40 bytes, bytes
 * outside printable ASCII as '?', "..." when cut; returns buf. */
FL_INTERNAL const char *fl_io_quote(char *buf, size_t size, const char *s, size_t n);
/* Parses the whole token as a number (inf and nan words accepted); on
 * failure writes "bad number 'x'" into why and returns 0. */
FL_INTERNAL int fl_io_number(const char *s, size_t n, double *out, char *why, size_t why_size);
/* As fl_io_number, and the number must be finite: on failure why says
 * "bad number 'x'", "coordinate 'nan' is not finite" or "coordinate '1e999'
 * is out of range". */
FL_INTERNAL int fl_io_coord(const char *s, size_t n, double *out, char *why, size_t why_size);
/* Parses an unsigned decimal token (digits only); 0 when malformed. The
 * value stops growing once it reaches cap, so a huge count compares as
 * huge without overflow. */
FL_INTERNAL int fl_io_uint(const char *s, size_t n, uint64_t cap, uint64_t *v);

/* }====== */

/* {====== errors: fill err and return st */

/* "NAME:LINE: message" with status st. */
FL_INTERNAL femlod_status fl_io_vfail_line(femlod_error *err, femlod_status st, const char *name,
                                           size_t line, const char *fmt, va_list ap)
    FL_PRINTF(5, 0);
/* "NAME: byte N: message" with FEMLOD_EPARSE (binary data). */
FL_INTERNAL femlod_status fl_io_vfail_byte(femlod_error *err, const char *name, size_t byte,
                                           const char *fmt, va_list ap) FL_PRINTF(4, 0);
/* Fills err with "PATH: cannot write: <strerror(errno), EIO when 0>". */
FL_INTERNAL femlod_status fl_io_write_error(const char *path, femlod_error *err);

/* }====== */

/* {====== the token reader
 * Whitespace-separated tokens with line numbers. comment: the byte that
 * starts a comment to the end of the line, or 0. fl_text_init skips a UTF-8
 * byte order mark. fl_text_next returns the next token on any line (NULL at
 * the end, where line names the file's last line); fl_text_line_next the
 * next one on the current line (NULL at its end, the newline left for
 * fl_text_next to count). fl_text_fail fills err with "name:line: message".
 * fl_text_u64 parses an unsigned decimal token (saturating at 2^60);
 * fl_text_is compares a token with a word. */

typedef struct fl_text {
    const char *p, *end, *start;
    const char *name;
    size_t line;
    femlod_error *err;
    int eof;
    char comment;
} fl_text;

FL_INTERNAL void fl_text_init(fl_text *t, const char *data, size_t size, const char *name,
                              char comment, femlod_error *err);
FL_INTERNAL const char *fl_text_next(fl_text *t, size_t *len);
FL_INTERNAL const char *fl_text_line_next(fl_text *t, size_t *len);
FL_INTERNAL femlod_status fl_text_fail(fl_text *t, femlod_status st, const char *fmt, ...)
    FL_PRINTF(3, 4);
FL_INTERNAL int fl_text_u64(const char *s, size_t n, uint64_t *v);
FL_INTERNAL int fl_text_is(const char *s, size_t n, const char *word);

/* }====== */

/* {====== building the mesh */

/* A polygon read one corner at a time, made a fan of triangles from its
 * first corner (OBJ, OFF and PLY faces). Start from {0}; count is the
 * corners added. */
typedef struct fl_io_fan {
    uint32_t first, prev;
    uint64_t count;
} fl_io_fan;

/* Adds corner v; from the third corner on appends the triangle (first,
 * prev, v) to b. FEMLOD_OK, FEMLOD_ELIMIT when b holds UINT32_MAX triangles
 * already, or FEMLOD_ENOMEM; err is not filled (the reader names the place). */
FL_INTERNAL femlod_status fl_io_fan_add(fl_meshbuf *b, fl_io_fan *f, uint32_t v);
/* A reader's end: on st == FEMLOD_OK moves b into *out (ENOMEM names
 * name); frees b in every case and returns the outcome. */
FL_INTERNAL femlod_status fl_io_finish(fl_meshbuf *b, femlod_status st, femlod_mesh **out,
                                       const char *name, femlod_error *err);
/* The boundary edges (sides of exactly one triangle) as 2*count vertex
 * indices, oriented as their triangle runs, in triangle order; caller frees.
 * A triangle listing an edge twice (a, b, a) counts it as one side. */
FL_INTERNAL femlod_status fl_io_boundary_sides(const femlod_mesh *m, uint32_t **sides,
                                               size_t *count, femlod_error *err);

/* }====== */

/* {====== text output */

/* Writes "x y z" with the shortest round-trip digits into buf (at least
 * FL_IO_XYZ_SIZE bytes, NUL-terminated); returns the length. */
#define FL_IO_XYZ_SIZE 100
FL_INTERNAL size_t fl_io_format_xyz(char *buf, const double *p);
/* Writes x y z with the shortest round-trip digits, separated by sep, then
 * end; 0 on a write error. */
FL_INTERNAL int fl_io_put_xyz(FILE *fp, const double *p, const char *sep, const char *end);
/* The body OFF and ASCII PLY share: a line "x y z" a vertex, then a line
 * "3 a b c" (0-based indices) a triangle. FEMLOD_EIO on a write error. */
FL_INTERNAL femlod_status fl_io_put_vertex_face_lines(const femlod_mesh *m, FILE *fp);

/* }====== */

#endif
