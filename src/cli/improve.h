/* improve.h - `femlod improve IN OUT [flags]` (improve.c). */
#ifndef FEMLOD_CLI_IMPROVE_H
#define FEMLOD_CLI_IMPROVE_H

#include <lua.h>

/* args[0] = IN, args[1] = OUT, then the flags; returns the exit status. */
int fl_cli_improve(lua_State *L, int nargs, char **args, int quiet);

#endif
