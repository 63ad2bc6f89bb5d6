/*
 * sandbox.c - safe recipes: `femlod run --sandbox [--allow DIR]...
 * [--max-memory SIZE] [--max-time SECONDS]` (docs/design.md, "Safe
 * recipes", has the rules and the reasons).
 *
 * Three parts:
 *   - the library surface: functions removed, and every function that takes
 *     a path wrapped so that it asks the same check as femlod's readers and
 *     writers (the binding calls it through the guard, lfemlod.h);
 *   - the memory cap: the counting lua_Alloc the program's state runs on,
 *     the core memory the binding charges, and RLIMIT_AS behind both;
 *   - the time cap: a count hook that re-arms itself after the first trip,
 *     the guard's expired() polled by long C calls, and a SIGALRM backstop.
 */
#include "sandbox.h"

#include <lualib.h>

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/time.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#if defined(__SANITIZE_ADDRESS__)
#define FL_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define FL_ASAN 1
#endif
#endif

/* The backstop fires this long after the deadline, for a C call without a
 * progress callback or a recipe blocked on standard input. */
#define BACKSTOP_SECONDS 10
/* Instructions between two looks at the clock. */
#define HOOK_COUNT 1000

struct fl_sandbox {
    fl_lua_guard guard; /* first: the guard callbacks cast back */
    int sandbox;        /* --sandbox given */
    char **allow;       /* canonical --allow folders */
    size_t nallow;
    char *recipe_dir;   /* canonical folder of the recipe; NULL for stdin and -e */
    char *why;          /* the last refusal's message */

    size_t cap;         /* --max-memory in bytes; 0 for none */
    int cap_lifted;     /* fl_sandbox_stop ran */
    size_t used;        /* live bytes of the Lua heap */
    double charged;     /* core bytes charged by the binding */
    int refused;        /* the allocator refused a request under the cap */

    double max_time;    /* --max-time in seconds; 0 for none */
    lua_State *main;    /* the thread SIGALRM arms */
    struct timespec deadline;
    volatile sig_atomic_t expired, alarmed;

    char time_message[96], memory_message[96];
};

static fl_sandbox the_sandbox;

fl_sandbox *fl_sandbox_get(void) {
    return &the_sandbox;
}

int fl_sandbox_active(const fl_sandbox *sb) {
    return sb->sandbox || sb->nallow > 0 || sb->cap > 0 || sb->max_time > 0;
}

const char *fl_sandbox_confines(const fl_sandbox *sb) {
    return sb->sandbox ? "--sandbox" : sb->nallow ? "--allow" : NULL;
}

/* {====================================================================
 * Memory
 * ===================================================================== */

void *fl_sandbox_alloc(void *ud, void *ptr, size_t osize, size_t nsize) {
    fl_sandbox *sb = (fl_sandbox *)ud;
    /* With ptr NULL, osize is the type of the new object (Lua 5.4 manual). */
    size_t old = ptr ? osize : 0;
    if (nsize == 0) {
        free(ptr);
        sb->used -= old;
        return NULL;
    }
    int capped = sb->cap > 0 && !sb->cap_lifted;
    /* Only growth is refused: Lua assumes a shrink never fails. */
    if (capped && nsize > old &&
        (double)(sb->used - old) + (double)nsize + sb->charged > (double)sb->cap) {
        sb->refused = 1;
        return NULL;
    }
    void *p = realloc(ptr, nsize);
    if (!p) {
        if (capped) sb->refused = 1; /* RLIMIT_AS, set for the cap */
        return NULL;
    }
    sb->used = sb->used - old + nsize;
    return p;
}

static int guard_charge(fl_lua_guard *g, double bytes) {
    fl_sandbox *sb = (fl_sandbox *)g;
    sb->charged += bytes;
    if (sb->charged < 0) sb->charged = 0;
    return sb->cap > 0 && !sb->cap_lifted && (double)sb->used + sb->charged > (double)sb->cap;
}

/* 200M, 1.5G, 65536, 64k: bytes, K, M, G (powers of 1024). */
const char *fl_sandbox_max_memory(fl_sandbox *sb, const char *value) {
    char *end;
    errno = 0;
    double v = strtod(value, &end);
    double unit = 1;
    if (*end) {
        switch (end[0]) {
        case 'k': case 'K': unit = 1024.0; break;
        case 'm': case 'M': unit = 1024.0 * 1024.0; break;
        case 'g': case 'G': unit = 1024.0 * 1024.0 * 1024.0; break;
        default: unit = 0; break;
        }
        if (end[1] != '\0' && !((end[1] == 'B' || end[1] == 'b') && end[2] == '\0')) unit = 0;
    }
    if (end == value || errno || unit == 0 || !(v > 0) || v * unit > 1e18 || v * unit < 65536.0)
        return "--max-memory: size of at least 64K expected (a number with K, M or G), got";
    sb->cap = (size_t)(v * unit);
    snprintf(sb->memory_message, sizeof sb->memory_message,
             "memory limit of %s exceeded (--max-memory)", value);
    sb->guard.memory_message = sb->memory_message;
    sb->guard.memory_capped = 1;
    return NULL;
}

#ifndef FL_ASAN
/* The address space in use now, from /proc/self/statm; 0 when unknown. */
static double address_space(void) {
    FILE *f = fopen("/proc/self/statm", "r");
    if (!f) return 0;
    unsigned long pages = 0;
    int ok = fscanf(f, "%lu", &pages) == 1;
    fclose(f);
    long page = sysconf(_SC_PAGESIZE);
    return ok && page > 0 ? (double)pages * (double)page : 0;
}
#endif

/* RLIMIT_AS for what passes neither the allocator nor the charges; not under
 * ASan, whose shadow memory is terabytes of address space. */
static void limit_address_space(const fl_sandbox *sb) {
#ifndef FL_ASAN
    double now = address_space();
    if (now <= 0) return;
    double want = now + 2.0 * (double)sb->cap + 256.0 * 1024 * 1024;
    struct rlimit rl;
    if (getrlimit(RLIMIT_AS, &rl) != 0) return;
    if (rl.rlim_cur != RLIM_INFINITY && (double)rl.rlim_cur <= want) return;
    rl.rlim_cur = (rlim_t)want;
    if (rl.rlim_max != RLIM_INFINITY && rl.rlim_cur > rl.rlim_max) rl.rlim_cur = rl.rlim_max;
    (void)setrlimit(RLIMIT_AS, &rl);
#else
    (void)sb;
#endif
}

/* }==================================================================== */

/* {====================================================================
 * Time
 * ===================================================================== */

const char *fl_sandbox_max_time(fl_sandbox *sb, const char *value) {
    char *end;
    errno = 0;
    double v = strtod(value, &end);
    if (end == value || *end || errno || !(v > 0) || v > 1e7)
        return "--max-time: number of seconds > 0 expected, got";
    sb->max_time = v;
    snprintf(sb->time_message, sizeof sb->time_message, "time limit of %s s exceeded (--max-time)",
             value);
    sb->guard.time_message = sb->time_message;
    return NULL;
}

static void time_hook(lua_State *L, lua_Debug *ar);

/* No allocation, no error: called from the core through progress callbacks.
 * Once tripped, the hook fires at every instruction of L (and of every
 * coroutine, which re-arms its own), so a pcall that caught the stop is
 * stopped at its next instruction. */
static int guard_expired(fl_lua_guard *g, lua_State *L) {
    fl_sandbox *sb = (fl_sandbox *)g;
    if (sb->max_time <= 0 || sb->cap_lifted) return 0;
    if (!sb->expired) {
        struct timespec now;
        clock_gettime(CLOCK_MONOTONIC, &now);
        if (now.tv_sec < sb->deadline.tv_sec ||
            (now.tv_sec == sb->deadline.tv_sec && now.tv_nsec < sb->deadline.tv_nsec))
            return 0;
        sb->expired = 1;
    }
    if (L) lua_sethook(L, time_hook, LUA_MASKCOUNT, 1);
    return 1;
}

static void time_hook(lua_State *L, lua_Debug *ar) {
    (void)ar;
    if (guard_expired(&the_sandbox.guard, L)) fl_lua_raise_limit(L, 0, the_sandbox.time_message);
}

/* SIGALRM: the first at the deadline arms the hook of the main thread (as
 * lua.c's laction does; lua_sethook may be called from a signal handler)
 * and sets the flag the progress callbacks and coroutines see; the second,
 * BACKSTOP_SECONDS later, ends the process from here. */
static void on_alarm(int sig) {
    (void)sig;
    /* expired may already be set by a look at the clock that came first. */
    if (!the_sandbox.alarmed) {
        the_sandbox.alarmed = 1;
        the_sandbox.expired = 1;
        lua_sethook(the_sandbox.main, time_hook, LUA_MASKCOUNT, 1);
        alarm(BACKSTOP_SECONDS);
        return;
    }
    static const char pre[] = "femlod: ", post[] = " (stopped inside a C function)\n";
    ssize_t r = write(2, pre, sizeof pre - 1);
    r = write(2, the_sandbox.time_message, strlen(the_sandbox.time_message));
    r = write(2, post, sizeof post - 1);
    (void)r;
    _exit(3);
}

static int guarded_xpcall(lua_State *L);

/* Coroutines: the signal reaches only the main thread, so each new
 * coroutine gets a count hook that looks at the clock (every HOOK_COUNT
 * instructions; a count hook slows the VM for every instruction, so the
 * main thread has none until the deadline). coroutine.create and
 * coroutine.wrap (upvalue 1) are wrapped; wrap's function holds its thread
 * as its upvalue. */
static int hooked_coroutine(lua_State *L) {
    int n = lua_gettop(L);
    lua_pushvalue(L, lua_upvalueindex(1));
    lua_insert(L, 1);
    lua_call(L, n, 1);
    lua_State *co = lua_tothread(L, -1);
    if (!co && lua_getupvalue(L, -1, 1)) {
        co = lua_tothread(L, -1);
        lua_pop(L, 1);
    }
    if (co) {
        if (the_sandbox.expired)
            lua_sethook(co, time_hook, LUA_MASKCOUNT, 1);
        else
            lua_sethook(co, time_hook, LUA_MASKCOUNT, HOOK_COUNT);
    }
    return 1;
}

static void start_clock(fl_sandbox *sb, lua_State *L) {
    sb->main = L;
    clock_gettime(CLOCK_MONOTONIC, &sb->deadline);
    double whole = floor(sb->max_time);
    sb->deadline.tv_sec += (time_t)whole;
    sb->deadline.tv_nsec += (long)((sb->max_time - whole) * 1e9);
    if (sb->deadline.tv_nsec >= 1000000000L) {
        sb->deadline.tv_sec++;
        sb->deadline.tv_nsec -= 1000000000L;
    }
    lua_getglobal(L, "xpcall");
    lua_pushcclosure(L, guarded_xpcall, 1);
    lua_setglobal(L, "xpcall");
    lua_getglobal(L, "coroutine");
    if (lua_istable(L, -1)) {
        static const char *const makers[] = {"create", "wrap"};
        for (int i = 0; i < 2; i++) {
            lua_getfield(L, -1, makers[i]);
            lua_pushcclosure(L, hooked_coroutine, 1);
            lua_setfield(L, -2, makers[i]);
        }
    }
    lua_pop(L, 1);
    /* No SA_RESTART: a recipe blocked reading standard input gets EINTR and
     * meets the hook. Reads and writes of regular files are not interrupted. */
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_alarm;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGALRM, &sa, NULL);
    struct itimerval it;
    memset(&it, 0, sizeof it);
    it.it_value.tv_sec = (time_t)whole;
    it.it_value.tv_usec = (suseconds_t)((sb->max_time - whole) * 1e6);
    if (it.it_value.tv_sec == 0 && it.it_value.tv_usec == 0) it.it_value.tv_usec = 1;
    setitimer(ITIMER_REAL, &it, NULL);
}

/* }==================================================================== */

/* {====================================================================
 * Paths
 * ===================================================================== */

void fl_sandbox_enable(fl_sandbox *sb) {
    sb->sandbox = 1;
}

/* The canonical folder of path's parent (path's folder); NULL when it cannot
 * be made. */
static char *parent_realpath(const char *path) {
    const char *slash = strrchr(path, '/');
    if (!slash) return realpath(".", NULL);
    size_t n = slash == path ? 1 : (size_t)(slash - path);
    char *dir = malloc(n + 1);
    if (!dir) return NULL;
    memcpy(dir, path, n);
    dir[n] = '\0';
    char *r = realpath(dir, NULL);
    free(dir);
    return r;
}

const char *fl_sandbox_allow(fl_sandbox *sb, const char *dir) {
    static char msg[PATH_MAX + 64];
    char *real = realpath(dir, NULL);
    struct stat st;
    if (!real || stat(real, &st) != 0 || !S_ISDIR(st.st_mode)) {
        snprintf(msg, sizeof msg, "--allow: %s: %s", dir, real ? strerror(ENOTDIR) : strerror(errno));
        free(real);
        return msg;
    }
    char **a = realloc(sb->allow, (sb->nallow + 1) * sizeof *a);
    if (!a) {
        free(real);
        return "--allow: out of memory";
    }
    sb->allow = a;
    sb->allow[sb->nallow++] = real;
    return NULL;
}

static int inside(const char *real, const char *root) {
    size_t n = strlen(root);
    if (n == 1 && root[0] == '/') return 1;
    return strncmp(real, root, n) == 0 && (real[n] == '\0' || real[n] == '/');
}

/* Where path leads: the realpath of the file when it exists, otherwise of
 * its deepest existing ancestor (what would be created is below it).
 * *dangling is set for a symbolic link to nowhere. NULL when nothing can
 * be resolved (out of memory). */
static char *where(const char *path, int *dangling) {
    *dangling = 0;
    struct stat lst;
    if (lstat(path, &lst) == 0) {
        char *r = realpath(path, NULL);
        if (r) return r;
        if (S_ISLNK(lst.st_mode)) {
            *dangling = 1;
            return NULL;
        }
    }
    size_t n = strlen(path);
    char *p = malloc(n + 2);
    if (!p) return NULL;
    memcpy(p, path, n + 1);
    for (;;) {
        while (n > 1 && p[n - 1] == '/') p[--n] = '\0';
        char *slash = strrchr(p, '/');
        if (!slash) {
            memcpy(p, ".", 2);
        } else if (slash == p) {
            p[1] = '\0';
        } else {
            *slash = '\0';
        }
        n = strlen(p);
        char *r = realpath(p, NULL);
        if (r || (n == 1 && (p[0] == '.' || p[0] == '/'))) {
            free(p);
            return r;
        }
    }
}

static const char *refuse(fl_sandbox *sb, const char *path, const char *reason) {
    free(sb->why);
    size_t n = strlen(path) + strlen(reason) + 64;
    sb->why = malloc(n);
    if (!sb->why) return "not allowed in the sandbox";
    snprintf(sb->why, n, "%s: not allowed in the sandbox (%s)", path, reason);
    return sb->why;
}

static const char *guard_check_path(fl_lua_guard *g, const char *path, int write) {
    fl_sandbox *sb = (fl_sandbox *)g;
    if (!sb->sandbox) return NULL;
    int dangling;
    char *real = where(path, &dangling);
    if (dangling) return refuse(sb, path, "a symbolic link to nowhere");
    int ok = 0;
    if (real) {
        for (size_t i = 0; i < sb->nallow && !ok; i++) ok = inside(real, sb->allow[i]);
        if (!write && sb->recipe_dir) ok = ok || inside(real, sb->recipe_dir);
    }
    free(real);
    if (ok) return NULL;
    return refuse(sb, path, write ? "writing outside the --allow folders"
                                  : "reading outside the recipe's folder and the --allow folders");
}

/* Raises the refusal at the calling recipe line. */
static void check(lua_State *L, const char *path, int write) {
    const char *why = guard_check_path(&the_sandbox.guard, path, write);
    if (why) luaL_error(L, "%s", why);
}

/* }==================================================================== */

/* {====================================================================
 * The library surface
 * ===================================================================== */

enum wrap { W_OPEN, W_LINES, W_INPUT, W_OUTPUT, W_LOADFILE, W_LOAD };

/* Calls the original (upvalue 1) with the arguments, after the check its
 * kind (upvalue 2) asks for; load and loadfile get mode "t" whatever was
 * asked. */
static int wrapped(lua_State *L) {
    switch ((enum wrap)lua_tointeger(L, lua_upvalueindex(2))) {
    case W_OPEN: {
        const char *path = luaL_checkstring(L, 1);
        const char *mode = luaL_optstring(L, 2, "r");
        check(L, path, strpbrk(mode, "wa+") != NULL);
        break;
    }
    case W_LINES:
    case W_INPUT:
    case W_OUTPUT:
        if (lua_type(L, 1) == LUA_TSTRING)
            check(L, lua_tostring(L, 1), (enum wrap)lua_tointeger(L, lua_upvalueindex(2)) == W_OUTPUT);
        break;
    case W_LOADFILE:
    case W_LOAD: {
        int file = (enum wrap)lua_tointeger(L, lua_upvalueindex(2)) == W_LOADFILE;
        if (file && !lua_isnoneornil(L, 1)) check(L, luaL_checkstring(L, 1), 0);
        int mode = file ? 2 : 3;
        if (lua_gettop(L) < mode) lua_settop(L, mode); /* env stays absent if it was */
        lua_pushliteral(L, "t");
        lua_replace(L, mode);
        break;
    }
    }
    int n = lua_gettop(L);
    lua_pushvalue(L, lua_upvalueindex(1));
    lua_insert(L, 1);
    lua_call(L, n, LUA_MULTRET);
    return lua_gettop(L);
}

/* After a trip, the message handler of an xpcall runs inside the hook that
 * raised, where no hook fires: a handler that loops would never stop. So
 * once the time is up the handler is skipped and the message kept. */
static int guarded_handler(lua_State *L) {
    if (the_sandbox.expired) return 1;
    int n = lua_gettop(L);
    lua_pushvalue(L, lua_upvalueindex(1));
    lua_insert(L, 1);
    lua_call(L, n, LUA_MULTRET);
    return lua_gettop(L);
}

static int finish_call(lua_State *L, int status, lua_KContext ctx) {
    (void)status;
    (void)ctx;
    return lua_gettop(L);
}

static int guarded_xpcall(lua_State *L) {
    luaL_checktype(L, 2, LUA_TFUNCTION);
    lua_pushvalue(L, 2);
    lua_pushcclosure(L, guarded_handler, 1);
    lua_replace(L, 2);
    int n = lua_gettop(L);
    lua_pushvalue(L, lua_upvalueindex(1));
    lua_insert(L, 1);
    /* With a continuation, so that the function may still yield. */
    lua_callk(L, n, LUA_MULTRET, 0, finish_call);
    return finish_call(L, LUA_OK, 0);
}

/* Replaces table[name] (table on the top) with its wrapped version. */
static void wrap_field(lua_State *L, const char *name, enum wrap kind) {
    lua_getfield(L, -1, name);
    lua_pushinteger(L, kind);
    lua_pushcclosure(L, wrapped, 2);
    lua_setfield(L, -2, name);
}

static void remove_fields(lua_State *L, const char *const names[]) {
    for (int i = 0; names[i]; i++) {
        lua_pushnil(L);
        lua_setfield(L, -2, names[i]);
    }
}

static int finish_dofile(lua_State *L, int status, lua_KContext ctx) {
    (void)status;
    (void)ctx;
    return lua_gettop(L) - 1;
}

/* dofile, text only. */
static int sandbox_dofile(lua_State *L) {
    const char *name = luaL_optstring(L, 1, NULL);
    lua_settop(L, 1);
    if (name) check(L, name, 0);
    /* Unlike the stock dofile, a load error gets the caller's position. */
    if (luaL_loadfilex(L, name, "t") != LUA_OK) return luaL_error(L, "%s", lua_tostring(L, -1));
    lua_callk(L, 0, LUA_MULTRET, 0, finish_dofile);
    return finish_dofile(L, LUA_OK, 0);
}

/* require's searcher for NAME.lua in the recipe's folder (dots become /). */
static int search_recipe_folder(lua_State *L) {
    const char *name = luaL_checkstring(L, 1);
    if (!the_sandbox.recipe_dir) {
        lua_pushliteral(L, "no recipe folder to search (sandbox)");
        return 1;
    }
    luaL_Buffer b;
    luaL_buffinit(L, &b);
    luaL_addstring(&b, the_sandbox.recipe_dir);
    luaL_addchar(&b, '/');
    for (const char *p = name; *p; p++) luaL_addchar(&b, *p == '.' ? '/' : *p);
    luaL_addstring(&b, ".lua");
    luaL_pushresult(&b);
    const char *path = lua_tostring(L, -1);
    check(L, path, 0);
    FILE *f = fopen(path, "r");
    if (!f) {
        lua_pushfstring(L, "no file '%s' (sandbox)", path);
        return 1;
    }
    fclose(f);
    if (luaL_loadfilex(L, path, "t") != LUA_OK)
        return luaL_error(L, "error loading module '%s' from file '%s':\n\t%s", name, path,
                          lua_tostring(L, -1));
    lua_pushvalue(L, -2);
    return 2;
}

static void restrict_libraries(lua_State *L) {
    static const char *const os_removed[] = {"execute", "exit", "getenv", "remove",
                                             "rename", "tmpname", NULL};
    static const char *const io_removed[] = {"popen", "tmpfile", NULL};
    static const char *const package_removed[] = {"loadlib", "searchpath", NULL};
    static const char *const string_removed[] = {"dump", NULL};
    static const char *const global_removed[] = {"debug", NULL};

    lua_getglobal(L, "os");
    remove_fields(L, os_removed);
    lua_getglobal(L, "io");
    remove_fields(L, io_removed);
    wrap_field(L, "open", W_OPEN);
    wrap_field(L, "lines", W_LINES);
    wrap_field(L, "input", W_INPUT);
    wrap_field(L, "output", W_OUTPUT);
    lua_getglobal(L, "string");
    remove_fields(L, string_removed);
    lua_getglobal(L, "package");
    remove_fields(L, package_removed);
    lua_pushliteral(L, "");
    lua_setfield(L, -2, "path");
    lua_pushliteral(L, "");
    lua_setfield(L, -2, "cpath");
    lua_getfield(L, -1, "loaded");
    remove_fields(L, global_removed); /* package.loaded.debug */
    lua_pop(L, 1);
    /* preload (femlod and its helpers), then the recipe's folder. */
    lua_getfield(L, -1, "searchers");
    lua_createtable(L, 2, 0);
    lua_rawgeti(L, -2, 1);
    lua_rawseti(L, -2, 1);
    lua_pushcfunction(L, search_recipe_folder);
    lua_rawseti(L, -2, 2);
    lua_setfield(L, -3, "searchers");
    lua_pop(L, 5); /* searchers, package, string, io, os */

    lua_pushglobaltable(L);
    remove_fields(L, global_removed);
    wrap_field(L, "load", W_LOAD);
    wrap_field(L, "loadfile", W_LOADFILE);
    lua_pushcfunction(L, sandbox_dofile);
    lua_setfield(L, -2, "dofile");
    lua_pop(L, 1);
}

/* }==================================================================== */

void fl_sandbox_start(fl_sandbox *sb, lua_State *L, const char *recipe) {
    if (!fl_sandbox_active(sb)) return;
    sb->guard.check_path = guard_check_path;
    sb->guard.charge = guard_charge;
    sb->guard.expired = guard_expired;
    if (sb->sandbox) {
        if (recipe) sb->recipe_dir = parent_realpath(recipe);
        restrict_libraries(L);
    }
    lua_pushlightuserdata(L, &sb->guard);
    lua_setfield(L, LUA_REGISTRYINDEX, FL_GUARD_KEY);
    if (sb->cap > 0) limit_address_space(sb);
    if (sb->max_time > 0) start_clock(sb, L);
}

const char *fl_sandbox_stop(fl_sandbox *sb, lua_State *L, const char *msg) {
    if (!fl_sandbox_active(sb)) return NULL;
    if (sb->max_time > 0) {
        struct itimerval off;
        memset(&off, 0, sizeof off);
        setitimer(ITIMER_REAL, &off, NULL);
        lua_sethook(L, NULL, 0, 0);
    }
    sb->cap_lifted = 1;
    if (!sb->refused || !msg) return NULL;
    /* Lua's own memory error, possibly re-raised by error(e) with a position. */
    static const char nomem[] = "not enough memory";
    size_t n = strlen(msg), k = sizeof nomem - 1;
    if (n >= k && strcmp(msg + n - k, nomem) == 0) return sb->memory_message;
    return NULL;
}
