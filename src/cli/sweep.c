/*
 * sweep.c - `femlod sweep`: a recipe run once per point of a parameter grid,
 * each point in its own worker process, and the manifest of what every point
 * read, wrote and measured; and `--record FILE`, which makes one run write
 * its part of that manifest.
 *
 * A worker is this program again (/proc/self/exe), started with posix_spawn
 * as `femlod --record DIR/points/NNN/record.json run RECIPE pairs... out_dir=...`,
 * its standard output and error going to files in the point's folder. The
 * sweep waits for each with wait4 (exit status or signal, CPU time, peak
 * memory) and writes DIR/points/NNN/run.json; once all points are done it
 * collects record.json and run.json of every point into DIR/manifest.json
 * and DIR/results.csv. The same collection runs alone with --collect, after
 * the points of --emit-jobs ran elsewhere (`--point N` runs one).
 *
 * JSON is Debian's cJSON (libcjson), SHA-256 is nettle's.
 */
#include "sweep.h"

#include "cliutil.h"

#include "core.h" /* fl_out, fl_format_double */
#include "femlod.h"
#include "lua/lfemlod.h"

#include <cjson/cJSON.h>
#include <nettle/sha2.h>

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <signal.h>
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <lauxlib.h>

extern char **environ;

#define MAX_POINTS 100000
#define MAX_JOBS 256

/* {====================================================================
 * Small helpers: files, hashes, JSON values
 * ===================================================================== */

/* SHA-256 of a file as 64 hex digits into hex[65]; its size into *bytes.
 * Returns 0, or -1 with errno set. */
static int sha256_file(const char *path, char hex[65], long long *bytes) {
    FILE *f = fopen(path, "rb");
    if (!f) return -1;
    struct sha256_ctx ctx;
    sha256_init(&ctx);
    unsigned char buf[1 << 16];
    size_t n;
    long long total = 0;
    while ((n = fread(buf, 1, sizeof buf, f)) > 0) {
        sha256_update(&ctx, n, buf);
        total += (long long)n;
    }
    int bad = ferror(f);
    int e = errno;
    fclose(f);
    if (bad) {
        errno = e;
        return -1;
    }
    unsigned char d[SHA256_DIGEST_SIZE];
    sha256_digest(&ctx, sizeof d, d);
    for (int i = 0; i < SHA256_DIGEST_SIZE; i++) snprintf(hex + 2 * i, 3, "%02x", d[i]);
    *bytes = total;
    return 0;
}

static void sha256_text(const char *s, char hex[65]) {
    struct sha256_ctx ctx;
    sha256_init(&ctx);
    sha256_update(&ctx, strlen(s), (const uint8_t *)s);
    unsigned char d[SHA256_DIGEST_SIZE];
    sha256_digest(&ctx, sizeof d, d);
    for (int i = 0; i < SHA256_DIGEST_SIZE; i++) snprintf(hex + 2 * i, 3, "%02x", d[i]);
}

/* Writes text to path through the atomic writer; 0, or -1 with the message
 * printed. */
static int write_file(const char *path, const char *text) {
    fl_out o;
    femlod_error err;
    if (fl_out_open(&o, path, &err) != FEMLOD_OK || fputs(text, o.fp) < 0 ||
        fl_out_commit(&o, &err) != FEMLOD_OK) {
        fprintf(stderr, "femlod: %s\n", err.message[0] ? err.message : path);
        return -1;
    }
    return 0;
}

/* Writes a cJSON tree, indented, ending in a newline. */
static int write_json(const char *path, const cJSON *j) {
    char *text = cJSON_Print(j);
    if (!text) {
        fprintf(stderr, "femlod: %s: out of memory\n", path);
        return -1;
    }
    size_t n = strlen(text);
    char *line = malloc(n + 2);
    int st = -1;
    if (line) {
        memcpy(line, text, n);
        line[n] = '\n';
        line[n + 1] = '\0';
        st = write_file(path, line);
        free(line);
    }
    cJSON_free(text);
    return st;
}

/* A JSON object from a file; NULL when the file is missing, or when it is
 * not a JSON object (then *malformed is set, when given). */
static cJSON *read_json_object(const char *path, int *malformed) {
    char *data;
    size_t size;
    if (malformed) *malformed = 0;
    if (fl_file_read_all(path, &data, &size, NULL) != FEMLOD_OK) return NULL;
    cJSON *j = cJSON_ParseWithLength(data, size);
    free(data);
    if (!cJSON_IsObject(j)) {
        cJSON_Delete(j);
        if (malformed) *malformed = 1;
        return NULL;
    }
    return j;
}

static cJSON *read_json(const char *path) {
    return read_json_object(path, NULL);
}

static int make_dir(const char *path) {
    if (mkdir(path, 0777) == 0 || errno == EEXIST) {
        struct stat st;
        if (stat(path, &st) == 0 && S_ISDIR(st.st_mode)) return 0;
        errno = ENOTDIR;
    }
    fprintf(stderr, "femlod: %s: cannot create folder: %s\n", path, strerror(errno));
    return -1;
}

/* mkdir -p */
static int make_dirs(const char *path) {
    char *p = strdup(path);
    if (!p) return -1;
    for (char *s = p + 1; *s; s++) {
        if (*s != '/') continue;
        *s = '\0';
        if (mkdir(p, 0777) != 0 && errno != EEXIST) {
            fprintf(stderr, "femlod: %s: cannot create folder: %s\n", p, strerror(errno));
            free(p);
            return -1;
        }
        *s = '/';
    }
    int st = make_dir(p);
    free(p);
    return st;
}

/* A word of the command line as the worker's params will hold it: Lua's
 * number syntax, true/false, or a string (main.c push_value). */
static cJSON *json_word(lua_State *L, const char *s) {
    if (strcmp(s, "true") == 0) return cJSON_CreateTrue();
    if (strcmp(s, "false") == 0) return cJSON_CreateFalse();
    if (lua_stringtonumber(L, s)) {
        double v = (double)lua_tonumber(L, -1);
        lua_pop(L, 1);
        if (isfinite(v)) return cJSON_CreateNumber(v);
    }
    return cJSON_CreateString(s);
}

/* A number as results.csv and the messages print it: integers as such,
 * others in the shortest form that reads back exactly. */
static void format_number(char *buf, size_t size, double v) {
    if (v == floor(v) && fabs(v) < 9007199254740992.0)
        snprintf(buf, size, "%.0f", v);
    else
        fl_format_double(buf, size, v);
}

/* }==================================================================== */

/* {====================================================================
 * --record: the worker's side
 * ===================================================================== */

static int push_sweep_module(lua_State *L) {
    lua_getfield(L, LUA_REGISTRYINDEX, LUA_LOADED_TABLE);
    if (lua_getfield(L, -1, "femlod.sweep") == LUA_TTABLE) {
        lua_remove(L, -2);
        return 1;
    }
    lua_pop(L, 2);
    luaL_getsubtable(L, LUA_REGISTRYINDEX, LUA_PRELOAD_TABLE);
    lua_getfield(L, -1, "femlod.sweep");
    lua_remove(L, -2);
    lua_pushliteral(L, "femlod.sweep");
    lua_call(L, 1, 1);
    /* Also as require would leave it, so that the recipe shares the state. */
    lua_getfield(L, LUA_REGISTRYINDEX, LUA_LOADED_TABLE);
    lua_pushvalue(L, -2);
    lua_setfield(L, -2, "femlod.sweep");
    lua_pop(L, 1);
    return 1;
}

void fl_record_start(lua_State *L, const char *recipe) {
    push_sweep_module(L);
    lua_getfield(L, -1, "start");
    lua_getglobal(L, "params");
    lua_createtable(L, 1, 0);
    if (recipe) {
        lua_pushstring(L, recipe);
        lua_rawseti(L, -2, 1);
    }
    lua_call(L, 2, 1);
    lua_setfield(L, LUA_REGISTRYINDEX, FL_IO_HOOK);
    lua_pop(L, 1);
}

static cJSON *lua_to_json(lua_State *L, int idx, int depth);

static int compare_strings(const void *a, const void *b) {
    return strcmp(*(const char *const *)a, *(const char *const *)b);
}

/* A Lua table as a JSON array (a sequence 1..n) or an object with its
 * string keys sorted, so that the same record prints the same bytes. */
static cJSON *table_to_json(lua_State *L, int idx, int depth) {
    size_t n = 0, seq = (size_t)lua_rawlen(L, idx);
    lua_pushnil(L);
    while (lua_next(L, idx)) {
        n++;
        lua_pop(L, 1);
    }
    if (n > 0 && n == seq) {
        cJSON *a = cJSON_CreateArray();
        for (size_t i = 1; a && i <= n; i++) {
            lua_rawgeti(L, idx, (lua_Integer)i);
            cJSON_AddItemToArray(a, lua_to_json(L, lua_gettop(L), depth + 1));
            lua_pop(L, 1);
        }
        return a;
    }
    /* Keys anchored in a table, so the pointers stay valid while sorted. */
    lua_createtable(L, (int)(n < INT_MAX ? n : 0), 0);
    int anchor = lua_gettop(L);
    const char **keys = (const char **)lua_newuserdatauv(L, (n ? n : 1) * sizeof *keys, 0);
    size_t k = 0;
    lua_pushnil(L);
    while (lua_next(L, idx)) {
        lua_pop(L, 1);
        if (lua_type(L, -1) == LUA_TSTRING) {
            lua_pushvalue(L, -1);
            keys[k++] = lua_tostring(L, -1);
            lua_rawseti(L, anchor, (lua_Integer)k);
        }
    }
    qsort(keys, k, sizeof *keys, compare_strings);
    cJSON *o = cJSON_CreateObject();
    for (size_t i = 0; o && i < k; i++) {
        lua_getfield(L, idx, keys[i]);
        cJSON_AddItemToObject(o, keys[i], lua_to_json(L, lua_gettop(L), depth + 1));
        lua_pop(L, 1);
    }
    lua_pop(L, 2);
    return o;
}

static cJSON *lua_to_json(lua_State *L, int idx, int depth) {
    switch (lua_type(L, idx)) {
    case LUA_TBOOLEAN: return cJSON_CreateBool(lua_toboolean(L, idx));
    case LUA_TNUMBER: {
        double v = (double)lua_tonumber(L, idx);
        return isfinite(v) ? cJSON_CreateNumber(v) : cJSON_CreateNull();
    }
    case LUA_TSTRING: return cJSON_CreateString(lua_tostring(L, idx));
    case LUA_TTABLE:
        if (depth < 16) return table_to_json(L, idx, depth);
        return cJSON_CreateNull();
    default: return cJSON_CreateString(luaL_typename(L, idx));
    }
}

/* A list of paths as [{path, sha256, bytes}]; a file gone since is
 * {path, sha256: null, error}. */
static cJSON *hashed_files(lua_State *L, int list) {
    cJSON *a = cJSON_CreateArray();
    lua_Integer n = (lua_Integer)lua_rawlen(L, list);
    for (lua_Integer i = 1; a && i <= n; i++) {
        lua_rawgeti(L, list, i);
        const char *path = lua_tostring(L, -1);
        cJSON *f = cJSON_CreateObject();
        cJSON_AddStringToObject(f, "path", path ? path : "?");
        char hex[65];
        long long bytes;
        if (path && sha256_file(path, hex, &bytes) == 0) {
            cJSON_AddStringToObject(f, "sha256", hex);
            cJSON_AddNumberToObject(f, "bytes", (double)bytes);
        } else {
            cJSON_AddNullToObject(f, "sha256");
            cJSON_AddStringToObject(f, "error", strerror(errno));
        }
        cJSON_AddItemToArray(a, f);
        lua_pop(L, 1);
    }
    return a;
}

/* Under lua_pcall: upvalues none; arguments path, error (or nil). */
static int record_write_protected(lua_State *L) {
    const char *path = lua_tostring(L, 1);
    push_sweep_module(L);
    lua_getfield(L, -1, "result");
    lua_call(L, 0, 1);
    int r = lua_gettop(L);
    cJSON *j = cJSON_CreateObject();
    cJSON_AddStringToObject(j, "femlod", "femlod " FEMLOD_VERSION_STRING);
    lua_getfield(L, r, "params");
    cJSON_AddItemToObject(j, "params", table_to_json(L, lua_gettop(L), 0));
    lua_getfield(L, r, "reads");
    cJSON_AddItemToObject(j, "reads", hashed_files(L, lua_gettop(L)));
    lua_getfield(L, r, "writes");
    cJSON_AddItemToObject(j, "writes", hashed_files(L, lua_gettop(L)));
    lua_getfield(L, r, "meshes");
    cJSON *meshes = lua_rawlen(L, -1) ? table_to_json(L, lua_gettop(L), 0) : cJSON_CreateArray();
    cJSON_AddItemToObject(j, "meshes", meshes);
    lua_getfield(L, r, "recorded");
    cJSON_AddItemToObject(j, "recorded", table_to_json(L, lua_gettop(L), 0));
    if (lua_isstring(L, 2))
        cJSON_AddStringToObject(j, "error", lua_tostring(L, 2));
    else
        cJSON_AddNullToObject(j, "error");
    int st = write_json(path, j);
    cJSON_Delete(j);
    lua_pushboolean(L, st == 0);
    return 1;
}

int fl_record_write(lua_State *L, const char *path, const char *error) {
    lua_pushcfunction(L, record_write_protected);
    lua_pushstring(L, path);
    if (error)
        lua_pushstring(L, error);
    else
        lua_pushnil(L);
    if (lua_pcall(L, 2, 1, 0) != LUA_OK) {
        fprintf(stderr, "femlod: %s: cannot write the record: %s\n", path, lua_tostring(L, -1));
        lua_pop(L, 1);
        return 1;
    }
    int ok = lua_toboolean(L, -1);
    lua_pop(L, 1);
    return ok ? 0 : 1;
}

/* }==================================================================== */

/* {====================================================================
 * The sweep's command line
 * ===================================================================== */

typedef struct axis {
    const char *name; /* points into argv: name=... */
    size_t name_len;
    char **values;    /* copies, split at commas */
    size_t count;
} axis;

typedef struct sweep {
    const fl_sweep_cli *cli;
    const char *recipe;
    const char *out;       /* DIR */
    char **fixed;          /* the name=value words, as given */
    size_t nfixed;
    axis *axes;
    size_t naxes;
    size_t npoints;
    int jobs, emit, collect;
    int sandbox;           /* points run with --sandbox (default; --no-sandbox: off) */
    const char **allow;    /* --allow DIR, passed to the points */
    size_t nallow;
    long point;            /* --point N, or -1 */
    int width;             /* digits of NNN */
    char exe[PATH_MAX];
} sweep;

static void sweep_free(sweep *s) {
    for (size_t i = 0; i < s->naxes; i++) {
        for (size_t k = 0; k < s->axes[i].count; k++) free(s->axes[i].values[k]);
        free(s->axes[i].values);
    }
    free(s->axes);
    free(s->fixed);
    free(s->allow);
}

/* Names become CSV columns and Lua table keys: identifiers. */
static int valid_name(const char *s, size_t n) {
    if (n == 0 || !(s[0] == '_' || (s[0] >= 'A' && s[0] <= 'Z') || (s[0] >= 'a' && s[0] <= 'z')))
        return 0;
    for (size_t i = 1; i < n; i++) {
        char c = s[i];
        if (!(c == '_' || (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9')))
            return 0;
    }
    return 1;
}

static int name_taken(const sweep *s, const char *name, size_t len) {
    for (size_t i = 0; i < s->naxes; i++)
        if (s->axes[i].name_len == len && strncmp(s->axes[i].name, name, len) == 0) return 1;
    for (size_t i = 0; i < s->nfixed; i++)
        if (strncmp(s->fixed[i], name, len) == 0 && s->fixed[i][len] == '=') return 1;
    return 0;
}

static int add_axis(sweep *s, const char *spec) {
    const char *eq = strchr(spec, '=');
    if (!eq) return fl_cli_usage_error("--grid: name=v1,v2,... expected, got '%s'", spec);
    size_t len = (size_t)(eq - spec);
    if (!valid_name(spec, len))
        return fl_cli_usage_error("--grid: '%.*s' is not a name (letters, digits, _)", (int)len, spec);
    if (len == 7 && strncmp(spec, "out_dir", 7) == 0)
        return fl_cli_usage_error("--grid: out_dir is set by the sweep (DIR/points/NNN)");
    if (name_taken(s, spec, len))
        return fl_cli_usage_error("parameter given twice: '%.*s'", (int)len, spec);
    axis *a = realloc(s->axes, (s->naxes + 1) * sizeof *a);
    if (!a) return fl_cli_usage_error("out of memory");
    s->axes = a;
    axis *x = &a[s->naxes++];
    x->name = spec;
    x->name_len = len;
    x->values = NULL;
    x->count = 0;
    const char *p = eq + 1;
    for (;;) {
        const char *comma = strchr(p, ',');
        size_t n = comma ? (size_t)(comma - p) : strlen(p);
        if (n == 0)
            return fl_cli_usage_error("--grid %.*s: empty value in '%s'", (int)len, spec, eq + 1);
        char **v = realloc(x->values, (x->count + 1) * sizeof *v);
        if (!v) return fl_cli_usage_error("out of memory");
        x->values = v;
        v[x->count] = strndup(p, n);
        if (!v[x->count]) return fl_cli_usage_error("out of memory");
        x->count++;
        if (!comma) break;
        p = comma + 1;
    }
    for (size_t i = 0; i < x->count; i++)
        for (size_t k = i + 1; k < x->count; k++)
            if (strcmp(x->values[i], x->values[k]) == 0)
                return fl_cli_usage_error("--grid %.*s: value '%s' given twice", (int)len, spec,
                                          x->values[i]);
    return -1;
}

static int parse_count(const char *opt, const char *v, long lo, long hi, long *out) {
    char *end;
    errno = 0;
    long n = strtol(v, &end, 10);
    if (errno || end == v || *end || n < lo || n > hi)
        return fl_cli_usage_error("%s: integer %ld..%ld expected, got '%s'", opt, lo, hi, v);
    *out = n;
    return -1;
}

/* --opt VALUE or --opt=VALUE; *i advances past a separate value. */
static const char *option_value(const sweep *s, int *i, const char *opt) {
    const char *a = s->cli->argv[*i];
    size_t n = strlen(opt);
    if (a[n] == '=') return a + n + 1;
    if (*i + 1 >= s->cli->argc) return NULL;
    return s->cli->argv[++*i];
}

static int is_option(const char *a, const char *opt) {
    size_t n = strlen(opt);
    return strncmp(a, opt, n) == 0 && (a[n] == '\0' || a[n] == '=');
}

static int parse_sweep(sweep *s) {
    const fl_sweep_cli *c = s->cli;
    s->recipe = c->argv[c->operand];
    s->out = "sweep";
    s->jobs = 2;
    s->point = -1;
    s->sandbox = 1;
    if (s->recipe[0] == '-' && s->recipe[1] == '-')
        return fl_cli_usage_error("sweep: RECIPE.lua comes first, then pairs and options");
    if (strcmp(s->recipe, "-") == 0)
        return fl_cli_usage_error("sweep: the recipe must be a file (each point reads it again)");
    s->fixed = calloc((size_t)c->argc, sizeof *s->fixed);
    s->allow = calloc((size_t)c->argc, sizeof *s->allow);
    if (!s->fixed || !s->allow) return fl_cli_usage_error("out of memory");
    for (int i = c->operand + 1; i < c->argc; i++) {
        const char *a = c->argv[i];
        if (strncmp(a, "--", 2) == 0) {
            const char *v = NULL;
            long n = 0;
            int st = -1;
            if (is_option(a, "--grid")) {
                if (!(v = option_value(s, &i, "--grid"))) return fl_cli_usage_error("--grid needs a value");
                st = add_axis(s, v);
            } else if (is_option(a, "--jobs")) {
                if (!(v = option_value(s, &i, "--jobs"))) return fl_cli_usage_error("--jobs needs a value");
                st = parse_count("--jobs", v, 1, MAX_JOBS, &n);
                s->jobs = (int)n;
            } else if (is_option(a, "--out")) {
                if (!(v = option_value(s, &i, "--out"))) return fl_cli_usage_error("--out needs a value");
                if (!*v) return fl_cli_usage_error("--out: folder name expected, got ''");
                s->out = v;
            } else if (is_option(a, "--point")) {
                if (!(v = option_value(s, &i, "--point"))) return fl_cli_usage_error("--point needs a value");
                st = parse_count("--point", v, 0, MAX_POINTS - 1, &n);
                s->point = n;
            } else if (is_option(a, "--allow")) {
                if (!(v = option_value(s, &i, "--allow"))) return fl_cli_usage_error("--allow needs a value");
                if (!*v) return fl_cli_usage_error("--allow: folder name expected, got ''");
                s->allow[s->nallow++] = v;
            } else if (strcmp(a, "--no-sandbox") == 0) {
                s->sandbox = 0;
            } else if (strcmp(a, "--emit-jobs") == 0) {
                s->emit = 1;
            } else if (strcmp(a, "--collect") == 0) {
                s->collect = 1;
            } else {
                static const char *const names[] = {"--grid",  "--jobs",       "--out",
                                                    "--point", "--allow",      "--no-sandbox",
                                                    "--emit-jobs", "--collect", NULL};
                const char *eq = strchr(a, '=');
                return fl_cli_unknown("option", a, eq ? (size_t)(eq - a) : strlen(a), names,
                                      "--grid, --jobs, --out, --point, --allow, --no-sandbox, "
                                      "--emit-jobs, --collect");
            }
            if (st >= 0) return st;
            continue;
        }
        const char *eq = strchr(a, '=');
        if (!eq || eq == a) return fl_cli_usage_error("expected name=value, got '%s'", a);
        size_t len = (size_t)(eq - a);
        if (!valid_name(a, len))
            return fl_cli_usage_error("'%.*s' is not a name (letters, digits, _)", (int)len, a);
        if (len == 7 && strncmp(a, "out_dir", 7) == 0)
            return fl_cli_usage_error("out_dir is set by the sweep (DIR/points/NNN)");
        if (name_taken(s, a, len)) return fl_cli_usage_error("parameter given twice: '%s'", a);
        s->fixed[s->nfixed++] = c->argv[i];
    }
    if (s->emit + s->collect + (s->point >= 0) > 1)
        return fl_cli_usage_error("sweep: --emit-jobs, --collect and --point exclude each other");
    s->npoints = 1;
    for (size_t i = 0; i < s->naxes; i++) {
        if (s->npoints > MAX_POINTS / s->axes[i].count)
            return fl_cli_usage_error("sweep: more than %d points", MAX_POINTS);
        s->npoints *= s->axes[i].count;
    }
    if (s->point >= 0 && (size_t)s->point >= s->npoints)
        return fl_cli_usage_error("--point %ld: the grid has points 0..%zu", s->point, s->npoints - 1);
    s->width = 3;
    for (size_t n = s->npoints - 1; n >= 1000; n /= 10) s->width++;
    ssize_t len = readlink("/proc/self/exe", s->exe, sizeof s->exe - 1);
    if (len > 0) {
        s->exe[len] = '\0';
    } else if (!realpath(c->argv[0], s->exe)) {
        snprintf(s->exe, sizeof s->exe, "%s", c->argv[0]);
    }
    return -1;
}

/* The value index of each axis at point p: the last axis varies fastest. */
static size_t axis_index(const sweep *s, size_t p, size_t a) {
    size_t stride = 1;
    for (size_t k = s->naxes; k-- > a + 1;) stride *= s->axes[k].count;
    return (p / stride) % s->axes[a].count;
}

/* DIR/points/NNN[/file] into buf. */
static void point_path(const sweep *s, size_t p, const char *file, char *buf, size_t size) {
    snprintf(buf, size, "%s/points/%0*zu%s%s", s->out, s->width, p, file ? "/" : "", file ? file : "");
}

/* }==================================================================== */

/* {====================================================================
 * Running the points
 * ===================================================================== */

typedef struct running {
    pid_t pid;
    size_t point;
    struct timespec start;
} running;

static double seconds_since(const struct timespec *t0) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)(t.tv_sec - t0->tv_sec) + 1e-9 * (double)(t.tv_nsec - t0->tv_nsec);
}

/* The worker's command line; the strings are malloc'd into *strings. */
static char **worker_argv(const sweep *s, size_t p, char ***strings, size_t *nstrings) {
    size_t cap = 14 + s->nfixed + s->naxes + 2 * s->nallow;
    char **argv = calloc(cap, sizeof *argv);
    char **own = calloc(s->naxes + 5, sizeof *own);
    if (!argv || !own) {
        free(argv);
        free(own);
        return NULL;
    }
    size_t n = 0, k = 0;
    char buf[PATH_MAX + 64];
    argv[n++] = (char *)(uintptr_t)s->exe;
    snprintf(buf, sizeof buf, "--seed=%lld", (long long)s->cli->seed);
    argv[n++] = own[k++] = strdup(buf);
    if (s->cli->traceback) argv[n++] = (char *)(uintptr_t)"--traceback";
    argv[n++] = (char *)(uintptr_t)"--record";
    point_path(s, p, "record.json", buf, sizeof buf);
    argv[n++] = own[k++] = strdup(buf);
    argv[n++] = (char *)(uintptr_t)"run";
    /* Points run sandboxed (issue 8): they write only in their own folder
     * and the --allow folders, read also the recipe's folder. */
    if (s->sandbox) {
        argv[n++] = (char *)(uintptr_t)"--sandbox";
        argv[n++] = (char *)(uintptr_t)"--allow";
        point_path(s, p, NULL, buf, sizeof buf);
        argv[n++] = own[k++] = strdup(buf);
        for (size_t i = 0; i < s->nallow; i++) {
            argv[n++] = (char *)(uintptr_t)"--allow";
            argv[n++] = (char *)(uintptr_t)s->allow[i];
        }
    }
    argv[n++] = (char *)(uintptr_t)s->recipe;
    for (size_t i = 0; i < s->nfixed; i++) argv[n++] = s->fixed[i];
    for (size_t a = 0; a < s->naxes; a++) {
        const axis *x = &s->axes[a];
        snprintf(buf, sizeof buf, "%.*s=%s", (int)x->name_len, x->name, x->values[axis_index(s, p, a)]);
        argv[n++] = own[k++] = strdup(buf);
    }
    point_path(s, p, NULL, buf, sizeof buf);
    char dir[PATH_MAX + 80];
    snprintf(dir, sizeof dir, "out_dir=%s", buf);
    argv[n++] = own[k++] = strdup(dir);
    argv[n] = NULL;
    *strings = own;
    *nstrings = k;
    for (size_t i = 0; i < k; i++)
        if (!own[i]) return NULL;
    return argv;
}

static void free_strings(char **own, size_t n) {
    for (size_t i = 0; i < n; i++) free(own[i]);
    free(own);
}

/* Starts point p: its folder, stale record removed, stdout.txt and
 * stderr.txt. 0, or -1 with the reason printed. */
static int start_point(const sweep *s, size_t p, running *r) {
    char path[PATH_MAX + 64], out[PATH_MAX + 64], errp[PATH_MAX + 64];
    point_path(s, p, NULL, path, sizeof path);
    if (make_dir(path) != 0) return -1;
    point_path(s, p, "record.json", path, sizeof path);
    if (unlink(path) != 0 && errno != ENOENT) {
        fprintf(stderr, "femlod: %s: cannot remove: %s\n", path, strerror(errno));
        return -1;
    }
    point_path(s, p, "run.json", path, sizeof path);
    unlink(path);
    point_path(s, p, "stdout.txt", out, sizeof out);
    point_path(s, p, "stderr.txt", errp, sizeof errp);
    char **own = NULL;
    size_t nown = 0;
    char **argv = worker_argv(s, p, &own, &nown);
    if (!argv) {
        free_strings(own, nown);
        fprintf(stderr, "femlod: out of memory\n");
        return -1;
    }
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&fa, 1, out, O_WRONLY | O_CREAT | O_TRUNC, 0666);
    posix_spawn_file_actions_addopen(&fa, 2, errp, O_WRONLY | O_CREAT | O_TRUNC, 0666);
    fflush(NULL);
    clock_gettime(CLOCK_MONOTONIC, &r->start);
    int e = posix_spawn(&r->pid, s->exe, &fa, NULL, argv, environ);
    posix_spawn_file_actions_destroy(&fa);
    free(argv);
    free_strings(own, nown);
    if (e != 0) {
        fprintf(stderr, "femlod: cannot start %s: %s\n", s->exe, strerror(e));
        return -1;
    }
    r->point = p;
    return 0;
}

static double tv_seconds(struct timeval t) {
    return (double)t.tv_sec + 1e-6 * (double)t.tv_usec;
}

/* What the sweep saw of a worker, in DIR/points/NNN/run.json. */
static int write_run(const sweep *s, size_t p, int status, const struct rusage *ru, double wall) {
    cJSON *j = cJSON_CreateObject();
    if (WIFEXITED(status)) {
        cJSON_AddNumberToObject(j, "exit", WEXITSTATUS(status));
        cJSON_AddNullToObject(j, "signal");
    } else {
        cJSON_AddNullToObject(j, "exit");
        cJSON_AddNumberToObject(j, "signal", WIFSIGNALED(status) ? WTERMSIG(status) : 0);
    }
    cJSON_AddNumberToObject(j, "seconds", round(wall * 1e3) / 1e3);
    cJSON_AddNumberToObject(j, "user_seconds", round(tv_seconds(ru->ru_utime) * 1e3) / 1e3);
    cJSON_AddNumberToObject(j, "system_seconds", round(tv_seconds(ru->ru_stime) * 1e3) / 1e3);
    cJSON_AddNumberToObject(j, "max_rss_kb", (double)ru->ru_maxrss);
    char path[PATH_MAX + 64];
    point_path(s, p, "run.json", path, sizeof path);
    int st = write_json(path, j);
    cJSON_Delete(j);
    return st;
}

/* {=== the progress bar: on stderr when it is a terminal (and not --quiet),
 * one line redrawn in place, cleared before any other output. */
typedef struct progress {
    int on;
    size_t total, done, failed;
    struct timespec start;
} progress;

static void progress_clear(const progress *b) {
    if (b->on) fputs("\r\033[K", stderr);
}

static void progress_draw(const progress *b) {
    if (!b->on) return;
    double t = seconds_since(&b->start);
    enum { WIDTH = 24 };
    char bar[WIDTH + 1];
    size_t fill = b->total ? b->done * WIDTH / b->total : WIDTH;
    for (size_t i = 0; i < WIDTH; i++) bar[i] = i < fill ? '#' : '.';
    bar[WIDTH] = '\0';
    char eta[32] = "ETA ?";
    double rate = t > 0 ? (double)b->done / t : 0.0;
    if (b->done > 0 && rate > 0) snprintf(eta, sizeof eta, "ETA %.0f s", (double)(b->total - b->done) / rate);
    fprintf(stderr, "\r\033[Ksweep [%s] %zu/%zu points", bar, b->done, b->total);
    if (b->failed) fprintf(stderr, " (%zu failed)", b->failed);
    fprintf(stderr, "  %.1f s  %.2f points/s  %s", t, rate, eta);
    fflush(stderr);
}
/* }=== */

static char *last_stderr_line(const sweep *s, size_t p);

/* Why a point failed, for its console line: the first line of the error its
 * record gives (the recipe's message), else the last line of its
 * stderr.txt; NULL when neither says anything. */
static char *failure_reason(const sweep *s, size_t p) {
    char path[PATH_MAX + 64];
    point_path(s, p, "record.json", path, sizeof path);
    int bad = 0;
    cJSON *rec = read_json_object(path, &bad);
    cJSON *e = rec ? cJSON_GetObjectItemCaseSensitive(rec, "error") : NULL;
    char *why = cJSON_IsString(e) && e->valuestring[0] ? strdup(e->valuestring) : NULL;
    cJSON_Delete(rec);
    if (!why) why = last_stderr_line(s, p);
    if (why) why[strcspn(why, "\r\n")] = '\0';
    return why;
}

/* One line per finished point (unless --quiet); a failed one ends with
 * its reason, so that the console says what results.csv says. */
static void print_point(const sweep *s, size_t p, int status, double wall, long rss_kb) {
    if (s->cli->quiet) return;
    char what[64];
    int ok = WIFEXITED(status) && WEXITSTATUS(status) == 0;
    if (WIFEXITED(status))
        snprintf(what, sizeof what, WEXITSTATUS(status) ? "failed (exit %d)" : "ok", WEXITSTATUS(status));
    else
        snprintf(what, sizeof what, "crashed (%s)", strsignal(WTERMSIG(status)));
    printf("point %0*zu", s->width, p);
    for (size_t a = 0; a < s->naxes; a++)
        printf(" %.*s=%s", (int)s->axes[a].name_len, s->axes[a].name, s->axes[a].values[axis_index(s, p, a)]);
    printf(": %s, %.2f s, %.1f MB", what, wall, (double)rss_kb / 1024.0);
    char *why = ok ? NULL : failure_reason(s, p);
    if (why) printf(": %s", why);
    free(why);
    putchar('\n');
    fflush(stdout);
}

/* Runs points [first, last) with at most s->jobs at once. Returns 0 when
 * every worker could be started and waited for (whatever they returned). */
static int run_points(const sweep *s, size_t first, size_t last) {
    running *r = calloc((size_t)s->jobs, sizeof *r);
    if (!r) return -1;
    size_t next = first, active = 0;
    int failed = 0;
    progress bar = {0};
    bar.on = !s->cli->quiet && isatty(STDERR_FILENO);
    bar.total = last - first;
    clock_gettime(CLOCK_MONOTONIC, &bar.start);
    while (next < last || active > 0) {
        while (!failed && next < last && active < (size_t)s->jobs) {
            progress_clear(&bar); /* a message of start_point starts its own line */
            if (start_point(s, next, &r[active]) != 0) {
                failed = 1;
                break;
            }
            if (s->cli->verbose) {
                fprintf(stderr, "femlod: point %0*zu: started (process %ld)\n", s->width, next,
                        (long)r[active].pid);
                fflush(stderr);
            }
            active++;
            next++;
        }
        if (active == 0) break;
        int status;
        struct rusage ru;
        progress_draw(&bar);
        /* With a bar, poll so that its clock moves; else just wait. */
        pid_t pid = wait4(-1, &status, bar.on ? WNOHANG : 0, &ru);
        if (pid == 0) {
            struct timespec nap = {0, 250000000};
            nanosleep(&nap, NULL);
            continue;
        }
        if (pid < 0) {
            if (errno == EINTR) continue;
            progress_clear(&bar);
            fprintf(stderr, "femlod: waiting for the points: %s\n", strerror(errno));
            free(r);
            return -1;
        }
        for (size_t i = 0; i < active; i++) {
            if (r[i].pid != pid) continue;
            double wall = seconds_since(&r[i].start);
            progress_clear(&bar);
            if (write_run(s, r[i].point, status, &ru, wall) != 0) failed = 1;
            print_point(s, r[i].point, status, wall, ru.ru_maxrss);
            bar.done++;
            if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) bar.failed++;
            r[i] = r[--active];
            break;
        }
    }
    progress_clear(&bar);
    free(r);
    return failed ? -1 : 0;
}

/* }==================================================================== */

/* {====================================================================
 * The manifest and results.csv
 * ===================================================================== */

/* A path under DIR/ as relative to DIR, so that two sweeps into different
 * folders record the same paths. */
static const char *relative_to_out(const sweep *s, const char *path) {
    size_t n = strlen(s->out);
    if (strncmp(path, s->out, n) == 0 && path[n] == '/') return path + n + 1;
    return path;
}

static void relativise_files(const sweep *s, cJSON *list) {
    cJSON *f;
    cJSON_ArrayForEach(f, list) {
        cJSON *p = cJSON_GetObjectItemCaseSensitive(f, "path");
        if (cJSON_IsString(p)) {
            const char *rel = relative_to_out(s, p->valuestring);
            if (rel != p->valuestring) {
                /* a copy: cJSON copies the new value over the old in place,
                 * and the two overlap */
                char *copy = strdup(rel);
                if (copy) {
                    cJSON_SetValuestring(p, copy);
                    free(copy);
                }
            }
        }
    }
}

/* The last non-empty line of a point's stderr.txt, for the error column. */
static char *last_stderr_line(const sweep *s, size_t p) {
    char path[PATH_MAX + 64];
    point_path(s, p, "stderr.txt", path, sizeof path);
    char *data;
    size_t size;
    if (fl_file_read_all(path, &data, &size, NULL) != FEMLOD_OK) return NULL;
    while (size > 0 && (data[size - 1] == '\n' || data[size - 1] == '\r')) data[--size] = '\0';
    char *nl = strrchr(data, '\n');
    char *line = strdup(nl ? nl + 1 : data);
    free(data);
    if (line && !*line) {
        free(line);
        line = NULL;
    }
    return line;
}

static cJSON *detach(cJSON *o, const char *key) {
    cJSON *v = cJSON_DetachItemFromObjectCaseSensitive(o, key);
    return v ? v : cJSON_CreateNull();
}

/* One point's entry of "points" (deterministic) and of "runs" (timings).
 * Returns 1 when the point succeeded. */
static int collect_point(lua_State *L, const sweep *s, size_t p, cJSON *points, cJSON *runs) {
    char path[PATH_MAX + 64], dir[PATH_MAX + 64];
    point_path(s, p, NULL, dir, sizeof dir);
    cJSON *pt = cJSON_CreateObject();
    cJSON_AddNumberToObject(pt, "index", (double)p);
    cJSON_AddStringToObject(pt, "dir", relative_to_out(s, dir));
    cJSON *params = cJSON_AddObjectToObject(pt, "params");
    for (size_t a = 0; a < s->naxes; a++) {
        char name[256];
        snprintf(name, sizeof name, "%.*s", (int)s->axes[a].name_len, s->axes[a].name);
        cJSON_AddItemToObject(params, name, json_word(L, s->axes[a].values[axis_index(s, p, a)]));
    }
    int bad_run, bad_rec;
    point_path(s, p, "run.json", path, sizeof path);
    cJSON *run = read_json_object(path, &bad_run);
    point_path(s, p, "record.json", path, sizeof path);
    cJSON *rec = read_json_object(path, &bad_rec);

    const char *status = "ok";
    char *error = NULL;
    cJSON *ex = run ? cJSON_GetObjectItemCaseSensitive(run, "exit") : NULL;
    cJSON *sig = run ? cJSON_GetObjectItemCaseSensitive(run, "signal") : NULL;
    cJSON *rerr = rec ? cJSON_GetObjectItemCaseSensitive(rec, "error") : NULL;
    char buf[PATH_MAX + 128];
    if (bad_run || bad_rec) {
        status = "failed";
        point_path(s, p, bad_run ? "run.json" : "record.json", path, sizeof path);
        snprintf(buf, sizeof buf, "%s: not a JSON object (damaged?)", relative_to_out(s, path));
        error = strdup(buf);
        cJSON_Delete(rec);
        rec = NULL;
    } else if (!run) {
        status = "not run";
    } else if (cJSON_IsNumber(sig)) {
        status = "crashed";
        snprintf(buf, sizeof buf, "killed by signal %d (%s)", sig->valueint, strsignal(sig->valueint));
        error = strdup(buf);
    } else if (!cJSON_IsNumber(ex) || ex->valueint != 0) {
        status = "failed";
        if (cJSON_IsString(rerr)) error = strdup(rerr->valuestring);
        else error = last_stderr_line(s, p);
    } else if (!rec) {
        status = "failed";
        error = strdup("the point wrote no record (did the recipe call os.exit?)");
    }
    cJSON_AddStringToObject(pt, "status", status);
    if (cJSON_IsNumber(ex)) cJSON_AddNumberToObject(pt, "exit", ex->valuedouble);
    else cJSON_AddNullToObject(pt, "exit");
    if (cJSON_IsNumber(sig)) cJSON_AddNumberToObject(pt, "signal", sig->valuedouble);
    else cJSON_AddNullToObject(pt, "signal");
    if (error) cJSON_AddStringToObject(pt, "error", error);
    else cJSON_AddNullToObject(pt, "error");
    free(error);
    if (rec) {
        cJSON *reads = detach(rec, "reads"), *writes = detach(rec, "writes");
        relativise_files(s, reads);
        relativise_files(s, writes);
        cJSON *meshes = detach(rec, "meshes");
        relativise_files(s, meshes);
        cJSON_AddItemToObject(pt, "femlod", detach(rec, "femlod"));
        cJSON_AddItemToObject(pt, "reads", reads);
        cJSON_AddItemToObject(pt, "writes", writes);
        cJSON_AddItemToObject(pt, "meshes", meshes);
        cJSON_AddItemToObject(pt, "recorded", detach(rec, "recorded"));
    } else {
        cJSON_AddNullToObject(pt, "femlod");
        cJSON_AddArrayToObject(pt, "reads");
        cJSON_AddArrayToObject(pt, "writes");
        cJSON_AddArrayToObject(pt, "meshes");
        cJSON_AddObjectToObject(pt, "recorded");
    }
    cJSON_AddItemToArray(points, pt);

    cJSON *t = cJSON_CreateObject();
    cJSON_AddNumberToObject(t, "index", (double)p);
    static const char *const keys[] = {"seconds", "user_seconds", "system_seconds", "max_rss_kb"};
    for (size_t k = 0; k < sizeof keys / sizeof *keys; k++) {
        cJSON *v = run ? cJSON_GetObjectItemCaseSensitive(run, keys[k]) : NULL;
        if (cJSON_IsNumber(v)) cJSON_AddNumberToObject(t, keys[k], v->valuedouble);
        else cJSON_AddNullToObject(t, keys[k]);
    }
    cJSON_AddItemToArray(runs, t);
    cJSON_Delete(run);
    cJSON_Delete(rec);
    return strcmp(status, "ok") == 0;
}

/* {=== results.csv (RFC 4180: fields with , " or newlines quoted) */

typedef struct text {
    char *s;
    size_t n, cap;
    int bad;
} text;

static void text_add(text *t, const char *s, size_t n) {
    if (t->bad) return;
    if (t->n + n + 1 > t->cap) {
        size_t cap = t->cap ? t->cap : 4096;
        while (cap < t->n + n + 1) cap *= 2;
        char *p = realloc(t->s, cap);
        if (!p) {
            t->bad = 1;
            return;
        }
        t->s = p;
        t->cap = cap;
    }
    memcpy(t->s + t->n, s, n);
    t->n += n;
    t->s[t->n] = '\0';
}

static void csv_field(text *t, const char *s, int first) {
    if (!first) text_add(t, ",", 1);
    if (!s) return;
    if (strpbrk(s, ",\"\r\n") == NULL) {
        text_add(t, s, strlen(s));
        return;
    }
    text_add(t, "\"", 1);
    for (const char *p = s; *p; p++) {
        if (*p == '"') text_add(t, "\"", 1);
        text_add(t, p, 1);
    }
    text_add(t, "\"", 1);
}

static void csv_value(text *t, const cJSON *v) {
    char buf[64];
    if (cJSON_IsNumber(v)) {
        format_number(buf, sizeof buf, v->valuedouble);
        csv_field(t, buf, 0);
    } else if (cJSON_IsString(v)) {
        csv_field(t, v->valuestring, 0);
    } else if (cJSON_IsBool(v)) {
        csv_field(t, cJSON_IsTrue(v) ? "true" : "false", 0);
    } else {
        csv_field(t, NULL, 0);
    }
}

static const char *const MESH_COLUMNS[] = {"triangles", "vertices", "stretch_avg", "stretch_min",
                                           "size_max", "valence_max", "hausdorff", "hausdorff_rel"};
#define N_MESH_COLUMNS (sizeof MESH_COLUMNS / sizeof *MESH_COLUMNS)
static const char *const RUN_COLUMNS[] = {"seconds", "max_rss_kb"};

static int key_in(char **keys, size_t n, const char *k) {
    for (size_t i = 0; i < n; i++)
        if (strcmp(keys[i], k) == 0) return 1;
    return 0;
}

static int compare_cstrings(const void *a, const void *b) {
    return strcmp(*(char *const *)a, *(char *const *)b);
}

static int write_results(const sweep *s, const char *path, const cJSON *points, const cJSON *runs) {
    /* The recorded keys of all points, sorted: one column each. */
    char **keys = NULL;
    size_t nkeys = 0;
    const cJSON *pt, *kv;
    cJSON_ArrayForEach(pt, points) {
        cJSON_ArrayForEach(kv, cJSON_GetObjectItemCaseSensitive(pt, "recorded")) {
            if (key_in(keys, nkeys, kv->string)) continue;
            char **k = realloc(keys, (nkeys + 1) * sizeof *k);
            if (!k) break;
            keys = k;
            keys[nkeys++] = kv->string;
        }
    }
    if (nkeys) qsort(keys, nkeys, sizeof *keys, compare_cstrings);

    text t = {0};
    csv_field(&t, "point", 1);
    csv_field(&t, "dir", 0);
    csv_field(&t, "status", 0);
    char name[300];
    for (size_t a = 0; a < s->naxes; a++) {
        snprintf(name, sizeof name, "%.*s", (int)s->axes[a].name_len, s->axes[a].name);
        csv_field(&t, name, 0);
    }
    csv_field(&t, "mesh", 0);
    for (size_t k = 0; k < N_MESH_COLUMNS; k++) csv_field(&t, MESH_COLUMNS[k], 0);
    for (size_t k = 0; k < nkeys; k++) {
        snprintf(name, sizeof name, "recorded.%s", keys[k]);
        csv_field(&t, name, 0);
    }
    for (size_t k = 0; k < 2; k++) csv_field(&t, RUN_COLUMNS[k], 0);
    csv_field(&t, "error", 0);
    text_add(&t, "\n", 1);

    size_t i = 0;
    cJSON_ArrayForEach(pt, points) {
        char buf[64];
        snprintf(buf, sizeof buf, "%zu", i);
        csv_field(&t, buf, 1);
        csv_value(&t, cJSON_GetObjectItemCaseSensitive(pt, "dir"));
        csv_value(&t, cJSON_GetObjectItemCaseSensitive(pt, "status"));
        const cJSON *params = cJSON_GetObjectItemCaseSensitive(pt, "params");
        for (size_t a = 0; a < s->naxes; a++) {
            snprintf(name, sizeof name, "%.*s", (int)s->axes[a].name_len, s->axes[a].name);
            csv_value(&t, cJSON_GetObjectItemCaseSensitive(params, name));
        }
        /* The point's mesh: the last one it saved. */
        const cJSON *meshes = cJSON_GetObjectItemCaseSensitive(pt, "meshes");
        int nm = cJSON_GetArraySize(meshes);
        const cJSON *m = nm > 0 ? cJSON_GetArrayItem(meshes, nm - 1) : NULL;
        csv_value(&t, m ? cJSON_GetObjectItemCaseSensitive(m, "path") : NULL);
        for (size_t k = 0; k < N_MESH_COLUMNS; k++)
            csv_value(&t, m ? cJSON_GetObjectItemCaseSensitive(m, MESH_COLUMNS[k]) : NULL);
        const cJSON *rec = cJSON_GetObjectItemCaseSensitive(pt, "recorded");
        for (size_t k = 0; k < nkeys; k++) csv_value(&t, cJSON_GetObjectItemCaseSensitive(rec, keys[k]));
        const cJSON *run = cJSON_GetArrayItem(runs, (int)i);
        for (size_t k = 0; k < 2; k++) csv_value(&t, cJSON_GetObjectItemCaseSensitive(run, RUN_COLUMNS[k]));
        csv_value(&t, cJSON_GetObjectItemCaseSensitive(pt, "error"));
        text_add(&t, "\n", 1);
        i++;
    }
    free(keys);
    int st = -1;
    if (t.bad)
        fprintf(stderr, "femlod: %s: out of memory\n", path);
    else
        st = write_file(path, t.s);
    free(t.s);
    return st;
}

/* }=== */

/* The sweep page: femlod.report.sweep_page(manifest-as-Lua, path), so that
 * the page is built by the same Lua as the mesh reports. */
static int push_json_as_lua(lua_State *L, const cJSON *j, int depth) {
    luaL_checkstack(L, 4, "manifest too deep");
    if (cJSON_IsNumber(j)) {
        double v = j->valuedouble;
        if (v == floor(v) && fabs(v) < 9007199254740992.0) lua_pushinteger(L, (lua_Integer)v);
        else lua_pushnumber(L, v);
    } else if (cJSON_IsString(j)) {
        lua_pushstring(L, j->valuestring);
    } else if (cJSON_IsBool(j)) {
        lua_pushboolean(L, cJSON_IsTrue(j));
    } else if (cJSON_IsArray(j) && depth < 16) {
        lua_newtable(L);
        lua_Integer i = 0;
        const cJSON *e;
        cJSON_ArrayForEach(e, j) {
            push_json_as_lua(L, e, depth + 1);
            lua_rawseti(L, -2, ++i);
        }
    } else if (cJSON_IsObject(j) && depth < 16) {
        lua_newtable(L);
        const cJSON *e;
        cJSON_ArrayForEach(e, j) {
            push_json_as_lua(L, e, depth + 1);
            lua_setfield(L, -2, e->string);
        }
    } else {
        lua_pushnil(L);
    }
    return 1;
}

static int sweep_page_protected(lua_State *L) {
    const cJSON *m = (const cJSON *)lua_touserdata(L, 1);
    const char *path = lua_tostring(L, 2);
    lua_getglobal(L, "require");
    lua_pushliteral(L, "femlod.report");
    lua_call(L, 1, 1);
    lua_getfield(L, -1, "sweep_page");
    if (!lua_isfunction(L, -1)) return 0; /* a report module without sweep pages */
    push_json_as_lua(L, m, 0);
    lua_pushstring(L, path);
    lua_call(L, 2, 0);
    lua_pushboolean(L, 1);
    return 1;
}

/* 1 written, 0 no page (a host's own femlod.report), -1 failed. */
static int write_sweep_page(lua_State *L, const cJSON *manifest, const char *path) {
    lua_pushcfunction(L, sweep_page_protected);
    lua_pushlightuserdata(L, (void *)(uintptr_t)manifest);
    lua_pushstring(L, path);
    if (lua_pcall(L, 2, 1, 0) != LUA_OK) {
        fprintf(stderr, "femlod: %s: %s\n", path, lua_tostring(L, -1));
        lua_pop(L, 1);
        return -1;
    }
    int written = lua_toboolean(L, -1);
    lua_pop(L, 1);
    return written;
}

/* Collects every point into DIR/manifest.json, DIR/results.csv and
 * DIR/report.html. Returns the number of points that did not succeed, or
 * -1 when a file could not be written. */
static long collect(lua_State *L, const sweep *s) {
    cJSON *man = cJSON_CreateObject();
    cJSON_AddStringToObject(man, "format", "femlod-sweep");
    cJSON_AddNumberToObject(man, "version", 1);
    cJSON_AddStringToObject(man, "digest", "");
    cJSON *det = cJSON_CreateObject(); /* the part the digest covers */
    cJSON_AddStringToObject(det, "femlod", "femlod " FEMLOD_VERSION_STRING);
    cJSON *recipe = cJSON_AddObjectToObject(det, "recipe");
    cJSON_AddStringToObject(recipe, "path", s->recipe);
    char hex[65];
    long long bytes;
    if (sha256_file(s->recipe, hex, &bytes) == 0) cJSON_AddStringToObject(recipe, "sha256", hex);
    else cJSON_AddNullToObject(recipe, "sha256");
    cJSON_AddNumberToObject(det, "seed", (double)s->cli->seed);
    cJSON *grid = cJSON_AddArrayToObject(det, "grid");
    for (size_t a = 0; a < s->naxes; a++) {
        cJSON *x = cJSON_CreateObject();
        char name[256];
        snprintf(name, sizeof name, "%.*s", (int)s->axes[a].name_len, s->axes[a].name);
        cJSON_AddStringToObject(x, "name", name);
        cJSON *vals = cJSON_AddArrayToObject(x, "values");
        for (size_t k = 0; k < s->axes[a].count; k++)
            cJSON_AddItemToArray(vals, json_word(L, s->axes[a].values[k]));
        cJSON_AddItemToArray(grid, x);
    }
    cJSON *fixed = cJSON_AddObjectToObject(det, "fixed");
    for (size_t i = 0; i < s->nfixed; i++) {
        const char *eq = strchr(s->fixed[i], '=');
        char name[256];
        snprintf(name, sizeof name, "%.*s", (int)(eq - s->fixed[i]), s->fixed[i]);
        cJSON_AddItemToObject(fixed, name, json_word(L, eq + 1));
    }
    cJSON *points = cJSON_AddArrayToObject(det, "points");
    cJSON *runs = cJSON_CreateArray();
    long bad = 0;
    for (size_t p = 0; p < s->npoints; p++)
        if (!collect_point(L, s, p, points, runs)) bad++;

    char *canon = cJSON_PrintUnformatted(det);
    if (canon) {
        sha256_text(canon, hex);
        cJSON_SetValuestring(cJSON_GetObjectItemCaseSensitive(man, "digest"), hex);
        cJSON_free(canon);
    }
    /* Move the deterministic members into the manifest, then the timings. */
    while (det->child) {
        cJSON *item = det->child;
        cJSON_DetachItemViaPointer(det, item);
        cJSON_AddItemToObject(man, item->string, item);
    }
    cJSON_Delete(det);
    cJSON_AddItemToObject(man, "runs", runs);

    char path[PATH_MAX + 32];
    int st = 0;
    snprintf(path, sizeof path, "%s/manifest.json", s->out);
    if (write_json(path, man) != 0) st = -1;
    snprintf(path, sizeof path, "%s/results.csv", s->out);
    if (st == 0 && write_results(s, path, cJSON_GetObjectItemCaseSensitive(man, "points"), runs) != 0)
        st = -1;
    snprintf(path, sizeof path, "%s/report.html", s->out);
    int page = st == 0 ? write_sweep_page(L, man, path) : 0;
    if (page < 0) st = -1;
    if (st == 0 && !s->cli->quiet) {
        printf("%zu point%s: %zu ok, %ld failed; digest %s\n", s->npoints, s->npoints == 1 ? "" : "s",
               s->npoints - (size_t)bad, bad,
               cJSON_GetObjectItemCaseSensitive(man, "digest")->valuestring);
        printf("%s/manifest.json, %s/results.csv%s%s%s\n", s->out, s->out, page ? ", " : "",
               page ? s->out : "", page ? "/report.html" : "");
    }
    cJSON_Delete(man);
    return st == 0 ? bad : -1;
}

/* }==================================================================== */

/* {====================================================================
 * --emit-jobs: one self-contained shell command per point
 * ===================================================================== */

/* Prints s single-quoted for sh when it needs quoting. */
static void print_quoted(const char *s) {
    if (*s && strspn(s, "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_-./=,:+@%") ==
                  strlen(s)) {
        fputs(s, stdout);
        return;
    }
    putchar('\'');
    for (const char *p = s; *p; p++) {
        if (*p == '\'') fputs("'\\''", stdout);
        else putchar(*p);
    }
    putchar('\'');
}

static int emit_jobs(const sweep *s) {
    char cwd[PATH_MAX];
    if (!getcwd(cwd, sizeof cwd)) {
        fprintf(stderr, "femlod: cannot get the current folder: %s\n", strerror(errno));
        return 1;
    }
    for (size_t p = 0; p < s->npoints; p++) {
        fputs("cd ", stdout);
        print_quoted(cwd);
        fputs(" && ", stdout);
        print_quoted(s->exe);
        printf(" --seed=%lld%s sweep ", (long long)s->cli->seed, s->cli->traceback ? " --traceback" : "");
        print_quoted(s->recipe);
        for (size_t i = 0; i < s->nfixed; i++) {
            putchar(' ');
            print_quoted(s->fixed[i]);
        }
        for (size_t a = 0; a < s->naxes; a++) {
            fputs(" --grid ", stdout);
            text t = {0};
            text_add(&t, s->axes[a].name, s->axes[a].name_len + 1); /* with the '=' */
            for (size_t k = 0; k < s->axes[a].count; k++) {
                if (k) text_add(&t, ",", 1);
                text_add(&t, s->axes[a].values[k], strlen(s->axes[a].values[k]));
            }
            if (!t.bad) print_quoted(t.s);
            free(t.s);
        }
        for (size_t i = 0; i < s->nallow; i++) {
            fputs(" --allow ", stdout);
            print_quoted(s->allow[i]);
        }
        if (!s->sandbox) fputs(" --no-sandbox", stdout);
        fputs(" --out ", stdout);
        print_quoted(s->out);
        printf(" --point %zu\n", p);
    }
    return 0;
}

/* }==================================================================== */

int fl_sweep_main(lua_State *L, const fl_sweep_cli *c) {
    sweep s = {0};
    s.cli = c;
    int st = parse_sweep(&s);
    if (st >= 0) {
        sweep_free(&s);
        return st;
    }
    /* Every point would fail the same way: say it once. */
    FILE *rf = fopen(s.recipe, "r");
    if (!rf) {
        fprintf(stderr, "femlod: %s: cannot open: %s\n", s.recipe, strerror(errno));
        sweep_free(&s);
        return 1;
    }
    fclose(rf);
    if (s.emit) {
        st = emit_jobs(&s);
        sweep_free(&s);
        return st;
    }
    char path[PATH_MAX + 32];
    snprintf(path, sizeof path, "%s/points", s.out);
    struct stat sb;
    if (s.collect) {
        long bad = collect(L, &s);
        sweep_free(&s);
        return bad == 0 ? 0 : 1;
    }
    if (s.point < 0 && stat(path, &sb) == 0) {
        fprintf(stderr, "femlod: %s: already holds a sweep; remove it or choose another --out\n", s.out);
        sweep_free(&s);
        return 1;
    }
    if (make_dirs(path) != 0) {
        sweep_free(&s);
        return 1;
    }
    if (s.point >= 0) {
        st = run_points(&s, (size_t)s.point, (size_t)s.point + 1);
        if (st == 0) {
            char rec[PATH_MAX + 64];
            point_path(&s, (size_t)s.point, "run.json", rec, sizeof rec);
            cJSON *run = read_json(rec);
            cJSON *ex = run ? cJSON_GetObjectItemCaseSensitive(run, "exit") : NULL;
            st = cJSON_IsNumber(ex) && ex->valueint == 0 ? 0 : 1;
            cJSON_Delete(run);
        } else {
            st = 1;
        }
        sweep_free(&s);
        return st;
    }
    int ran = run_points(&s, 0, s.npoints);
    long bad = collect(L, &s);
    sweep_free(&s);
    return ran == 0 && bad == 0 ? 0 : 1;
}
