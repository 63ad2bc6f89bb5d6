/*
 * help.h - the femlod program's help texts (help.c): the overview of
 * `femlod --help` and one page per command (`femlod help COMMAND`,
 * `femlod COMMAND --help`). docs/cli.md shows the same texts, and
 * tests/lua/test_help.lua checks that they agree. Below main.c.
 */
#ifndef FEMLOD_CLI_HELP_H
#define FEMLOD_CLI_HELP_H

#include <stdio.h>

/* Prints the overview: every command in a line, the program's options. */
void fl_cli_help_overview(FILE *f);

/* Prints the page of command name ("simplify", "-e", "help"); returns 0, or
 * -1 when there is no such command. */
int fl_cli_help_command(FILE *f, const char *name);

/* The first line of command name's usage ("simplify IN OUT [options]"),
 * its length in *len; NULL for no such command. */
const char *fl_cli_help_synopsis(const char *name, int *len);

/* The command words, NULL-terminated (for "did you mean"). */
extern const char *const fl_cli_command_names[];

#endif
