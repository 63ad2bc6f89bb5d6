/*
 * report.c - `femlod report MESH [--reference ORIGINAL] [--html OUT.html]
 * [--no-viewer]`: femlod.report from the command line. Prints the quality
 * report (with the deviation when there is a reference) and the Table 1 rows;
 * writes the HTML page when asked.
 */
#include "sweep.h"

#include "cliutil.h"

#include "lua/lfemlod.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include <lauxlib.h>

static const char *base_name(const char *path) {
    const char *slash = strrchr(path, '/');
    return slash ? slash + 1 : path;
}

int fl_report_main(lua_State *L, const fl_sweep_cli *c) {
    const char *mesh = c->argv[c->operand], *ref = NULL, *html = NULL;
    if (strncmp(mesh, "--", 2) == 0) return fl_cli_usage_error("report: MESH comes first, then the options");
    /* --reference X, --html X, --no-viewer, or as pairs: reference=X ... */
    static const fl_cli_option options[] = {{"reference", 0}, {"html", 0}, {"viewer", 1}, {"max_deviation", 0},
                                            {NULL, 0}};
    int st = fl_cli_read_options(L, c->argc, c->argv, c->operand + 1, options);
    if (st >= 0) return st;
    int values = lua_gettop(L) - 1, spell = values + 1;
    static const char *const files[] = {"reference", "html"};
    for (int k = 0; k < 2; k++) {
        if (lua_getfield(L, values, files[k]) == LUA_TNIL) continue;
        /* reference=1 names a file called 1 */
        const char *v = lua_type(L, -1) == LUA_TBOOLEAN ? NULL : luaL_tolstring(L, -1, NULL);
        lua_getfield(L, spell, files[k]);
        if (!v || !*v)
            return fl_cli_usage_error("%s: file name expected, got '%s'", lua_tostring(L, -1),
                                      v ? v : luaL_tolstring(L, -3, NULL));
        if (k == 0) ref = v;
        else html = v;
    }
    if (lua_getfield(L, values, "viewer") != LUA_TNIL && !lua_isboolean(L, -1)) {
        lua_getfield(L, spell, "viewer");
        return fl_cli_usage_error("%s: true or false expected, got '%s'", lua_tostring(L, -1),
                                  luaL_tolstring(L, -2, NULL));
    }
    int viewer = lua_isnil(L, -1) || lua_toboolean(L, -1);
    if ((st = fl_cli_check_input(mesh, "mesh")) >= 0) return st;
    if (ref && (st = fl_cli_check_input(ref, "mesh")) >= 0) return st;
    if (html && (st = fl_cli_check_output(html, "html")) >= 0) return st;

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
    /* --max-deviation D: the page and the text flag a deviation above D */
    if (lua_getfield(L, values, "max_deviation") != LUA_TNIL) {
        lua_Number d = lua_tonumber(L, -1);
        if (!lua_isnumber(L, -1) || !(d > 0) || !isfinite(d)) {
            lua_getfield(L, spell, "max_deviation");
            return fl_cli_usage_error("%s: positive number expected, got '%s'", lua_tostring(L, -1),
                                      luaL_tolstring(L, -2, NULL));
        }
        if (!ref) return fl_cli_usage_error("--max-deviation needs --reference (the deviation is from it)");
        lua_pushnumber(L, d);
        lua_setfield(L, opts, "max_deviation");
    }
    lua_pop(L, 1);
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
