/*
 * cliutil.c - owns what the femlod program's command files share
 * (cliutil.h): the usage error (one line naming the problem, one pointing at
 * the help) and femlod.load called from C. Below main.c, sweep.c and
 * report.c; it calls none of them.
 */
#include "cliutil.h"

#include <stdarg.h>
#include <stdio.h>

int fl_cli_usage_error(const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    fputs(FL_CLI_PROGNAME ": ", stderr);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputs("\nusage: " FL_CLI_PROGNAME " [options] COMMAND [ARGS] [name=value ...]"
          " (try '" FL_CLI_PROGNAME " --help')\n",
          stderr);
    fflush(stderr);
    return FL_CLI_EXIT_USAGE;
}

void fl_cli_load_mesh(lua_State *L, int module, const char *path, const char *format) {
    lua_getfield(L, module, "load");
    lua_pushstring(L, path);
    lua_createtable(L, 0, 1);
    if (format) {
        lua_pushstring(L, format);
        lua_setfield(L, -2, "format");
    }
    lua_call(L, 2, 1);
}
