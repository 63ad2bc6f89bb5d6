/*
 * main.c - the femlod program: runs Lua recipes and the info, convert,
 * simplify and lod commands (shaped like Lua's own lua.c: all work happens in pmain, under
 * lua_pcall, and errors are reported once, in main).
 *
 * Grammar: femlod [options] COMMAND [ARGS] [options of the command]; the
 * help texts are in help.c, and what the commands share (usage errors, the
 * reading of --name VALUE / name=VALUE options, the checks of input and
 * output paths before any work) in cliutil.c.
 * Exit status: 0 success, 1 error, 2 usage error, 3 a limit was exceeded.
 *
 * The program never calls setlocale, so the C library stays in the "C"
 * locale: number conversion of name=value pairs (lua_stringtonumber) and all
 * number printing are locale independent.
 */
#include "cliutil.h"
#include "help.h"
#include "improve.h"
#include "lua/lfemlod.h"
#include "sandbox.h"
#include "sweep.h"

#include <lualib.h>

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PROGNAME FL_CLI_PROGNAME

enum { EXIT_OK = 0, EXIT_ERROR = 1, EXIT_USAGE = FL_CLI_EXIT_USAGE, EXIT_LIMIT = 3 };

typedef enum command {
    CMD_NONE, CMD_RUN, CMD_EVAL, CMD_INFO, CMD_CONVERT, CMD_SIMPLIFY, CMD_LOD, CMD_SWEEP, CMD_REPORT,
    CMD_REPAIR, CMD_IMPROVE
} command;

/* What the command line asked for. Indices point into argv. */
typedef struct cli {
    int argc;
    char **argv;
    lua_Integer seed;
    int quiet, verbose, traceback;
    const char *record; /* --record FILE, or NULL */
    command cmd;
    int script;     /* argv index that becomes arg[0] (lua.c's convention); 0 for -e */
    int operand;    /* first operand: recipe, code, mesh or input */
    int pairs;      /* first name=value pair */
} cli;

static void print_version(void) {
    printf(PROGNAME " " FEMLOD_VERSION_STRING " (" LUA_RELEASE ")\n");
}

/* {====================================================================
 * Command line
 * ===================================================================== */

/* Lua's own conversion (lua_stringtonumber) decides what is a number. */
static int parse_seed(lua_State *L, cli *c, const char *s) {
    int isint = 0;
    if (lua_stringtonumber(L, s)) {
        c->seed = lua_tointegerx(L, -1, &isint);
        lua_pop(L, 1);
    }
    if (!isint) return fl_cli_usage_error("--seed: integer expected, got '%s'", s);
    return EXIT_OK;
}

/* --sandbox, --allow DIR, --max-memory SIZE, --max-time SECONDS (also
 * spelled --name=value): returns -2 when argv[*i] is none of them, -1 when
 * it was taken (with its value), or a usage error's exit status. */
static int sandbox_option(cli *c, int *i) {
    static const char *const named[] = {"--allow", "--max-memory", "--max-time"};
    const char *a = c->argv[*i];
    fl_sandbox *sb = fl_sandbox_get();
    if (strcmp(a, "--sandbox") == 0) {
        fl_sandbox_enable(sb);
        return -1;
    }
    for (int k = 0; k < 3; k++) {
        size_t n = strlen(named[k]);
        if (strncmp(a, named[k], n) != 0 || (a[n] != '\0' && a[n] != '=')) continue;
        const char *v = a + n + 1;
        if (a[n] == '\0') {
            if (*i + 1 >= c->argc) return fl_cli_usage_error("%s needs a value", named[k]);
            v = c->argv[++*i];
        }
        const char *msg = k == 0 ? fl_sandbox_allow(sb, v)
                        : k == 1 ? fl_sandbox_max_memory(sb, v)
                                 : fl_sandbox_max_time(sb, v);
        if (msg)
            return k == 0 ? fl_cli_usage_error("%s", msg) : fl_cli_usage_error("%s '%s'", msg, v);
        return -1;
    }
    return -2;
}

/* Not a command word: a recipe when it looks like a file name. */
static int looks_like_recipe(const char *s) {
    size_t n = strlen(s);
    return strchr(s, '/') != NULL || (n > 4 && strcmp(s + n - 4, ".lua") == 0);
}

/* An unknown command word: the nearest command, or the list. */
static int unknown_command(const char *w) {
    const char *near = fl_cli_suggest(w, strlen(w), fl_cli_command_names);
    if (near) return fl_cli_usage_error("unknown command '%s'; did you mean %s?", w, near);
    return fl_cli_usage_error("unknown command '%s' (valid: run, -e, info, convert, repair, "
                              "simplify, lod, sweep, report, help)", w);
}

/* Fills c from argv; returns -1 to go on, or an exit status (help, version,
 * usage error). */
static int parse_args(lua_State *L, cli *c) {
    int i = 1;
    for (; i < c->argc; i++) {
        const char *a = c->argv[i];
        if (a[0] != '-' || strcmp(a, "-") == 0 || strcmp(a, "-e") == 0) break;
        if (strcmp(a, "--") == 0) {
            i++;
            break;
        }
        if (strcmp(a, "-h") == 0 || strcmp(a, "--help") == 0) {
            fl_cli_help_overview(stdout);
            return EXIT_OK;
        }
        if (strcmp(a, "--version") == 0) {
            print_version();
            return EXIT_OK;
        }
        if (strcmp(a, "--quiet") == 0 || strcmp(a, "-q") == 0) {
            c->quiet = 1;
        } else if (strcmp(a, "--verbose") == 0 || strcmp(a, "-v") == 0) {
            c->verbose = 1;
        } else if (strcmp(a, "--traceback") == 0) {
            c->traceback = 1;
        } else if (strcmp(a, "--record") == 0 || strncmp(a, "--record=", 9) == 0) {
            if (a[8] == '=') {
                c->record = a + 9;
            } else {
                if (i + 1 >= c->argc) return fl_cli_usage_error("%s needs a value", a);
                c->record = c->argv[++i];
            }
            if (!*c->record) return fl_cli_usage_error("--record: file name expected, got ''");
        } else if (strcmp(a, "--seed") == 0) {
            if (i + 1 >= c->argc) return fl_cli_usage_error("%s needs a value", a);
            int st = parse_seed(L, c, c->argv[++i]);
            if (st != EXIT_OK) return st;
        } else if (strncmp(a, "--seed=", 7) == 0) {
            int st = parse_seed(L, c, a + 7);
            if (st != EXIT_OK) return st;
        } else {
            int st = sandbox_option(c, &i);
            if (st == -2) {
                static const char *const global[] = {
                    "--seed", "--quiet", "--verbose", "--traceback", "--record", "--sandbox",
                    "--allow", "--max-memory", "--max-time", "--help", "--version", NULL};
                const char *eq = strchr(a, '=');
                size_t len = eq ? (size_t)(eq - a) : strlen(a);
                const char *near = fl_cli_suggest(a, len, global);
                /* A command's option before the command word. */
                if (!near)
                    return fl_cli_usage_error("unknown option '%.*s' (the options of a command "
                                              "follow it: femlod help COMMAND)", (int)len, a);
                return fl_cli_usage_error("unknown option '%.*s'; did you mean %s?", (int)len, a, near);
            }
            if (st >= 0) return st;
        }
    }
    if (c->quiet && c->verbose)
        return fl_cli_usage_error("--quiet and --verbose exclude each other");
    if (i >= c->argc) return fl_cli_usage_error("no command given");

    const char *w = c->argv[i];
    int need = 1; /* operands after the command word */
    if (strcmp(w, "-e") == 0) {
        c->cmd = CMD_EVAL;
    } else if (strcmp(w, "run") == 0) {
        c->cmd = CMD_RUN;
        fl_cli_set_command("run");
        /* femlod run --sandbox --allow out RECIPE.lua: the sandbox's options
         * may follow the word run. */
        while (i + 1 < c->argc && strncmp(c->argv[i + 1], "--", 2) == 0) {
            if (strcmp(c->argv[i + 1], "--help") == 0) {
                fl_cli_help_command(stdout, "run");
                return EXIT_OK;
            }
            if (strcmp(c->argv[i + 1], "--") == 0) {
                i++;
                break;
            }
            i++;
            int st = sandbox_option(c, &i);
            if (st == -2) {
                static const char *const run_opts[] = {"--sandbox", "--allow", "--max-memory",
                                                       "--max-time", "--help", NULL};
                const char *a = c->argv[i], *eq = strchr(a, '=');
                return fl_cli_unknown("option", a, eq ? (size_t)(eq - a) : strlen(a), run_opts,
                                      "--sandbox, --allow, --max-memory, --max-time");
            }
            if (st >= 0) return st;
        }
    } else if (strcmp(w, "info") == 0) {
        c->cmd = CMD_INFO;
    } else if (strcmp(w, "convert") == 0) {
        c->cmd = CMD_CONVERT;
        need = 2;
    } else if (strcmp(w, "simplify") == 0) {
        c->cmd = CMD_SIMPLIFY;
        need = 2;
    } else if (strcmp(w, "repair") == 0) {
        c->cmd = CMD_REPAIR;
        need = 2;
    } else if (strcmp(w, "improve") == 0) {
        c->cmd = CMD_IMPROVE;
        need = 2;
    } else if (strcmp(w, "lod") == 0) {
        c->cmd = CMD_LOD;
        need = 2;
    } else if (strcmp(w, "sweep") == 0) {
        c->cmd = CMD_SWEEP;
    } else if (strcmp(w, "report") == 0) {
        c->cmd = CMD_REPORT;
    } else if (strcmp(w, "help") == 0) {
        if (i + 1 >= c->argc) {
            fl_cli_help_overview(stdout);
            return EXIT_OK;
        }
        const char *topic = c->argv[i + 1];
        if (strcmp(topic, "--help") == 0 || strcmp(topic, "-h") == 0) topic = "help";
        if (i + 2 < c->argc) return fl_cli_usage_error("help: one command expected, got '%s' too", c->argv[i + 2]);
        if (fl_cli_help_command(stdout, topic) == 0) return EXIT_OK;
        return unknown_command(topic);
    } else if (looks_like_recipe(w) || strcmp(w, "-") == 0) {
        c->cmd = CMD_RUN; /* femlod RECIPE.lua, as lua RECIPE.lua */
        need = 0;
        i--;              /* the word itself is the operand */
    } else {
        return unknown_command(w);
    }
    static const char *const names[] = {"", "run", "-e", "info", "convert", "simplify",
                                        "lod", "sweep", "report", "repair", "improve"};
    if (need) fl_cli_set_command(names[c->cmd]);
    /* femlod COMMAND --help (or -h): the command's page. For run and -e only
     * right after the word: what follows the recipe is the recipe's. */
    for (int k = i + 1; k < c->argc && need; k++) {
        const char *a = c->argv[k];
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            fl_cli_help_command(stdout, names[c->cmd]);
            return EXIT_OK;
        }
        if (c->cmd == CMD_RUN || c->cmd == CMD_EVAL) break;
    }
    c->operand = i + 1;
    if (c->operand + need > c->argc) {
        static const char *const what[] = {"", "a recipe", "a line of Lua", "a mesh file",
                                           "an input and an output file",
                                           "an input and an output file",
                                           "a hierarchy file and an output file",
                                           "a recipe", "a mesh file",
                                           "an input and an output file",
                                           "an input and an output file"};
        return fl_cli_usage_error("missing %s", what[c->cmd]);
    }
    c->pairs = c->operand + (need ? need : 1);
    const char *confine = fl_sandbox_confines(fl_sandbox_get());
    if (confine && c->cmd != CMD_RUN && c->cmd != CMD_EVAL)
        return fl_cli_usage_error("%s applies to run and -e only", confine);
    if (confine && strcmp(confine, "--allow") == 0)
        return fl_cli_usage_error("--allow needs --sandbox");
    c->script = c->cmd == CMD_RUN ? c->operand : 0;
    if (c->record && c->cmd != CMD_RUN) return fl_cli_usage_error("--record goes with run only");
    return -1;
}

/* Builds the table of the name=value pairs. A pair given twice is an error:
 * in a sweep it is far more often a mistake than an override. */
static int push_pairs(lua_State *L, const cli *c) {
    lua_newtable(L);
    for (int i = c->pairs; i < c->argc; i++) {
        const char *a = c->argv[i];
        const char *eq = strchr(a, '=');
        if (!eq || eq == a) return fl_cli_usage_error("expected name=value, got '%s'", a);
        lua_pushlstring(L, a, (size_t)(eq - a));
        if (lua_rawget(L, -2) != LUA_TNIL) {
            lua_pop(L, 1);
            return fl_cli_usage_error("parameter given twice: '%s'", a);
        }
        lua_pop(L, 1);
        lua_pushlstring(L, a, (size_t)(eq - a));
        fl_cli_push_value(L, eq + 1);
        lua_rawset(L, -3);
    }
    return -1;
}

/* }==================================================================== */

/* {====================================================================
 * Running Lua (lua.c's msghandler and docall)
 * ===================================================================== */

/* Turns any error value into a message; adds the traceback when asked
 * (upvalue 1), since most recipe errors are clear from their first line. */
static int msghandler(lua_State *L) {
    const char *msg = lua_tostring(L, 1);
    if (msg == NULL) {
        if (luaL_callmeta(L, 1, "__tostring") && lua_type(L, -1) == LUA_TSTRING) return 1;
        msg = lua_pushfstring(L, "(error object is a %s value)", luaL_typename(L, 1));
    }
    if (lua_toboolean(L, lua_upvalueindex(1))) luaL_traceback(L, L, msg, 1);
    return 1;
}

/* Calls the function below narg arguments; on error leaves the message. */
static int docall(lua_State *L, int narg, int traceback) {
    int base = lua_gettop(L) - narg;
    lua_pushboolean(L, traceback);
    lua_pushcclosure(L, msghandler, 1);
    lua_insert(L, base);
    int status = lua_pcall(L, narg, 0, base);
    lua_remove(L, base);
    return status;
}

/* Prints the error on the top of the stack and gives the exit status. The
 * caps are lifted first, so that reporting cannot trip them; Lua's own
 * memory error under --max-memory is reported as the cap. */
static int report(lua_State *L) {
    const char *msg = lua_tostring(L, -1);
    const char *cap = fl_sandbox_stop(fl_sandbox_get(), L, msg);
    fflush(stdout);
    fprintf(stderr, PROGNAME ": %s\n", cap ? cap : msg ? msg : "(error object is not a string)");
    fflush(stderr);
    int status = cap || fl_lua_is_limit_error(L, msg) ? EXIT_LIMIT : EXIT_ERROR;
    lua_pop(L, 1);
    return status;
}

/* The global `arg`, as lua.c makes it: arg[0] is the script, the program and
 * the options have negative indices, the pairs positive ones. */
static void set_arg_table(lua_State *L, const cli *c) {
    lua_createtable(L, c->argc - c->script, c->script + 1);
    for (int i = 0; i < c->argc; i++) {
        lua_pushstring(L, c->argv[i]);
        lua_rawseti(L, -2, i - c->script);
    }
    lua_setglobal(L, "arg");
}

/* --record: the record starts before the chunk runs (argument: the recipe's path). */
static int record_start(lua_State *L) {
    fl_record_start(L, lua_tostring(L, 1));
    return 0;
}

/* Whether path opens for reading (errno says why not). */
static int readable(const char *path) {
    FILE *f = fopen(path, "r");
    if (!f) return 0;
    fclose(f);
    return 1;
}

/* Runs a recipe or a line of code with params and arg set, the module in
 * the global `femlod`, math.random seeded, and the sandbox and caps in
 * force when asked for. */
static int cmd_lua(lua_State *L, const cli *c) {
    int st = push_pairs(L, c);
    if (st >= 0) return st;
    lua_setglobal(L, "params");
    set_arg_table(L, c);
    luaL_requiref(L, "femlod", luaopen_femlod, 1);
    lua_pop(L, 1);

    lua_getglobal(L, "math");
    lua_getfield(L, -1, "randomseed");
    lua_pushinteger(L, c->seed);
    lua_call(L, 1, 0);
    lua_pop(L, 1);

    int status;
    const char *src = c->argv[c->operand];
    fl_sandbox_start(fl_sandbox_get(), L,
                     c->cmd == CMD_EVAL || strcmp(src, "-") == 0 ? NULL : src);
    if (c->cmd == CMD_EVAL) {
        status = luaL_loadbufferx(L, src, strlen(src), "=(command line)", "t");
    } else if (strcmp(src, "-") != 0 && (st = fl_cli_check_input(src, "recipe")) >= 0) {
        return st;
    } else if (strcmp(src, "-") != 0 && !readable(src)) {
        /* In the words of every other "cannot open" (lauxlib's differ). */
        int e = errno;
        fprintf(stderr, PROGNAME ": %s: cannot open: %s\n", src, strerror(e));
        if (c->record) {
            lua_pushfstring(L, "%s: cannot open: %s", src, strerror(e));
            fl_record_write(L, c->record, lua_tostring(L, -1));
        }
        return EXIT_ERROR;
    } else {
        /* Text only: bytecode can crash the interpreter (manual, load). */
        status = luaL_loadfilex(L, strcmp(src, "-") == 0 ? NULL : src, "t");
    }
    if (status == LUA_OK && c->record) {
        lua_pushcfunction(L, record_start);
        lua_pushstring(L, strcmp(src, "-") == 0 ? NULL : src);
        status = docall(L, 1, c->traceback);
    }
    if (status != LUA_OK) {
        if (c->record) fl_record_write(L, c->record, lua_tostring(L, -1));
        return report(L);
    }
    /* The pairs are also the chunk's varargs, as script arguments are in lua.c. */
    int n = c->argc - c->pairs;
    luaL_checkstack(L, n + 3, "too many parameters"); /* a C function gets only LUA_MINSTACK */
    for (int i = c->pairs; i < c->argc; i++) lua_pushstring(L, c->argv[i]);
    status = docall(L, n, c->traceback);
    /* The record is written either way: a failed point's reads are worth keeping. */
    int rec = c->record ? fl_record_write(L, c->record, status == LUA_OK ? NULL : lua_tostring(L, -1)) : 0;
    if (status != LUA_OK) return report(L);
    return rec ? EXIT_ERROR : EXIT_OK;
}

/* }==================================================================== */

/* {====================================================================
 * info and convert: C calls into the module, so that errors carry no
 * recipe position (there is no Lua caller for luaL_error to name).
 * ===================================================================== */

/* Reads the command's options (--name VALUE, --name=VALUE, name=VALUE)
 * after its operands; leaves the spelling table and, on top, the values. */
static int check_pairs(lua_State *L, const cli *c, const fl_cli_option *options) {
    int st = fl_cli_read_options(L, c->argc, c->argv, c->pairs, options);
    if (st >= 0) return st;
    lua_insert(L, -2);
    return -1;
}

/* How the user spelled option key: "--color-by" or "color_by". */
static const char *spelling(lua_State *L, int pairs, const char *key) {
    lua_getfield(L, pairs - 1, key);
    const char *s = lua_tostring(L, -1);
    lua_pop(L, 1); /* the string stays alive in the spelling table */
    return s ? s : key;
}

/* The string value of a pair (converted back from a number if need be:
 * "reference=1" names a file called 1), or NULL. */
static const char *pair_string(lua_State *L, int pairs, const char *key) {
    lua_getfield(L, pairs, key);
    const char *s = lua_isnil(L, -1) ? NULL : luaL_tolstring(L, -1, NULL);
    /* The pairs table keeps no converted string alive: park it in the table. */
    if (s) {
        lua_setfield(L, pairs, key);
        lua_getfield(L, pairs, key);
        s = lua_tostring(L, -1);
    }
    lua_pop(L, s ? 2 : 1);
    return s;
}

static int check_format(const char *key, const char *name) {
    if (name && femlod_format_from_name(name) == FEMLOD_FORMAT_AUTO) {
        char valid[256] = "";
        size_t n = 0;
        for (const char *const *f = femlod_format_names(); *f && n + 16 < sizeof valid; f++)
            n += (size_t)snprintf(valid + n, sizeof valid - n, "%s%s", n ? ", " : "", *f);
        const char *near = fl_cli_suggest(name, strlen(name), femlod_format_names());
        if (near)
            return fl_cli_usage_error("%s: unknown format '%s'; did you mean %s? (valid: %s)", key,
                                      name, near, valid);
        return fl_cli_usage_error("%s: unknown format '%s' (valid: %s)", key, name, valid);
    }
    return -1;
}

/* The pairs format= (of OUT) and input_format= (of IN) of convert and
 * repair, checked: -1, or the usage error's exit status. */
static int io_formats(lua_State *L, int pairs, const char **format, const char **input_format) {
    *format = pair_string(L, pairs, "format");
    *input_format = pair_string(L, pairs, "input_format");
    int st = check_format(spelling(L, pairs, "format"), *format);
    return st >= 0 ? st : check_format(spelling(L, pairs, "input_format"), *input_format);
}

/* Pushes a femlod.progress bar labelled label (drawn only when stderr is a
 * terminal) and returns its index, or pushes nothing and returns 0 under
 * --quiet. */
static int push_bar(lua_State *L, const cli *c, const char *label) {
    if (c->quiet) return 0;
    lua_getglobal(L, "require");
    lua_pushliteral(L, "femlod.progress");
    lua_call(L, 1, 1);
    lua_getfield(L, -1, "bar");
    lua_createtable(L, 0, 1);
    lua_pushstring(L, label);
    lua_setfield(L, -2, "label");
    lua_call(L, 1, 1);
    lua_remove(L, -2);
    return lua_gettop(L);
}

/* Clears the bar at index bar (0: none). */
static void close_bar(lua_State *L, int bar) {
    if (!bar) return;
    lua_getfield(L, bar, "close");
    lua_pushvalue(L, bar);
    lua_call(L, 1, 0);
}

/* Calls method name on the object at obj with nargs arguments already pushed. */
static void call_method(lua_State *L, int obj, const char *name, int nargs, int nres) {
    lua_getfield(L, obj, name);
    lua_pushvalue(L, obj);
    lua_rotate(L, -2 - nargs, 2);
    lua_call(L, nargs + 1, nres);
}

/* The fields of the quality table that report.row prints (triangles,
 * bbox, stretch_avg and _min, size_max, valence_max) of the Mesh at idx,
 * pushed as a table: computed by the same functions as m:quality()
 * (femlod_triangle_stretch and _size in triangle order, valences as
 * distinct neighbours), so the row is the same, without the adjacency,
 * topology, duplicates and angles that m:quality() also computes and the
 * row does not print (5.9% of the instructions of `femlod simplify` on
 * cover.obj to 12,000). Raises on ENOMEM. */
static void push_row_quality(lua_State *L, int idx) {
    const femlod_mesh *m = fl_lmesh_check(L, idx);
    size_t nv = femlod_mesh_vertex_count(m), nt = femlod_mesh_triangle_count(m);
    const double *pos = femlod_mesh_positions(m);
    const uint32_t *tri = femlod_mesh_triangles(m);
    uint32_t *val = malloc((nv ? nv : 1) * sizeof *val);
    femlod_error err;
    if (!val) luaL_error(L, "out of memory");
    if (femlod_valence_array(val, nv, tri, nt, &err) != FEMLOD_OK) {
        free(val);
        luaL_error(L, "%s", err.message);
    }
    uint32_t vmax = 0;
    for (size_t v = 0; v < nv; v++)
        if (val[v] > vmax) vmax = val[v];
    free(val);
    double sum = 0.0, smin = INFINITY, zmax = 0.0;
    for (size_t t = 0; t < nt; t++) {
        const double *a = pos + 3 * (size_t)tri[3 * t], *b = pos + 3 * (size_t)tri[3 * t + 1],
                     *c = pos + 3 * (size_t)tri[3 * t + 2];
        double st = femlod_triangle_stretch(a, b, c), sz = femlod_triangle_size(a, b, c);
        sum += st;
        if (st < smin) smin = st;
        if (sz > zmax) zmax = sz;
    }
    double lo[3], hi[3];
    femlod_mesh_bbox(m, lo, hi);
    lua_createtable(L, 0, 6);
    lua_pushinteger(L, (lua_Integer)nt);
    lua_setfield(L, -2, "triangles");
    lua_pushnumber(L, nt ? sum / (double)nt : 0.0);
    lua_setfield(L, -2, "stretch_avg");
    lua_pushnumber(L, nt ? smin : 0.0);
    lua_setfield(L, -2, "stretch_min");
    lua_pushnumber(L, zmax);
    lua_setfield(L, -2, "size_max");
    lua_pushinteger(L, (lua_Integer)vmax);
    lua_setfield(L, -2, "valence_max");
    lua_createtable(L, 0, 2);
    const double *ends[2] = {lo, hi};
    static const char *const names[2] = {"min", "max"};
    for (int e = 0; e < 2; e++) {
        lua_createtable(L, 3, 0);
        for (int k = 0; k < 3; k++) {
            lua_pushnumber(L, ends[e][k]);
            lua_rawseti(L, -2, k + 1);
        }
        lua_setfield(L, -2, names[e]);
    }
    lua_setfield(L, -2, "bbox");
}

static const char *base_name(const char *path) {
    const char *slash = strrchr(path, '/');
    return slash ? slash + 1 : path;
}

static int cmd_info(lua_State *L, const cli *c) {
    static const fl_cli_option keys[] = {{"format", 0}, {"reference", 0}, {"report", 0}, {NULL, 0}};
    int st = check_pairs(L, c, keys);
    if (st >= 0) return st;
    int pairs = lua_gettop(L);
    const char *format = pair_string(L, pairs, "format");
    const char *reference = pair_string(L, pairs, "reference");
    const char *mode = pair_string(L, pairs, "report");
    if (!mode) mode = "text";
    if (strcmp(mode, "text") != 0 && strcmp(mode, "row") != 0 && strcmp(mode, "fields") != 0)
        return fl_cli_usage_error("%s: unknown report '%s' (valid: text, row, fields)",
                                  spelling(L, pairs, "report"), mode);
    if ((st = check_format(spelling(L, pairs, "format"), format)) >= 0) return st;

    const char *path = c->argv[c->operand];
    if ((st = fl_cli_check_input(path, "mesh")) >= 0) return st;
    if (reference && (st = fl_cli_check_input(reference, "mesh")) >= 0) return st;
    luaL_requiref(L, "femlod", luaopen_femlod, 0);
    int module = lua_gettop(L);
    fl_cli_load_mesh(L, module, path, format);
    int mesh = lua_gettop(L);
    int nargs = 1, bar = 0;
    if (reference) {
        fl_cli_load_mesh(L, module, reference, NULL);
        int ref = lua_gettop(L);
        bar = push_bar(L, c, "hausdorff");
        lua_pushvalue(L, ref);
        if (bar) {
            lua_createtable(L, 0, 1);
            lua_getfield(L, bar, "update");
            lua_setfield(L, -2, "progress");
            nargs = 2;
        }
    } else {
        lua_pushnil(L);
    }
    call_method(L, mesh, "quality", nargs, 1);
    close_bar(L, bar);
    int q = lua_gettop(L);

    lua_getglobal(L, "require");
    lua_pushliteral(L, "femlod.report");
    lua_call(L, 1, 1);
    lua_getfield(L, -1, mode);
    lua_pushvalue(L, q);
    lua_pushstring(L, base_name(path));
    lua_call(L, 2, 1);
    size_t len;
    const char *text = lua_tolstring(L, -1, &len);
    fwrite(text, 1, len, stdout);
    putchar('\n');
    return EXIT_OK;
}

/* The line convert and repair print for the file they wrote. */
static void print_written(const char *out, const char *format, lua_Integer triangles,
                          lua_Integer vertices) {
    femlod_format f = format ? femlod_format_from_name(format) : femlod_format_from_path(out);
    printf("%s: %lld triangles, %lld vertices (%s)\n", out, (long long)triangles,
           (long long)vertices, f == FEMLOD_FORMAT_AUTO ? "?" : femlod_format_name(f));
}

static int cmd_convert(lua_State *L, const cli *c) {
    static const fl_cli_option keys[] = {{"format", 0},   {"input_format", 0}, {"color_by", 0},
                                         {"normals", 1}, {NULL, 0}};
    int st = check_pairs(L, c, keys);
    if (st >= 0) return st;
    int pairs = lua_gettop(L);
    const char *format, *input_format;
    if ((st = io_formats(L, pairs, &format, &input_format)) >= 0) return st;
    const char *in = c->argv[c->operand], *out = c->argv[c->operand + 1];
    if ((st = fl_cli_check_input(in, "mesh")) >= 0 || (st = fl_cli_check_output(out, format)) >= 0)
        return st;
    /* The glTF options: their values, and that OUT is glTF. */
    int gltf_opts = 0;
    if (lua_getfield(L, pairs, "color_by") != LUA_TNIL) {
        static const char *const measures[] = {"stretch", "size", "valence", "none", NULL};
        const char *m = lua_type(L, -1) == LUA_TSTRING ? lua_tostring(L, -1) : NULL;
        int known = 0;
        for (int k = 0; m && measures[k]; k++) known |= strcmp(measures[k], m) == 0;
        if (!known) {
            const char *v = luaL_tolstring(L, -1, NULL);
            const char *near = fl_cli_suggest(v, strlen(v), measures);
            return fl_cli_usage_error("%s: unknown measure '%s'%s%s%s (valid: stretch, size, valence, none)",
                                      spelling(L, pairs, "color_by"), v, near ? "; did you mean " : "",
                                      near ? near : "", near ? "?" : "");
        }
        gltf_opts = 1;
    }
    if (lua_getfield(L, pairs, "normals") != LUA_TNIL) {
        if (!lua_isboolean(L, -1))
            return fl_cli_usage_error("%s: true or false expected, got '%s'",
                                      spelling(L, pairs, "normals"), luaL_tolstring(L, -1, NULL));
        gltf_opts = 1;
    }
    lua_pop(L, 2);
    if (gltf_opts) {
        femlod_format f = format ? femlod_format_from_name(format) : femlod_format_from_path(out);
        if (f != FEMLOD_FORMAT_GLTF && f != FEMLOD_FORMAT_GLB)
            return fl_cli_usage_error("%s: color_by and normals are glTF options; %s is %s, not "
                                      "gltf or glb", out, out, femlod_format_name(f));
    }

    luaL_requiref(L, "femlod", luaopen_femlod, 0);
    int module = lua_gettop(L);
    fl_cli_load_mesh(L, module, in, input_format);
    int mesh = lua_gettop(L);
    lua_pushstring(L, out);
    lua_createtable(L, 0, 3);
    if (format) {
        lua_pushstring(L, format);
        lua_setfield(L, -2, "format");
    }
    /* glTF options go to mesh:save as given (normals=true is a boolean). */
    lua_getfield(L, pairs, "color_by");
    lua_setfield(L, -2, "color_by");
    lua_getfield(L, pairs, "normals");
    lua_setfield(L, -2, "normals");
    call_method(L, mesh, "save", 2, 0);
    if (!c->quiet) {
        call_method(L, mesh, "counts", 0, 1);
        lua_getfield(L, -1, "triangles");
        lua_getfield(L, -2, "vertices");
        print_written(out, format, lua_tointeger(L, -2), lua_tointeger(L, -1));
    }
    return EXIT_OK;
}

/* femlod repair IN OUT [name=value ...]: m:repair with the pairs as its
 * options (the binding checks them), the result saved, every change
 * printed. */
static int cmd_repair(lua_State *L, const cli *c) {
    static const char *const keys[] = {"weld", "drop_degenerate", "drop_duplicates",
                                       "split_nonmanifold", "orient", "drop_unused"};
    static const fl_cli_option options[] = {
        {"weld", 0},   {"drop_degenerate", 1}, {"drop_duplicates", 1}, {"split_nonmanifold", 1},
        {"orient", 1}, {"drop_unused", 1},     {"format", 0},          {"input_format", 0},
        {NULL, 0}};
    int st = check_pairs(L, c, options);
    if (st >= 0) return st;
    int pairs = lua_gettop(L);
    const char *format, *input_format;
    if ((st = io_formats(L, pairs, &format, &input_format)) >= 0) return st;
    const char *in = c->argv[c->operand], *out = c->argv[c->operand + 1];
    if ((st = fl_cli_check_input(in, "mesh")) >= 0 || (st = fl_cli_check_output(out, format)) >= 0)
        return st;
    luaL_requiref(L, "femlod", luaopen_femlod, 0);
    int module = lua_gettop(L);
    /* the repair options: the pairs without the two formats, checked here
     * so that a bad value is a usage error */
    lua_createtable(L, 0, 6);
    int opts = lua_gettop(L);
    for (int k = 0; k < 6; k++) {
        int t = lua_getfield(L, pairs, keys[k]);
        if (k == 0 && t == LUA_TNUMBER) {
            double w = (double)lua_tonumber(L, -1);
            if (!(w >= 0.0) || !(w < HUGE_VAL))
                return fl_cli_usage_error("%s: a finite length >= 0 or false expected, got %s",
                                          spelling(L, pairs, "weld"), lua_tostring(L, -1));
        } else if (t != LUA_TNIL && t != LUA_TBOOLEAN) {
            return fl_cli_usage_error("%s: %s expected, got '%s'", spelling(L, pairs, keys[k]),
                                      k == 0 ? "a length or false" : "true or false",
                                      luaL_tolstring(L, -1, NULL));
        }
        lua_setfield(L, opts, keys[k]);
    }
    fl_cli_load_mesh(L, module, in, input_format);
    int mesh = lua_gettop(L);
    lua_pushvalue(L, opts);
    call_method(L, mesh, "repair", 1, 2);
    int fixed = lua_gettop(L) - 1, rep = fixed + 1;
    lua_pushstring(L, out);
    lua_createtable(L, 0, 1);
    if (format) {
        lua_pushstring(L, format);
        lua_setfield(L, -2, "format");
    }
    call_method(L, fixed, "save", 2, 0);
    if (c->quiet) return EXIT_OK;
    static const char *const rows[][2] = {
        {"welded", "vertices welded into an earlier one"},
        {"degenerate", "degenerate triangles dropped"},
        {"duplicates", "duplicate triangles dropped"},
        {"split_vertices", "vertex copies cutting non-manifold vertices"},
        {"flipped", "triangles turned over"},
        {"unused", "unused vertices dropped"},
        {"unorientable_edges", "edges left inconsistent (not orientable)"},
        {"nonmanifold_edges_left", "non-manifold edges left"},
    };
    lua_getfield(L, rep, "triangles_in");
    lua_getfield(L, rep, "vertices_in");
    printf("%s: %lld triangles, %lld vertices\n", in, (long long)lua_tointeger(L, -2),
           (long long)lua_tointeger(L, -1));
    lua_pop(L, 2);
    for (size_t r = 0; r < sizeof rows / sizeof rows[0]; r++) {
        lua_getfield(L, rep, rows[r][0]);
        printf("  %8lld  %s\n", (long long)lua_tointeger(L, -1), rows[r][1]);
        lua_pop(L, 1);
    }
    lua_getfield(L, rep, "triangles");
    lua_getfield(L, rep, "vertices");
    print_written(out, format, lua_tointeger(L, -2), lua_tointeger(L, -1));
    return EXIT_OK;
}

/* }==================================================================== */

/* {====================================================================
 * simplify: flags (--min-stretch 0.3, --min-stretch=0.3) or name=value
 * pairs (min_stretch=0.3) after IN and OUT. Every value is checked before
 * IN is read, by the binding's own option reader, so a bad value is a usage
 * error (exit 2) with the same rules as the Lua API.
 * ===================================================================== */

enum { OPT_NUMBER, OPT_THRESHOLD, OPT_SWITCH, OPT_LOCK, OPT_PATH, OPT_SWITCH_OFF };

typedef struct simplify_opt {
    const char *flag, *key;
    int kind;
} simplify_opt;

static const simplify_opt simplify_opts[] = {
    {"--target", "target", OPT_NUMBER},
    {"--ratio", "ratio", OPT_NUMBER},
    {"--tolerance", "tolerance", OPT_THRESHOLD},
    {"--max-deviation", "max_deviation", OPT_THRESHOLD},
    {"--min-stretch", "min_stretch", OPT_THRESHOLD},
    {"--max-size", "max_size", OPT_THRESHOLD},
    {"--max-valence", "max_valence", OPT_THRESHOLD},
    {"--feature-angle", "feature_angle", OPT_THRESHOLD},
    {"--feature-weight", "feature_weight", OPT_THRESHOLD},
    {"--max-normal-change", "max_normal_change", OPT_THRESHOLD},
    {"--keep-boundary", "keep_boundary", OPT_SWITCH},
    {"--area-weighted", "area_weighted", OPT_SWITCH},
    {"--error-order", "error_order", OPT_SWITCH},
    {"--no-error-order", "error_order", OPT_SWITCH_OFF}, /* error_order = false: the paper's order */
    {"--no-improve", "improve", OPT_SWITCH_OFF}, /* the option improve = false */
    {"--fast-above", "fast_above", OPT_THRESHOLD},
    {"--threads", "threads", OPT_NUMBER},
    {"--lock", "lock", OPT_LOCK},
    {"--hierarchy", "hierarchy", OPT_PATH}, /* not a simplify option: the .flh to write */
    {"--hierarchy-floor", "hierarchy_floor", OPT_THRESHOLD},
};
#define N_SIMPLIFY_OPTS (sizeof simplify_opts / sizeof simplify_opts[0])


/* Pushes the list "I,J,K" as a table of integers (range checked later,
 * against the mesh). */
static int push_lock_list(lua_State *L, const char *name, const char *s) {
    lua_newtable(L);
    lua_Integer n = 0;
    const char *p = s;
    for (;;) {
        const char *comma = strchr(p, ',');
        size_t len = comma ? (size_t)(comma - p) : strlen(p);
        char word[32];
        int isint = 0;
        lua_Integer v = 0;
        if (len > 0 && len < sizeof word) {
            memcpy(word, p, len);
            word[len] = '\0';
            if (word[0] >= '0' && word[0] <= '9' && lua_stringtonumber(L, word)) {
                v = lua_tointegerx(L, -1, &isint);
                lua_pop(L, 1);
            }
        }
        if (!isint || v < 1)
            return fl_cli_usage_error("%s: list of vertex indices (1, 2, ...) expected, got '%s'",
                                      name, s);
        lua_pushinteger(L, v);
        lua_rawseti(L, -2, ++n);
        if (!comma) break;
        p = comma + 1;
    }
    return -1;
}

/* Puts one option into the table at opts; name is how the user spelled it
 * (recorded in the table at spell, for messages), value NULL for a flag
 * without one. */
static int set_simplify_opt(lua_State *L, int opts, int spell, const simplify_opt *o,
                            const char *name, const char *value) {
    if (lua_getfield(L, opts, o->key) != LUA_TNIL) {
        lua_pop(L, 1);
        return fl_cli_usage_error("option given twice: '%s'", name);
    }
    lua_pop(L, 1);
    lua_pushstring(L, name);
    lua_setfield(L, spell, o->key);
    switch (o->kind) {
    case OPT_SWITCH_OFF: /* --no-X: X = false; X=true|false as a switch */
        if (!value) {
            lua_pushboolean(L, 0);
            break;
        }
        /* fall through */
    case OPT_SWITCH:
        if (!value || strcmp(value, "true") == 0)
            lua_pushboolean(L, 1);
        else if (strcmp(value, "false") == 0)
            lua_pushboolean(L, 0);
        else
            return fl_cli_usage_error("%s: true or false expected, got '%s'", name, value);
        break;
    case OPT_LOCK: {
        int st = push_lock_list(L, name, value);
        if (st >= 0) return st;
        break;
    }
    case OPT_PATH:
        if (value[0] == '\0') return fl_cli_usage_error("%s: file name expected, got ''", name);
        lua_pushstring(L, value);
        break;
    default:
        if (o->kind == OPT_THRESHOLD && (strcmp(value, "off") == 0 || strcmp(value, "false") == 0))
            lua_pushboolean(L, 0);
        else if (lua_stringtonumber(L, value) == 0)
            return fl_cli_usage_error("%s: number%s expected, got '%s'", name,
                                      o->kind == OPT_THRESHOLD ? " or off" : "", value);
        break;
    }
    lua_setfield(L, opts, o->key);
    return -1;
}

/* The usage error for an unknown option of simplify (flag: spelled --name). */
static int simplify_unknown(const char *word, size_t len, int flag) {
    const char *names[N_SIMPLIFY_OPTS + 1];
    char list[512] = "";
    size_t used = 0, n = 0;
    for (size_t k = 0; k < N_SIMPLIFY_OPTS; k++) {
        /* a key spelled by two flags (--error-order, --no-error-order) once */
        if (!flag && k > 0 && strcmp(simplify_opts[k].key, simplify_opts[k - 1].key) == 0) continue;
        names[n] = flag ? simplify_opts[k].flag : simplify_opts[k].key;
        used += (size_t)snprintf(list + used, used < sizeof list ? sizeof list - used : 0, "%s%s",
                                 n ? ", " : "", names[n]);
        n++;
    }
    names[n] = NULL;
    return fl_cli_unknown(flag ? "option" : "parameter", word, len, names, list);
}

/* Reads the words after IN OUT into an option table; leaves the option
 * table and the spelling table on the stack. */
static int simplify_options(lua_State *L, const cli *c) {
    lua_newtable(L);
    int opts = lua_gettop(L);
    lua_newtable(L);
    int spell = lua_gettop(L);
    for (int i = c->pairs; i < c->argc; i++) {
        const char *a = c->argv[i];
        const simplify_opt *o = NULL;
        const char *value = NULL, *name = a;
        if (strncmp(a, "--", 2) == 0) {
            const char *eq = strchr(a, '=');
            size_t len = eq ? (size_t)(eq - a) : strlen(a);
            for (size_t k = 0; k < N_SIMPLIFY_OPTS && !o; k++)
                if (strlen(simplify_opts[k].flag) == len && strncmp(simplify_opts[k].flag, a, len) == 0)
                    o = &simplify_opts[k];
            if (!o) return simplify_unknown(a, len, 1);
            name = lua_pushlstring(L, a, len); /* popped at the end of the iteration */
            if (eq) {
                value = eq + 1;
                if (o->kind == OPT_SWITCH || o->kind == OPT_SWITCH_OFF)
                    return fl_cli_usage_error("%s takes no value", name);
            } else if (o->kind != OPT_SWITCH && o->kind != OPT_SWITCH_OFF) {
                if (i + 1 >= c->argc) return fl_cli_usage_error("%s needs a value", name);
                value = c->argv[++i];
            }
        } else {
            const char *eq = strchr(a, '=');
            if (!eq || eq == a) return fl_cli_usage_error("expected name=value, got '%s'", a);
            size_t len = (size_t)(eq - a);
            for (size_t k = 0; k < N_SIMPLIFY_OPTS && !o; k++)
                if (strlen(simplify_opts[k].key) == len && strncmp(simplify_opts[k].key, a, len) == 0)
                    o = &simplify_opts[k];
            if (!o) return simplify_unknown(a, len, 0);
            name = lua_pushlstring(L, a, len);
            value = eq + 1;
        }
        int st = set_simplify_opt(L, opts, spell, o, name, value);
        if (st >= 0) return st;
        lua_settop(L, spell);
    }
    femlod_simplify_options so = FEMLOD_SIMPLIFY_OPTIONS_INIT;
    const char *key;
    const char *msg = fl_simplify_read_options(L, opts, &so, "off", &key);
    if (msg) {
        if (!key) { /* the one message about two keys */
            lua_getfield(L, spell, "target");
            lua_getfield(L, spell, "ratio");
            return fl_cli_usage_error("give %s or %s, not both", lua_tostring(L, -2),
                                      lua_tostring(L, -1));
        }
        lua_getfield(L, spell, key);
        /* The binding's words for a Lua table; on the command line a
         * threshold is turned off with "off". */
        const char *cli_msg = luaL_gsub(L, msg, " or boolean", " or off");
        return fl_cli_usage_error("%s: %s", lua_tostring(L, -2), cli_msg);
    }
    lua_settop(L, spell);
    return -1;
}

static int cmd_simplify(lua_State *L, const cli *c) {
    const char *in = c->argv[c->operand], *out = c->argv[c->operand + 1];
    if (strncmp(in, "--", 2) == 0 || strncmp(out, "--", 2) == 0)
        return fl_cli_usage_error("simplify: IN and OUT come first, then the options");
    int st = simplify_options(L, c);
    if (st >= 0) return st;
    int spell = lua_gettop(L), opts = spell - 1;
    /* --hierarchy is the program's, not the simplification's. It is
     * checked first, as it is written first. */
    lua_getfield(L, opts, "hierarchy");
    int flh = lua_gettop(L);
    if ((st = fl_cli_check_input(in, "mesh")) >= 0 ||
        (!lua_isnil(L, flh) && (st = fl_cli_check_output(lua_tostring(L, flh), "flh")) >= 0) ||
        (st = fl_cli_check_output(out, NULL)) >= 0)
        return st;
    /* Without a hierarchy to write (and no --hierarchy-floor), none is
     * built: no collapse log, and the improve stage's polish may run
     * (docs/cli.md). */
    if (lua_isnil(L, flh) && lua_getfield(L, opts, "hierarchy_floor") == LUA_TNIL)
        lua_pushboolean(L, 0);
    else
        lua_pushnil(L);
    lua_setfield(L, opts, "hierarchy");
    lua_settop(L, flh);

    luaL_requiref(L, "femlod", luaopen_femlod, 0);
    int module = lua_gettop(L);
    fl_cli_load_mesh(L, module, in, NULL);
    int mesh = lua_gettop(L);
    /* The lock indices against the mesh: a usage error too. */
    if (lua_getfield(L, opts, "lock") == LUA_TTABLE) {
        call_method(L, mesh, "counts", 0, 1);
        lua_getfield(L, -1, "vertices");
        lua_Integer nv = lua_tointeger(L, -1);
        lua_pop(L, 2);
        for (lua_Integer k = 1; lua_rawgeti(L, -1, k) == LUA_TNUMBER; k++) {
            lua_Integer v = lua_tointeger(L, -1);
            lua_pop(L, 1);
            if (v > nv) {
                lua_getfield(L, spell, "lock");
                return fl_cli_usage_error("%s: vertex %lld out of range (1..%lld)",
                                          lua_tostring(L, -1), (long long)v, (long long)nv);
            }
        }
        lua_pop(L, 1);
    }
    lua_pop(L, 1);

    /* A target at or above the input's size leaves nothing to do: say so,
     * since the report alone would look like a failure. */
    if (!c->quiet) {
        call_method(L, mesh, "counts", 0, 1);
        lua_getfield(L, -1, "triangles");
        lua_Integer nt = lua_tointeger(L, -1);
        lua_pop(L, 2);
        int tt = lua_getfield(L, opts, "target"), rt = lua_getfield(L, opts, "ratio");
        if (tt == LUA_TNUMBER && lua_tonumber(L, -2) >= (lua_Number)nt) {
            lua_getfield(L, spell, "target");
            fprintf(stderr, PROGNAME ": %s %s is not below %s's %lld triangles: nothing to simplify\n",
                    lua_tostring(L, -1), lua_tostring(L, -3), base_name(in), (long long)nt);
            lua_pop(L, 1);
        } else if (rt == LUA_TNUMBER && lua_tonumber(L, -1) >= 1) {
            lua_getfield(L, spell, "ratio");
            fprintf(stderr, PROGNAME ": %s %s keeps all of %s's %lld triangles: nothing to simplify\n",
                    lua_tostring(L, -1), lua_tostring(L, -2), base_name(in), (long long)nt);
            lua_pop(L, 1);
        }
        lua_pop(L, 2);
    }

    /* A progress bar on stderr when it is a terminal (femlod.progress); it
     * covers the building of the hierarchy too, when one is built. */
    int bar = push_bar(L, c, "simplify");
    if (bar) {
        lua_getfield(L, bar, "update");
        lua_setfield(L, opts, "progress");
    }
    lua_pushvalue(L, opts);
    call_method(L, mesh, "simplify", 1, 1);
    close_bar(L, bar);
    int h = lua_gettop(L);
    call_method(L, h, "mesh", 0, 1);
    int result = lua_gettop(L);
    /* The hierarchy first: OUT is written last, so that OUT exists only
     * when everything asked for was written. */
    if (!lua_isnil(L, flh)) {
        lua_pushvalue(L, flh);
        call_method(L, h, "save", 1, 0);
    }
    lua_pushstring(L, out);
    call_method(L, result, "save", 1, 0);
    if (c->quiet) return EXIT_OK;

    lua_getglobal(L, "require");
    lua_pushliteral(L, "femlod.report");
    lua_call(L, 1, 1);
    int report_mod = lua_gettop(L);
    /* What the report needs of the hierarchy, then the hierarchy goes: the
     * input's quality below builds its adjacency, which should not come on
     * top of the hierarchy (on 1.25M triangles 270 + 110 MB). */
    lua_getfield(L, report_mod, "stats");
    lua_pushvalue(L, h);
    lua_call(L, 1, 1);
    int stats_line = lua_gettop(L);
    lua_Integer counts[3] = {0, 0, 0};
    if (!lua_isnil(L, flh)) {
        call_method(L, h, "counts", 0, 1);
        static const char *const keys[] = {"nodes", "input_vertices", "collapses"};
        for (int k = 0; k < 3; k++) {
            lua_getfield(L, -1, keys[k]);
            counts[k] = lua_tointeger(L, -1);
            lua_pop(L, 1);
        }
        lua_pop(L, 1);
    }
    call_method(L, h, "close", 0, 0);
    const char *name = base_name(in);
    lua_getfield(L, report_mod, "header");
    lua_call(L, 0, 1);
    printf("%s\n", lua_tostring(L, -1));
    static const char *const states[] = {"original", "simplified"};
    for (int k = 0; k < 2; k++) {
        lua_getfield(L, report_mod, "row");
        push_row_quality(L, k == 0 ? mesh : result);
        lua_pushstring(L, name);
        lua_pushstring(L, states[k]);
        lua_call(L, 3, 1);
        printf("%s\n", lua_tostring(L, -1));
    }
    printf("%s\n", lua_tostring(L, stats_line));
    call_method(L, result, "counts", 0, 1);
    lua_getfield(L, -1, "triangles");
    lua_getfield(L, -2, "vertices");
    femlod_format f = femlod_format_from_path(out);
    printf("%s: %lld triangles, %lld vertices (%s)\n", out, (long long)lua_tointeger(L, -2),
           (long long)lua_tointeger(L, -1), femlod_format_name(f));
    if (!lua_isnil(L, flh))
        printf("%s: %lld nodes: %lld input vertices, %lld collapses (hierarchy)\n",
               lua_tostring(L, flh), (long long)counts[0], (long long)counts[1], (long long)counts[2]);
    return EXIT_OK;
}

/* }==================================================================== */

/* {====================================================================
 * lod: a mesh from a saved hierarchy at a uniform size threshold. The
 * front is first brought back to the simplification's result, then refined,
 * so the output depends only on the file and T, not on the front the file
 * was saved with.
 * ===================================================================== */

/* Reads --size T, --size=T or size=T after PART.flh OUT into *size. */
/* lod's options: --size T (or size=T) or --target N (or target=N), one of
 * them; *target is 0 for --size. */
static int lod_options(lua_State *L, const cli *c, double *size, lua_Integer *target,
                       const char **spelled) {
    *spelled = NULL;
    *target = 0;
    for (int i = c->pairs; i < c->argc; i++) {
        const char *a = c->argv[i], *value = NULL, *name = a;
        int is_target;
        if (strncmp(a, "--", 2) == 0) {
            const char *eq = strchr(a, '=');
            size_t len = eq ? (size_t)(eq - a) : strlen(a);
            if (len == 6 && strncmp(a, "--size", 6) == 0)
                name = "--size";
            else if (len == 8 && strncmp(a, "--target", 8) == 0)
                name = "--target";
            else {
                static const char *const flags[] = {"--size", "--target", NULL};
                return fl_cli_unknown("option", a, len, flags, "--size, --target");
            }
            if (eq) {
                value = eq + 1;
            } else {
                if (i + 1 >= c->argc) return fl_cli_usage_error("%s needs a value", name);
                value = c->argv[++i];
            }
        } else {
            const char *eq = strchr(a, '=');
            if (!eq || eq == a) return fl_cli_usage_error("expected name=value, got '%s'", a);
            size_t len = (size_t)(eq - a);
            if (len == 4 && strncmp(a, "size", 4) == 0)
                name = "size";
            else if (len == 6 && strncmp(a, "target", 6) == 0)
                name = "target";
            else {
                static const char *const keys[] = {"size", "target", NULL};
                return fl_cli_unknown("parameter", a, len, keys, "size, target");
            }
            value = eq + 1;
        }
        is_target = strstr(name, "target") != NULL;
        if (*spelled)
            return fl_cli_usage_error((strstr(*spelled, "target") != NULL) == is_target
                                          ? "option given twice: '%s'"
                                          : "give one of --size and --target, not both ('%s')",
                                      name + (name[0] == '-' ? 2 : 0));
        *spelled = name;
        if (is_target) {
            int ok = lua_stringtonumber(L, value) != 0 && lua_isinteger(L, -1);
            lua_Integer n = ok ? lua_tointeger(L, -1) : 0;
            if (lua_gettop(L) && ok) lua_pop(L, 1);
            if (!ok || n < 1 || n > 4294967295LL)
                return fl_cli_usage_error("%s: a triangle count >= 1 expected, got '%s'", name, value);
            *target = n;
        } else if (strcmp(value, "inf") == 0) {
            *size = HUGE_VAL;
        } else {
            int ok = lua_stringtonumber(L, value) != 0;
            if (ok) {
                *size = (double)lua_tonumber(L, -1);
                lua_pop(L, 1);
            }
            if (!ok || !(*size >= 0.0))
                return fl_cli_usage_error("%s: number >= 0 or inf expected, got '%s'", name, value);
        }
    }
    if (!*spelled) return fl_cli_usage_error("lod: --size T or --target N is required");
    return -1;
}

static int cmd_lod(lua_State *L, const cli *c) {
    const char *in = c->argv[c->operand], *out = c->argv[c->operand + 1];
    if (strncmp(in, "--", 2) == 0 || strncmp(out, "--", 2) == 0)
        return fl_cli_usage_error("lod: PART.flh and OUT come first, then --size T");
    double size = 0.0;
    lua_Integer target = 0;
    const char *spelled;
    int st = lod_options(L, c, &size, &target, &spelled);
    if (st >= 0) return st;
    if ((st = fl_cli_check_input(in, "hierarchy")) >= 0 || (st = fl_cli_check_output(out, NULL)) >= 0)
        return st;

    luaL_requiref(L, "femlod", luaopen_femlod, 0);
    int module = lua_gettop(L);
    lua_getfield(L, module, "load_hierarchy");
    lua_pushstring(L, in);
    lua_call(L, 1, 1);
    int h = lua_gettop(L);
    lua_Integer splits = 0, ops = 0;
    if (target > 0) {
        /* from the saved front, keeping its density (a warning says why
         * when the count cannot be met) */
        lua_createtable(L, 0, 1);
        lua_pushinteger(L, target);
        lua_setfield(L, -2, "target");
        call_method(L, h, "rescale", 1, 1);
        ops = lua_tointeger(L, -1);
    } else {
        /* a uniform threshold: from the coarsest front, split while e_size > T */
        lua_pushnumber(L, HUGE_VAL);
        call_method(L, h, "coarsen", 1, 0);
        lua_pushnumber(L, size);
        call_method(L, h, "refine", 1, 1);
        splits = lua_tointeger(L, -1);
    }
    call_method(L, h, "mesh", 0, 1);
    int result = lua_gettop(L);
    lua_pushstring(L, out);
    call_method(L, result, "save", 1, 0);
    if (c->quiet) return EXIT_OK;

    char state[48];
    if (target > 0)
        snprintf(state, sizeof state, "target %lld", (long long)target);
    else
        snprintf(state, sizeof state, "size %.6g", size);
    lua_getglobal(L, "require");
    lua_pushliteral(L, "femlod.report");
    lua_call(L, 1, 1);
    int report_mod = lua_gettop(L);
    lua_getfield(L, report_mod, "header");
    lua_call(L, 0, 1);
    printf("%s\n", lua_tostring(L, -1));
    lua_getfield(L, report_mod, "row");
    lua_pushvalue(L, result);
    lua_pushstring(L, base_name(in));
    lua_pushstring(L, state);
    lua_call(L, 3, 1);
    printf("%s\n", lua_tostring(L, -1));
    if (target > 0)
        printf("%lld operations from the saved front\n", (long long)ops);
    else
        printf("%lld splits from the coarsest front\n", (long long)splits);
    call_method(L, result, "counts", 0, 1);
    lua_getfield(L, -1, "triangles");
    lua_getfield(L, -2, "vertices");
    femlod_format f = femlod_format_from_path(out);
    printf("%s: %lld triangles, %lld vertices (%s)\n", out, (long long)lua_tointeger(L, -2),
           (long long)lua_tointeger(L, -1), femlod_format_name(f));
    return EXIT_OK;
}

/* }==================================================================== */

static int pmain(lua_State *L) {
    cli c = {0};
    c.argc = (int)lua_tointeger(L, 1);
    c.argv = (char **)lua_touserdata(L, 2);
    luaL_checkversion(L);
    int st = parse_args(L, &c);
    if (st < 0) {
        double t0 = fl_lua_clock();
        luaL_openlibs(L);
        /* femlod.verbose and femlod.quiet, wherever the module opens */
        lua_pushinteger(L, c.verbose ? 1 : c.quiet ? -1 : 0);
        lua_setfield(L, LUA_REGISTRYINDEX, FL_VERBOSITY_KEY);
        if (c.verbose && (c.cmd == CMD_RUN || c.cmd == CMD_EVAL))
            fl_lua_log(L, "%s %s: %d parameters, seed %lld", c.cmd == CMD_RUN ? "run" : "-e",
                       c.cmd == CMD_RUN ? c.argv[c.operand] : "(command line)", c.argc - c.pairs,
                       (long long)c.seed);
        /* Caps alone apply to every command; run and -e start them later,
         * with the sandbox, once the recipe's folder is known. */
        if (c.cmd != CMD_RUN && c.cmd != CMD_EVAL) fl_sandbox_start(fl_sandbox_get(), L, NULL);
        /* require "femlod" and its helpers work in every command. */
        luaL_getsubtable(L, LUA_REGISTRYINDEX, LUA_PRELOAD_TABLE);
        lua_pushcfunction(L, luaopen_femlod);
        lua_setfield(L, -2, "femlod");
        lua_pop(L, 1);
        fl_lua_preload_helpers(L);
        switch (c.cmd) {
        case CMD_RUN:
        case CMD_EVAL: st = cmd_lua(L, &c); break;
        case CMD_INFO: st = cmd_info(L, &c); break;
        case CMD_CONVERT: st = cmd_convert(L, &c); break;
        case CMD_SIMPLIFY: st = cmd_simplify(L, &c); break;
        case CMD_LOD: st = cmd_lod(L, &c); break;
        case CMD_REPAIR: st = cmd_repair(L, &c); break;
        case CMD_IMPROVE: st = fl_cli_improve(L, c.argc - c.operand, c.argv + c.operand, c.quiet); break;
        case CMD_SWEEP:
        case CMD_REPORT: {
            fl_sweep_cli sc = {c.argc, c.argv, c.operand, c.seed, c.quiet, c.verbose, c.traceback};
            st = c.cmd == CMD_SWEEP ? fl_sweep_main(L, &sc) : fl_report_main(L, &sc);
            break;
        }
        case CMD_NONE: st = EXIT_USAGE; break;
        }
        if (c.verbose && st != EXIT_USAGE) {
            static const char *const names[] = {"", "run", "-e", "info", "convert", "simplify",
                                                "lod", "sweep", "report", "repair", "improve"};
            fl_lua_log(L, "%s: %s in %.3f s", names[c.cmd], st == EXIT_OK ? "done" : "failed",
                       fl_lua_clock() - t0);
        }
    }
    lua_pushinteger(L, st);
    return 1;
}

/* As lauxlib's: the message of an error outside any protected call. */
static int panic(lua_State *L) {
    const char *msg = lua_tostring(L, -1);
    fprintf(stderr, PROGNAME ": unprotected error in call to Lua API (%s)\n",
            msg ? msg : "error object is not a string");
    return 0;
}

int main(int argc, char **argv) {
    /* luaL_newstate with the sandbox's counting allocator (no cap unless
     * --max-memory sets one). */
    lua_State *L = lua_newstate(fl_sandbox_alloc, fl_sandbox_get());
    if (L) lua_atpanic(L, panic);
    if (L == NULL) {
        fputs(PROGNAME ": cannot create the Lua state: not enough memory\n", stderr);
        return EXIT_ERROR;
    }
    lua_pushcfunction(L, pmain);
    lua_pushinteger(L, argc);
    lua_pushlightuserdata(L, argv);
    int status = lua_pcall(L, 2, 1, 0);
    int result = status == LUA_OK ? (int)lua_tointeger(L, -1) : report(L);
    fl_sandbox_stop(fl_sandbox_get(), L, NULL);
    lua_close(L);
    /* A full disk or closed pipe on stdout is a failure too. */
    if (fflush(stdout) != 0 || ferror(stdout)) {
        fputs(PROGNAME ": error writing to standard output\n", stderr);
        if (result == EXIT_OK) result = EXIT_ERROR;
    }
    return result;
}
