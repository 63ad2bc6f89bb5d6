/*
 * limprove.c - mesh:improve{...} (femlod_improve, docs/design.md "Improving a
 * mesh in place"): a new Mesh and a report table; mesh:census{...}
 * (femlod_improve_census): the report alone, for the mesh as it is.
 *
 *   local better, rep = m:improve{ min_stretch = 0.2, max_valence = 12,
 *                                  max_size = 5, max_deviation = 0.01,
 *                                  feature_angle = 40, max_normal_change = 60,
 *                                  max_rounds = 20, lock = { 1, 7 } }
 *
 * Thresholds as femlod.simplify takes them: nil the default, false off, a
 * number the value. rep: triangles_in, triangles, vertices_in, vertices,
 * rounds, operations = { flip, split, collapse, relax }, input = { stretch,
 * size, valence } (elements breaking each threshold), remaining = { stretch,
 * size, valence }, remaining_by = { stretch = { REASON = n }, size, valence,
 * triangles (stretch or size, each once) }, violating (their count),
 * corner_angle_min/max (degrees, when a forced corner remains),
 * refused = { REASON = n }, stretch_min_in, stretch_min, valence_max_in,
 * valence_max, the thresholds in force and seconds.
 */
#include "lfemlod.h"
#include "lopts.h"

#include <math.h>
#include <stdint.h>
#include <string.h>

static const char *const improve_keys[] = {"min_stretch", "max_size", "max_valence", "max_deviation",
                                           "feature_angle", "max_normal_change", "max_rounds", "lock",
                                           NULL};

/* nil: 0 (the default); false: off; a number in (0, max] */
static double threshold(const fl_opts *o, const char *key, double max, const char *expected) {
    lua_State *L = o->L;
    int t = fl_opts_push(o, key);
    if (t == LUA_TNIL) return 0.0;
    double v = lua_tonumber(L, -1);
    int off = t == LUA_TBOOLEAN && !lua_toboolean(L, -1);
    lua_pop(L, 1);
    if (off) return FEMLOD_SIMPLIFY_OFF;
    if (t != LUA_TNUMBER || !(v > 0.0 && v <= max && isfinite(v)))
        fl_opts_error(o, key, lua_pushfstring(L, "%s or false expected", expected));
    return v;
}

static void set_counts(lua_State *L, const char *name, size_t st, size_t sz, size_t val) {
    lua_createtable(L, 0, 3);
    lua_pushinteger(L, (lua_Integer)st);
    lua_setfield(L, -2, "stretch");
    lua_pushinteger(L, (lua_Integer)sz);
    lua_setfield(L, -2, "size");
    lua_pushinteger(L, (lua_Integer)val);
    lua_setfield(L, -2, "valence");
    lua_setfield(L, -2, name);
}

static void push_reasons(lua_State *L, const size_t *by) {
    lua_newtable(L);
    for (int k = 0; k < FEMLOD_IMPROVE_REASON_COUNT; k++) {
        if (!by[k]) continue;
        lua_pushinteger(L, (lua_Integer)by[k]);
        lua_setfield(L, -2, femlod_improve_reason_name((femlod_improve_reason)k));
    }
}

static void set_threshold(lua_State *L, const char *key, double v) {
    if (v < 0) lua_pushboolean(L, 0);
    else lua_pushnumber(L, v);
    lua_setfield(L, -2, key);
}

/* The options table at index 2 into *io (a lock list kept in a userdata
 * pushed on the stack). */
static void read_options(lua_State *L, const femlod_mesh *m, femlod_improve_options *out) {
    fl_opts o;
    fl_opts_open(&o, L, 2, improve_keys);
    femlod_improve_options io = FEMLOD_IMPROVE_OPTIONS_INIT;
    io.min_stretch = threshold(&o, "min_stretch", 1.0, "number in (0, 1]");
    io.max_size = threshold(&o, "max_size", HUGE_VAL, "number > 0");
    io.max_deviation = threshold(&o, "max_deviation", HUGE_VAL, "number > 0");
    io.feature_angle = threshold(&o, "feature_angle", 180.0, "number in (0, 180]");
    io.max_normal_change = threshold(&o, "max_normal_change", 180.0, "number in (0, 180]");
    int t = fl_opts_push(&o, "max_valence");
    if (t == LUA_TBOOLEAN && !lua_toboolean(L, -1)) {
        io.max_valence = -1;
        lua_pop(L, 1);
    } else if (t != LUA_TNIL) {
        int isint = 0;
        lua_Integer n = lua_tointegerx(L, -1, &isint);
        lua_pop(L, 1);
        if (t != LUA_TNUMBER || !isint || n < 3 || n > 100000)
            fl_opts_error(&o, "max_valence", "integer >= 3 or false expected");
        io.max_valence = (int)n;
    }
    lua_Integer rounds = fl_opts_integer(&o, "max_rounds", 0);
    if (rounds < 0 || rounds > 100000) fl_opts_error(&o, "max_rounds", "integer >= 1 expected");
    io.max_rounds = (int)rounds;
    /* lock: a list of 1-based vertex indices, kept in a Lua-owned buffer */
    t = fl_opts_push(&o, "lock");
    if (t != LUA_TNIL) {
        if (t != LUA_TTABLE)
            fl_opts_error(&o, "lock", lua_pushfstring(L, "table expected, got %s", luaL_typename(L, -1)));
        int lk = lua_gettop(L);
        lua_Integer len = luaL_len(L, lk);
        size_t nv = femlod_mesh_vertex_count(m);
        if (len < 0 || (lua_Unsigned)len > SIZE_MAX / sizeof(uint32_t)) fl_opts_error(&o, "lock", "list too long");
        uint32_t *buf = (uint32_t *)lua_newuserdatauv(L, (size_t)len * sizeof *buf + 1, 0);
        for (lua_Integer i = 1; i <= len; i++) {
            int isint = 0;
            lua_geti(L, lk, i);
            lua_Integer v = lua_tointegerx(L, -1, &isint);
            lua_pop(L, 1);
            if (!isint || v < 1 || (lua_Unsigned)v > nv)
                luaL_argerror(L, 2, lua_pushfstring(L, "lock[%I]: index out of range (1..%I)", i, (lua_Integer)nv));
            buf[i - 1] = (uint32_t)(v - 1);
        }
        io.lock = buf;
        io.lock_count = (size_t)len;
    }
    *out = io;
}

/* The report as a table on the stack. */
static void push_report(lua_State *L, const femlod_improve_report *rp) {
    femlod_improve_report r = *rp;
    lua_createtable(L, 0, 24);
    static const struct {
        const char *key;
        size_t off;
    } sizes[] = {
        {"triangles_in", offsetof(femlod_improve_report, triangles_in)},
        {"triangles", offsetof(femlod_improve_report, triangles)},
        {"vertices_in", offsetof(femlod_improve_report, vertices_in)},
        {"vertices", offsetof(femlod_improve_report, vertices)},
        {"rounds", offsetof(femlod_improve_report, rounds)},
    };
    for (size_t i = 0; i < sizeof sizes / sizeof sizes[0]; i++) {
        size_t v;
        memcpy(&v, (const char *)&r + sizes[i].off, sizeof v);
        lua_pushinteger(L, (lua_Integer)v);
        lua_setfield(L, -2, sizes[i].key);
    }
    lua_createtable(L, 0, 4);
    lua_pushinteger(L, (lua_Integer)r.flips);
    lua_setfield(L, -2, "flip");
    lua_pushinteger(L, (lua_Integer)r.splits);
    lua_setfield(L, -2, "split");
    lua_pushinteger(L, (lua_Integer)r.collapses);
    lua_setfield(L, -2, "collapse");
    lua_pushinteger(L, (lua_Integer)r.relaxations);
    lua_setfield(L, -2, "relax");
    lua_setfield(L, -2, "operations");
    set_counts(L, "input", r.stretch_in, r.size_in, r.valence_in);
    set_counts(L, "remaining", r.stretch_out, r.size_out, r.valence_out);
    lua_createtable(L, 0, 3);
    push_reasons(L, r.stretch_by);
    lua_setfield(L, -2, "stretch");
    push_reasons(L, r.size_by);
    lua_setfield(L, -2, "size");
    push_reasons(L, r.valence_by);
    lua_setfield(L, -2, "valence");
    push_reasons(L, r.violating_by);
    lua_setfield(L, -2, "triangles");
    lua_setfield(L, -2, "remaining_by");
    lua_pushinteger(L, (lua_Integer)r.violating);
    lua_setfield(L, -2, "violating");
    if (r.corner_angle_max > 0.0) {
        lua_pushnumber(L, r.corner_angle_min);
        lua_setfield(L, -2, "corner_angle_min");
        lua_pushnumber(L, r.corner_angle_max);
        lua_setfield(L, -2, "corner_angle_max");
    }
    push_reasons(L, r.refused);
    lua_setfield(L, -2, "refused");
    lua_pushnumber(L, r.stretch_min_in);
    lua_setfield(L, -2, "stretch_min_in");
    lua_pushnumber(L, r.stretch_min);
    lua_setfield(L, -2, "stretch_min");
    lua_pushinteger(L, (lua_Integer)r.valence_max_in);
    lua_setfield(L, -2, "valence_max_in");
    lua_pushinteger(L, (lua_Integer)r.valence_max);
    lua_setfield(L, -2, "valence_max");
    set_threshold(L, "min_stretch", r.min_stretch);
    set_threshold(L, "max_size", r.max_size);
    set_threshold(L, "max_deviation", r.max_deviation);
    set_threshold(L, "feature_angle", r.feature_angle);
    set_threshold(L, "max_normal_change", r.max_normal_change);
    if (r.max_valence < 0) lua_pushboolean(L, 0);
    else lua_pushinteger(L, r.max_valence);
    lua_setfield(L, -2, "max_valence");
    lua_pushnumber(L, r.seconds);
    lua_setfield(L, -2, "seconds");
}

static int mesh_improve(lua_State *L) {
    const femlod_mesh *m = fl_lmesh_check(L, 1);
    femlod_improve_options io;
    read_options(L, m, &io);
    femlod_mesh **slot = fl_lmesh_box(L);
    femlod_improve_report r;
    femlod_error err;
    if (femlod_improve(slot, m, &io, &r, &err) != FEMLOD_OK) return fl_lua_raise(L, &err);
    fl_lmesh_charge(L, slot);
    push_report(L, &r);
    return 2;
}

/* mesh:census{...}: femlod_improve_census, the report of mesh:improve for
 * the mesh as it is (no mesh returned) */
static int mesh_census(lua_State *L) {
    const femlod_mesh *m = fl_lmesh_check(L, 1);
    femlod_improve_options io;
    read_options(L, m, &io);
    femlod_improve_report r;
    femlod_error err;
    if (femlod_improve_census(m, &io, &r, &err) != FEMLOD_OK) return fl_lua_raise(L, &err);
    push_report(L, &r);
    return 1;
}

void fl_limprove_open(lua_State *L) {
    luaL_getmetatable(L, FL_MESH_MT);
    lua_getfield(L, -1, "__index");
    lua_pushcfunction(L, mesh_improve);
    lua_setfield(L, -2, "improve");
    lua_pushcfunction(L, mesh_census);
    lua_setfield(L, -2, "census");
    lua_pop(L, 2);
}
