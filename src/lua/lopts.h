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

#include "lutil.h"

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

/* {====== The `progress` option: a Lua function called from the core
 * through lua_pcall (no Lua error may cross the core). Its errors, a result
 * other than a boolean or nil, and the time cap (--max-time, polled through
 * the same callback) are recorded and raised once the core returned. */

enum { FL_PROGRESS_OK, FL_PROGRESS_ERROR, FL_PROGRESS_BAD_RESULT, FL_PROGRESS_LIMIT };

typedef struct fl_progress_call {
    lua_State *L;
    int fn;              /* stack index of the function; 0 for none */
    fl_lua_guard *guard; /* polled for the time cap when not NULL */
    int failed;          /* FL_PROGRESS_*; on FL_PROGRESS_ERROR the error value is on the top */
    const char *got;     /* FL_PROGRESS_BAD_RESULT: type name of the result (static) */
    double offset, scale; /* the function sees offset + scale * done */
    int keep_going;      /* nonzero: a true result stops nothing */
    int stopped;         /* the function returned true: it is not called again */
} fl_progress_call;

/* Reads the option `progress` (nil or a function, left on the stack) of o
 * into pc; returns the callback to give the core, or NULL when neither a
 * function nor a time cap needs one. Reserves the stack space the callback
 * needs (it must not raise). */
FL_LUA_INTERNAL femlod_progress_fn fl_opts_progress(const fl_opts *o, fl_progress_call *pc);
/* The femlod_progress_fn: nothing in it raises. */
FL_LUA_INTERNAL int fl_progress_call_fn(void *payload, double done);
/* After the core returned st: raises what pc recorded (the function's own
 * error value, the time cap, a bad result), then "cancelled" when the
 * function stopped the operation (st FEMLOD_ECANCELLED). Returns otherwise. */
FL_LUA_INTERNAL void fl_opts_progress_check(const fl_opts *o, fl_progress_call *pc,
                                            femlod_status st);

/* }====== */

#endif
