/*
 * cliutil.h - what the femlod program's command files share (cliutil.c):
 * usage errors, "did you mean", the checks of input and output paths made
 * before any work, and loading a mesh through the module. Below main.c,
 * which dispatches the commands, and sweep.c and report.c, which run some of
 * them.
 */
#ifndef FEMLOD_CLI_CLIUTIL_H
#define FEMLOD_CLI_CLIUTIL_H

#include <lua.h>

#include <stddef.h>

#define FL_CLI_PROGNAME "femlod"

/* The exit status of a usage error. */
#define FL_CLI_EXIT_USAGE 2

/* The command being run ("simplify"), or NULL: the usage hint then points at
 * its own help. name must outlive the program's run (a literal). */
void fl_cli_set_command(const char *name);

/* Prints "femlod: MESSAGE" and the usage hint on stderr; returns
 * FL_CLI_EXIT_USAGE. */
#if defined(__GNUC__)
__attribute__((format(printf, 1, 2)))
#endif
int fl_cli_usage_error(const char *fmt, ...);

/* The name in names (NULL-terminated) closest to word[0..len) by edit
 * distance, when it is close enough to be a likely misspelling; else NULL. */
const char *fl_cli_suggest(const char *word, size_t len, const char *const *names);

/* The usage error for an unknown option or parameter word[0..len), spelled
 * as the user did: "unknown option '--targt'; did you mean --target?", or
 * with the valid names when none is close. names are the valid spellings in
 * the same style as word (with or without "--"); list is how they are
 * shown. */
int fl_cli_unknown(const char *what, const char *word, size_t len, const char *const *names,
                   const char *list);

/* Before any work: an input file that is a folder, or a saved hierarchy (the
 * lod command's) given as a mesh, is a usage error. what is "mesh",
 * "hierarchy" or "recipe". Returns -1 when
 * the path may be read (a missing file is left to the reader, exit 1), or
 * the usage error's exit status. */
int fl_cli_check_input(const char *path, const char *what);

/* Before any work: the output's folder exists, is a folder and may be
 * written in; the path is neither a folder nor a read-only file; and
 * (format NULL) the extension names a format the program writes. Returns -1
 * or the usage error's exit status. */
int fl_cli_check_output(const char *path, const char *format);

/* Pushes a name=value pair's value: Lua's number syntax, then true and
 * false, else the string. */
void fl_cli_push_value(lua_State *L, const char *s);

/* One option of a command: key as in name=value (with '_'); a switch takes
 * no value (--normals is true, --no-normals false) but may be followed by
 * true or false. */
typedef struct fl_cli_option {
    const char *key;
    int is_switch;
} fl_cli_option;

/* Reads argv[first..argc) as --name VALUE, --name=VALUE or name=VALUE (the
 * name of a flag with '-' where the key has '_'), every name one of
 * options (a NULL-terminated list). Pushes two tables: key -> value
 * (converted as fl_cli_push_value does) and key -> the name as the user
 * spelled it ("--color-by" or "color_by"), for messages. Returns -1, or the
 * usage error's exit status (unknown name, with "did you mean"; a name
 * given twice; a missing value). */
int fl_cli_read_options(lua_State *L, int argc, char **argv, int first, const fl_cli_option *options);

/* femlod.load(path, {format = format}) with the module table at index
 * module; leaves the mesh on the stack. A mesh without triangles is an
 * error ("PATH: no triangles"). */
void fl_cli_load_mesh(lua_State *L, int module, const char *path, const char *format);

#endif
