/*
 * lfemlod.c - luaopen_femlod: the module table, the registration of its types
 * (lmesh.c, lhierarchy.c), and the embedded pure-Lua helpers
 * (lua/femlod/NAME.lua). What the binding's files share is in lutil.c.
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
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* Where femlod.report looks for the 3D viewer of its HTML pages. */
static const char *const viewer_paths[] = {
#ifdef FEMLOD_VIEWER_BUILD
    FEMLOD_VIEWER_BUILD,
#endif
#ifdef FEMLOD_VIEWER_INSTALL
    FEMLOD_VIEWER_INSTALL,
#endif
    NULL};

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

/* femlod._clock(): wall-clock seconds from an arbitrary origin (monotonic),
 * for femlod.progress: os.clock is CPU time, which runs ahead of the wall
 * when the core works on several threads. */
static int lib_clock(lua_State *L) {
    lua_pushnumber(L, fl_lua_clock());
    return 1;
}

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
    fl_limprove_open(L);
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
    lua_pushcfunction(L, lib_clock);
    lua_setfield(L, -2, "_clock");
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
