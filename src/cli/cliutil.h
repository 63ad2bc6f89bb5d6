/*
 * cliutil.h - what the femlod program's command files share (cliutil.c):
 * usage errors and loading a mesh through the module. Below main.c, which
 * dispatches the commands, and sweep.c and report.c, which run some of them.
 */
#ifndef FEMLOD_CLI_CLIUTIL_H
#define FEMLOD_CLI_CLIUTIL_H

#include <lua.h>

#define FL_CLI_PROGNAME "femlod"

/* The exit status of a usage error. */
#define FL_CLI_EXIT_USAGE 2

/* Prints "femlod: MESSAGE" and the usage hint on stderr; returns
 * FL_CLI_EXIT_USAGE. */
#if defined(__GNUC__)
__attribute__((format(printf, 1, 2)))
#endif
int fl_cli_usage_error(const char *fmt, ...);

/* femlod.load(path, {format = format}) with the module table at index
 * module; leaves the mesh on the stack. */
void fl_cli_load_mesh(lua_State *L, int module, const char *path, const char *format);

#endif
