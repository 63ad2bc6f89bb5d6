/*
 * lopts.c - option tables: typed getters, unknown keys rejected with the
 * valid list (LÖVE's luax_checktablefields and luax_enumerror are the model).
 */
#include "lopts.h"

#include <assert.h>
#include <string.h>

static int is_valid_key(const char *const keys[], const char *k) {
    for (size_t i = 0; keys[i]; i++)
        if (strcmp(keys[i], k) == 0) return 1;
    return 0;
}

/* Appends the keys in strcmp order without allocating: repeated selection is
 * quadratic, but lists are a handful of names and this runs only to raise. */
static void add_sorted(luaL_Buffer *b, const char *const keys[]) {
    const char *prev = NULL;
    for (;;) {
        const char *next = NULL;
        for (size_t i = 0; keys[i]; i++) {
            if (prev && strcmp(keys[i], prev) <= 0) continue;
            if (!next || strcmp(keys[i], next) < 0) next = keys[i];
        }
        if (!next) break;
        if (prev) luaL_addstring(b, ", ");
        luaL_addstring(b, next);
        prev = next;
    }
}

static int unknown_key(lua_State *L, int arg, const char *const keys[], int keyidx) {
    luaL_Buffer b;
    luaL_buffinit(L, &b);
    if (lua_type(L, keyidx) == LUA_TSTRING) {
        luaL_addstring(&b, "unknown key '");
        luaL_addstring(&b, lua_tostring(L, keyidx));
        luaL_addstring(&b, "'");
    } else {
        /* A positional entry such as {"obj"} is the usual way to get here. */
        lua_pushfstring(L, "unexpected %s key ", luaL_typename(L, keyidx));
        luaL_addvalue(&b);
        luaL_tolstring(L, keyidx, NULL);
        luaL_addvalue(&b);
    }
    if (keys[0]) {
        luaL_addstring(&b, "; valid keys: ");
        add_sorted(&b, keys);
    } else {
        luaL_addstring(&b, "; this function takes no options");
    }
    luaL_pushresult(&b);
    return luaL_argerror(L, arg, lua_tostring(L, -1));
}

void fl_opts_open(fl_opts *o, lua_State *L, int arg, const char *const keys[]) {
    o->L = L;
    o->arg = arg;
    o->keys = keys;
    o->idx = 0;
    if (lua_isnoneornil(L, arg)) return;
    luaL_checktype(L, arg, LUA_TTABLE);
    o->idx = lua_absindex(L, arg);
    lua_pushnil(L);
    while (lua_next(L, o->idx)) {
        lua_pop(L, 1);
        /* lua_type, not lua_isstring: a number key must not pass as "1". */
        if (lua_type(L, -1) != LUA_TSTRING || !is_valid_key(keys, lua_tostring(L, -1)))
            unknown_key(L, arg, keys, lua_gettop(L));
    }
}

int fl_opts_error(const fl_opts *o, const char *key, const char *message) {
    const char *msg = lua_pushfstring(o->L, "%s: %s", key, message);
    return luaL_argerror(o->L, o->arg, msg);
}

static int type_error(const fl_opts *o, const char *key, const char *expected) {
    const char *msg = lua_pushfstring(o->L, "%s expected, got %s", expected,
                                      luaL_typename(o->L, -1));
    return fl_opts_error(o, key, msg);
}

/* Pushes the value (nil when there is no table) and returns its type. */
static int get(const fl_opts *o, const char *key) {
    assert(is_valid_key(o->keys, key));
    if (!o->idx) {
        lua_pushnil(o->L);
        return LUA_TNIL;
    }
    return lua_getfield(o->L, o->idx, key);
}

int fl_opts_push(const fl_opts *o, const char *key) {
    int t = get(o, key);
    if (t == LUA_TNIL) lua_pop(o->L, 1);
    return t;
}

lua_Number fl_opts_number(const fl_opts *o, const char *key, lua_Number def) {
    lua_Number v = def;
    int t = get(o, key);
    if (t == LUA_TNUMBER) v = lua_tonumber(o->L, -1);
    else if (t != LUA_TNIL) type_error(o, key, "number");
    lua_pop(o->L, 1);
    return v;
}

lua_Integer fl_opts_integer(const fl_opts *o, const char *key, lua_Integer def) {
    lua_Integer v = def;
    int t = get(o, key);
    if (t == LUA_TNUMBER) {
        int isint;
        v = lua_tointegerx(o->L, -1, &isint);
        if (!isint) fl_opts_error(o, key, "number has no integer representation");
    } else if (t != LUA_TNIL) {
        type_error(o, key, "integer");
    }
    lua_pop(o->L, 1);
    return v;
}

int fl_opts_boolean(const fl_opts *o, const char *key, int def) {
    int v = def;
    int t = get(o, key);
    if (t == LUA_TBOOLEAN) v = lua_toboolean(o->L, -1);
    else if (t != LUA_TNIL) type_error(o, key, "boolean");
    lua_pop(o->L, 1);
    return v;
}

const char *fl_opts_string(const fl_opts *o, const char *key, const char *def) {
    const char *v = def;
    int t = get(o, key);
    /* The table keeps the string alive, so the pointer outlives the pop. */
    if (t == LUA_TSTRING) v = lua_tostring(o->L, -1);
    else if (t != LUA_TNIL) type_error(o, key, "string");
    lua_pop(o->L, 1);
    return v;
}

int fl_opts_enum(const fl_opts *o, const char *key, const char *const names[], int def) {
    const char *s = fl_opts_string(o, key, NULL);
    if (!s) return def;
    for (int i = 0; names[i]; i++)
        if (strcmp(names[i], s) == 0) return i;
    luaL_Buffer b;
    luaL_buffinit(o->L, &b);
    luaL_addstring(&b, "invalid value '");
    luaL_addstring(&b, s);
    luaL_addstring(&b, "'; valid values: ");
    /* Declaration order: the caller lists values in their natural order. */
    for (int i = 0; names[i]; i++) {
        if (i) luaL_addstring(&b, ", ");
        luaL_addstring(&b, names[i]);
    }
    luaL_pushresult(&b);
    return fl_opts_error(o, key, lua_tostring(o->L, -1));
}

/* {====== The progress option */

femlod_progress_fn fl_opts_progress(const fl_opts *o, fl_progress_call *pc) {
    lua_State *L = o->L;
    memset(pc, 0, sizeof *pc);
    pc->L = L;
    pc->scale = 1.0;
    pc->failed = FL_PROGRESS_OK;
    pc->guard = fl_lua_guard_get(L);
    /* Under a time cap the core polls it through the progress callback. */
    if (pc->guard && !pc->guard->time_message) pc->guard = NULL;
    int t = fl_opts_push(o, "progress");
    if (t != LUA_TNIL) {
        if (t != LUA_TFUNCTION)
            fl_opts_error(o, "progress",
                          lua_pushfstring(L, "function expected, got %s", luaL_typename(L, -1)));
        pc->fn = lua_gettop(L);
    }
    luaL_checkstack(L, 4, NULL); /* for fl_progress_call_fn, which must not raise */
    return pc->fn || pc->guard ? fl_progress_call_fn : NULL;
}

/* The stack space was reserved by fl_opts_progress, and every call leaves
 * the stack as it found it, except the failing one, which leaves the error
 * value. */
int fl_progress_call_fn(void *payload, double done) {
    fl_progress_call *pc = (fl_progress_call *)payload;
    lua_State *L = pc->L;
    if (pc->failed != FL_PROGRESS_OK) return 1;
    if (pc->guard && pc->guard->expired(pc->guard, L)) {
        pc->failed = FL_PROGRESS_LIMIT;
        return 1;
    }
    if (!pc->fn) return 0;
    if (pc->stopped) return !pc->keep_going;
    lua_pushvalue(L, pc->fn);
    lua_pushnumber(L, pc->offset + pc->scale * done);
    if (lua_pcall(L, 1, 1, 0) != LUA_OK) {
        pc->failed = FL_PROGRESS_ERROR;
        return 1;
    }
    int t = lua_type(L, -1);
    pc->stopped = lua_toboolean(L, -1);
    int stop = pc->stopped && !pc->keep_going;
    if (t != LUA_TNIL && t != LUA_TBOOLEAN) {
        pc->failed = FL_PROGRESS_BAD_RESULT;
        pc->got = lua_typename(L, t);
        stop = 1;
    }
    lua_pop(L, 1);
    return stop;
}

void fl_opts_progress_check(const fl_opts *o, fl_progress_call *pc, femlod_status st) {
    lua_State *L = o->L;
    if (pc->failed == FL_PROGRESS_ERROR) lua_error(L);
    if (pc->failed == FL_PROGRESS_LIMIT) fl_lua_raise_limit(L, 1, pc->guard->time_message);
    if (pc->failed == FL_PROGRESS_BAD_RESULT)
        fl_opts_error(o, "progress",
                      lua_pushfstring(L, "function returned %s (boolean or nil expected)", pc->got));
    if (st == FEMLOD_ECANCELLED && pc->fn) luaL_error(L, "cancelled");
}

/* }====== */
