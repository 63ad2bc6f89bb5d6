/*
 * lopts.h - reading option tables passed to the Lua API.
 *
 * A recipe's typo must never be silently ignored (a sweep over `targt_ratio`
 * would run with the default and look fine), so fl_opts_open rejects every
 * key that is not in the function's list, and the error lists the valid
 * keys. Errors are argument errors of the option table's argument:
 *
 *   bad argument #2 to 'load' (unknown key 'formt'; valid keys: format)
 *   bad argument #2 to 'load' (format: string expected, got number)
 *
 * A missing or nil key gives the default; an absent or nil table is an empty
 * one. Getters may only be called with keys from the list (asserted).
 */
#ifndef FEMLOD_LOPTS_H
#define FEMLOD_LOPTS_H

#include "lfemlod.h"

typedef struct fl_opts {
    lua_State *L;
    int idx;                 /* absolute stack index of the table; 0 when none was given */
    int arg;                 /* argument number, for messages */
    const char *const *keys; /* the valid keys, NULL-terminated */
} fl_opts;

/* Checks argument arg: none or nil, or a table whose keys are all in keys. */
FL_LUA_INTERNAL void fl_opts_open(fl_opts *o, lua_State *L, int arg, const char *const keys[]);

/* Typed getters. Each raises "KEY: T expected, got U" on a wrong type. */
FL_LUA_INTERNAL lua_Number fl_opts_number(const fl_opts *o, const char *key, lua_Number def);
/* An integer, or a float with an exact integer value. */
FL_LUA_INTERNAL lua_Integer fl_opts_integer(const fl_opts *o, const char *key, lua_Integer def);
FL_LUA_INTERNAL int fl_opts_boolean(const fl_opts *o, const char *key, int def);
/* Only strings (numbers are not converted: a number here is a mistake). The
 * string stays valid while the option table is on the stack. */
FL_LUA_INTERNAL const char *fl_opts_string(const fl_opts *o, const char *key, const char *def);
/* The index of the key's string value in names (NULL-terminated), or def when
 * the key is absent; another string raises with the list of valid values. */
FL_LUA_INTERNAL int fl_opts_enum(const fl_opts *o, const char *key, const char *const names[],
                                 int def);
/* Pushes the key's value when it is present and not nil, and returns its type;
 * pushes nothing and returns LUA_TNIL otherwise. For values the other getters
 * do not cover (tables, userdata). */
FL_LUA_INTERNAL int fl_opts_push(const fl_opts *o, const char *key);

/* Raises an argument error about key: "KEY: MESSAGE". */
FL_LUA_INTERNAL int fl_opts_error(const fl_opts *o, const char *key, const char *message);

#endif
