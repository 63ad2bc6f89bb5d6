/*
 * improve.c - `femlod improve IN OUT`: mesh:improve with the flags as its
 * options, the result saved, the report printed (docs/cli.md).
 *
 *   femlod improve part.stl part_fe.obj --min-stretch 0.25 --max-valence 10
 *
 * Flags: --min-stretch X --max-size X --max-valence N --max-deviation X
 * --feature-angle DEG --max-normal-change DEG (each also 'off'),
 * --max-rounds N, --lock I,J,K (1-based), or the same as name=value pairs.
 */
#include "improve.h"

#include "../lua/lfemlod.h"
#include "cliutil.h"

#include <lauxlib.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const keys[] = {"min_stretch",       "max_size",   "max_valence", "max_deviation",
                                   "feature_angle",     "max_normal_change", "max_rounds", "lock", NULL};

/* Sets key in the table on the top from the text v: a number, 'off', or
 * for lock a comma-separated list. 0, or the usage error's exit status. */
static int set_option(lua_State *L, const char *key, const char *v) {
    if (strcmp(key, "lock") == 0) {
        lua_newtable(L);
        lua_Integer n = 0;
        const char *s = v;
        while (*s) {
            char *end;
            long long x = strtoll(s, &end, 10);
            if (end == s || (*end && *end != ',')) return fl_cli_usage_error("lock: list of indices expected, got '%s'", v);
            lua_pushinteger(L, (lua_Integer)x);
            lua_rawseti(L, -2, ++n);
            s = *end ? end + 1 : end;
        }
        lua_setfield(L, -2, key);
        return 0;
    }
    if (strcmp(v, "off") == 0 || strcmp(v, "false") == 0) {
        if (strcmp(key, "max_rounds") == 0) return fl_cli_usage_error("max_rounds: a number expected, got '%s'", v);
        lua_pushboolean(L, 0);
    } else {
        char *end;
        double d = strtod(v, &end);
        if (end == v || *end) return fl_cli_usage_error("%s: a number or off expected, got '%s'", key, v);
        if (strcmp(key, "max_valence") == 0 || strcmp(key, "max_rounds") == 0) lua_pushinteger(L, (lua_Integer)d);
        else lua_pushnumber(L, d);
    }
    lua_setfield(L, -2, key);
    return 0;
}

static int known(const char *k) {
    for (int i = 0; keys[i]; i++)
        if (strcmp(keys[i], k) == 0) return 1;
    return 0;
}

static int report_call(lua_State *L) {
    /* args: module, in, out, opts */
    lua_getfield(L, 1, "load");
    lua_pushvalue(L, 2);
    lua_call(L, 1, 1);
    int mesh = lua_gettop(L);
    lua_getfield(L, mesh, "improve");
    lua_pushvalue(L, mesh);
    lua_pushvalue(L, 4);
    lua_call(L, 2, 2);
    int out = mesh + 1;
    lua_getfield(L, out, "save");
    lua_pushvalue(L, out);
    lua_pushvalue(L, 3);
    lua_call(L, 2, 0);
    return 2;
}

static lua_Integer geti(lua_State *L, int t, const char *a, const char *b) {
    lua_getfield(L, t, a);
    if (b) lua_getfield(L, -1, b);
    lua_Integer v = lua_tointeger(L, -1);
    lua_pop(L, b ? 2 : 1);
    return v;
}

static void print_reasons(lua_State *L, int rep, const char *what) {
    lua_getfield(L, rep, "remaining_by");
    lua_getfield(L, -1, what);
    lua_pushnil(L);
    /* the names in the core's order, so the output does not depend on hash order */
    lua_pop(L, 1);
    for (int i = 0; i < FEMLOD_IMPROVE_REASON_COUNT; i++) {
        const char *name = femlod_improve_reason_name((femlod_improve_reason)i);
        lua_getfield(L, -1, name);
        if (!lua_isnil(L, -1))
            printf("      %8lld  %s%s\n", (long long)lua_tointeger(L, -1), name,
                   femlod_improve_reason_forced((femlod_improve_reason)i) ? " (forced)" : "");
        lua_pop(L, 1);
    }
    lua_pop(L, 2);
}

int fl_cli_improve(lua_State *L, int nargs, char **args, int quiet) {
    const char *in = args[0], *out = args[1];
    /* before any work: the input is a file, OUT can be written */
    int chk = fl_cli_check_input(in, "mesh");
    if (chk >= 0) return chk;
    if ((chk = fl_cli_check_output(out, NULL)) >= 0) return chk;
    lua_createtable(L, 0, 8);
    int opts = lua_gettop(L);
    for (int i = 2; i < nargs; i++) {
        const char *a = args[i];
        char key[64];
        const char *v = NULL;
        if (strncmp(a, "--", 2) == 0) {
            const char *eq = strchr(a, '=');
            size_t n = eq ? (size_t)(eq - a - 2) : strlen(a + 2);
            if (n >= sizeof key) return fl_cli_usage_error("unknown option '%s'", a);
            memcpy(key, a + 2, n);
            key[n] = 0;
            for (char *p = key; *p; p++)
                if (*p == '-') *p = '_';
            if (eq) v = eq + 1;
            else if (i + 1 < nargs) v = args[++i];
            else return fl_cli_usage_error("%s needs a value", a);
        } else {
            const char *eq = strchr(a, '=');
            if (!eq || eq == a || (size_t)(eq - a) >= sizeof key) return fl_cli_usage_error("expected name=value, got '%s'", a);
            memcpy(key, a, (size_t)(eq - a));
            key[eq - a] = 0;
            v = eq + 1;
        }
        if (!known(key))
            return fl_cli_usage_error("unknown option '%s' (valid: min_stretch, max_size, max_valence, "
                                      "max_deviation, feature_angle, max_normal_change, max_rounds, lock)",
                                      key);
        lua_pushvalue(L, opts);
        int st = set_option(L, key, v);
        if (st) return st;
        lua_pop(L, 1);
    }
    lua_pushcfunction(L, report_call);
    luaL_requiref(L, "femlod", luaopen_femlod, 0);
    lua_pushstring(L, in);
    lua_pushstring(L, out);
    lua_pushvalue(L, opts);
    if (lua_pcall(L, 4, 2, 0) != LUA_OK) {
        fprintf(stderr, FL_CLI_PROGNAME ": %s\n", lua_tostring(L, -1));
        return 1;
    }
    if (quiet) return 0;
    int rep = lua_gettop(L);
    lua_getfield(L, rep, "seconds");
    double secs = lua_tonumber(L, -1);
    lua_pop(L, 1);
    printf("%s: %lld triangles, %lld vertices\n", in, (long long)geti(L, rep, "triangles_in", NULL),
           (long long)geti(L, rep, "vertices_in", NULL));
    printf("  operations: %lld flips, %lld splits, %lld collapses, %lld relaxations in %lld rounds (%.3f s)\n",
           (long long)geti(L, rep, "operations", "flip"), (long long)geti(L, rep, "operations", "split"),
           (long long)geti(L, rep, "operations", "collapse"), (long long)geti(L, rep, "operations", "relax"),
           (long long)geti(L, rep, "rounds", NULL), secs);
    static const char *const rows[][2] = {{"stretch", "triangles below min_stretch"},
                                          {"size", "triangles above max_size"},
                                          {"valence", "vertices above max_valence"}};
    for (int r = 0; r < 3; r++) {
        printf("  %8lld -> %-8lld %s\n", (long long)geti(L, rep, "input", rows[r][0]),
               (long long)geti(L, rep, "remaining", rows[r][0]), rows[r][1]);
        print_reasons(L, rep, rows[r][0]);
    }
    lua_getfield(L, rep, "stretch_min_in");
    lua_getfield(L, rep, "stretch_min");
    printf("  stretch min %.3f -> %.3f, valence max %lld -> %lld\n", lua_tonumber(L, -2), lua_tonumber(L, -1),
           (long long)geti(L, rep, "valence_max_in", NULL), (long long)geti(L, rep, "valence_max", NULL));
    lua_pop(L, 2);
    printf("wrote %s: %lld triangles, %lld vertices\n", out, (long long)geti(L, rep, "triangles", NULL),
           (long long)geti(L, rep, "vertices", NULL));
    return 0;
}
