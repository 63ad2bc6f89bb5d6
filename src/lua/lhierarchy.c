/*
 * lhierarchy.c - femlod.simplify and the femlod.Hierarchy userdata.
 *
 * A Hierarchy is a box (fl_hierarchy, lfemlod.h) holding what one
 * simplification made: the simplified mesh, the collapse log and the
 * result record. Like a Mesh it is pushed empty, with its metatable and
 * __gc in place, before femlod_simplify fills it, and it frees its C
 * memory in one release shared by __gc, __close and close().
 *
 * No Lua error may cross femlod_simplify (a longjmp through it would leak
 * its work memory and skip its clean-up), so the recipe's Lua runs outside
 * it or under lua_pcall:
 *   - lock: the indices are read, or the lock function is called for every
 *     vertex, before femlod_simplify runs; the result is an index list in a
 *     Lua-owned buffer, so a raise there (a bad index, an error inside the
 *     function) leaks nothing;
 *   - progress: called from femlod_simplify through lua_pcall; an error
 *     cancels the run, and is raised again once femlod_simplify returned
 *     and its results were freed.
 * While femlod_simplify runs, the input Mesh's box is empty, so a progress
 * function that closes or uses that mesh finds it closed instead of freeing
 * it under the simplifier.
 */
#include "lfemlod.h"
#include "lopts.h"

#include <limits.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

/* {====================================================================
 * Options
 * ===================================================================== */

static const char *const simplify_keys[] = {
    "target",         "ratio",          "tolerance",         "max_deviation",
    "min_stretch",    "max_size",       "max_valence",       "feature_angle",
    "feature_weight", "max_normal_change", "keep_boundary",  "area_weighted",
    "lock",           "progress",       NULL};

/* The thresholds of type double that `false` switches off, in the order of
 * femlod_simplify_options; max is the largest value allowed. */
typedef struct threshold {
    const char *key;
    size_t offset;
    double max;
    const char *expected;
} threshold;

#define THRESHOLD(name, max, expected) {#name, offsetof(femlod_simplify_options, name), max, expected}
static const threshold thresholds[] = {
    THRESHOLD(tolerance, HUGE_VAL, "number > 0"),
    THRESHOLD(max_deviation, HUGE_VAL, "number > 0"),
    THRESHOLD(min_stretch, 1.0, "number in (0, 1]"),
    THRESHOLD(max_size, HUGE_VAL, "number > 0"),
    THRESHOLD(feature_angle, 180.0, "number in (0, 180]"),
    THRESHOLD(feature_weight, HUGE_VAL, "number > 0"),
    THRESHOLD(max_normal_change, 180.0, "number in (0, 180]"),
};
#undef THRESHOLD

/* Replaces the bad value on the top of the stack by the message "EXPECTED
 * [or OFF] expected, got VALUE": numbers and booleans show their value, the
 * rest their type. Returns the message. */
static const char *bad_value(lua_State *L, const char *expected, const char *off) {
    int t = lua_type(L, -1);
    if (t == LUA_TNUMBER || t == LUA_TBOOLEAN)
        luaL_tolstring(L, -1, NULL);
    else
        lua_pushstring(L, luaL_typename(L, -1));
    const char *got = lua_tostring(L, -1);
    if (off)
        lua_pushfstring(L, "%s or %s expected, got %s", expected, off, got);
    else
        lua_pushfstring(L, "%s expected, got %s", expected, got);
    lua_replace(L, -3);
    lua_pop(L, 1);
    return lua_tostring(L, -1);
}

const char *fl_simplify_read_options(lua_State *L, int idx, femlod_simplify_options *o,
                                     const char *off, const char **key) {
    idx = lua_absindex(L, idx);
    *key = "target";
    int t = lua_getfield(L, idx, "target");
    if (t != LUA_TNIL) {
        int isint = 0;
        lua_Integer n = lua_tointegerx(L, -1, &isint);
        if (t != LUA_TNUMBER || !isint || n < 1 || (lua_Unsigned)n > SIZE_MAX)
            return bad_value(L, "integer >= 1", NULL);
        o->target = (size_t)n;
    }
    lua_pop(L, 1);

    *key = "ratio";
    t = lua_getfield(L, idx, "ratio");
    if (t != LUA_TNIL) {
        double r = lua_tonumber(L, -1);
        if (t != LUA_TNUMBER || !(r > 0.0 && r <= 1.0)) return bad_value(L, "number in (0, 1]", NULL);
        o->ratio = r;
    }
    lua_pop(L, 1);
    if (o->target && o->ratio > 0.0) {
        *key = NULL;
        return lua_pushliteral(L, "give target or ratio, not both");
    }

    for (size_t k = 0; k < sizeof thresholds / sizeof thresholds[0]; k++) {
        const threshold *th = &thresholds[k];
        double *field = (double *)(void *)((char *)o + th->offset);
        *key = th->key;
        t = lua_getfield(L, idx, th->key);
        if (t == LUA_TBOOLEAN && !lua_toboolean(L, -1)) {
            *field = FEMLOD_SIMPLIFY_OFF;
        } else if (t != LUA_TNIL) {
            double v = lua_tonumber(L, -1);
            /* Zero would mean "the default" to the core: refused, not guessed. */
            if (t != LUA_TNUMBER || !(v > 0.0 && v <= th->max && isfinite(v)))
                return bad_value(L, th->expected, off);
            *field = v;
        }
        lua_pop(L, 1);
    }

    *key = "max_valence";
    t = lua_getfield(L, idx, "max_valence");
    if (t == LUA_TBOOLEAN && !lua_toboolean(L, -1)) {
        o->max_valence = -1;
    } else if (t != LUA_TNIL) {
        int isint = 0;
        lua_Integer n = lua_tointegerx(L, -1, &isint);
        if (t != LUA_TNUMBER || !isint || n < 3 || n > INT_MAX)
            return bad_value(L, "integer >= 3", off);
        o->max_valence = (int)n;
    }
    lua_pop(L, 1);

    static const char *const flags[] = {"keep_boundary", "area_weighted"};
    for (int k = 0; k < 2; k++) {
        *key = flags[k];
        t = lua_getfield(L, idx, flags[k]);
        if (t != LUA_TNIL && t != LUA_TBOOLEAN) return bad_value(L, "boolean", NULL);
        int on = lua_toboolean(L, -1);
        if (k == 0) o->keep_boundary = on;
        else o->area_weighted = on;
        lua_pop(L, 1);
    }
    *key = NULL;
    return NULL;
}

/* The lock option as a list of 0-based indices in a Lua-owned buffer, left
 * on the stack (nothing is pushed when there is no lock). The mesh is
 * argument 1; a lock function may close it, so it is looked up again for
 * every vertex. */
static void read_lock(lua_State *L, const fl_opts *o, femlod_simplify_options *so) {
    int t = fl_opts_push(o, "lock");
    if (t == LUA_TNIL) return;
    int lk = lua_gettop(L);
    size_t nv = femlod_mesh_vertex_count(fl_lmesh_check(L, 1));
    uint32_t *buf;
    size_t n = 0;
    if (t == LUA_TTABLE) {
        lua_Integer len = luaL_len(L, lk);
        /* A set such as { [5] = true } would read as an empty list: refuse
         * every key that is not a list position. */
        lua_pushnil(L);
        while (lua_next(L, lk)) {
            lua_pop(L, 1);
            int isint = 0;
            lua_Integer k = lua_tointegerx(L, -1, &isint);
            if (lua_type(L, -1) != LUA_TNUMBER || !isint || k < 1 || k > len) {
                luaL_tolstring(L, -1, NULL);
                fl_opts_error(o, "lock", lua_pushfstring(L, "list of vertex indices expected, "
                                                            "found key %s",
                                                         lua_tostring(L, -1)));
            }
        }
        if (len < 0 || (lua_Unsigned)len > SIZE_MAX / sizeof *buf)
            fl_opts_error(o, "lock", "list too long");
        buf = (uint32_t *)lua_newuserdatauv(L, (size_t)len * sizeof *buf, 0);
        for (lua_Integer i = 1; i <= len; i++) {
            if (lua_geti(L, lk, i) != LUA_TNUMBER)
                luaL_argerror(L, o->arg, lua_pushfstring(L, "lock[%I]: number expected, got %s", i,
                                                         luaL_typename(L, -1)));
            double d = lua_tonumber(L, -1);
            lua_pop(L, 1);
            /* As femlod.mesh checks indices: a float such as 2.5 is refused. */
            if (!(d >= 1 && d <= (double)nv && d == floor(d))) {
                if (d == floor(d) && fabs(d) <= 9007199254740992.0)
                    luaL_argerror(L, o->arg,
                                  lua_pushfstring(L, "lock[%I]: index %I out of range (1..%I)", i,
                                                  (lua_Integer)d, (lua_Integer)nv));
                luaL_argerror(L, o->arg,
                              lua_pushfstring(L, "lock[%I]: index %f is not a valid index", i, d));
            }
            buf[n++] = (uint32_t)(d - 1);
        }
    } else if (t == LUA_TFUNCTION) {
        buf = (uint32_t *)lua_newuserdatauv(L, nv * sizeof *buf, 0);
        luaL_checkstack(L, 5, NULL);
        for (size_t v = 0; v < nv; v++) {
            const double *p = femlod_mesh_positions(fl_lmesh_check(L, 1)) + 3 * v;
            lua_pushvalue(L, lk);
            lua_pushnumber(L, p[0]);
            lua_pushnumber(L, p[1]);
            lua_pushnumber(L, p[2]);
            lua_pushinteger(L, (lua_Integer)v + 1);
            /* Unprotected: an error in the function is the recipe's error,
             * raised with its own message (and traceback); nothing C-owned
             * is alive yet. */
            lua_call(L, 4, 1);
            int r = lua_type(L, -1);
            if (r == LUA_TBOOLEAN) {
                if (lua_toboolean(L, -1)) buf[n++] = (uint32_t)v;
            } else if (r != LUA_TNIL) {
                fl_opts_error(o, "lock",
                              lua_pushfstring(L, "function returned %s for vertex %I "
                                                 "(boolean or nil expected)",
                                              luaL_typename(L, -1), (lua_Integer)v + 1));
            }
            lua_pop(L, 1);
        }
    } else {
        fl_opts_error(o, "lock", lua_pushfstring(L, "table or function expected, got %s",
                                                 luaL_typename(L, -1)));
        return;
    }
    so->lock = buf;
    so->lock_count = n;
}

/* }==================================================================== */

/* {====================================================================
 * femlod.simplify
 * ===================================================================== */

enum { PROGRESS_OK, PROGRESS_ERROR, PROGRESS_BAD_RESULT };

typedef struct progress_call {
    lua_State *L;
    int fn;              /* stack index of the function */
    int failed;          /* PROGRESS_*; on PROGRESS_ERROR the error value is on the top */
    const char *got;     /* PROGRESS_BAD_RESULT: type name of the result (static) */
} progress_call;

/* femlod_progress_fn: nothing here may raise. The stack space was reserved
 * before femlod_simplify ran, and every call leaves the stack as it found
 * it, except the failing one, which leaves the error value. */
static int call_progress(void *payload, double done) {
    progress_call *pc = (progress_call *)payload;
    lua_State *L = pc->L;
    if (pc->failed != PROGRESS_OK) return 1;
    lua_pushvalue(L, pc->fn);
    lua_pushnumber(L, done);
    if (lua_pcall(L, 1, 1, 0) != LUA_OK) {
        pc->failed = PROGRESS_ERROR;
        return 1;
    }
    int t = lua_type(L, -1);
    int stop = lua_toboolean(L, -1);
    if (t != LUA_TNIL && t != LUA_TBOOLEAN) {
        pc->failed = PROGRESS_BAD_RESULT;
        pc->got = lua_typename(L, t);
        stop = 1;
    }
    lua_pop(L, 1);
    return stop;
}

static fl_hierarchy *hierarchy_box(lua_State *L) {
    fl_hierarchy *h = (fl_hierarchy *)lua_newuserdatauv(L, sizeof *h, 0);
    memset(h, 0, sizeof *h);
    luaL_setmetatable(L, FL_HIERARCHY_MT);
    return h;
}

static void hierarchy_release(fl_hierarchy *h) {
    femlod_mesh_free(h->mesh);
    femlod_collapse_log_free(h->log);
    memset(h, 0, sizeof *h);
}

/* femlod.simplify(mesh [, opts]) and mesh:simplify([opts]). */
static int lib_simplify(lua_State *L) {
    fl_lmesh_check(L, 1);
    fl_opts o;
    fl_opts_open(&o, L, 2, simplify_keys);
    femlod_simplify_options so = FEMLOD_SIMPLIFY_OPTIONS_INIT;
    if (o.idx) {
        const char *key;
        const char *msg = fl_simplify_read_options(L, o.idx, &so, "false", &key);
        if (msg) {
            if (key) fl_opts_error(&o, key, msg);
            luaL_argerror(L, o.arg, msg);
        }
    }
    progress_call pc = {L, 0, PROGRESS_OK, NULL};
    int t = fl_opts_push(&o, "progress");
    if (t != LUA_TNIL) {
        if (t != LUA_TFUNCTION)
            fl_opts_error(&o, "progress", lua_pushfstring(L, "function expected, got %s",
                                                          luaL_typename(L, -1)));
        pc.fn = lua_gettop(L);
        so.progress = call_progress;
        so.progress_payload = &pc;
    }
    read_lock(L, &o, &so);

    /* The lock function may have closed the mesh: look it up again. */
    femlod_mesh **mbox = (femlod_mesh **)luaL_checkudata(L, 1, FL_MESH_MT);
    femlod_mesh *mesh = fl_lmesh_check(L, 1);
    fl_hierarchy *h = hierarchy_box(L);
    int hidx = lua_gettop(L);
    luaL_checkstack(L, 4, NULL); /* for call_progress, which must not raise */
    femlod_error err;
    *mbox = NULL; /* busy: see the top of the file */
    femlod_status st = femlod_simplify(&h->mesh, &h->log, mesh, &so, &h->result, &err);
    *mbox = mesh;
    if (pc.failed != PROGRESS_OK) {
        hierarchy_release(h);
        if (pc.failed == PROGRESS_ERROR) return lua_error(L);
        return fl_opts_error(&o, "progress",
                             lua_pushfstring(L, "function returned %s (boolean or nil expected)",
                                             pc.got));
    }
    if (st != FEMLOD_OK) return fl_lua_raise(L, &err);
    lua_settop(L, hidx);
    return 1;
}

/* }==================================================================== */

/* {====================================================================
 * Methods
 * ===================================================================== */

fl_hierarchy *fl_lhierarchy_check(lua_State *L, int arg) {
    fl_hierarchy *h = (fl_hierarchy *)luaL_checkudata(L, arg, FL_HIERARCHY_MT);
    if (!h->mesh) luaL_error(L, "attempt to use a closed femlod.Hierarchy");
    return h;
}

/* h:mesh(): a new Mesh, a copy of the simplified mesh. */
static int hierarchy_mesh(lua_State *L) {
    const fl_hierarchy *h = fl_lhierarchy_check(L, 1);
    femlod_mesh **slot = fl_lmesh_box(L);
    femlod_error err;
    if (femlod_mesh_copy(slot, h->mesh, &err) != FEMLOD_OK) return fl_lua_raise(L, &err);
    return 1;
}

static void set_integer(lua_State *L, const char *key, size_t v) {
    lua_pushinteger(L, (lua_Integer)v);
    lua_setfield(L, -2, key);
}

/* A threshold in force, or false when it is off (negative). */
static void set_threshold(lua_State *L, const char *key, double v) {
    if (v < 0.0) lua_pushboolean(L, 0);
    else lua_pushnumber(L, v);
    lua_setfield(L, -2, key);
}

static int hierarchy_stats(lua_State *L) {
    const femlod_simplify_result *r = &fl_lhierarchy_check(L, 1)->result;
    lua_createtable(L, 0, 12);
    set_integer(L, "triangles", r->triangles);
    set_integer(L, "vertices", r->vertices);
    lua_pushstring(L, femlod_stop_reason_name(r->stop_reason));
    lua_setfield(L, -2, "stop_reason");
    set_integer(L, "collapses", r->collapses);
    set_integer(L, "prephase_collapses", r->prephase_collapses);
    lua_createtable(L, 0, FEMLOD_REJECT_COUNT);
    for (int k = 0; k < FEMLOD_REJECT_COUNT; k++)
        set_integer(L, femlod_reject_name((femlod_reject)k), r->rejected[k]);
    lua_setfield(L, -2, "rejected");
    set_integer(L, "violating_input", r->violating_input);
    set_integer(L, "dropped_degenerate", r->dropped_degenerate);
    lua_pushnumber(L, r->seconds);
    lua_setfield(L, -2, "seconds");

    lua_createtable(L, 0, 9);
    if (r->target) set_integer(L, "target", r->target);
    else set_threshold(L, "target", -1.0);
    set_threshold(L, "tolerance", r->tolerance);
    set_threshold(L, "max_deviation", r->max_deviation);
    set_threshold(L, "min_stretch", r->min_stretch);
    set_threshold(L, "max_size", r->max_size);
    if (r->max_valence >= 0) set_integer(L, "max_valence", (size_t)r->max_valence);
    else set_threshold(L, "max_valence", -1.0);
    set_threshold(L, "feature_angle", r->feature_angle);
    set_threshold(L, "feature_weight", r->feature_weight);
    set_threshold(L, "max_normal_change", r->max_normal_change);
    lua_setfield(L, -2, "thresholds");
    return 1;
}

static int hierarchy_collapses(lua_State *L) {
    const fl_hierarchy *h = fl_lhierarchy_check(L, 1);
    lua_pushinteger(L, (lua_Integer)femlod_collapse_log_count(h->log));
    return 1;
}

static int hierarchy_input_vertices(lua_State *L) {
    const fl_hierarchy *h = fl_lhierarchy_check(L, 1);
    lua_pushinteger(L, (lua_Integer)femlod_collapse_log_input_vertices(h->log));
    return 1;
}

static int hierarchy_log_bytes(lua_State *L) {
    const fl_hierarchy *h = fl_lhierarchy_check(L, 1);
    lua_pushinteger(L, (lua_Integer)femlod_collapse_log_bytes(h->log));
    return 1;
}

/* __gc, __close and close(): one release that tolerates a closed box. */
static int hierarchy_gc(lua_State *L) {
    hierarchy_release((fl_hierarchy *)luaL_checkudata(L, 1, FL_HIERARCHY_MT));
    return 0;
}

static int hierarchy_tostring(lua_State *L) {
    const fl_hierarchy *h = (const fl_hierarchy *)luaL_checkudata(L, 1, FL_HIERARCHY_MT);
    if (!h->mesh)
        lua_pushliteral(L, "femlod.Hierarchy (closed)");
    else
        lua_pushfstring(L, "femlod.Hierarchy (%I collapses, %I triangles)",
                        (lua_Integer)femlod_collapse_log_count(h->log),
                        (lua_Integer)femlod_mesh_triangle_count(h->mesh));
    return 1;
}

/* }==================================================================== */

static const luaL_Reg hierarchy_methods[] = {
    {"mesh", hierarchy_mesh},
    {"stats", hierarchy_stats},
    {"collapses", hierarchy_collapses},
    {"input_vertices", hierarchy_input_vertices},
    {"log_bytes", hierarchy_log_bytes},
    {"close", hierarchy_gc},
    {NULL, NULL},
};

static const luaL_Reg hierarchy_meta[] = {
    {"__index", NULL}, /* placeholder, set to the method table below */
    {"__gc", hierarchy_gc},
    {"__close", hierarchy_gc},
    {"__tostring", hierarchy_tostring},
    {NULL, NULL},
};

void fl_lhierarchy_open(lua_State *L) {
    if (luaL_newmetatable(L, FL_HIERARCHY_MT)) {
        luaL_setfuncs(L, hierarchy_meta, 0);
        luaL_newlibtable(L, hierarchy_methods);
        luaL_setfuncs(L, hierarchy_methods, 0);
        lua_setfield(L, -2, "__index");
    }
    lua_pop(L, 1);
    /* mesh:simplify(opts) is femlod.simplify(mesh, opts). */
    luaL_getmetatable(L, FL_MESH_MT);
    lua_getfield(L, -1, "__index");
    lua_pushcfunction(L, lib_simplify);
    lua_setfield(L, -2, "simplify");
    lua_pop(L, 2);
    lua_pushcfunction(L, lib_simplify);
    lua_setfield(L, -2, "simplify");
}
