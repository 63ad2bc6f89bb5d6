/*
 * sandbox.h - the femlod program's --sandbox, --allow, --max-memory and
 * --max-time (docs/design.md, "Safe recipes"). One per process: the caps use
 * process-wide resources (a signal, setrlimit).
 */
#ifndef FEMLOD_CLI_SANDBOX_H
#define FEMLOD_CLI_SANDBOX_H

#include "lua/lfemlod.h"

#include <stddef.h>

typedef struct fl_sandbox fl_sandbox;

/* The one instance, zeroed: no sandbox, no caps. */
fl_sandbox *fl_sandbox_get(void);

/* The counting allocator the program's Lua state runs on (lua_newstate). */
void *fl_sandbox_alloc(void *ud, void *ptr, size_t osize, size_t nsize);

/* Command-line settings; each returns NULL or a usage message (static or in
 * a buffer that lives until the next call). */
void fl_sandbox_enable(fl_sandbox *sb);
const char *fl_sandbox_allow(fl_sandbox *sb, const char *dir);
const char *fl_sandbox_max_memory(fl_sandbox *sb, const char *value);
const char *fl_sandbox_max_time(fl_sandbox *sb, const char *value);
/* True when any of the above was given. */
int fl_sandbox_active(const fl_sandbox *sb);
/* "--sandbox" or "--allow" when given (--sandbox first), otherwise NULL. */
const char *fl_sandbox_confines(const fl_sandbox *sb);

/* Called once the libraries and the module are open, before the recipe
 * (recipe: its path, NULL for standard input and -e): removes and wraps the
 * library functions (with --sandbox), installs the guard, starts the clock
 * and sets the process limits. Raises on memory errors only. */
void fl_sandbox_start(fl_sandbox *sb, lua_State *L, const char *recipe);

/* Called before the program reports the run's end: lifts the caps, so that
 * reporting cannot trip them. Returns the message of the memory cap when the
 * run died of the Lua allocator's refusal (msg is Lua's memory error),
 * otherwise NULL. */
const char *fl_sandbox_stop(fl_sandbox *sb, lua_State *L, const char *msg);

#endif
