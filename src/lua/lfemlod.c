/*
 * lfemlod.c - luaopen_femlod: the module table, its types, and the embedded
 * pure-Lua helpers (lua/femlod/NAME.lua).
 *
 * `require "femlod"` returns one table and sets no global (unlike lfs.c's
 * luaopen_lfs). The helpers are compiled in (cmake/embed_lua.cmake), so that
 * neither the installed program nor the module needs a search path to find
 * them: luaopen_femlod registers them in package.preload, and each also has
 * its own luaopen_femlod_NAME so that the stock interpreter's all-in-one
 * loader finds `require "femlod.report"` in femlod.so even before
 * `require "femlod"` ran.
 */
#include "lfemlod.h"

#include "core.h" /* fl_out: the atomic writer */

#include <errno.h>
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

/* Where femlod.report looks for the 3D viewer of its HTML pages. */
static const char *const viewer_paths[] = {
#ifdef FEMLOD_VIEWER_BUILD
    FEMLOD_VIEWER_BUILD,
#endif
#ifdef FEMLOD_VIEWER_INSTALL
    FEMLOD_VIEWER_INSTALL,
#endif
    NULL};

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

/* femlod._viewer_js(): the text and path of femlod's own copy of the 3D
 * viewer script (the first of _VIEWER_PATHS that reads), or nothing. Read
 * here and not through io.open: it is femlod's installed file, not one the
 * recipe names, so a sandboxed recipe's report still gets its viewer. */
static int lib_viewer_js(lua_State *L) {
    for (int i = 0; viewer_paths[i]; i++) {
        char *data = NULL;
        size_t size = 0;
        femlod_error err;
        if (fl_file_read_all(viewer_paths[i], &data, &size, &err) != FEMLOD_OK) continue;
        fl_lua_push_owned(L, data, size);
        lua_pushstring(L, viewer_paths[i]);
        return 2;
    }
    return 0;
}

/* femlod.write_file(path, data): writes the string data to path as every
 * femlod writer does (a temporary file beside it, renamed over it once
 * complete; a failure leaves path as it was), within the sandbox's folders
 * (the same path check as m:save). For recipes' own reports and tables. */
static int lib_write_file(lua_State *L) {
    const char *path = fl_lua_check_path(L, 1, 1);
    size_t len;
    const char *data = luaL_checklstring(L, 2, &len);
    femlod_error err;
    fl_out o;
    if (fl_out_open(&o, path, &err) != FEMLOD_OK) return fl_lua_raise(L, &err);
    if (len && fwrite(data, 1, len, o.fp) != len) {
        int e = errno;
        fl_out_abort(&o);
        return luaL_error(L, "%s: cannot write: %s", path, strerror(e ? e : EIO));
    }
    if (fl_out_commit(&o, &err) != FEMLOD_OK) return fl_lua_raise(L, &err);
    fl_lua_io_hook(L, "write", 1, 2);
    return 0;
}

/* femlod._isatty(fd): whether file descriptor fd (1 standard output, 2
 * standard error) is a terminal; femlod.progress draws its bar only then. */
static int lib_isatty(lua_State *L) {
    lua_Integer fd = luaL_checkinteger(L, 1);
    luaL_argcheck(L, fd >= 0 && fd <= 2, 1, "0, 1 or 2 expected");
    lua_pushboolean(L, isatty((int)fd));
    return 1;
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

void fl_lua_log(lua_State *L, const char *fmt, ...) {
    (void)L;
    va_list ap;
    fflush(stdout); /* keep the order of interleaved lines on a terminal */
    /* a progress bar may be on the line: clear it (it redraws itself) */
    fputs(isatty(2) ? "\r\033[Kfemlod: " : "femlod: ", stderr);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
    fflush(stderr);
}

void fl_lua_warn(lua_State *L, const char *fmt, ...) {
    (void)L;
    va_list ap;
    fflush(stdout);
    fputs(isatty(2) ? "\r\033[Kfemlod: warning: " : "femlod: warning: ", stderr);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
    fflush(stderr);
}

/* }==================================================================== */

/* {====================================================================
 * Embedded helpers
 * ===================================================================== */

static const fl_lua_chunk *find_chunk(const char *module) {
    for (const fl_lua_chunk *c = fl_lua_embedded; c->module; c++)
        if (strcmp(c->module, module) == 0) return c;
    return NULL;
}

/* Loads and runs a chunk the way require runs a Lua file: with the module
 * name and the chunk name as its arguments. Text mode only: the sources are
 * ours, and refusing bytecode costs nothing. */
static int run_chunk(lua_State *L, const fl_lua_chunk *c) {
    if (luaL_loadbufferx(L, c->source, c->size, c->chunkname, "t") != LUA_OK) return lua_error(L);
    lua_pushstring(L, c->module);
    lua_pushstring(L, c->chunkname);
    lua_call(L, 2, 1);
    return 1;
}

/* package.preload loader; the chunk is the upvalue. */
static int preload_loader(lua_State *L) {
    return run_chunk(L, (const fl_lua_chunk *)lua_touserdata(L, lua_upvalueindex(1)));
}

void fl_lua_preload_helpers(lua_State *L) {
    luaL_getsubtable(L, LUA_REGISTRYINDEX, LUA_PRELOAD_TABLE);
    for (const fl_lua_chunk *c = fl_lua_embedded; c->module; c++) {
        if (lua_getfield(L, -1, c->module) == LUA_TNIL) {
            lua_pop(L, 1);
            /* cast: the table is const, the upvalue slot is not; it is only read. */
            lua_pushlightuserdata(L, (void *)(uintptr_t)c);
            lua_pushcclosure(L, preload_loader, 1);
            lua_setfield(L, -2, c->module);
        } else {
            lua_pop(L, 1);
        }
    }
    lua_pop(L, 1);
}

/* Entry for the all-in-one loader (require "femlod.NAME" finding femlod.so).
 * require has already made sure this name is not loaded. */
static int open_helper(lua_State *L, const char *module) {
    const fl_lua_chunk *c = find_chunk(module);
    if (!c) return luaL_error(L, "module '%s' is not embedded in femlod", module);
    return run_chunk(L, c);
}

/* One line per helper in lua/femlod/: the C searcher needs a real symbol. */
FL_LUA_EXPORT int luaopen_femlod_report(lua_State *L);
int luaopen_femlod_report(lua_State *L) {
    return open_helper(L, "femlod.report");
}
FL_LUA_EXPORT int luaopen_femlod_progress(lua_State *L);
int luaopen_femlod_progress(lua_State *L) {
    return open_helper(L, "femlod.progress");
}
FL_LUA_EXPORT int luaopen_femlod_sweep(lua_State *L);
int luaopen_femlod_sweep(lua_State *L) {
    return open_helper(L, "femlod.sweep");
}

/* }==================================================================== */

int luaopen_femlod(lua_State *L) {
    luaL_checkversion(L);
    fl_lua_preload_helpers(L);
    lua_newtable(L);
    fl_lmesh_open(L);
    fl_lhierarchy_open(L);
    lua_pushliteral(L, "femlod " FEMLOD_VERSION_STRING);
    lua_setfield(L, -2, "_VERSION");
    lua_newtable(L);
    for (int i = 0; viewer_paths[i]; i++) {
        lua_pushstring(L, viewer_paths[i]);
        lua_rawseti(L, -2, i + 1);
    }
    lua_setfield(L, -2, "_VIEWER_PATHS");
    lua_pushcfunction(L, lib_isatty);
    lua_setfield(L, -2, "_isatty");
    lua_getfield(L, LUA_REGISTRYINDEX, FL_VERBOSITY_KEY);
    lua_Integer level = lua_tointeger(L, -1);
    lua_pop(L, 1);
    lua_pushboolean(L, level > 0);
    lua_setfield(L, -2, "verbose");
    lua_pushboolean(L, level < 0);
    lua_setfield(L, -2, "quiet");
    lua_pushcfunction(L, lib_write_file);
    lua_setfield(L, -2, "write_file");
    lua_pushcfunction(L, lib_viewer_js);
    lua_setfield(L, -2, "_viewer_js");
    /* femlod.report(mesh, opts): the helper's report function. */
    const fl_lua_chunk *c = find_chunk("femlod.report");
    if (c) {
        luaL_getsubtable(L, LUA_REGISTRYINDEX, LUA_LOADED_TABLE);
        if (lua_getfield(L, -1, "femlod.report") != LUA_TTABLE) {
            lua_pop(L, 1);
            run_chunk(L, c);
            lua_pushvalue(L, -1);
            lua_setfield(L, -3, "femlod.report");
        }
        lua_getfield(L, -1, "report");
        lua_setfield(L, -4, "report");
        lua_pop(L, 2);
    }
    return 1;
}
