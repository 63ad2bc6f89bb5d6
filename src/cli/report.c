/*
 * report.c - `femlod report MESH [--reference ORIGINAL] [--html OUT.html]
 * [--no-viewer] [--max-deviation X]`: femlod.report from the command line. Prints the quality
 * report (with the deviation when there is a reference) and the Table 1 rows;
 * writes the HTML page when asked.
 */
#include "sweep.h"

#include "cliutil.h"

#include "lua/lfemlod.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <lauxlib.h>

static const char *base_name(const char *path) {
    const char *slash = strrchr(path, '/');
    return slash ? slash + 1 : path;
}

/* --opt VALUE or --opt=VALUE; NULL when the value is missing. */
static const char *value_of(const fl_sweep_cli *c, int *i, const char *opt) {
    const char *a = c->argv[*i];
    size_t n = strlen(opt);
    if (a[n] == '=') return a + n + 1;
    if (*i + 1 >= c->argc) return NULL;
    return c->argv[++*i];
}

static int is_opt(const char *a, const char *opt) {
    size_t n = strlen(opt);
    return strncmp(a, opt, n) == 0 && (a[n] == '\0' || a[n] == '=');
}

int fl_report_main(lua_State *L, const fl_sweep_cli *c) {
    const char *mesh = c->argv[c->operand], *ref = NULL, *html = NULL, *maxdev = NULL;
    int viewer = 1;
    if (strncmp(mesh, "--", 2) == 0) return fl_cli_usage_error("report: MESH comes first, then the options");
    for (int i = c->operand + 1; i < c->argc; i++) {
        const char *a = c->argv[i];
        const char **slot = NULL;
        const char *opt = NULL;
        if (is_opt(a, "--reference")) {
            slot = &ref;
            opt = "--reference";
        } else if (is_opt(a, "--html")) {
            slot = &html;
            opt = "--html";
        } else if (is_opt(a, "--max-deviation")) {
            slot = &maxdev;
            opt = "--max-deviation";
        } else if (strcmp(a, "--no-viewer") == 0) {
            viewer = 0;
            continue;
        } else {
            const char *eq = strchr(a, '=');
            return fl_cli_usage_error("report: unknown option '%.*s' (valid: --reference, --html, --no-viewer, --max-deviation)",
                                      (int)(eq && strncmp(a, "--", 2) == 0 ? (size_t)(eq - a) : strlen(a)), a);
        }
        if (*slot) return fl_cli_usage_error("option given twice: '%s'", opt);
        const char *v = value_of(c, &i, opt);
        if (!v) return fl_cli_usage_error("%s needs a value", opt);
        if (!*v) return fl_cli_usage_error("%s: file name expected, got ''", opt);
        *slot = v;
    }

    luaL_requiref(L, "femlod", luaopen_femlod, 0);
    int module = lua_gettop(L);
    fl_cli_load_mesh(L, module, mesh, NULL);
    int m = lua_gettop(L);
    lua_createtable(L, 0, 5);
    int opts = lua_gettop(L);
    if (ref) {
        fl_cli_load_mesh(L, module, ref, NULL);
        lua_setfield(L, opts, "reference");
        lua_pushstring(L, base_name(ref));
        lua_setfield(L, opts, "reference_name");
    }
    if (html) {
        lua_pushstring(L, html);
        lua_setfield(L, opts, "html");
    }
    if (maxdev) {
        char *end;
        double d = strtod(maxdev, &end);
        if (*end || !(d > 0.0)) return fl_cli_usage_error("--max-deviation: positive number expected, got '%s'", maxdev);
        lua_pushnumber(L, d);
        lua_setfield(L, opts, "max_deviation");
    }
    if (!viewer) {
        lua_pushboolean(L, 0);
        lua_setfield(L, opts, "viewer");
    }
    lua_pushstring(L, base_name(mesh));
    lua_setfield(L, opts, "name");
    /* The deviation from the reference is the long part: a bar for it on a
     * terminal (femlod.progress), as simplify has. */
    int bar = 0;
    if (ref && !c->quiet) {
        lua_getglobal(L, "require");
        lua_pushliteral(L, "femlod.progress");
        lua_call(L, 1, 1);
        lua_getfield(L, -1, "bar");
        lua_createtable(L, 0, 1);
        lua_pushliteral(L, "hausdorff");
        lua_setfield(L, -2, "label");
        lua_call(L, 1, 1);
        lua_remove(L, -2);
        bar = lua_gettop(L);
        lua_getfield(L, bar, "update");
        lua_setfield(L, opts, "progress");
    }
    lua_getfield(L, module, "report");
    lua_pushvalue(L, m);
    lua_pushvalue(L, opts);
    lua_call(L, 2, 1);
    int r = lua_gettop(L);
    if (bar) {
        lua_getfield(L, bar, "close");
        lua_pushvalue(L, bar);
        lua_call(L, 1, 0);
    }
    if (c->quiet) return 0;

    lua_getfield(L, r, "text");
    printf("%s\n\n", lua_tostring(L, -1));
    lua_getglobal(L, "require");
    lua_pushliteral(L, "femlod.report");
    lua_call(L, 1, 1);
    lua_getfield(L, -1, "header");
    lua_call(L, 0, 1);
    printf("%s\n", lua_tostring(L, -1));
    lua_pop(L, 2);
    if (lua_getfield(L, r, "reference_row") == LUA_TSTRING) printf("%s\n", lua_tostring(L, -1));
    lua_getfield(L, r, "row");
    printf("%s\n", lua_tostring(L, -1));
    if (html) {
        lua_getfield(L, r, "viewer");
        printf("%s: written (%s)\n", html, lua_toboolean(L, -1) ? "with the 3D view" : "without the 3D view");
    }
    return 0;
}
