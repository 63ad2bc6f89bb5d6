/*
 * sweep.h - `femlod sweep`, `femlod run --record` (sweep.c) and `femlod report`
 * (report.c), called by main.c; what they share with it is in cliutil.h.
 */
#ifndef FEMLOD_CLI_SWEEP_H
#define FEMLOD_CLI_SWEEP_H

#include <lua.h>

/* The options main.c parsed before the command, passed on to the workers. */
typedef struct fl_sweep_cli {
    int argc;
    char **argv;
    int operand;       /* argv index of RECIPE.lua */
    lua_Integer seed;
    int quiet, verbose, traceback;
} fl_sweep_cli;

/* `femlod sweep RECIPE.lua ...`: returns the exit status (0 every point ran
 * and succeeded, 1 some point failed or crashed, 2 usage error). Runs in the
 * program's Lua state (for the number syntax and the report page). */
int fl_sweep_main(lua_State *L, const fl_sweep_cli *c);

/* `femlod report MESH [--reference ORIGINAL] [--html OUT.html] [--no-viewer]`
 * (report.c): prints the summary of femlod.report; returns the exit status. */
int fl_report_main(lua_State *L, const fl_sweep_cli *c);

/* --record FILE, before a recipe runs: starts femlod.sweep's record with the
 * global params and the recipe as the first file read, and installs its hook
 * (FL_IO_HOOK). Raises on failure. */
void fl_record_start(lua_State *L, const char *recipe);
/* After the recipe: writes FILE (atomically) with the record, the SHA-256 and
 * size of every file read and written, and error (the recipe's message, or
 * NULL when it succeeded). Returns 0, or prints why it could not on stderr
 * and returns 1. Never raises. */
int fl_record_write(lua_State *L, const char *path, const char *error);

#endif
