/*
 * lutil.h - what the Lua binding's files share (lutil.c), below the module
 * (lfemlod.c), its types (lmesh.c, lhierarchy.c) and the option reader
 * (lopts.c): raising core failures and limit errors, the host's guard and
 * memory charges, the file log hook, owned strings and verbosity. Never
 * installed; the build hides every fl_ symbol (-fvisibility=hidden).
 */
#ifndef FEMLOD_LUTIL_H
#define FEMLOD_LUTIL_H

#include "femlod.h"

#include <lua.h>
#include <lauxlib.h>

#if defined(__GNUC__)
#define FL_LUA_EXPORT __attribute__((visibility("default")))
#define FL_LUA_INTERNAL __attribute__((visibility("hidden")))
#else
#define FL_LUA_EXPORT
#define FL_LUA_INTERNAL
#endif

/* Raises a Lua error carrying a core failure's message, with the calling
 * recipe's "file:line:" in front (as luaL_error does). The message of a
 * FEMLOD_ELIMIT failure is also recorded, so that the program can tell when
 * a recipe died of it (fl_lua_is_limit_error) and exit with code 3. */
FL_LUA_INTERNAL int fl_lua_raise(lua_State *L, const femlod_error *err);
/* True when msg is the last recorded limit failure (a position may come
 * before it, a traceback after it).
 * A recipe that caught that failure and died of another error gets false. */
FL_LUA_INTERNAL int fl_lua_is_limit_error(lua_State *L, const char *msg);

/* {====== The guard: a host's policy (the femlod program's --sandbox and
 * caps, src/cli/sandbox.c). A host stores a pointer to one in the registry
 * under FL_GUARD_KEY; without one (the module in a stock lua5.4) every path
 * is allowed and nothing is charged. The core knows nothing of it: the
 * binding asks before it calls the core. */

#define FL_GUARD_KEY "femlod.guard"

typedef struct fl_lua_guard fl_lua_guard;
struct fl_lua_guard {
    /* NULL when path may be read (write == 0) or created or replaced
     * (write == 1); otherwise the reason, a message naming the path (valid
     * until the next call). Must not raise. */
    const char *(*check_path)(fl_lua_guard *g, const char *path, int write);
    /* Adds bytes (a refund when negative) to the memory charged against
     * the cap; returns nonzero when the total now passes it. Must not raise. */
    int (*charge)(fl_lua_guard *g, double bytes);
    /* Nonzero once the time cap has passed; polled by long C calls through
     * their progress callbacks, with the thread that called them, on which
     * it then arms the hook that stops every later instruction (so that the
     * stop cannot be caught). Must not raise or allocate. */
    int (*expired)(fl_lua_guard *g, lua_State *L);
    /* The message of each cap ("time limit of 2 s exceeded (--max-time)"). */
    const char *time_message, *memory_message;
    /* Nonzero when a memory cap is in force: the core's FEMLOD_ENOMEM then
     * counts as the cap (setrlimit made the allocation fail). */
    int memory_capped;
};

/* Pushes size bytes of data as a Lua string and frees data, also when
 * making the string fails (the memory error is raised after the free). */
FL_LUA_INTERNAL void fl_lua_push_owned(lua_State *L, char *data, size_t size);

/* The installed guard, or NULL. */
FL_LUA_INTERNAL fl_lua_guard *fl_lua_guard_get(lua_State *L);
/* The path at argument arg, for reading or writing: raises on a non-string,
 * a zero byte or a path the guard refuses. */
FL_LUA_INTERNAL const char *fl_lua_check_path(lua_State *L, int arg, int write);
/* Charges bytes of core memory held by a Lua object (a refund when
 * negative); a charge that passes the cap raises the memory limit error.
 * The charge stays made either way, so the object's release refunds it. */
FL_LUA_INTERNAL void fl_lua_charge(lua_State *L, double bytes);
/* Raises the memory limit error when charging bytes more would pass the
 * cap; charges nothing (for a result about to be made). */
FL_LUA_INTERNAL void fl_lua_reserve(lua_State *L, double bytes);
/* Raises msg as a limit failure (exit status 3 from the program), with the
 * position of the function at stack level `level` in front. */
FL_LUA_INTERNAL int fl_lua_raise_limit(lua_State *L, int level, const char *msg);

/* }====== */

/* The file log of `femlod run --record` (femlod.sweep): when the registry
 * holds a function under FL_IO_HOOK, the functions that read or write files
 * (femlod.load, m:save, femlod.load_hierarchy, h:save) call it after each
 * success as hook(kind, path, object), kind "read" or "write", the path as
 * given and the object read or saved. Leaves the stack as it found it; an
 * error in the hook propagates. Without a hook it costs one table lookup. */
#define FL_IO_HOOK "femlod.io_hook"
FL_LUA_INTERNAL void fl_lua_io_hook(lua_State *L, const char *kind, int path, int object);

/* {====== Verbosity. `femlod.verbose` and `femlod.quiet` are
 * plain fields of the module table: the program sets them from -v and -q
 * (through the registry, FL_VERBOSITY_KEY, read when the module opens), and
 * a recipe may change them. With verbose true the functions that read,
 * write or transform print one line each on standard error, with its time. */

#define FL_VERBOSITY_KEY "femlod.verbosity" /* registry: integer -1 quiet, 0, 1 verbose */

/* Whether package.loaded.femlod.verbose is true (never raises). */
FL_LUA_INTERNAL int fl_lua_verbose(lua_State *L);
/* Wall-clock seconds from an arbitrary origin (for durations). */
FL_LUA_INTERNAL double fl_lua_clock(void);
#if defined(__GNUC__)
__attribute__((format(printf, 2, 3)))
#endif
/* Prints "femlod: MESSAGE\n" on standard error (call when fl_lua_verbose). */
FL_LUA_INTERNAL void fl_lua_log(lua_State *L, const char *fmt, ...);
#if defined(__GNUC__)
__attribute__((format(printf, 2, 3)))
#endif
/* Prints "femlod: warning: MESSAGE\n" on standard error, whatever the
 * verbosity: a request that could not be met (rescale). */
FL_LUA_INTERNAL void fl_lua_warn(lua_State *L, const char *fmt, ...);

/* }====== */

#endif
