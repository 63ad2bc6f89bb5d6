/*
 * lhierarchy.c - femlod.simplify, femlod.load_hierarchy and the
 * femlod.Hierarchy userdata.
 *
 * A Hierarchy is a box (fl_hierarchy, lfemlod.h) holding the vertex
 * hierarchy of one simplification, with its front, and the simplification's
 * result record. femlod.simplify builds the hierarchy from the input mesh
 * and the collapse log as soon as femlod_simplify returns, then frees the
 * simplified mesh and the log: the hierarchy holds all they said, and
 * h:mesh() extracts the front. With hierarchy = false the box keeps the
 * simplified mesh (flat) and no hierarchy: femlod_simplify runs without a
 * log (no log recorded, no hierarchy built, and the end-of-run polish of
 * the improve stage may run); h:mesh() copies it, h:stats() and
 * h:log_bytes() answer, every LOD method raises. Like a Mesh the box is pushed empty, with its
 * metatable and __gc in place, before it is filled, and it frees its C
 * memory in one release shared by __gc, __close and close(). Node ids are
 * 1-based here and in every message (C id + 1).
 *
 * No Lua error may cross the core (a longjmp through it would leak its work
 * memory and skip its clean-up), so the recipe's Lua runs outside it or
 * under lua_pcall:
 *   - lock: the indices are read, or the lock function is called for every
 *     vertex, before femlod_simplify runs; the result is an index list in a
 *     Lua-owned buffer, so a raise there (a bad index, an error inside the
 *     function) leaks nothing;
 *   - progress (fl_opts_progress, lopts.c): called from femlod_simplify,
 *     femlod_hierarchy_create and the LOD operations through lua_pcall; an
 *     error cancels the run, and is raised again once the core returned and
 *     its results were freed;
 *   - the size functions of refine and coarsen: called from the core
 *     through lua_pcall (a trampoline builds the node table under it); a
 *     failure returns NaN, which stops the operation with a valid front,
 *     and is raised once the core returned.
 * While femlod_simplify runs and its hierarchy is built, the input Mesh's
 * box is empty, so a progress function that closes or uses that mesh finds
 * it closed instead of freeing it under the simplifier. While a size or
 * progress function of a LOD operation runs, its Hierarchy is busy: using or
 * closing it raises (inside the function).
 */
#include "lfemlod.h"
#include "lopts.h"

#include <limits.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* {====================================================================
 * Options
 * ===================================================================== */

static const char *const simplify_keys[] = {
    "target",         "ratio",          "tolerance",         "max_deviation",
    "min_stretch",    "max_size",       "max_valence",       "feature_angle",
    "feature_weight", "max_normal_change", "keep_boundary",  "area_weighted",
    "error_order",    "fast_above",        "threads",        "lock",
    "progress",       "hierarchy_floor",   "improve",        "hierarchy",
    NULL};

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

    *key = "fast_above";
    t = lua_getfield(L, idx, "fast_above");
    if (t == LUA_TBOOLEAN) {
        o->fast_above = lua_toboolean(L, -1) ? 2.0 : FEMLOD_SIMPLIFY_OFF;
    } else if (t != LUA_TNIL) {
        double v = lua_tonumber(L, -1);
        if (t != LUA_TNUMBER || !(v >= 1.0 && isfinite(v))) return bad_value(L, "number >= 1 or boolean", NULL);
        o->fast_above = v;
    }
    lua_pop(L, 1);

    *key = "threads";
    t = lua_getfield(L, idx, "threads");
    if (t != LUA_TNIL) {
        int isint = 0;
        lua_Integer n = lua_tointegerx(L, -1, &isint);
        if (t != LUA_TNUMBER || !isint || n < 0 || n > 1024) return bad_value(L, "integer >= 0", NULL);
        o->threads = (int)n;
    }
    lua_pop(L, 1);

    /* true: as coarse as the thresholds allow; false: stop at the target */
    *key = "hierarchy_floor";
    t = lua_getfield(L, idx, "hierarchy_floor");
    if (t == LUA_TBOOLEAN) {
        o->hierarchy_floor = lua_toboolean(L, -1) ? 1 : 0;
    } else if (t != LUA_TNIL) {
        int isint = 0;
        lua_Integer n = lua_tointegerx(L, -1, &isint);
        if (t != LUA_TNUMBER || !isint || n < 1) return bad_value(L, "integer >= 1 or boolean", NULL);
        o->hierarchy_floor = (size_t)n;
    }
    lua_pop(L, 1);

    static const char *const flags[] = {"keep_boundary", "area_weighted", "error_order", "improve"};
    for (int k = 0; k < 4; k++) {
        *key = flags[k];
        t = lua_getfield(L, idx, flags[k]);
        if (t != LUA_TNIL && t != LUA_TBOOLEAN) return bad_value(L, "boolean", NULL);
        int on = lua_toboolean(L, -1);
        if (k == 0) o->keep_boundary = on;
        else if (k == 1) o->area_weighted = on;
        else if (k == 2) o->error_order = t == LUA_TNIL ? 0 : (on ? 1 : -1); /* nil: the default (on) */
        else o->no_improve = t == LUA_TBOOLEAN && !on; /* nil: the default, on */
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

static fl_hierarchy *hierarchy_box(lua_State *L) {
    fl_hierarchy *h = (fl_hierarchy *)lua_newuserdatauv(L, sizeof *h, 0);
    memset(h, 0, sizeof *h);
    luaL_setmetatable(L, FL_HIERARCHY_MT);
    return h;
}

/* Frees the hierarchy (or the flat mesh) and refunds its charge
 * (docs/design.md "Caps"). */
static void hierarchy_release(lua_State *L, fl_hierarchy *h) {
    double bytes = h->charged;
    femlod_hierarchy_free(h->hier);
    femlod_mesh_free(h->flat);
    memset(h, 0, sizeof *h);
    fl_lua_guard *g = bytes > 0 ? fl_lua_guard_get(L) : NULL;
    if (g) g->charge(g, -bytes);
}

/* Charges a new hierarchy's memory (or the flat mesh's) to the cap
 * (raising past it; the box's release refunds the charge either way). */
static void hierarchy_charge(lua_State *L, fl_hierarchy *h) {
    h->charged = h->hier ? (double)femlod_hierarchy_bytes(h->hier)
                         : fl_lmesh_bytes((double)femlod_mesh_vertex_count(h->flat),
                                          (double)femlod_mesh_triangle_count(h->flat));
    fl_lua_charge(L, h->charged);
}

/* What a simplification of nt triangles holds at its peak besides its input,
 * for the memory cap to refuse it before it starts: measured 301 bytes per
 * input triangle of work memory (tests/bench, docs/simplify.md) and about 200
 * for the hierarchy built from its log; rounded up. */
#define SIMPLIFY_BYTES_PER_TRIANGLE 600.0
/* The same with hierarchy = false: the work memory alone, rounded up. */
#define SIMPLIFY_FLAT_BYTES_PER_TRIANGLE 400.0

/* Reads the option hierarchy (true by default); false refuses a
 * hierarchy_floor in force, which only a hierarchy uses. */
static int read_hierarchy_option(lua_State *L, fl_opts *o) {
    if (!o->idx) return 1;
    int t = lua_getfield(L, o->idx, "hierarchy");
    int keep = t == LUA_TNIL || lua_toboolean(L, -1);
    if (t != LUA_TNIL && t != LUA_TBOOLEAN)
        fl_opts_error(o, "hierarchy", lua_pushfstring(L, "boolean expected, got %s", luaL_typename(L, -1)));
    lua_pop(L, 1);
    if (!keep) {
        t = lua_getfield(L, o->idx, "hierarchy_floor");
        if (t != LUA_TNIL && !(t == LUA_TBOOLEAN && !lua_toboolean(L, -1)))
            fl_opts_error(o, "hierarchy_floor", "needs the hierarchy (hierarchy = false keeps none)");
        lua_pop(L, 1);
    }
    return keep;
}

/* femlod.simplify(mesh [, opts]) and mesh:simplify([opts]). */
static int lib_simplify(lua_State *L) {
    fl_lmesh_check(L, 1);
    fl_opts o;
    fl_opts_open(&o, L, 2, simplify_keys);
    femlod_simplify_options so = FEMLOD_SIMPLIFY_OPTIONS_INIT;
    so.hierarchy_floor = 1; /* the hierarchy reaches the coarsest mesh the thresholds allow */
    int keep = read_hierarchy_option(L, &o);
    if (o.idx) {
        const char *key;
        const char *msg = fl_simplify_read_options(L, o.idx, &so, "false", &key);
        if (msg) {
            if (key) fl_opts_error(&o, key, msg);
            luaL_argerror(L, o.arg, msg);
        }
    }
    fl_progress_call pc;
    so.progress = fl_opts_progress(&o, &pc);
    so.progress_payload = &pc;
    /* Building the hierarchy is the last 5% of done: about its share of
     * the time (cover.obj at ratio 0.1). */
    pc.scale = keep ? 0.95 : 1.0;
    read_lock(L, &o, &so);

    /* The lock function may have closed the mesh: look it up again. */
    femlod_mesh **mbox = (femlod_mesh **)luaL_checkudata(L, 1, FL_MESH_MT);
    femlod_mesh *mesh = fl_lmesh_check(L, 1);
    fl_hierarchy *h = hierarchy_box(L);
    int hidx = lua_gettop(L);
    femlod_error err;
    femlod_mesh *simplified = NULL;
    femlod_collapse_log *log = NULL;
    luaL_checkstack(L, 4, NULL); /* for fl_progress_call_fn, which must not raise */
    /* under --max-memory: refused before the work memory is taken */
    fl_lua_reserve(L, (keep ? SIMPLIFY_BYTES_PER_TRIANGLE : SIMPLIFY_FLAT_BYTES_PER_TRIANGLE) *
                          (double)femlod_mesh_triangle_count(mesh));
    double t0 = fl_lua_clock();
    *mbox = NULL; /* busy: see the top of the file */
    femlod_status st = femlod_simplify(&simplified, keep ? &log : NULL, mesh, &so, &h->result, &err);
    double t1 = fl_lua_clock();
    if (!keep && st == FEMLOD_OK && pc.failed == FL_PROGRESS_OK) {
        h->flat = simplified; /* the box owns it now */
        simplified = NULL;
        h->has_result = 1;
        /* done ends at 1, as the hierarchy's build makes it end with one
         * (the run is over: a true returned here changes nothing) */
        if (so.progress && !pc.stopped) so.progress(so.progress_payload, 1.0);
    }
    /* The hierarchy holds everything the simplified mesh and the log said:
     * both go as soon as it is built. Its building cannot be stopped by a
     * true from the function (the simplification, stopped short or not, is
     * done), only by an error or the time cap; a function that returned true
 * is not called again. The input stays busy until the hierarchy is built. */
    if (keep && st == FEMLOD_OK && pc.failed == FL_PROGRESS_OK) {
        femlod_progress_options po = {so.progress, so.progress_payload};
        pc.offset = pc.scale;
        pc.scale = 1.0 - pc.scale;
        pc.keep_going = 1;
        h->log_bytes = femlod_collapse_log_bytes(log);
        femlod_mesh_free(simplified); /* not needed for the build: gone before its peak */
        simplified = NULL;
        st = femlod_hierarchy_create_from_log(&h->hier, mesh, &log, &po, &err);
        h->has_result = 1;
    }
    *mbox = mesh;
    femlod_mesh_free(simplified);
    femlod_collapse_log_free(log);
    if (pc.failed != FL_PROGRESS_OK) {
        hierarchy_release(L, h);
        fl_opts_progress_check(&o, &pc, st);
    }
    if (st != FEMLOD_OK) {
        hierarchy_release(L, h);
        return fl_lua_raise(L, &err);
    }
    hierarchy_charge(L, h);
    if (fl_lua_verbose(L)) {
        const femlod_simplify_result *r = &h->result;
        fl_lua_log(L, "simplify: %zu -> %zu triangles, %zu collapses, stopped: %s (%.3f s)",
                   femlod_mesh_triangle_count(mesh), r->triangles, r->collapses,
                   femlod_stop_reason_name(r->stop_reason), t1 - t0);
        if (keep)
            fl_lua_log(L, "build hierarchy: %zu nodes, %zu bytes (%.3f s)",
                       femlod_hierarchy_node_count(h->hier), femlod_hierarchy_bytes(h->hier),
                       fl_lua_clock() - t1);
    }
    lua_settop(L, hidx);
    return 1;
}

/* Refuses extra arguments: a recipe's options table there would be ignored. */
static void no_more_arguments(lua_State *L, int arg) {
    luaL_argcheck(L, lua_isnone(L, arg), arg, "no more arguments expected");
}

/* A result as femlod_hierarchy_load gives it for a file saved without one:
 * all zero. A real one never has min_stretch and max_valence both 0 (each
 * is in force, > 0, or off, < 0). */
static int result_is_none(const femlod_simplify_result *r) {
    return r->min_stretch == 0.0 && r->max_valence == 0 && r->triangles == 0 && r->collapses == 0;
}

/* femlod.load_hierarchy(path): a Hierarchy from a .flh file, with its front. */
static int lib_load_hierarchy(lua_State *L) {
    const char *path = fl_lua_check_path(L, 1, 0);
    no_more_arguments(L, 2);
    fl_hierarchy *h = hierarchy_box(L);
    femlod_error err;
    double t0 = fl_lua_clock();
    if (femlod_hierarchy_load(&h->hier, path, &h->result, &err) != FEMLOD_OK) {
        hierarchy_release(L, h);
        return fl_lua_raise(L, &err);
    }
    hierarchy_charge(L, h);
    if (fl_lua_verbose(L))
        fl_lua_log(L, "load %s: %zu nodes, front %zu triangles (%.3f s)", path,
                   femlod_hierarchy_node_count(h->hier), femlod_hierarchy_front_triangles(h->hier),
                   fl_lua_clock() - t0);
    h->has_result = !result_is_none(&h->result);
    fl_lua_io_hook(L, "read", 1, -1);
    return 1;
}

/* }==================================================================== */

/* {====================================================================
 * Methods. Node ids are 1-based here (Lua id = C id + 1); every message
 * names them so.
 * ===================================================================== */

/* A hierarchy box that is open, with a hierarchy or (hierarchy = false) the
 * flat mesh: what h:mesh(), h:stats() and h:log_bytes() accept. */
static fl_hierarchy *check_open(lua_State *L, int arg) {
    fl_hierarchy *h = (fl_hierarchy *)luaL_checkudata(L, arg, FL_HIERARCHY_MT);
    if (h->busy) luaL_error(L, "attempt to use a femlod.Hierarchy inside its own size or progress function");
    if (!h->hier && !h->flat) luaL_error(L, "attempt to use a closed femlod.Hierarchy");
    return h;
}

fl_hierarchy *fl_lhierarchy_check(lua_State *L, int arg) {
    fl_hierarchy *h = check_open(L, arg);
    if (!h->hier)
        luaL_error(L, "this femlod.Hierarchy has only its mesh and stats: "
                      "simplify with hierarchy = false keeps no hierarchy");
    return h;
}

static void set_integer(lua_State *L, const char *key, size_t v) {
    lua_pushinteger(L, (lua_Integer)v);
    lua_setfield(L, -2, key);
}

static lua_Integer lid(uint32_t id) { return (lua_Integer)id + 1; }

static const char *state_name(femlod_node_state s) {
    return s == FEMLOD_NODE_FRONT ? "front" : s == FEMLOD_NODE_ABOVE ? "above" : "below";
}

/* Pushes the node table {id, parent, children, e_size, depth, state} and,
 * when with_position, position = {x, y, z}. */
static void push_node(lua_State *L, const femlod_node_info *n, int with_position) {
    lua_createtable(L, 0, 7);
    lua_pushinteger(L, lid(n->id));
    lua_setfield(L, -2, "id");
    if (n->parent != UINT32_MAX) {
        lua_pushinteger(L, lid(n->parent));
        lua_setfield(L, -2, "parent");
    }
    if (n->child[0] != UINT32_MAX) {
        lua_createtable(L, 2, 0);
        lua_pushinteger(L, lid(n->child[0]));
        lua_rawseti(L, -2, 1);
        lua_pushinteger(L, lid(n->child[1]));
        lua_rawseti(L, -2, 2);
        lua_setfield(L, -2, "children");
    }
    lua_pushnumber(L, n->e_size);
    lua_setfield(L, -2, "e_size");
    lua_pushinteger(L, (lua_Integer)n->depth);
    lua_setfield(L, -2, "depth");
    lua_pushstring(L, state_name(n->state));
    lua_setfield(L, -2, "state");
    if (with_position) {
        lua_createtable(L, 3, 0);
        for (int k = 0; k < 3; k++) {
            lua_pushnumber(L, n->position[k]);
            lua_rawseti(L, -2, k + 1);
        }
        lua_setfield(L, -2, "position");
    }
}

/* Extracts the front into a new Mesh box pushed on the stack (the mesh is
 * Lua-owned before anything can raise). When ids is not NULL, *ids gets the
 * malloc'd node ids, which the caller frees before anything raises. */
static femlod_mesh *push_front_mesh(lua_State *L, fl_hierarchy *h, uint32_t **ids) {
    femlod_mesh **slot = fl_lmesh_box(L);
    fl_lua_guard *g = fl_lua_guard_get(L);
    femlod_error err;
    if (femlod_hierarchy_extract(h->hier, slot, ids, &err) != FEMLOD_OK) fl_lua_raise(L, &err);
    /* Charged, and refunded by its release; over the cap it raises unless
     * the caller holds ids (it frees them, then releases the mesh). */
    if (g && g->charge(g, fl_lmesh_bytes((double)femlod_mesh_vertex_count(*slot),
                                         (double)femlod_mesh_triangle_count(*slot))) && !ids)
        fl_lua_raise_limit(L, 1, g->memory_message);
    return *slot;
}

/* h:mesh(): the current front as a new Mesh; with hierarchy = false a copy
 * of the simplified mesh. */
static int hierarchy_mesh(lua_State *L) {
    fl_hierarchy *h = check_open(L, 1);
    no_more_arguments(L, 2);
    if (h->hier) {
        push_front_mesh(L, h, NULL);
        return 1;
    }
    femlod_mesh **slot = fl_lmesh_box(L);
    femlod_error err;
    if (femlod_mesh_copy(slot, h->flat, &err) != FEMLOD_OK) return fl_lua_raise(L, &err);
    fl_lmesh_charge(L, slot);
    return 1;
}

/* h:front(): the node id of each vertex of h:mesh(), in its order. */
static int hierarchy_front(lua_State *L) {
    fl_hierarchy *h = fl_lhierarchy_check(L, 1);
    no_more_arguments(L, 2);
    /* The table is sized before the extraction (the front has at least as
     * many nodes as the mesh has vertices), so that filling its array part
     * allocates nothing and cannot raise while ids is held. */
    size_t bound = femlod_hierarchy_front_nodes(h->hier);
    if (bound > (size_t)INT_MAX) return luaL_error(L, "front too large for a Lua table");
    lua_createtable(L, (int)bound, 0);
    uint32_t *ids = NULL;
    femlod_mesh *m = push_front_mesh(L, h, &ids);
    size_t nv = femlod_mesh_vertex_count(m);
    for (size_t i = 0; i < nv; i++) {
        lua_pushinteger(L, lid(ids[i]));
        lua_rawseti(L, -3, (lua_Integer)i + 1);
    }
    free(ids);
    femlod_mesh **slot = (femlod_mesh **)lua_touserdata(L, -1);
    fl_lmesh_release(L, slot); /* now, rather than at some later collection */
    lua_pop(L, 1);
    return 1;
}

/* Vertices of the front mesh (front nodes used by a triangle): counted on
 * an extraction, linear in the front. */
static size_t front_vertices(lua_State *L, fl_hierarchy *h) {
    femlod_mesh *m = push_front_mesh(L, h, NULL);
    size_t nv = femlod_mesh_vertex_count(m);
    femlod_mesh **slot = (femlod_mesh **)lua_touserdata(L, -1);
    fl_lmesh_release(L, slot);
    lua_pop(L, 1);
    return nv;
}

static int hierarchy_counts(lua_State *L) {
    fl_hierarchy *h = fl_lhierarchy_check(L, 1);
    const femlod_hierarchy *x = h->hier;
    size_t vertices = front_vertices(L, h);
    lua_createtable(L, 0, 7);
    set_integer(L, "nodes", femlod_hierarchy_node_count(x));
    set_integer(L, "input_vertices", femlod_hierarchy_input_vertices(x));
    set_integer(L, "collapses",
                femlod_hierarchy_node_count(x) - femlod_hierarchy_input_vertices(x));
    set_integer(L, "front_nodes", femlod_hierarchy_front_nodes(x));
    set_integer(L, "triangles", femlod_hierarchy_front_triangles(x));
    set_integer(L, "vertices", vertices);
    set_integer(L, "bytes", femlod_hierarchy_bytes(x));
    return 1;
}

/* The node id (1-based) on the top of the stack, of type t, checked against
 * the hierarchy; returns the C id. what (NULL or "ids[3]") prefixes the
 * messages. */
static uint32_t check_node_id(lua_State *L, int arg, const femlod_hierarchy *x, int t,
                              const char *what) {
    int isint = 0;
    lua_Integer id = lua_tointegerx(L, -1, &isint);
    const char *pre = what ? what : "", *sep = what ? ": " : "";
    if (t != LUA_TNUMBER || !isint) {
        const char *got = t == LUA_TNUMBER ? lua_pushfstring(L, "%f", (double)lua_tonumber(L, -1))
                                           : lua_typename(L, t);
        luaL_argerror(L, arg, lua_pushfstring(L, "%s%snode id expected, got %s", pre, sep, got));
    }
    lua_Integer n = (lua_Integer)femlod_hierarchy_node_count(x);
    if (id < 1 || id > n)
        luaL_argerror(L, arg,
                      lua_pushfstring(L, "%s%snode %I does not exist (1..%I)", pre, sep, id, n));
    return (uint32_t)(id - 1);
}

/* The front node holding node x (x below the front). */
static uint32_t front_above(const femlod_hierarchy *x, uint32_t id) {
    femlod_node_info n;
    while (femlod_hierarchy_node(x, id, &n) && n.state != FEMLOD_NODE_FRONT) id = n.parent;
    return id;
}

/* Checks that node id (C) can be split (split) or collapsed (!split) now;
 * raises an argument error naming it otherwise. */
static void check_operable(lua_State *L, int arg, const femlod_hierarchy *x, uint32_t id,
                           int split, const char *what) {
    femlod_node_info n;
    femlod_hierarchy_node(x, id, &n);
    const char *why = NULL;
    if (n.child[0] == UINT32_MAX) {
        why = split ? "is an input vertex: it has no split"
                    : "is an input vertex: it has no children to collapse";
    } else if (split && n.state == FEMLOD_NODE_ABOVE) {
        why = "is above the front (already split)";
    } else if (split && n.state == FEMLOD_NODE_BELOW) {
        why = lua_pushfstring(L, "is below the front (inside front node %I)",
                              lid(front_above(x, id)));
    } else if (!split && n.state == FEMLOD_NODE_FRONT) {
        why = "is already collapsed (it is on the front)";
    } else if (!split && n.state == FEMLOD_NODE_BELOW) {
        why = lua_pushfstring(L, "is already collapsed (inside front node %I)",
                              lid(front_above(x, id)));
    }
    if (why)
        luaL_argerror(L, arg, lua_pushfstring(L, "%s%snode %I %s", what ? what : "",
                                              what ? ": " : "", lid(id), why));
}

/* h:split(ids) and h:collapse(ids): every id is checked before anything is
 * done, so an error changes nothing; then each is done in order, an id that
 * an earlier one already did (as a dependency) being skipped. */
static int split_or_collapse(lua_State *L, int split) {
    fl_hierarchy *h = fl_lhierarchy_check(L, 1);
    no_more_arguments(L, 3);
    femlod_hierarchy *x = h->hier;
    uint32_t *ids;
    size_t n;
    int t = lua_type(L, 2);
    if (t == LUA_TTABLE) {
        lua_Integer len = luaL_len(L, 2);
        if (len < 0 || (lua_Unsigned)len > SIZE_MAX / sizeof *ids)
            luaL_argerror(L, 2, "list too long");
        n = (size_t)len;
        /* Lua-owned: a raise below leaks nothing. */
        ids = (uint32_t *)lua_newuserdatauv(L, n * sizeof *ids, 0);
        for (size_t i = 0; i < n; i++) {
            int et = lua_geti(L, 2, (lua_Integer)i + 1);
            const char *what = lua_pushfstring(L, "ids[%I]", (lua_Integer)i + 1);
            lua_insert(L, -2);
            ids[i] = check_node_id(L, 2, x, et, what);
            check_operable(L, 2, x, ids[i], split, what);
            lua_pop(L, 2);
        }
    } else if (t == LUA_TNUMBER) {
        n = 1;
        ids = (uint32_t *)lua_newuserdatauv(L, sizeof *ids, 0);
        lua_pushvalue(L, 2);
        ids[0] = check_node_id(L, 2, x, t, NULL);
        check_operable(L, 2, x, ids[0], split, NULL);
        lua_pop(L, 1);
    } else {
        return luaL_typeerror(L, 2, "node id or list of node ids");
    }
    size_t total = 0;
    for (size_t i = 0; i < n; i++) {
        femlod_node_info info;
        femlod_hierarchy_node(x, ids[i], &info);
        if (info.state != (split ? FEMLOD_NODE_FRONT : FEMLOD_NODE_ABOVE)) continue;
        size_t ops = 0;
        femlod_error err;
        femlod_status st = split ? femlod_hierarchy_split(x, ids[i], &ops, &err)
                                 : femlod_hierarchy_collapse(x, ids[i], &ops, &err);
        if (st != FEMLOD_OK) return fl_lua_raise(L, &err);
        total += ops;
    }
    lua_pushinteger(L, (lua_Integer)total);
    return 1;
}

static int hierarchy_split(lua_State *L) { return split_or_collapse(L, 1); }
static int hierarchy_collapse(lua_State *L) { return split_or_collapse(L, 0); }

/* {====== refine and coarsen with a size function
 *
 * The function runs under lua_pcall from inside the core's operation: a
 * trampoline (number_call_lua) builds the node table and calls it, so that
 * nothing, not even a memory error in making the table, can raise through
 * the core. A failure makes call_size return NaN, which stops the operation
 * with FEMLOD_ECANCELLED and a valid front; the failure is raised once the
 * core returned. While it runs, the box is busy: the function cannot use or
 * close the hierarchy it is refining. */

enum { SIZE_OK, SIZE_ERROR, SIZE_BAD_RESULT };

/* A Lua function that the core calls for a number: refine's size function,
 * refine_curvature's map. push_args pushes the arguments of the current
 * call and returns their count. */
typedef struct number_call number_call;
struct number_call {
    lua_State *L;
    int fn;          /* stack index of the function */
    int failed;      /* SIZE_*; on SIZE_ERROR the error value is on the top */
    const char *got; /* SIZE_BAD_RESULT: what came back (static string) */
    double value;    /* the result of the current call */
    int (*push_args)(lua_State *L, const number_call *c);
};

/* Arguments: the function, the number_call. Raises freely: it runs under pcall. */
static int number_call_lua(lua_State *L) {
    number_call *c = (number_call *)lua_touserdata(L, 2);
    lua_pushvalue(L, 1);
    lua_call(L, c->push_args(L, c), 1);
    if (lua_type(L, -1) != LUA_TNUMBER) {
        c->failed = SIZE_BAD_RESULT;
        c->got = lua_typename(L, lua_type(L, -1));
    } else {
        c->value = (double)lua_tonumber(L, -1);
        if (isnan(c->value)) {
            c->failed = SIZE_BAD_RESULT;
            c->got = "nan";
        }
    }
    return 0;
}

/* The function's result for the current call, NaN once a call failed.
 * Nothing here may raise: the stack space was reserved before the core
 * ran; every call leaves the stack as it found it, but the failing one,
 * which may leave the error value. */
static double number_call_run(number_call *c) {
    lua_State *L = c->L;
    lua_pushcfunction(L, number_call_lua); /* a light C function: allocates nothing */
    lua_pushvalue(L, c->fn);
    lua_pushlightuserdata(L, c);
    if (lua_pcall(L, 2, 0, 0) != LUA_OK) {
        c->failed = SIZE_ERROR;
        return NAN;
    }
    return c->failed == SIZE_OK ? c->value : NAN;
}

typedef struct size_call {
    number_call c;         /* first: the number_call is the size_call */
    femlod_node_info info; /* the node of the current call */
} size_call;

/* x, y, z and the node table. */
static int push_size_args(lua_State *L, const number_call *c) {
    const femlod_node_info *n = &((const size_call *)c)->info;
    lua_pushnumber(L, n->position[0]);
    lua_pushnumber(L, n->position[1]);
    lua_pushnumber(L, n->position[2]);
    push_node(L, n, 0);
    return 4;
}

/* femlod_size_fn: nothing here may raise (number_call_run). */
static double call_size(void *payload, const femlod_node_info *node) {
    size_call *sc = (size_call *)payload;
    if (sc->c.failed != SIZE_OK) return NAN;
    sc->info = *node;
    return number_call_run(&sc->c);
}

typedef femlod_status (*lod_op)(femlod_hierarchy *, double, femlod_size_fn, void *, size_t *,
                                femlod_error *);

/* h:refine(size | fn) and h:coarsen(size | fn). */
static int refine_or_coarsen(lua_State *L, lod_op op, const char *name) {
    fl_hierarchy *h = fl_lhierarchy_check(L, 1);
    int t = lua_type(L, 2);
    double size = 0.0;
    size_call sc = {{L, 0, SIZE_OK, NULL, 0.0, push_size_args}, {0}};
    if (t == LUA_TNUMBER) {
        size = (double)lua_tonumber(L, 2);
        luaL_argcheck(L, !isnan(size), 2, "size is NaN");
    } else if (t == LUA_TFUNCTION) {
        sc.c.fn = 2;
    } else {
        return luaL_typeerror(L, 2, "number or function");
    }
    no_more_arguments(L, 3);
    luaL_checkstack(L, 4, NULL); /* for call_size, which must not raise */
    size_t ops = 0;
    femlod_error err;
    double t0 = fl_lua_clock();
    h->busy = 1;
    femlod_status st = op(h->hier, size, sc.c.fn ? call_size : NULL, &sc, &ops, &err);
    h->busy = 0;
    if (sc.c.failed == SIZE_ERROR) return lua_error(L);
    if (sc.c.failed == SIZE_BAD_RESULT)
        return luaL_argerror(L, 2, lua_pushfstring(L, "size function returned %s for node %I "
                                                      "(number expected)",
                                                   sc.c.got, lid(sc.info.id)));
    if (st != FEMLOD_OK) return fl_lua_raise(L, &err);
    if (fl_lua_verbose(L))
        fl_lua_log(L, "%s: %zu %s, front %zu triangles (%.3f s)", name, ops,
                   op == femlod_hierarchy_refine ? "splits" : "collapses",
                   femlod_hierarchy_front_triangles(h->hier), fl_lua_clock() - t0);
    lua_pushinteger(L, (lua_Integer)ops);
    return 1;
}

static int hierarchy_refine(lua_State *L) {
    return refine_or_coarsen(L, femlod_hierarchy_refine, "refine");
}
static int hierarchy_coarsen(lua_State *L) {
    return refine_or_coarsen(L, femlod_hierarchy_coarsen, "coarsen");
}

/* h:rescale{ target = N } or h:rescale{ factor = f }: global LOD with the
 * density of the current front kept (paper 5.3.2, femlod_hierarchy_rescale);
 * factor multiplies the front's triangle count. Returns the operations done. */
static int hierarchy_rescale(lua_State *L) {
    static const char *const keys[] = {"factor", "progress", "target", NULL};
    fl_hierarchy *h = fl_lhierarchy_check(L, 1);
    luaL_checktype(L, 2, LUA_TTABLE);
    fl_opts o;
    fl_opts_open(&o, L, 2, keys);
    no_more_arguments(L, 3);
    int has_target = fl_opts_push(&o, "target") != LUA_TNIL;
    int has_factor = fl_opts_push(&o, "factor") != LUA_TNIL;
    lua_pop(L, has_target + has_factor);
    if (has_target == has_factor) return luaL_argerror(L, 2, "give exactly one of target and factor");
    lua_Integer target = 0;
    if (has_target) {
        target = fl_opts_integer(&o, "target", 0);
        if (target < 1 || (lua_Unsigned)target > UINT32_MAX)
            return fl_opts_error(&o, "target", "must be an integer in 1..4294967295");
    } else {
        lua_Number factor = fl_opts_number(&o, "factor", 0.0);
        if (!(factor > 0.0) || !(factor < HUGE_VAL))
            return fl_opts_error(&o, "factor", "must be a positive finite number");
        double t = floor(factor * (double)femlod_hierarchy_front_triangles(h->hier) + 0.5);
        target = t < 1.0 ? 1 : t > 4294967295.0 ? (lua_Integer)4294967295.0 : (lua_Integer)t;
    }
    size_t ops = 0, before = femlod_hierarchy_front_triangles(h->hier);
    femlod_error err;
    fl_progress_call pc;
    femlod_progress_options po = {fl_opts_progress(&o, &pc), &pc};
    double t0 = fl_lua_clock();
    h->busy = 1; /* the progress function may not use or close the hierarchy */
    femlod_status st = femlod_hierarchy_rescale(h->hier, (size_t)target, &po, &ops, &err);
    h->busy = 0;
    fl_opts_progress_check(&o, &pc, st);
    if (st != FEMLOD_OK) return fl_lua_raise(L, &err);
    size_t reached = femlod_hierarchy_front_triangles(h->hier);
    if (fl_lua_verbose(L))
        fl_lua_log(L, "rescale: %zu -> %zu triangles (target %zu), %zu operations (%.3f s)", before,
                   reached, (size_t)target, ops, fl_lua_clock() - t0);
    /* A count more than 0.5% away from the request is said, with why. */
    const char *why = femlod_hierarchy_limit_reason(h->hier);
    double off = fabs((double)reached - (double)target);
    int missed = off > 0.005 * (double)target && off > 2.0;
    if (missed) fl_lua_warn(L, "rescale: asked %zu, reached %zu: %s", (size_t)target, reached, why);
    lua_pushinteger(L, (lua_Integer)ops);
    lua_pushinteger(L, (lua_Integer)reached);
    if (missed) lua_pushstring(L, why); else lua_pushnil(L);
    return 3;
}

/* h:refine_curvature{ fine, coarse, map, radius, percentile }: curvature LOD
 * (paper 5.3.1a, femlod_hierarchy_refine_curvature). The curvature of the
 * input mesh is computed on the first call (or again when radius is given)
 * and kept with the hierarchy. A map function runs like refine's size
 * function: under lua_pcall, its failure raised once the core returned.
 * Returns the splits done. */

typedef struct kappa_call {
    number_call c; /* first: the number_call is the kappa_call */
    double kappa;  /* the argument of the current call */
} kappa_call;

static int push_kappa_args(lua_State *L, const number_call *c) {
    lua_pushnumber(L, ((const kappa_call *)c)->kappa);
    return 1;
}

/* femlod_kappa_map_fn: nothing here may raise (as call_size). */
static double call_kappa_map(void *payload, double kappa) {
    kappa_call *kc = (kappa_call *)payload;
    if (kc->c.failed != SIZE_OK) return NAN;
    kc->kappa = kappa;
    return number_call_run(&kc->c);
}

/* Computes the input mesh's kappa (in a Lua-owned buffer, so that a raise
 * leaks nothing) and stores it on the hierarchy. */
static void set_curvature(lua_State *L, fl_hierarchy *h, double radius, const fl_opts *o,
                          fl_progress_call *pc, femlod_progress_fn progress) {
    femlod_error err;
    femlod_mesh *in = NULL;
    size_t nv = femlod_hierarchy_input_vertices(h->hier);
    double *kappa = (double *)lua_newuserdatauv(L, (nv ? nv : 1) * sizeof(double), 0);
    if (femlod_hierarchy_input_mesh(h->hier, &in, &err) != FEMLOD_OK) fl_lua_raise(L, &err);
    femlod_curvature_options co = FEMLOD_CURVATURE_OPTIONS_INIT;
    co.radius = radius;
    co.progress = progress;
    co.progress_payload = pc;
    double t0 = fl_lua_clock();
    h->busy = 1;
    femlod_status st = femlod_mesh_curvature(in, &co, NULL, NULL, kappa, NULL, NULL, &err);
    h->busy = 0;
    femlod_mesh_free(in);
    fl_opts_progress_check(o, pc, st);
    if (st == FEMLOD_OK) st = femlod_hierarchy_set_curvature(h->hier, kappa, &err);
    if (st != FEMLOD_OK) fl_lua_raise(L, &err);
    h->has_curvature = 1;
    lua_pop(L, 1);
    if (fl_lua_verbose(L))
        fl_lua_log(L, "curvature: %zu vertices (%.3f s)", nv, fl_lua_clock() - t0);
}

static int hierarchy_refine_curvature(lua_State *L) {
    static const char *const keys[] = {"coarse", "fine", "map", "percentile", "progress", "radius",
                                       NULL};
    fl_hierarchy *h = fl_lhierarchy_check(L, 1);
    fl_opts o;
    fl_opts_open(&o, L, 2, keys);
    no_more_arguments(L, 3);
    kappa_call kc = {{L, 0, SIZE_OK, NULL, 0.0, push_kappa_args}, 0.0};
    femlod_curvature_lod_options co = FEMLOD_CURVATURE_LOD_OPTIONS_INIT;
    int mt = fl_opts_push(&o, "map");
    if (mt == LUA_TFUNCTION) {
        kc.c.fn = lua_gettop(L); /* stays on the stack for the calls */
    } else if (mt != LUA_TNIL) {
        if (mt != LUA_TSTRING)
            return fl_opts_error(&o, "map", lua_pushfstring(L, "'linear', 'log' or function "
                                                               "expected, got %s",
                                                            lua_typename(L, mt)));
        const char *name = lua_tostring(L, -1);
        if (strcmp(name, "log") == 0)
            co.map = FEMLOD_KAPPA_LOG;
        else if (strcmp(name, "linear") != 0)
            return fl_opts_error(&o, "map", lua_pushfstring(L, "'linear', 'log' or function "
                                                               "expected, got '%s'",
                                                            name));
        lua_pop(L, 1);
    }
    double fine = NAN, coarse = NAN, percentile = NAN;
    if (fl_opts_push(&o, "fine") != LUA_TNIL) {
        lua_pop(L, 1);
        fine = (double)fl_opts_number(&o, "fine", 0.0);
        if (!(fine >= 0.0) || !(fine < HUGE_VAL))
            return fl_opts_error(&o, "fine", "must be a finite number >= 0");
    }
    if (fl_opts_push(&o, "coarse") != LUA_TNIL) {
        lua_pop(L, 1);
        coarse = (double)fl_opts_number(&o, "coarse", 0.0);
        if (!(coarse >= 0.0) || !(coarse < HUGE_VAL))
            return fl_opts_error(&o, "coarse", "must be a finite number >= 0");
    }
    if (fl_opts_push(&o, "percentile") != LUA_TNIL) {
        lua_pop(L, 1);
        percentile = (double)fl_opts_number(&o, "percentile", 0.95);
        if (!(percentile > 0.0 && percentile <= 1.0))
            return fl_opts_error(&o, "percentile", "must be in (0, 1]");
    }
    if (kc.c.fn && !(isnan(fine) && isnan(coarse) && isnan(percentile)))
        return luaL_argerror(L, 2, "a map function replaces fine, coarse and percentile: "
                                   "give one or the other");
    fl_progress_call pc;
    femlod_progress_fn progress = fl_opts_progress(&o, &pc);
    int has_radius = fl_opts_push(&o, "radius") != LUA_TNIL;
    /* When the curvature is computed here it takes the first 90% of done:
     * about its share of the time (cover.obj, the default radius). */
    if (has_radius || !h->has_curvature) pc.scale = 0.9;
    if (has_radius) {
        lua_pop(L, 1);
        double radius = (double)fl_opts_number(&o, "radius", 0.0);
        if (!(radius >= 0.0) || !(radius < HUGE_VAL))
            return fl_opts_error(&o, "radius", "must be a finite number >= 0");
        set_curvature(L, h, radius, &o, &pc, progress);
    } else if (!h->has_curvature) {
        set_curvature(L, h, 0.0, &o, &pc, progress);
    }
    if (pc.scale < 1.0) {
        pc.offset = pc.scale;
        pc.scale = 1.0 - pc.scale;
    }
    co.progress = progress;
    co.progress_payload = &pc;
    luaL_checkstack(L, 8, NULL); /* for call_kappa_map and the progress, which must not raise */
    size_t ops = 0;
    femlod_error err;
    double t0 = fl_lua_clock();
    h->busy = 1;
    co.fine = fine;
    co.coarse = coarse;
    co.percentile = percentile;
    co.fn = kc.c.fn ? call_kappa_map : NULL;
    co.payload = &kc;
    femlod_status st = femlod_hierarchy_refine_curvature(h->hier, &co, &ops, &err);
    h->busy = 0;
    if (kc.c.failed == SIZE_ERROR) return lua_error(L);
    if (kc.c.failed == SIZE_BAD_RESULT)
        return fl_opts_error(&o, "map", lua_pushfstring(L, "function returned %s for kappa %f "
                                                           "(number expected)",
                                                        kc.c.got, (lua_Number)kc.kappa));
    fl_opts_progress_check(&o, &pc, st);
    if (st != FEMLOD_OK) return fl_lua_raise(L, &err);
    if (fl_lua_verbose(L))
        fl_lua_log(L, "refine_curvature: %zu splits, front %zu triangles (%.3f s)", ops,
                   femlod_hierarchy_front_triangles(h->hier), fl_lua_clock() - t0);
    lua_pushinteger(L, (lua_Integer)ops);
    return 1;
}

/* }====== */

/* h:refine_region{ sphere = {center = {x, y, z}, radius = r} | box = {min =
 * {...}, max = {...}} | vertices = {...} | where = function(x, y, z) ->
 * boolean, size = T, grading = g }: region LOD (paper 5.3.1b,
 * femlod_hierarchy_refine_region). Exactly one region key. The where
 * function is called for every node's position before the core runs, so
 * its errors are the recipe's own (nothing C-owned is alive yet). Returns
 * the splits done and the number of nodes found inside. */

/* t[key] as a list of 3 finite numbers, into v. */
static void region_point(lua_State *L, const fl_opts *o, const char *shape, int t,
                         const char *key, double v[3]) {
    int ty = lua_getfield(L, t, key);
    if (ty != LUA_TTABLE || luaL_len(L, -1) != 3)
        fl_opts_error(o, shape, lua_pushfstring(L, "%s: {x, y, z} expected, got %s", key,
                                                ty == LUA_TTABLE ? "a table of another length"
                                                                 : lua_typename(L, ty)));
    for (lua_Integer i = 1; i <= 3; i++) {
        int isnum = 0;
        lua_geti(L, -1, i);
        v[i - 1] = (double)lua_tonumberx(L, -1, &isnum);
        if (lua_type(L, -1) != LUA_TNUMBER || !isnum || !isfinite(v[i - 1]))
            fl_opts_error(o, shape, lua_pushfstring(L, "%s[%I]: finite number expected", key, i));
        lua_pop(L, 1);
    }
    lua_pop(L, 1);
}

/* Rejects keys of a shape table other than the two it has. */
static void region_keys(lua_State *L, const fl_opts *o, const char *shape, int t, const char *a,
                        const char *b) {
    lua_pushnil(L);
    while (lua_next(L, t)) {
        lua_pop(L, 1);
        const char *k = lua_type(L, -1) == LUA_TSTRING ? lua_tostring(L, -1) : NULL;
        if (!k || (strcmp(k, a) != 0 && strcmp(k, b) != 0)) {
            if (k)
                lua_pushfstring(L, "'%s'", k);
            else
                luaL_tolstring(L, -1, NULL);
            fl_opts_error(o, shape, lua_pushfstring(L, "unknown key %s; valid keys: %s, %s",
                                                    lua_tostring(L, -1), a, b));
        }
    }
}

static int hierarchy_refine_region(lua_State *L) {
    static const char *const keys[] = {"box",    "grading",  "progress", "size",
                                       "sphere", "vertices", "where",    NULL};
    static const char *const shapes[] = {"sphere", "box", "vertices", "where"};
    fl_hierarchy *h = fl_lhierarchy_check(L, 1);
    luaL_checktype(L, 2, LUA_TTABLE);
    fl_opts o;
    fl_opts_open(&o, L, 2, keys);
    no_more_arguments(L, 3);
    int which = -1;
    for (int i = 0; i < 4; i++) {
        int t = fl_opts_push(&o, shapes[i]);
        if (t == LUA_TNIL) continue;
        lua_pop(L, 1);
        if (which >= 0)
            return luaL_argerror(L, 2, lua_pushfstring(L, "give one region: %s or %s, not both",
                                                       shapes[which], shapes[i]));
        which = i;
    }
    if (which < 0) return luaL_argerror(L, 2, "no region: give sphere, box, vertices or where");
    if (fl_opts_push(&o, "size") == LUA_TNIL)
        return luaL_argerror(L, 2, "size: the element size inside the region is required");
    lua_pop(L, 1);
    double size = (double)fl_opts_number(&o, "size", 0.0);
    if (!(size >= 0.0) || !(size < HUGE_VAL))
        return fl_opts_error(&o, "size", "must be a finite number >= 0");
    double grading = 1.5;
    int gt = fl_opts_push(&o, "grading");
    if (gt == LUA_TBOOLEAN) {
        if (lua_toboolean(L, -1)) return fl_opts_error(&o, "grading", "number >= 1 or false expected, got true");
        grading = INFINITY;
        lua_pop(L, 1);
    } else if (gt != LUA_TNIL) {
        lua_pop(L, 1);
        grading = (double)fl_opts_number(&o, "grading", 1.5);
        if (!(grading >= 1.0)) return fl_opts_error(&o, "grading", "must be a number >= 1 (or false)");
    }
    femlod_region region;
    memset(&region, 0, sizeof region);
    const femlod_hierarchy *x = h->hier;
    size_t nn = femlod_hierarchy_node_count(x), nv = femlod_hierarchy_input_vertices(x);
    fl_opts_push(&o, shapes[which]);
    int t = lua_gettop(L);
    if (which == 0) {
        if (!lua_istable(L, t)) return fl_opts_error(&o, "sphere", "table {center = {x, y, z}, radius = r} expected");
        region_keys(L, &o, "sphere", t, "center", "radius");
        region.kind = FEMLOD_REGION_SPHERE;
        region_point(L, &o, "sphere", t, "center", region.center);
        int isnum = 0;
        lua_getfield(L, t, "radius");
        region.radius = (double)lua_tonumberx(L, -1, &isnum);
        if (lua_type(L, -1) != LUA_TNUMBER || !isnum || !(region.radius >= 0.0) ||
            !(region.radius < HUGE_VAL))
            return fl_opts_error(&o, "sphere", "radius: finite number >= 0 expected");
        lua_pop(L, 1);
    } else if (which == 1) {
        if (!lua_istable(L, t)) return fl_opts_error(&o, "box", "table {min = {x, y, z}, max = {x, y, z}} expected");
        region_keys(L, &o, "box", t, "max", "min");
        region.kind = FEMLOD_REGION_BOX;
        region_point(L, &o, "box", t, "min", region.min);
        region_point(L, &o, "box", t, "max", region.max);
        for (int k = 0; k < 3; k++)
            if (region.min[k] > region.max[k])
                return fl_opts_error(&o, "box", lua_pushfstring(L, "min[%d] > max[%d]", k + 1, k + 1));
    } else if (which == 2) {
        if (!lua_istable(L, t)) return fl_opts_error(&o, "vertices", "list of input vertex indices expected");
        lua_Integer len = luaL_len(L, t);
        unsigned char *marks = (unsigned char *)lua_newuserdatauv(L, nv ? nv : 1, 0);
        memset(marks, 0, nv ? nv : 1);
        for (lua_Integer i = 1; i <= len; i++) {
            int isint = 0;
            lua_geti(L, t, i);
            lua_Integer v = lua_tointegerx(L, -1, &isint);
            if (lua_type(L, -1) != LUA_TNUMBER || !isint)
                return fl_opts_error(&o, "vertices", lua_pushfstring(L, "[%I]: integer expected, got %s", i, luaL_typename(L, -1)));
            if (v < 1 || (lua_Unsigned)v > nv)
                return fl_opts_error(&o, "vertices", lua_pushfstring(L, "[%I]: %I is not an input vertex (1..%I)", i, v, (lua_Integer)nv));
            marks[v - 1] = 1;
            lua_pop(L, 1);
        }
        region.kind = FEMLOD_REGION_VERTICES;
        region.marks = marks;
    } else {
        if (!lua_isfunction(L, t)) return fl_opts_error(&o, "where", lua_pushfstring(L, "function expected, got %s", luaL_typename(L, t)));
        unsigned char *marks = (unsigned char *)lua_newuserdatauv(L, nn ? nn : 1, 0);
        luaL_checkstack(L, 5, NULL);
        h->busy = 1; /* the function may not use or close the hierarchy */
        for (size_t id = 0; id < nn; id++) {
            femlod_node_info n;
            femlod_hierarchy_node(x, (uint32_t)id, &n);
            lua_pushvalue(L, t);
            lua_pushnumber(L, n.position[0]);
            lua_pushnumber(L, n.position[1]);
            lua_pushnumber(L, n.position[2]);
            /* protected, so that busy is cleared on an error */
            if (lua_pcall(L, 3, 1, 0) != LUA_OK) {
                h->busy = 0;
                return lua_error(L);
            }
            int r = lua_type(L, -1);
            if (r != LUA_TBOOLEAN && r != LUA_TNIL) {
                h->busy = 0;
                return fl_opts_error(&o, "where", lua_pushfstring(L, "function returned %s for node %I (boolean or nil expected)", luaL_typename(L, -1), lid((uint32_t)id)));
            }
            marks[id] = (unsigned char)lua_toboolean(L, -1);
            lua_pop(L, 1);
        }
        h->busy = 0;
        region.kind = FEMLOD_REGION_NODES;
        region.marks = marks;
    }
    size_t ops = 0, inside = 0;
    femlod_error err;
    fl_progress_call pc;
    femlod_progress_options po = {fl_opts_progress(&o, &pc), &pc};
    double t0 = fl_lua_clock();
    h->busy = 1;
    femlod_status st =
        femlod_hierarchy_refine_region(h->hier, &region, size, grading, &po, &ops, &inside, &err);
    h->busy = 0;
    fl_opts_progress_check(&o, &pc, st);
    if (st != FEMLOD_OK) return fl_lua_raise(L, &err);
    if (fl_lua_verbose(L))
        fl_lua_log(L, "refine_region: %zu nodes inside, %zu splits, front %zu triangles (%.3f s)",
                   inside, ops, femlod_hierarchy_front_triangles(h->hier), fl_lua_clock() - t0);
    lua_pushinteger(L, (lua_Integer)ops);
    lua_pushinteger(L, (lua_Integer)inside);
    return 2;
}

static int hierarchy_node(lua_State *L) {
    fl_hierarchy *h = fl_lhierarchy_check(L, 1);
    no_more_arguments(L, 3);
    int t = lua_type(L, 2);
    lua_pushvalue(L, 2);
    uint32_t id = check_node_id(L, 2, h->hier, t, NULL);
    femlod_node_info n;
    femlod_hierarchy_node(h->hier, id, &n);
    push_node(L, &n, 1);
    return 1;
}

/* h:validate(): true, or raises with the violation (the core's message,
 * whose node and face ids are the C API's, 0-based). */
static int hierarchy_validate(lua_State *L) {
    fl_hierarchy *h = fl_lhierarchy_check(L, 1);
    femlod_error err;
    if (femlod_hierarchy_validate(h->hier, &err) != FEMLOD_OK) {
        luaL_where(L, 1);
        lua_pushfstring(L, "invalid hierarchy (0-based C ids): %s", err.message);
        lua_concat(L, 2);
        return lua_error(L);
    }
    lua_pushboolean(L, 1);
    return 1;
}

static int hierarchy_save(lua_State *L) {
    fl_hierarchy *h = fl_lhierarchy_check(L, 1);
    const char *path = fl_lua_check_path(L, 2, 1);
    no_more_arguments(L, 3);
    femlod_error err;
    double t0 = fl_lua_clock();
    if (femlod_hierarchy_save(h->hier, path, h->has_result ? &h->result : NULL, &err) != FEMLOD_OK)
        return fl_lua_raise(L, &err);
    if (fl_lua_verbose(L))
        fl_lua_log(L, "write %s: %zu nodes (%.3f s)", path, femlod_hierarchy_node_count(h->hier),
                   fl_lua_clock() - t0);
    fl_lua_io_hook(L, "write", 2, 1);
    return 0;
}

/* A threshold in force, or false when it is off (negative). */
static void set_threshold(lua_State *L, const char *key, double v) {
    if (v < 0.0) lua_pushboolean(L, 0);
    else lua_pushnumber(L, v);
    lua_setfield(L, -2, key);
}

static int hierarchy_stats(lua_State *L) {
    const fl_hierarchy *h = check_open(L, 1);
    if (!h->has_result)
        return luaL_error(L, "this femlod.Hierarchy has no simplification statistics "
                             "(its file was saved without them)");
    const femlod_simplify_result *r = &h->result;
    lua_createtable(L, 0, 12);
    set_integer(L, "triangles", r->triangles);
    set_integer(L, "vertices", r->vertices);
    lua_pushstring(L, femlod_stop_reason_name(r->stop_reason));
    lua_setfield(L, -2, "stop_reason");
    set_integer(L, "collapses", r->collapses);
    set_integer(L, "prephase_collapses", r->prephase_collapses);
    set_integer(L, "fast_collapses", r->fast_collapses);
    set_integer(L, "threads", (size_t)r->threads);
    lua_createtable(L, 0, FEMLOD_REJECT_COUNT);
    for (int k = 0; k < FEMLOD_REJECT_COUNT; k++)
        set_integer(L, femlod_reject_name((femlod_reject)k), r->rejected[k]);
    lua_setfield(L, -2, "rejected");
    set_integer(L, "violating_input", r->violating_input);
    /* the honest count: by reason, only the reasons with elements */
    lua_createtable(L, 0, 4);
    for (int k = 0; k < FEMLOD_IMPROVE_REASON_COUNT; k++)
        if (r->violating_by[k]) set_integer(L, femlod_improve_reason_name((femlod_improve_reason)k), r->violating_by[k]);
    lua_setfield(L, -2, "violating_by");
    set_integer(L, "violating_valence", r->violating_valence);
    lua_createtable(L, 0, 4);
    for (int k = 0; k < FEMLOD_IMPROVE_REASON_COUNT; k++)
        if (r->violating_valence_by[k])
            set_integer(L, femlod_improve_reason_name((femlod_improve_reason)k), r->violating_valence_by[k]);
    lua_setfield(L, -2, "violating_valence_by");
    if (r->corner_angle_max > 0.0) {
        lua_pushnumber(L, r->corner_angle_min);
        lua_setfield(L, -2, "corner_angle_min");
        lua_pushnumber(L, r->corner_angle_max);
        lua_setfield(L, -2, "corner_angle_max");
    }
    if (r->stop_reason == FEMLOD_STOP_NO_VALID_EDGE) {
        lua_createtable(L, 0, FEMLOD_REJECT_COUNT);
        for (int k = 0; k < FEMLOD_REJECT_COUNT; k++)
            set_integer(L, femlod_reject_name((femlod_reject)k), r->stop_rejected[k]);
        lua_setfield(L, -2, "stop_rejected");
        size_t t = r->stop_rejected[FEMLOD_REJECT_TOPOLOGY], a = r->stop_topology[0], b = r->stop_topology[1],
               c = r->stop_topology[2];
        lua_createtable(L, 0, 4);
        set_integer(L, "nonmanifold", a);
        set_integer(L, "features", b);
        set_integer(L, "boundary", c);
        set_integer(L, "link", t >= a + b + c ? t - a - b - c : 0);
        lua_setfield(L, -2, "stop_topology");
        set_integer(L, "stop_taken", r->stop_taken);
    }
    set_integer(L, "dropped_degenerate", r->dropped_degenerate);
    lua_pushboolean(L, r->improved);
    lua_setfield(L, -2, "improved");
    set_integer(L, "improve_operations", r->improve_operations);
    set_integer(L, "improve_triangles", r->improve_triangles);
    lua_pushnumber(L, r->improve_seconds);
    lua_setfield(L, -2, "improve_seconds");
    set_integer(L, "hierarchy_triangles", r->hierarchy_triangles);
    lua_pushstring(L, femlod_stop_reason_name(r->hierarchy_stop));
    lua_setfield(L, -2, "hierarchy_stop");
    if (r->hierarchy_binding >= 0 && r->hierarchy_binding < FEMLOD_REJECT_COUNT) {
        lua_pushstring(L, femlod_reject_name((femlod_reject)r->hierarchy_binding));
        lua_setfield(L, -2, "hierarchy_binding");
    }
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
    lua_pushinteger(L, (lua_Integer)(femlod_hierarchy_node_count(h->hier) -
                                     femlod_hierarchy_input_vertices(h->hier)));
    return 1;
}

static int hierarchy_input_vertices(lua_State *L) {
    const fl_hierarchy *h = fl_lhierarchy_check(L, 1);
    lua_pushinteger(L, (lua_Integer)femlod_hierarchy_input_vertices(h->hier));
    return 1;
}

static int hierarchy_log_bytes(lua_State *L) {
    const fl_hierarchy *h = check_open(L, 1);
    lua_pushinteger(L, (lua_Integer)h->log_bytes);
    return 1;
}

/* __gc, __close and close(): one release that tolerates a closed box. A
 * busy box is on the stack of its refine, so the collector never sees it;
 * close() from its own size function is refused. */
static int hierarchy_gc(lua_State *L) {
    fl_hierarchy *h = (fl_hierarchy *)luaL_checkudata(L, 1, FL_HIERARCHY_MT);
    if (h->busy)
        return luaL_error(L, "attempt to close a femlod.Hierarchy inside its own size or progress function");
    hierarchy_release(L, h);
    return 0;
}

static int hierarchy_tostring(lua_State *L) {
    const fl_hierarchy *h = (const fl_hierarchy *)luaL_checkudata(L, 1, FL_HIERARCHY_MT);
    if (h->flat)
        lua_pushfstring(L, "femlod.Hierarchy (no hierarchy, %I triangles)",
                        (lua_Integer)femlod_mesh_triangle_count(h->flat));
    else if (!h->hier)
        lua_pushliteral(L, "femlod.Hierarchy (closed)");
    else
        lua_pushfstring(L, "femlod.Hierarchy (%I nodes, %I triangles on the front)",
                        (lua_Integer)femlod_hierarchy_node_count(h->hier),
                        (lua_Integer)femlod_hierarchy_front_triangles(h->hier));
    return 1;
}

/* }==================================================================== */

static const luaL_Reg hierarchy_methods[] = {
    {"mesh", hierarchy_mesh},
    {"front", hierarchy_front},
    {"refine", hierarchy_refine},
    {"coarsen", hierarchy_coarsen},
    {"rescale", hierarchy_rescale},
    {"refine_curvature", hierarchy_refine_curvature},
    {"refine_region", hierarchy_refine_region},
    {"split", hierarchy_split},
    {"collapse", hierarchy_collapse},
    {"counts", hierarchy_counts},
    {"node", hierarchy_node},
    {"validate", hierarchy_validate},
    {"save", hierarchy_save},
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
    lua_pushcfunction(L, lib_load_hierarchy);
    lua_setfield(L, -2, "load_hierarchy");
}
