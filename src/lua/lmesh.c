/*
 * lmesh.c - the femlod.Mesh userdata (shaped like liolib.c's file handles).
 *
 * A Mesh is a box holding one femlod_mesh pointer. The box is pushed empty,
 * with its metatable (and so its __gc) in place, before the C mesh is made:
 * if making it fails or raises, the box is simply an empty box (liolib.c
 * newprefile). The mesh arrays live outside the Lua heap, so recipes free
 * them early with `local m <close> = ...` or m:close().
 *
 * Every function raises on failure. Tables handed in by the recipe are read
 * into Lua-owned userdata buffers, so that a raise in the middle (a bad
 * element) leaks nothing: there is no malloc'd temporary to free.
 */
#include "lfemlod.h"
#include "lopts.h"

#include "core.h" /* fl_format_double: numbers in extras, whatever the locale */

#include <limits.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

femlod_mesh **fl_lmesh_box(lua_State *L) {
    femlod_mesh **p = (femlod_mesh **)lua_newuserdatauv(L, sizeof *p, 0);
    *p = NULL;
    luaL_setmetatable(L, FL_MESH_MT);
    return p;
}

double fl_lmesh_bytes(double vertices, double triangles) {
    return 24.0 * vertices + 12.0 * triangles;
}

void fl_lmesh_charge(lua_State *L, femlod_mesh *const *slot) {
    fl_lua_charge(L, fl_lmesh_bytes((double)femlod_mesh_vertex_count(*slot),
                                    (double)femlod_mesh_triangle_count(*slot)));
}

void fl_lmesh_release(lua_State *L, femlod_mesh **slot) {
    if (!*slot) return;
    double bytes = fl_lmesh_bytes((double)femlod_mesh_vertex_count(*slot),
                                  (double)femlod_mesh_triangle_count(*slot));
    femlod_mesh_free(*slot); /* first: the look-up below may raise (memory) */
    *slot = NULL;
    fl_lua_guard *g = fl_lua_guard_get(L);
    if (g) g->charge(g, -bytes);
}

femlod_mesh *fl_lmesh_check(lua_State *L, int arg) {
    femlod_mesh **p = (femlod_mesh **)luaL_checkudata(L, arg, FL_MESH_MT);
    if (!*p) luaL_error(L, "attempt to use a closed femlod.Mesh");
    return *p;
}

/* The format option: names as femlod_format_name spells them. */
#define format_names (femlod_format_names())
static const char *const io_keys[] = {"format", NULL};

static femlod_format check_format(lua_State *L, int arg) {
    fl_opts o;
    fl_opts_open(&o, L, arg, io_keys);
    int i = fl_opts_enum(&o, "format", format_names, -1);
    return i < 0 ? FEMLOD_FORMAT_AUTO : femlod_format_from_name(format_names[i]);
}

/* {====================================================================
 * Module functions: the constructors
 * ===================================================================== */

static int lib_load(lua_State *L) {
    const char *path = fl_lua_check_path(L, 1, 0);
    femlod_read_options opts = FEMLOD_READ_OPTIONS_INIT;
    opts.format = check_format(L, 2);
    femlod_mesh **slot = fl_lmesh_box(L);
    femlod_error err;
    double t0 = fl_lua_clock();
    if (femlod_mesh_read(slot, path, &opts, &err) != FEMLOD_OK) return fl_lua_raise(L, &err);
    if (fl_lua_verbose(L))
        fl_lua_log(L, "load %s: %zu triangles, %zu vertices (%.3f s)", path,
                   femlod_mesh_triangle_count(*slot), femlod_mesh_vertex_count(*slot),
                   fl_lua_clock() - t0);
    fl_lmesh_charge(L, slot);
    fl_lua_io_hook(L, "read", 1, -1);
    return 1;
}

/* Reads field[i] (and [j] when nested) as a number; names the element on
 * error. Leaves the stack as it found it. */
static double element_number(lua_State *L, int arg, int t, lua_Integer i, const char *field,
                             lua_Integer outer) {
    if (lua_geti(L, t, i) != LUA_TNUMBER) {
        const char *got = luaL_typename(L, -1);
        if (outer)
            luaL_argerror(L, arg, lua_pushfstring(L, "%s[%I][%I]: number expected, got %s",
                                                  field, outer, i, got));
        luaL_argerror(L, arg,
                      lua_pushfstring(L, "%s[%I]: number expected, got %s", field, i, got));
    }
    double v = lua_tonumber(L, -1);
    lua_pop(L, 1);
    return v;
}

/* A list of triples, flat {a1,b1,c1, a2,...} or nested {{a1,b1,c1}, ...},
 * told apart by the first element. Pushes a userdata of 3*count doubles and
 * returns it; count is the number of triples. */
static double *read_triples(lua_State *L, int arg, int t, const char *field, size_t *count) {
    lua_Integer n = luaL_len(L, t);
    int nested = n > 0 && lua_geti(L, t, 1) == LUA_TTABLE;
    if (n > 0) lua_pop(L, 1);
    if (!nested && n % 3 != 0)
        luaL_argerror(L, arg, lua_pushfstring(L, "%s: flat list length %I is not a multiple of 3",
                                              field, n));
    lua_Integer triples = nested ? n : n / 3;
    if ((lua_Unsigned)triples > SIZE_MAX / (3 * sizeof(double)) ||
        (lua_Unsigned)triples > UINT32_MAX)
        luaL_argerror(L, arg, lua_pushfstring(L, "%s: too many entries", field));
    double *v = (double *)lua_newuserdatauv(L, (size_t)triples * 3 * sizeof(double), 0);
    if (nested) {
        for (lua_Integer i = 1; i <= n; i++) {
            if (lua_geti(L, t, i) != LUA_TTABLE)
                luaL_argerror(L, arg, lua_pushfstring(L, "%s[%I]: table expected, got %s", field,
                                                      i, luaL_typename(L, -1)));
            int e = lua_gettop(L);
            lua_Integer len = luaL_len(L, e);
            if (len != 3)
                luaL_argerror(L, arg, lua_pushfstring(L, "%s[%I]: 3 entries expected, got %I",
                                                      field, i, len));
            for (lua_Integer j = 1; j <= 3; j++)
                v[3 * (i - 1) + (j - 1)] = element_number(L, arg, e, j, field, i);
            lua_pop(L, 1);
        }
    } else {
        for (lua_Integer i = 1; i <= n; i++) v[i - 1] = element_number(L, arg, t, i, field, 0);
    }
    *count = (size_t)triples;
    return v;
}

/* Names entry k (0-based) of a triple list the way the recipe wrote it. */
static const char *entry_name(lua_State *L, const char *field, int nested, size_t k) {
    if (nested)
        return lua_pushfstring(L, "%s[%I][%I]", field, (lua_Integer)(k / 3 + 1),
                               (lua_Integer)(k % 3 + 1));
    return lua_pushfstring(L, "%s[%I]", field, (lua_Integer)(k + 1));
}

static int is_nested(lua_State *L, int t) {
    int nested = lua_geti(L, t, 1) == LUA_TTABLE;
    lua_pop(L, 1);
    return nested;
}

static const char *const mesh_keys[] = {"triangles", "positions", NULL};

/* femlod.mesh{positions = ..., triangles = ...}: indices are 1-based, as
 * everywhere in Lua; they are checked here so that messages use them. */
static int lib_mesh(lua_State *L) {
    fl_opts o;
    luaL_checktype(L, 1, LUA_TTABLE);
    fl_opts_open(&o, L, 1, mesh_keys);

    size_t nv = 0, nt = 0;
    const double *pos = NULL, *idx = NULL;
    int pos_nested = 0, tri_nested = 0;
    int t = fl_opts_push(&o, "positions");
    if (t != LUA_TNIL) {
        if (t != LUA_TTABLE)
            fl_opts_error(&o, "positions",
                          lua_pushfstring(L, "table expected, got %s", luaL_typename(L, -1)));
        pos_nested = is_nested(L, lua_gettop(L));
        pos = read_triples(L, 1, lua_gettop(L), "positions", &nv);
    }
    t = fl_opts_push(&o, "triangles");
    if (t != LUA_TNIL) {
        if (t != LUA_TTABLE)
            fl_opts_error(&o, "triangles",
                          lua_pushfstring(L, "table expected, got %s", luaL_typename(L, -1)));
        tri_nested = is_nested(L, lua_gettop(L));
        idx = read_triples(L, 1, lua_gettop(L), "triangles", &nt);
    }
    for (size_t k = 0; k < 3 * nv; k++) {
        if (!isfinite(pos[k]))
            luaL_argerror(L, 1, lua_pushfstring(L, "%s: coordinate is not finite",
                                                entry_name(L, "positions", pos_nested, k)));
    }
    uint32_t *tri = (uint32_t *)lua_newuserdatauv(L, 3 * nt * sizeof *tri, 0);
    for (size_t k = 0; k < 3 * nt; k++) {
        double d = idx[k];
        /* Not lua_Integer: a float such as 2.5 must be refused, not rounded. */
        if (!(d >= 1 && d <= (double)nv && d == floor(d))) {
            const char *name = entry_name(L, "triangles", tri_nested, k);
            /* Integral and within +-2^53: exact as an integer, and printed as one. */
            if (d == floor(d) && fabs(d) <= 9007199254740992.0)
                luaL_argerror(L, 1, lua_pushfstring(L, "%s: index %I out of range (1..%I)", name,
                                                    (lua_Integer)d, (lua_Integer)nv));
            luaL_argerror(L, 1, lua_pushfstring(L, "%s: index %f is not a valid index", name, d));
        }
        tri[k] = (uint32_t)d - 1;
    }
    /* The core wants real pointers even for empty arrays. */
    static const double no_positions[3] = {0, 0, 0};
    if (!pos) pos = no_positions;
    femlod_mesh **slot = fl_lmesh_box(L);
    femlod_error err;
    if (femlod_mesh_create(slot, pos, nv, tri, nt, &err) != FEMLOD_OK) return fl_lua_raise(L, &err);
    fl_lmesh_charge(L, slot);
    return 1;
}

/* }==================================================================== */

/* {====================================================================
 * Methods
 * ===================================================================== */

/* save's options: format, for glTF color_by, normals and extras, for .inp
 * nsets and elsets. */
static const char *const save_keys[] = {"format", "color_by", "normals", "extras",
                                        "nsets",  "elsets",   NULL};
/* In femlod_color_by order. */
static const char *const color_names[] = {"none", "stretch", "size", "valence", NULL};

/* Appends s[0..n) as a JSON string. */
static void add_json_string(luaL_Buffer *b, const char *s, size_t n) {
    luaL_addchar(b, '"');
    for (size_t i = 0; i < n; i++) {
        unsigned char c = (unsigned char)s[i];
        if (c == '"' || c == '\\') {
            luaL_addchar(b, '\\');
            luaL_addchar(b, (char)c);
        } else if (c < 0x20) {
            char e[8];
            snprintf(e, sizeof e, "\\u%04x", (unsigned)c);
            luaL_addstring(b, e);
        } else {
            luaL_addchar(b, (char)c);
        }
    }
    luaL_addchar(b, '"');
}

/* The extras table on the top of the stack (string keys; string, number or
 * boolean values) as a JSON object; pushes it and returns it. Members go
 * in any order: the writer sorts them. */
static const char *extras_json(lua_State *L, const fl_opts *o) {
    int t = lua_gettop(L);
    if (!lua_istable(L, t))
        fl_opts_error(o, "extras",
                      lua_pushfstring(L, "table expected, got %s", luaL_typename(L, t)));
    lua_newtable(L);
    int parts = lua_gettop(L);
    lua_Integer n = 0;
    lua_pushnil(L);
    while (lua_next(L, t)) {
        int k = lua_gettop(L) - 1, v = k + 1;
        if (lua_type(L, k) != LUA_TSTRING)
            fl_opts_error(o, "extras", lua_pushfstring(L, "keys must be strings, got %s",
                                                       luaL_typename(L, k)));
        size_t klen;
        const char *key = lua_tolstring(L, k, &klen);
        luaL_Buffer b;
        luaL_buffinit(L, &b);
        add_json_string(&b, key, klen);
        luaL_addchar(&b, ':');
        if (lua_type(L, v) == LUA_TSTRING) {
            size_t len;
            const char *str = lua_tolstring(L, v, &len);
            add_json_string(&b, str, len);
        } else if (lua_type(L, v) == LUA_TBOOLEAN) {
            luaL_addstring(&b, lua_toboolean(L, v) ? "true" : "false");
        } else if (lua_isinteger(L, v)) {
            char num[32];
            snprintf(num, sizeof num, LUA_INTEGER_FMT, (LUAI_UACINT)lua_tointeger(L, v));
            luaL_addstring(&b, num);
        } else if (lua_type(L, v) == LUA_TNUMBER && isfinite(lua_tonumber(L, v))) {
            char num[40];
            fl_format_double(num, sizeof num, (double)lua_tonumber(L, v));
            luaL_addstring(&b, num);
        } else {
            const char *got = luaL_typename(L, v);
            fl_opts_error(o, "extras",
                          lua_pushfstring(L,
                                          "%s: string, finite number or boolean expected, got %s",
                                          key, got));
        }
        luaL_pushresult(&b);
        lua_rawseti(L, parts, ++n);
        lua_pop(L, 1); /* the value; the key stays for lua_next */
    }
    luaL_Buffer b;
    luaL_buffinit(L, &b);
    luaL_addchar(&b, '{');
    for (lua_Integer i = 1; i <= n; i++) {
        if (i > 1) luaL_addchar(&b, ',');
        lua_rawgeti(L, parts, i);
        luaL_addvalue(&b);
    }
    luaL_addchar(&b, '}');
    luaL_pushresult(&b);
    return lua_tostring(L, -1);
}

/* nsets / elsets: { NAME = {i, ...} | function } as femlod_index_set[*count]
 * in a Lua-owned buffer, with the index buffers, left on the stack (nothing
 * is pushed for an absent key). A function is called as f(x, y, z, i) for
 * every vertex (nsets) or with the centroid of every triangle (elsets) and
 * returns true for members. Names are sorted: the output does not depend
 * on the table's traversal order. */
static femlod_index_set *read_sets(lua_State *L, const fl_opts *o, const char *key, int elements,
                                   size_t *count) {
    *count = 0;
    int t = fl_opts_push(o, key);
    if (t == LUA_TNIL) return NULL;
    int tab = lua_gettop(L);
    if (t != LUA_TTABLE)
        fl_opts_error(o, key, lua_pushfstring(L, "table of name = indices or function expected, got %s",
                                              luaL_typename(L, tab)));
    size_t n = 0;
    lua_pushnil(L);
    while (lua_next(L, tab)) {
        lua_pop(L, 1);
        if (lua_type(L, -1) != LUA_TSTRING)
            fl_opts_error(o, key, lua_pushfstring(L, "set names must be strings, got %s",
                                                  luaL_typename(L, -1)));
        n++;
    }
    femlod_index_set *sets = (femlod_index_set *)lua_newuserdatauv(L, (n ? n : 1) * sizeof *sets, 0);
    size_t k = 0;
    lua_pushnil(L);
    while (lua_next(L, tab)) {
        lua_pop(L, 1);
        sets[k].name = lua_tostring(L, -1); /* kept alive by the option table */
        sets[k].indices = NULL;
        sets[k].count = 0;
        k++;
    }
    for (size_t i = 1; i < n; i++) /* insertion sort by name: few sets */
        for (size_t j = i; j > 0 && strcmp(sets[j - 1].name, sets[j].name) > 0; j--) {
            femlod_index_set tmp = sets[j];
            sets[j] = sets[j - 1];
            sets[j - 1] = tmp;
        }
    for (size_t i = 0; i < n; i++) {
        const femlod_mesh *m = fl_lmesh_check(L, 1);
        size_t limit = elements ? femlod_mesh_triangle_count(m) : femlod_mesh_vertex_count(m);
        const char *name = sets[i].name;
        int v = lua_getfield(L, tab, name);
        int val = lua_gettop(L);
        uint32_t *buf;
        size_t c = 0;
        if (v == LUA_TTABLE) {
            lua_Integer len = luaL_len(L, val);
            if (len < 0 || (lua_Unsigned)len > SIZE_MAX / sizeof *buf)
                fl_opts_error(o, key, lua_pushfstring(L, "%s: list too long", name));
            buf = (uint32_t *)lua_newuserdatauv(L, (size_t)(len ? len : 1) * sizeof *buf, 0);
            for (lua_Integer j = 1; j <= len; j++) {
                int isint = 0;
                lua_geti(L, val, j);
                lua_Integer x = lua_tointegerx(L, -1, &isint);
                if (!isint)
                    fl_opts_error(o, key, lua_pushfstring(L, "%s[%I]: integer index expected, got %s",
                                                          name, j, luaL_typename(L, -1)));
                if (x < 1 || (lua_Unsigned)x > limit)
                    fl_opts_error(o, key, lua_pushfstring(L, "%s[%I]: index %I out of range (1..%I)",
                                                          name, j, x, (lua_Integer)limit));
                lua_pop(L, 1);
                buf[c++] = (uint32_t)(x - 1);
            }
        } else if (v == LUA_TFUNCTION) {
            buf = (uint32_t *)lua_newuserdatauv(L, (limit ? limit : 1) * sizeof *buf, 0);
            luaL_checkstack(L, 6, NULL);
            for (size_t j = 0; j < limit; j++) {
                m = fl_lmesh_check(L, 1); /* the function may close it */
                if (j >= (elements ? femlod_mesh_triangle_count(m) : femlod_mesh_vertex_count(m)))
                    break;
                const double *pos = femlod_mesh_positions(m);
                double p[3];
                if (elements) {
                    const uint32_t *tr = femlod_mesh_triangles(m) + 3 * j;
                    for (int d = 0; d < 3; d++)
                        p[d] = (pos[3 * (size_t)tr[0] + d] + pos[3 * (size_t)tr[1] + d] +
                                pos[3 * (size_t)tr[2] + d]) / 3;
                } else {
                    for (int d = 0; d < 3; d++) p[d] = pos[3 * j + d];
                }
                lua_pushvalue(L, val);
                lua_pushnumber(L, p[0]);
                lua_pushnumber(L, p[1]);
                lua_pushnumber(L, p[2]);
                lua_pushinteger(L, (lua_Integer)j + 1);
                lua_call(L, 4, 1);
                int r = lua_type(L, -1);
                if (r == LUA_TBOOLEAN) {
                    if (lua_toboolean(L, -1)) buf[c++] = (uint32_t)j;
                } else if (r != LUA_TNIL) {
                    fl_opts_error(o, key, lua_pushfstring(L, "%s: function returned %s for %s %I "
                                                             "(boolean or nil expected)",
                                                          name, luaL_typename(L, -1),
                                                          elements ? "triangle" : "vertex",
                                                          (lua_Integer)j + 1));
                }
                lua_pop(L, 1);
            }
        } else {
            fl_opts_error(o, key, lua_pushfstring(L, "%s: list of indices or function expected, got %s",
                                                  name, luaL_typename(L, val)));
            return NULL;
        }
        /* The value and its buffer stay on the stack until the write. */
        sets[i].indices = buf;
        sets[i].count = c;
    }
    *count = n;
    return sets;
}

/* m:save(path, opts) and m:encode(name, opts): the options of both. */
static void write_options(lua_State *L, femlod_write_options *opts) {
    fl_opts o;
    fl_opts_open(&o, L, 3, save_keys);
    int f = fl_opts_enum(&o, "format", format_names, -1);
    opts->format = f < 0 ? FEMLOD_FORMAT_AUTO : femlod_format_from_name(format_names[f]);
    opts->color_by = (femlod_color_by)fl_opts_enum(&o, "color_by", color_names, 0);
    opts->normals = fl_opts_boolean(&o, "normals", 0);
    if (fl_opts_push(&o, "extras") != LUA_TNIL) opts->extras = extras_json(L, &o);
    opts->node_sets = read_sets(L, &o, "nsets", 0, &opts->node_set_count);
    opts->element_sets = read_sets(L, &o, "elsets", 1, &opts->element_set_count);
}

/* m:encode(name [, opts]): the bytes m:save(name, opts) would write, as a
 * string, with no file made (name gives the format by its extension, as for
 * save, and names the mesh in messages). For pages and messages that embed
 * a mesh, and for recipes under --sandbox. */
static int mesh_encode(lua_State *L) {
    fl_lmesh_check(L, 1);
    size_t len;
    const char *name = luaL_checklstring(L, 2, &len);
    luaL_argcheck(L, strlen(name) == len, 2, "name contains a zero byte");
    femlod_write_options opts = FEMLOD_WRITE_OPTIONS_INIT;
    write_options(L, &opts);
    const femlod_mesh *m = fl_lmesh_check(L, 1); /* a set function may have closed it */
    femlod_error err;
    char *data = NULL;
    size_t size = 0;
    if (femlod_mesh_write_memory(m, name, &opts, &data, &size, &err) != FEMLOD_OK)
        return fl_lua_raise(L, &err);
    fl_lua_push_owned(L, data, size);
    return 1;
}

static int mesh_save(lua_State *L) {
    const femlod_mesh *m = fl_lmesh_check(L, 1);
    const char *path = fl_lua_check_path(L, 2, 1);
    femlod_write_options opts = FEMLOD_WRITE_OPTIONS_INIT;
    write_options(L, &opts);
    m = fl_lmesh_check(L, 1); /* a set function may have closed it */
    femlod_error err;
    double t0 = fl_lua_clock();
    if (femlod_mesh_write(m, path, &opts, &err) != FEMLOD_OK) return fl_lua_raise(L, &err);
    if (fl_lua_verbose(L))
        fl_lua_log(L, "write %s: %zu triangles, %zu vertices (%.3f s)", path,
                   femlod_mesh_triangle_count(m), femlod_mesh_vertex_count(m), fl_lua_clock() - t0);
    fl_lua_io_hook(L, "write", 2, 1);
    return 0;
}

static void set_number(lua_State *L, const char *key, double v) {
    lua_pushnumber(L, v);
    lua_setfield(L, -2, key);
}

static void set_integer(lua_State *L, const char *key, size_t v) {
    lua_pushinteger(L, (lua_Integer)v);
    lua_setfield(L, -2, key);
}

static void set_boolean(lua_State *L, const char *key, int v) {
    lua_pushboolean(L, v);
    lua_setfield(L, -2, key);
}

static void push_point(lua_State *L, const double p[3]) {
    lua_createtable(L, 3, 0);
    for (int i = 0; i < 3; i++) {
        lua_pushnumber(L, p[i]);
        lua_rawseti(L, -2, i + 1);
    }
}

static void push_bbox(lua_State *L, const double min[3], const double max[3]) {
    lua_createtable(L, 0, 2);
    push_point(L, min);
    lua_setfield(L, -2, "min");
    push_point(L, max);
    lua_setfield(L, -2, "max");
}

/* m:quality([reference [, {progress = f}]]): the report as a table whose
 * keys are the C field names (topology flattened in); progress follows the
 * Hausdorff distance to the reference. */
static int mesh_quality(lua_State *L) {
    static const char *const keys[] = {"progress", NULL};
    const femlod_mesh *m = fl_lmesh_check(L, 1);
    const femlod_mesh *ref = lua_isnoneornil(L, 2) ? NULL : fl_lmesh_check(L, 2);
    fl_opts o;
    fl_opts_open(&o, L, 3, keys);
    luaL_argcheck(L, ref || !o.idx, 3, "options without a reference");
    femlod_quality q;
    femlod_hausdorff_result h;
    femlod_error err;
    /* Both computations before any table: a failure raises with nothing built. */
    if (femlod_mesh_quality(m, &q, &err) != FEMLOD_OK) return fl_lua_raise(L, &err);
    if (ref) {
        femlod_hausdorff_options ho = FEMLOD_HAUSDORFF_OPTIONS_INIT;
        fl_progress_call pc;
        ho.progress = fl_opts_progress(&o, &pc);
        ho.progress_payload = &pc;
        double t0 = fl_lua_clock();
        femlod_status st = femlod_mesh_hausdorff(m, ref, &ho, &h, &err);
        fl_opts_progress_check(&o, &pc, st);
        if (st != FEMLOD_OK) return fl_lua_raise(L, &err);
        if (fl_lua_verbose(L))
            fl_lua_log(L, "hausdorff: %.6g (%.3g of the diagonal), %zu samples (%.3f s)",
                       h.distance, h.relative, h.samples, fl_lua_clock() - t0);
    }

    lua_createtable(L, 0, 40);
    set_integer(L, "triangles", q.triangles);
    set_integer(L, "vertices", q.vertices);
    set_number(L, "stretch_avg", q.stretch_avg);
    set_number(L, "stretch_min", q.stretch_min);
    set_number(L, "stretch_max", q.stretch_max);
    set_number(L, "size_max", q.size_max);
    set_number(L, "size_min", q.size_min);
    set_number(L, "size_avg", q.size_avg);
    set_integer(L, "valence_max", q.valence_max);
    set_number(L, "valence_avg", q.valence_avg);
    set_number(L, "angle_min", q.angle_min);
    set_number(L, "angle_max", q.angle_max);
    set_integer(L, "degenerate", q.degenerate);
    set_integer(L, "duplicate", q.duplicate);
    set_number(L, "area", q.area);
    push_bbox(L, q.bbox_min, q.bbox_max);
    lua_setfield(L, -2, "bbox");
    lua_createtable(L, FEMLOD_HISTOGRAM_BINS, 0);
    for (int i = 0; i < FEMLOD_HISTOGRAM_BINS; i++) {
        lua_pushinteger(L, (lua_Integer)q.histogram[i]);
        lua_rawseti(L, -2, i + 1);
    }
    lua_setfield(L, -2, "histogram");

    const femlod_topology *t = &q.topology;
    set_integer(L, "edges", t->edges);
    set_integer(L, "boundary_edges", t->boundary_edges);
    set_integer(L, "nonmanifold_edges", t->nonmanifold_edges);
    set_integer(L, "nonmanifold_vertices", t->nonmanifold_vertices);
    set_integer(L, "inconsistent_edges", t->inconsistent_edges);
    set_integer(L, "isolated_vertices", t->isolated_vertices);
    set_integer(L, "components", t->components);
    set_boolean(L, "closed", t->closed);
    set_boolean(L, "manifold", t->manifold);
    set_boolean(L, "oriented", t->oriented);

    if (ref) {
        set_number(L, "hausdorff", h.distance);
        set_number(L, "hausdorff_rel", h.relative);
        set_number(L, "hausdorff_forward", h.forward);
        set_number(L, "hausdorff_backward", h.backward);
    }
    return 1;
}

static int mesh_counts(lua_State *L) {
    const femlod_mesh *m = fl_lmesh_check(L, 1);
    lua_createtable(L, 0, 2);
    set_integer(L, "vertices", femlod_mesh_vertex_count(m));
    set_integer(L, "triangles", femlod_mesh_triangle_count(m));
    return 1;
}

static int mesh_bbox(lua_State *L) {
    const femlod_mesh *m = fl_lmesh_check(L, 1);
    double min[3], max[3];
    femlod_mesh_bbox(m, min, max);
    push_bbox(L, min, max);
    return 1;
}

/* More levels can never succeed on a non-empty mesh (4^16 > UINT32_MAX
 * triangles), and the bound keeps the count within unsigned. */
#define MAX_LEVELS 16
#define MAX_LEVELS_TEXT "16"

static int mesh_subdivide(lua_State *L) {
    const femlod_mesh *m = fl_lmesh_check(L, 1);
    lua_Integer levels = luaL_optinteger(L, 2, 1);
    luaL_argcheck(L, levels >= 0 && levels <= MAX_LEVELS, 2,
                  "levels out of range (0.." MAX_LEVELS_TEXT ")");
    /* Under a memory cap, refuse before allocating: the result has at
     * least 4^levels times the triangles and all the vertices. */
    fl_lua_reserve(L, fl_lmesh_bytes((double)femlod_mesh_vertex_count(m),
                                     (double)femlod_mesh_triangle_count(m) *
                                         ldexp(1.0, 2 * (int)levels)));
    femlod_mesh **slot = fl_lmesh_box(L);
    femlod_error err;
    if (femlod_mesh_subdivide(slot, m, (unsigned)levels, &err) != FEMLOD_OK)
        return fl_lua_raise(L, &err);
    fl_lmesh_charge(L, slot);
    return 1;
}

/* m:repair{ weld = 0 | tol | false, drop_degenerate = true, drop_duplicates =
 * true, split_nonmanifold = true, orient = true, drop_unused = true }: a new,
 * repaired mesh and a table counting every change (femlod_mesh_repair). */
static int mesh_repair(lua_State *L) {
    static const char *const keys[] = {"drop_degenerate", "drop_duplicates", "drop_unused",
                                       "orient", "split_nonmanifold", "weld", NULL};
    const femlod_mesh *m = fl_lmesh_check(L, 1);
    fl_opts o;
    fl_opts_open(&o, L, 2, keys);
    femlod_repair_options ro = FEMLOD_REPAIR_OPTIONS_INIT;
    int wt = fl_opts_push(&o, "weld");
    if (wt == LUA_TBOOLEAN) {
        ro.weld = lua_toboolean(L, -1) ? 0.0 : -1.0;
        lua_pop(L, 1);
    } else if (wt != LUA_TNIL) {
        lua_pop(L, 1);
        ro.weld = (double)fl_opts_number(&o, "weld", 0.0);
        if (!(ro.weld >= 0.0) || !(ro.weld < HUGE_VAL))
            return fl_opts_error(&o, "weld", "must be a finite length >= 0, or false");
    }
    ro.drop_degenerate = fl_opts_boolean(&o, "drop_degenerate", 1);
    ro.drop_duplicates = fl_opts_boolean(&o, "drop_duplicates", 1);
    ro.split_nonmanifold = fl_opts_boolean(&o, "split_nonmanifold", 1);
    ro.orient = fl_opts_boolean(&o, "orient", 1);
    ro.drop_unused = fl_opts_boolean(&o, "drop_unused", 1);
    femlod_mesh **slot = fl_lmesh_box(L);
    femlod_repair_report r;
    femlod_error err;
    double t0 = fl_lua_clock();
    if (femlod_mesh_repair(slot, m, &ro, &r, &err) != FEMLOD_OK) return fl_lua_raise(L, &err);
    if (fl_lua_verbose(L))
        fl_lua_log(L, "repair: %zu -> %zu triangles, %zu -> %zu vertices (%.3f s)", r.triangles_in,
                   r.triangles_out, r.vertices_in, r.vertices_out, fl_lua_clock() - t0);
    lua_createtable(L, 0, 12);
    static const struct { const char *key; size_t off; } fields[] = {
        {"vertices_in", offsetof(femlod_repair_report, vertices_in)},
        {"triangles_in", offsetof(femlod_repair_report, triangles_in)},
        {"vertices", offsetof(femlod_repair_report, vertices_out)},
        {"triangles", offsetof(femlod_repair_report, triangles_out)},
        {"welded", offsetof(femlod_repair_report, welded)},
        {"degenerate", offsetof(femlod_repair_report, degenerate)},
        {"duplicates", offsetof(femlod_repair_report, duplicates)},
        {"split_vertices", offsetof(femlod_repair_report, split_vertices)},
        {"flipped", offsetof(femlod_repair_report, flipped)},
        {"unorientable_edges", offsetof(femlod_repair_report, unorientable_edges)},
        {"unused", offsetof(femlod_repair_report, unused)},
        {"nonmanifold_edges_left", offsetof(femlod_repair_report, nonmanifold_edges_left)},
    };
    for (size_t i = 0; i < sizeof fields / sizeof fields[0]; i++) {
        size_t v;
        memcpy(&v, (const char *)&r + fields[i].off, sizeof v);
        lua_pushinteger(L, (lua_Integer)v);
        lua_setfield(L, -2, fields[i].key);
    }
    return 2;
}

static int mesh_copy(lua_State *L) {
    const femlod_mesh *m = fl_lmesh_check(L, 1);
    femlod_mesh **slot = fl_lmesh_box(L);
    femlod_error err;
    if (femlod_mesh_copy(slot, m, &err) != FEMLOD_OK) return fl_lua_raise(L, &err);
    fl_lmesh_charge(L, slot);
    return 1;
}

/* lua_createtable takes an int hint; a bigger count just grows as it goes. */
static int size_hint(size_t n) {
    return n > INT_MAX ? 0 : (int)n;
}

static int mesh_positions(lua_State *L) {
    const femlod_mesh *m = fl_lmesh_check(L, 1);
    size_t nv = femlod_mesh_vertex_count(m);
    const double *p = femlod_mesh_positions(m);
    lua_createtable(L, size_hint(nv), 0);
    for (size_t v = 0; v < nv; v++) {
        push_point(L, p + 3 * v);
        lua_rawseti(L, -2, (lua_Integer)v + 1);
    }
    return 1;
}

static int mesh_triangles(lua_State *L) {
    const femlod_mesh *m = fl_lmesh_check(L, 1);
    size_t nt = femlod_mesh_triangle_count(m);
    const uint32_t *t = femlod_mesh_triangles(m);
    lua_createtable(L, size_hint(nt), 0);
    for (size_t i = 0; i < nt; i++) {
        lua_createtable(L, 3, 0);
        for (int c = 0; c < 3; c++) {
            lua_pushinteger(L, (lua_Integer)t[3 * i + c] + 1);
            lua_rawseti(L, -2, c + 1);
        }
        lua_rawseti(L, -2, (lua_Integer)i + 1);
    }
    return 1;
}

/* {=== m:curvature{radius = r} (femlod_mesh_curvature): per-vertex arrays,
 * 1-based, { k1 = {...}, k2 = {...}, kappa = {...}, dir1 = {{x,y,z},...},
 * dir2 = {...} }. The C results go into one Lua-owned buffer, so a raise
 * while the tables are built leaks nothing. */
static const char *const curvature_keys[] = {"progress", "radius", NULL};

static void push_numbers(lua_State *L, const double *v, size_t n) {
    lua_createtable(L, size_hint(n), 0);
    for (size_t i = 0; i < n; i++) {
        lua_pushnumber(L, v[i]);
        lua_rawseti(L, -2, (lua_Integer)i + 1);
    }
}

static void push_points(lua_State *L, const double *v, size_t n) {
    lua_createtable(L, size_hint(n), 0);
    for (size_t i = 0; i < n; i++) {
        push_point(L, v + 3 * i);
        lua_rawseti(L, -2, (lua_Integer)i + 1);
    }
}

static int mesh_curvature(lua_State *L) {
    const femlod_mesh *m = fl_lmesh_check(L, 1);
    fl_opts o;
    fl_opts_open(&o, L, 2, curvature_keys);
    femlod_curvature_options opts = FEMLOD_CURVATURE_OPTIONS_INIT;
    opts.radius = (double)fl_opts_number(&o, "radius", 0.0);
    size_t nv = femlod_mesh_vertex_count(m);
    if (nv > SIZE_MAX / (9 * sizeof(double))) return luaL_error(L, "curvature: mesh too large");
    double *k1 = (double *)lua_newuserdatauv(L, 9 * nv * sizeof(double), 0);
    double *k2 = k1 + nv, *kappa = k2 + nv, *dir1 = kappa + nv, *dir2 = dir1 + 3 * nv;
    femlod_error err;
    fl_progress_call pc;
    opts.progress = fl_opts_progress(&o, &pc);
    opts.progress_payload = &pc;
    double t0 = fl_lua_clock();
    femlod_status st = femlod_mesh_curvature(m, &opts, k1, k2, kappa, dir1, dir2, &err);
    fl_opts_progress_check(&o, &pc, st);
    if (st != FEMLOD_OK) return fl_lua_raise(L, &err);
    if (fl_lua_verbose(L))
        fl_lua_log(L, "curvature: %zu vertices (%.3f s)", nv, fl_lua_clock() - t0);
    lua_createtable(L, 0, 5);
    push_numbers(L, k1, nv);
    lua_setfield(L, -2, "k1");
    push_numbers(L, k2, nv);
    lua_setfield(L, -2, "k2");
    push_numbers(L, kappa, nv);
    lua_setfield(L, -2, "kappa");
    push_points(L, dir1, nv);
    lua_setfield(L, -2, "dir1");
    push_points(L, dir2, nv);
    lua_setfield(L, -2, "dir2");
    return 1;
}
/* }=== */

/* __gc, __close and close(): one release that tolerates a closed box, since
 * __close runs at scope exit even after an explicit close(), and __gc after
 * both. */
static int mesh_gc(lua_State *L) {
    fl_lmesh_release(L, (femlod_mesh **)luaL_checkudata(L, 1, FL_MESH_MT));
    return 0;
}

static int mesh_tostring(lua_State *L) {
    femlod_mesh **p = (femlod_mesh **)luaL_checkudata(L, 1, FL_MESH_MT);
    if (!*p)
        lua_pushliteral(L, "femlod.Mesh (closed)");
    else
        lua_pushfstring(L, "femlod.Mesh (%I triangles, %I vertices)",
                        (lua_Integer)femlod_mesh_triangle_count(*p),
                        (lua_Integer)femlod_mesh_vertex_count(*p));
    return 1;
}

/* }==================================================================== */

static const luaL_Reg lib_functions[] = {
    {"load", lib_load},
    {"mesh", lib_mesh},
    {NULL, NULL},
};

static const luaL_Reg mesh_methods[] = {
    {"save", mesh_save},
    {"quality", mesh_quality},
    {"counts", mesh_counts},
    {"bbox", mesh_bbox},
    {"subdivide", mesh_subdivide},
    {"repair", mesh_repair},
    {"encode", mesh_encode},
    {"copy", mesh_copy},
    {"positions", mesh_positions},
    {"triangles", mesh_triangles},
    {"curvature", mesh_curvature},
    {"close", mesh_gc},
    {NULL, NULL},
};

static const luaL_Reg mesh_meta[] = {
    {"__index", NULL}, /* placeholder, set to the method table below */
    {"__gc", mesh_gc},
    {"__close", mesh_gc},
    {"__tostring", mesh_tostring},
    {NULL, NULL},
};

void fl_lmesh_open(lua_State *L) {
    /* A second luaopen_femlod in the same state (package.loaded cleared)
     * reuses the metatable, so existing meshes keep working. */
    if (luaL_newmetatable(L, FL_MESH_MT)) {
        luaL_setfuncs(L, mesh_meta, 0);
        luaL_newlibtable(L, mesh_methods);
        luaL_setfuncs(L, mesh_methods, 0);
        lua_setfield(L, -2, "__index");
    }
    lua_pop(L, 1);
    luaL_setfuncs(L, lib_functions, 0);
}
