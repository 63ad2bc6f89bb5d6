/*
 * cliutil.c - owns what the femlod program's command files share
 * (cliutil.h): the usage error (one line naming the problem, one pointing at
 * the help), the nearest valid name for a misspelt one, the checks of input
 * and output paths that run before any work, and femlod.load called from C.
 * Below main.c, sweep.c and report.c; it calls none of them.
 */
#include "cliutil.h"

#include "femlod.h"
#include "help.h"

#include <lauxlib.h>

#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static const char *command_name;

void fl_cli_set_command(const char *name) { command_name = name; }

int fl_cli_usage_error(const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    fputs(FL_CLI_PROGNAME ": ", stderr);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    int len = 0;
    const char *synopsis = command_name ? fl_cli_help_synopsis(command_name, &len) : NULL;
    if (synopsis)
        fprintf(stderr, "\nusage: " FL_CLI_PROGNAME " %.*s (try '" FL_CLI_PROGNAME " help %s')\n",
                len, synopsis, command_name);
    else
        fputs("\nusage: " FL_CLI_PROGNAME " [options] COMMAND [ARGS] [options of the command]"
              " (try '" FL_CLI_PROGNAME " --help')\n",
              stderr);
    fflush(stderr);
    return FL_CLI_EXIT_USAGE;
}

/* {====== did you mean */

/* Optimal string alignment distance (Levenshtein with transpositions, which
 * are the commonest slip of the fingers); '-' and '_' count as equal, so
 * that min_stretch finds --min-stretch's twin. */
static size_t distance(const char *a, size_t la, const char *b, size_t lb) {
    enum { MAX = 64 };
    if (la >= MAX || lb >= MAX) return (size_t)-1;
    size_t d[MAX][MAX];
    for (size_t i = 0; i <= la; i++) d[i][0] = i;
    for (size_t j = 0; j <= lb; j++) d[0][j] = j;
    for (size_t i = 1; i <= la; i++) {
        for (size_t j = 1; j <= lb; j++) {
            char x = a[i - 1] == '_' ? '-' : a[i - 1], y = b[j - 1] == '_' ? '-' : b[j - 1];
            size_t best = d[i - 1][j - 1] + (x != y);
            if (d[i - 1][j] + 1 < best) best = d[i - 1][j] + 1;
            if (d[i][j - 1] + 1 < best) best = d[i][j - 1] + 1;
            if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] &&
                d[i - 2][j - 2] + 1 < best)
                best = d[i - 2][j - 2] + 1;
            d[i][j] = best;
        }
    }
    return d[la][lb];
}

const char *fl_cli_suggest(const char *word, size_t len, const char *const *names) {
    const char *best = NULL;
    size_t best_d = (size_t)-1;
    for (const char *const *n = names; *n; n++) {
        size_t d = distance(word, len, *n, strlen(*n));
        if (d < best_d) {
            best_d = d;
            best = *n;
        }
    }
    /* Close enough: a third of the letters (past any "--"), at least one. */
    size_t letters = len > 2 && word[0] == '-' && word[1] == '-' ? len - 2 : len;
    size_t limit = letters / 3 > 0 ? letters / 3 : 1;
    return best && best_d <= limit ? best : NULL;
}

int fl_cli_unknown(const char *what, const char *word, size_t len, const char *const *names,
                   const char *list) {
    /* The program's own options belong before the command word. */
    static const char *const global[] = {"--seed",    "--quiet",      "-q",         "--verbose",
                                         "-v",        "--traceback",  "--record",   "--sandbox",
                                         "--max-memory", "--max-time", "--version", NULL};
    for (const char *const *g = global; *g; g++)
        if (strlen(*g) == len && strncmp(*g, word, len) == 0)
            return fl_cli_usage_error("%.*s is an option of femlod, not of %s: put it before the "
                                      "command (femlod %.*s %s ...)",
                                      (int)len, word, command_name ? command_name : "the command",
                                      (int)len, word, command_name ? command_name : "COMMAND");
    const char *near = fl_cli_suggest(word, len, names);
    if (near)
        return fl_cli_usage_error("unknown %s '%.*s'; did you mean %s?", what, (int)len, word, near);
    return fl_cli_usage_error("unknown %s '%.*s' (valid: %s)", what, (int)len, word, list);
}

/* }====== */

/* {====== paths checked before any work */

int fl_cli_check_input(const char *path, const char *what) {
    struct stat st;
    if (stat(path, &st) == 0 && S_ISDIR(st.st_mode))
        return fl_cli_usage_error("%s: is a folder, not a %s file", path, what);
    size_t n = strlen(path);
    if (strcmp(what, "mesh") == 0 && n > 4 && strcmp(path + n - 4, ".flh") == 0)
        return fl_cli_usage_error("%s: a saved vertex hierarchy, not a mesh; "
                                  "'" FL_CLI_PROGNAME " lod %s OUT --size T' writes a mesh from it",
                                  path, path);
    return -1;
}

int fl_cli_check_output(const char *path, const char *format) {
    if (!*path) return fl_cli_usage_error("output file name expected, got ''");
    size_t n = strlen(path);
    struct stat st;
    if (path[n - 1] == '/' || (stat(path, &st) == 0 && S_ISDIR(st.st_mode)))
        return fl_cli_usage_error("%s: is a folder; give a file name", path);
    /* The writers refuse to replace a file without write permission, even
     * as root: so does the check. */
    if (stat(path, &st) == 0 && S_ISREG(st.st_mode) && !(st.st_mode & 0222))
        return fl_cli_usage_error("%s: cannot write: file is read-only (mode %04o)", path,
                                  (unsigned)(st.st_mode & 07777));
    const char *slash = strrchr(path, '/');
    if (slash) {
        char dir[4096];
        size_t dn = slash == path ? 1 : (size_t)(slash - path);
        if (dn >= sizeof dir) return fl_cli_usage_error("%s: path too long", path);
        memcpy(dir, path, dn);
        dir[dn] = '\0';
        if (stat(dir, &st) != 0) {
            if (errno == ENOENT || errno == ENOTDIR)
                return fl_cli_usage_error("%s: folder %s does not exist", path, dir);
            return fl_cli_usage_error("%s: folder %s: %s", path, dir, strerror(errno));
        }
        if (!S_ISDIR(st.st_mode)) return fl_cli_usage_error("%s: %s is not a folder", path, dir);
        if (access(dir, W_OK | X_OK) != 0)
            return fl_cli_usage_error("%s: cannot write in folder %s: %s", path, dir, strerror(errno));
    } else if (access(".", W_OK | X_OK) != 0) {
        return fl_cli_usage_error("%s: cannot write in the current folder: %s", path, strerror(errno));
    }
    if (!format && femlod_format_from_path(path) == FEMLOD_FORMAT_AUTO)
        return fl_cli_usage_error("%s: unknown file extension (valid: .obj, .stl, .off, .ply, "
                                  ".gltf, .glb, .msh, .vtk, .inp, .mesh; or give format=FMT)",
                                  path);
    return -1;
}

/* }====== */

void fl_cli_load_mesh(lua_State *L, int module, const char *path, const char *format) {
    lua_getfield(L, module, "load");
    lua_pushstring(L, path);
    lua_createtable(L, 0, 1);
    if (format) {
        lua_pushstring(L, format);
        lua_setfield(L, -2, "format");
    }
    lua_call(L, 2, 1);
    /* A file without triangles reads as an empty mesh; every command would
     * print zeros for it, so it is an error here. */
    int m = lua_gettop(L);
    lua_getfield(L, m, "counts");
    lua_pushvalue(L, m);
    lua_call(L, 1, 1);
    lua_getfield(L, -1, "triangles");
    lua_Integer nt = lua_tointeger(L, -1);
    lua_pop(L, 2);
    if (nt == 0) luaL_error(L, "%s: no triangles", path);
}

/* {====== options: --name VALUE, --name=VALUE, name=VALUE */

void fl_cli_push_value(lua_State *L, const char *s) {
    if (strcmp(s, "true") == 0)
        lua_pushboolean(L, 1);
    else if (strcmp(s, "false") == 0)
        lua_pushboolean(L, 0);
    else if (lua_stringtonumber(L, s) == 0)
        lua_pushstring(L, s);
}

/* The option whose key is word[0..len), with '-' for '_' when dashed. */
static const fl_cli_option *find_option(const fl_cli_option *options, const char *word, size_t len,
                                        int dashed) {
    for (const fl_cli_option *o = options; o->key; o++) {
        if (strlen(o->key) != len) continue;
        size_t k = 0;
        for (; k < len; k++) {
            char c = word[k];
            if (dashed && c == '-') c = '_';
            else if (dashed && c == '_') break; /* --color_by is not a spelling */
            if (c != o->key[k]) break;
        }
        if (k == len) return o;
    }
    return NULL;
}

/* The usage error for an unknown name: the valid names in the user's style. */
static int unknown_option(const fl_cli_option *options, const char *word, size_t len, int dashed) {
    enum { MAXN = 32 };
    char names[MAXN][48];
    const char *ptrs[MAXN + 1];
    char list[1024] = "";
    size_t n = 0, used = 0;
    for (const fl_cli_option *o = options; o->key && n < MAXN; o++, n++) {
        snprintf(names[n], sizeof names[n], "%s%s", dashed ? "--" : "", o->key);
        if (dashed)
            for (char *c = names[n] + 2; *c; c++)
                if (*c == '_') *c = '-';
        ptrs[n] = names[n];
        used += (size_t)snprintf(list + used, used < sizeof list ? sizeof list - used : 0, "%s%s",
                                 n ? ", " : "", names[n]);
    }
    ptrs[n] = NULL;
    return fl_cli_unknown(dashed ? "option" : "parameter", word, len, ptrs, list);
}

int fl_cli_read_options(lua_State *L, int argc, char **argv, int first, const fl_cli_option *options) {
    lua_newtable(L);
    int values = lua_gettop(L);
    lua_newtable(L);
    int spell = values + 1;
    for (int i = first; i < argc; i++) {
        const char *a = argv[i], *value = NULL, *name = a;
        const char *eq = strchr(a, '=');
        int dashed = a[0] == '-' && a[1] == '-';
        size_t len;
        const fl_cli_option *o;
        if (dashed) {
            name = a + 2;
            len = eq ? (size_t)(eq - name) : strlen(name);
            o = find_option(options, name, len, 1);
            int negated = 0;
            if (!o && !eq && len > 3 && strncmp(name, "no-", 3) == 0) {
                o = find_option(options, name + 3, len - 3, 1);
                negated = o && o->is_switch;
                if (!negated) o = NULL;
            }
            if (!o) return unknown_option(options, a, (size_t)(name - a) + len, 1);
            if (eq) {
                value = eq + 1;
            } else if (negated) {
                value = "false";
            } else if (o->is_switch) {
                value = "true";
                if (i + 1 < argc && (strcmp(argv[i + 1], "true") == 0 || strcmp(argv[i + 1], "false") == 0))
                    value = argv[++i];
            } else {
                if (i + 1 >= argc) return fl_cli_usage_error("%.*s needs a value", (int)len + 2, a);
                value = argv[++i];
            }
            lua_pushlstring(L, a, (size_t)(name - a) + len);
        } else {
            if (a[0] == '-' && a[1] != '\0' && !eq) return unknown_option(options, a, strlen(a), 1);
            if (!eq || eq == a) return fl_cli_usage_error("expected name=value, got '%s'", a);
            len = (size_t)(eq - a);
            o = find_option(options, a, len, 0);
            if (!o) return unknown_option(options, a, len, 0);
            value = eq + 1;
            lua_pushlstring(L, a, len);
        }
        if (lua_getfield(L, spell, o->key) != LUA_TNIL)
            return fl_cli_usage_error("option given twice: '%s'", lua_tostring(L, -2));
        lua_pop(L, 1);
        lua_setfield(L, spell, o->key);
        fl_cli_push_value(L, value);
        lua_setfield(L, values, o->key);
    }
    return -1;
}

/* }====== */
