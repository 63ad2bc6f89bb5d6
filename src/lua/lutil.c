/*
 * lutil.c - owns what every file of the Lua binding shares (lutil.h): core
 * failures and limit errors raised with the recipe's position, the host's
 * guard (path checks, memory charges), the file log hook of --record,
 * strings made from C buffers, and verbosity. Below lfemlod.c (the module
 * table), lmesh.c, lhierarchy.c and lopts.c; it calls none of them.
 */
#include "lutil.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

/* Registry key of the message of the last FEMLOD_ELIMIT failure raised. */
#define LIMIT_KEY "femlod.limit"

int fl_lua_raise(lua_State *L, const femlod_error *err) {
    luaL_where(L, 1);
    /* A core function that forgot its message still says what failed. */
    if (err->message[0] == '\0')
        lua_pushfstring(L, "femlod: %s error", femlod_status_name(err->status));
    else
        lua_pushstring(L, err->message);
    /* Under a memory cap, RLIMIT_AS is what made the core's malloc fail. */
    fl_lua_guard *g = err->status == FEMLOD_ENOMEM ? fl_lua_guard_get(L) : NULL;
    if (g && g->memory_capped) {
        lua_pushliteral(L, "; ");
        lua_pushstring(L, g->memory_message);
        lua_concat(L, 4);
    } else {
        lua_concat(L, 2);
    }
    if (err->status == FEMLOD_ELIMIT || (g && g->memory_capped)) {
        lua_pushvalue(L, -1);
        lua_setfield(L, LUA_REGISTRYINDEX, LIMIT_KEY);
    }
    return lua_error(L);
}

int fl_lua_is_limit_error(lua_State *L, const char *msg) {
    int hit = 0;
    if (msg && lua_getfield(L, LUA_REGISTRYINDEX, LIMIT_KEY) == LUA_TSTRING) {
        size_t n;
        const char *limit = lua_tolstring(L, -1, &n);
        /* The message may have grown a traceback, and a position in front
         * (coroutine.wrap adds one when the error leaves the coroutine). */
        for (const char *p = strstr(msg, limit); p && !hit; p = strstr(p + 1, limit))
            hit = p[n] == '\0' || p[n] == '\n';
    }
    lua_pop(L, 1);
    return hit;
}

int fl_lua_raise_limit(lua_State *L, int level, const char *msg) {
    luaL_where(L, level);
    lua_pushstring(L, msg);
    lua_concat(L, 2);
    lua_pushvalue(L, -1);
    lua_setfield(L, LUA_REGISTRYINDEX, LIMIT_KEY);
    return lua_error(L);
}

/* {====================================================================
 * The guard
 * ===================================================================== */

fl_lua_guard *fl_lua_guard_get(lua_State *L) {
    lua_getfield(L, LUA_REGISTRYINDEX, FL_GUARD_KEY);
    fl_lua_guard *g = (fl_lua_guard *)lua_touserdata(L, -1);
    lua_pop(L, 1);
    return g;
}

const char *fl_lua_check_path(lua_State *L, int arg, int write) {
    size_t len;
    const char *path = luaL_checklstring(L, arg, &len);
    /* A zero byte would silently cut the path short in the C library. */
    luaL_argcheck(L, strlen(path) == len, arg, "path contains a zero byte");
    fl_lua_guard *g = fl_lua_guard_get(L);
    const char *why = g ? g->check_path(g, path, write) : NULL;
    if (why) luaL_error(L, "%s", why);
    return path;
}

/* Over the cap, a full collection first: the meshes of unreachable boxes
 * are still charged, and the collector does not know their size. */
static int over_cap(lua_State *L, fl_lua_guard *g) {
    if (!g->charge(g, 0)) return 0;
    lua_gc(L, LUA_GCCOLLECT);
    return g->charge(g, 0);
}

void fl_lua_charge(lua_State *L, double bytes) {
    fl_lua_guard *g = fl_lua_guard_get(L);
    if (!g) return;
    int over = g->charge(g, bytes);
    if (bytes <= 0) return;
    if (over && over_cap(L, g)) fl_lua_raise_limit(L, 1, g->memory_message);
    /* Pace the collector as if the bytes were Lua's: otherwise it sees a
     * few bytes of box per mesh, and dropped meshes pile up until the
     * allocator refuses (its emergency collection runs no finalizer). */
    if (g->memory_capped) lua_gc(L, LUA_GCSTEP, bytes > 1e9 ? 1000000 : (int)(bytes / 1024));
}

void fl_lua_reserve(lua_State *L, double bytes) {
    fl_lua_guard *g = fl_lua_guard_get(L);
    if (!g) return;
    int over = g->charge(g, bytes);
    if (over) over = over_cap(L, g);
    g->charge(g, -bytes);
    if (over) fl_lua_raise_limit(L, 1, g->memory_message);
}

/* }==================================================================== */

void fl_lua_io_hook(lua_State *L, const char *kind, int path, int object) {
    path = lua_absindex(L, path);
    object = lua_absindex(L, object);
    if (lua_getfield(L, LUA_REGISTRYINDEX, FL_IO_HOOK) != LUA_TFUNCTION) {
        lua_pop(L, 1);
        return;
    }
    lua_pushstring(L, kind);
    lua_pushvalue(L, path);
    lua_pushvalue(L, object);
    lua_call(L, 3, 0);
}

static int push_text(lua_State *L) {
    lua_pushlstring(L, (const char *)lua_touserdata(L, 1), (size_t)lua_tointeger(L, 2));
    return 1;
}

void fl_lua_push_owned(lua_State *L, char *data, size_t size) {
    lua_pushcfunction(L, push_text); /* protected, so that data is freed either way */
    lua_pushlightuserdata(L, data);
    lua_pushinteger(L, (lua_Integer)size);
    int st = lua_pcall(L, 2, 1, 0);
    free(data);
    if (st != LUA_OK) lua_error(L);
}

/* {====================================================================
 * Verbosity
 * ===================================================================== */

int fl_lua_verbose(lua_State *L) {
    if (!lua_checkstack(L, 3)) return 0;
    int v = 0;
    if (lua_getfield(L, LUA_REGISTRYINDEX, LUA_LOADED_TABLE) == LUA_TTABLE &&
        lua_getfield(L, -1, "femlod") == LUA_TTABLE) {
        lua_pushliteral(L, "verbose");
        v = lua_rawget(L, -2) != LUA_TNIL && lua_toboolean(L, -1);
        lua_pop(L, 1);
    }
    lua_pop(L, 2);
    return v;
}

double fl_lua_clock(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* "femlod: [what]MESSAGE\n" on standard error, after standard output (so
 * that interleaved lines keep their order) and over a progress bar on a
 * terminal (it redraws itself). */
static void vlog(const char *what, const char *fmt, va_list ap) {
    fflush(stdout);
    fputs(isatty(2) ? "\r\033[Kfemlod: " : "femlod: ", stderr);
    fputs(what, stderr);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    fflush(stderr);
}

void fl_lua_log(lua_State *L, const char *fmt, ...) {
    (void)L;
    va_list ap;
    va_start(ap, fmt);
    vlog("", fmt, ap);
    va_end(ap);
}

void fl_lua_warn(lua_State *L, const char *fmt, ...) {
    (void)L;
    va_list ap;
    va_start(ap, fmt);
    vlog("warning: ", fmt, ap);
    va_end(ap);
}

/* }==================================================================== */
