/*
 * help.c - owns the femlod program's help texts (help.h). Each command's
 * page is one string: usage, what it does, its options, examples. The
 * overview names every command in one line and points at the pages. The
 * FMT line is built from the library's format table, so a new format shows
 * up here without an edit.
 */
#include "help.h"

#include "femlod.h"

#include <string.h>

typedef struct page {
    const char *name, *line, *text;
} page;

/* line: the command's row in the overview. text: its page, after the
 * "usage:" line, which is "usage: femlod " NAME and the synopsis, the
 * text's first line. */
static const page pages[] = {
    {"run", "  run RECIPE.lua   run a Lua recipe",
     "run [--sandbox] [--allow DIR] RECIPE.lua [name=value ...]\n"
     "\n"
     "Runs a Lua recipe ('-' reads it from standard input). The pairs are in the\n"
     "global table `params` and are the chunk's arguments (...); the module is\n"
     "require \"femlod\" and the global `femlod`. `femlod RECIPE.lua` is the same.\n"
     "\n"
     "Options (before or after the word run):\n"
     "  --sandbox        no os.execute, io.popen, os.remove ...; read only the\n"
     "                   recipe's folder and --allow folders, write only --allow\n"
     "                   folders\n"
     "  --allow DIR      with --sandbox: let the recipe read and write DIR\n"
     "  --max-memory SIZE  stop (exit 3) past SIZE bytes (suffix K, M, G)\n"
     "  --max-time SECONDS stop (exit 3) after SECONDS of wall-clock time\n"
     "  --record FILE    (before run) also write FILE, a JSON record of the\n"
     "                   parameters, the files read and written and the meshes saved\n"
     "\n"
     "Examples:\n"
     "  femlod run examples/simplify.lua target=3000\n"
     "  femlod run --sandbox --allow out part.lua out_dir=out\n"},
    {"-e", "  -e CODE          run a line of Lua, with params as for run",
     "-e CODE [name=value ...]\n"
     "\n"
     "Runs a line of Lua, with `params`, `femlod` and the options as for run.\n"
     "\n"
     "Examples:\n"
     "  femlod -e 'print(femlod.load(params.mesh))' mesh=part.obj\n"},
    {"info", "  info MESH        print the mesh's quality report",
     "info MESH [options]\n"
     "\n"
     "Prints the quality report of MESH: stretch, size, valence, angles, topology,\n"
     "defects and the stretch histogram.\n"
     "\n"
     "Options:\n"
     "  --report text|row|fields  the report with histograms (default), one\n"
     "                   Table 1 row, or sorted `key value` lines\n"
     "  --format FMT     read MESH in this format, not by its extension\n"
     "  --reference MESH also the Hausdorff distance to MESH\n"
     "\n"
     "Examples:\n"
     "  femlod info part.obj\n"
     "  femlod info part-3k.obj --reference part.obj --report row\n"},
    {"convert", "  convert IN OUT   read IN and write OUT",
     "convert IN OUT [options]\n"
     "\n"
     "Reads IN and writes OUT, each in the format of its extension unless given.\n"
     "\n"
     "Options:\n"
     "  --format FMT     write OUT in this format\n"
     "  --input-format FMT  read IN in this format\n"
     "  --color-by stretch|size|valence|none  (glTF OUT) colour the vertices by\n"
     "                   the measure\n"
     "  --normals        (glTF OUT) write vertex normals\n"
     "\n"
     "Examples:\n"
     "  femlod convert part.obj part.msh\n"
     "  femlod convert part.obj part.glb --color-by stretch --normals\n"},
    {"repair", "  repair IN OUT    repair IN into OUT and print what changed",
     "repair IN OUT [options]\n"
     "\n"
     "Repairs IN into OUT and prints what changed. Every step runs unless turned\n"
     "off with false (a switch alone is true).\n"
     "\n"
     "Options:\n"
     "  --weld TOL|false weld vertices closer than TOL (default 0: equal positions)\n"
     "  --drop-degenerate B  drop degenerate triangles\n"
     "  --drop-duplicates B  drop duplicate triangles\n"
     "  --split-nonmanifold B  cut non-manifold vertices into copies\n"
     "  --orient B       turn triangles to a consistent orientation\n"
     "  --drop-unused B  drop vertices no triangle uses\n"
     "  --format FMT     write OUT in this format\n"
     "  --input-format FMT  read IN in this format\n"
     "\n"
     "Examples:\n"
     "  femlod repair scan.stl scan.obj\n"
     "  femlod repair scan.stl scan.obj --weld 1e-6 --orient false\n"},
    {"improve", "  improve IN OUT   raise every element to the thresholds; print what was done",
     "improve IN OUT [options]\n"
     "\n"
     "Raises every element of IN to the thresholds by edge flips, splits, short-edge\n"
     "collapses and tangential relaxation, keeping features, locks, topology and the\n"
     "distance to IN; writes OUT and prints the operations and what remains, and why.\n"
     "\n"
     "Options (each of the thresholds also takes off):\n"
     "  --min-stretch X  least stretch of every triangle (default 0.2)\n"
     "  --max-size X     longest edge of every triangle\n"
     "  --max-valence N  most neighbours of every vertex (default 12)\n"
     "  --max-deviation X  distance to IN (default 0.001 x the diagonal)\n"
     "  --feature-angle DEG  sharper edges are features (default 40)\n"
     "  --max-normal-change DEG  most turn of a triangle's normal\n"
     "  --max-rounds N   passes over the mesh at most\n"
     "  --lock I,J,K     input vertices (1-based) that must not move\n"
     "\n"
     "Examples:\n"
     "  femlod improve part.stl part_fe.obj\n"
     "  femlod improve part.stl part_fe.obj --min-stretch 0.25 --max-valence 10\n"},
    {"simplify", "  simplify IN OUT  simplify IN into OUT; print the before/after report",
     "simplify IN OUT [options]\n"
     "\n"
     "Simplifies IN into OUT and prints the before/after report. A threshold\n"
     "given as off is not checked.\n"
     "\n"
     "Options:\n"
     "  --target N       stop at N triangles\n"
     "  --ratio R        stop at R x the input's triangles\n"
     "  --tolerance X  --max-deviation X  --min-stretch X  --max-size X\n"
     "  --max-valence N  --feature-angle DEG  --feature-weight W\n"
     "  --max-normal-change DEG   the thresholds (each also takes off)\n"
     "  --keep-boundary  boundary vertices and edges stay\n"
     "  --area-weighted  area-weighted quadrics\n"
     "  --no-error-order the paper's order (Table 1), not the error order: the\n"
     "                   default takes small quadric errors first\n"
     "  --no-improve     do not run the improve stage first on an input that\n"
     "                   breaks a threshold (femlod help improve)\n"
     "  --lock I,J,K     these vertices of IN keep their exact position (1-based)\n"
     "  --fast-above F|off  fast passes down to F x target (F >= 1); default 3\n"
     "                   in the error order, off with --no-error-order\n"
     "  --threads N      0: the idle processors (the output does not depend on it)\n"
     "  --hierarchy PART.flh  also write the vertex hierarchy, down to the\n"
     "                   coarsest mesh the thresholds allow\n"
     "  --hierarchy-floor N|off  stop the hierarchy at N triangles\n"
     "\n"
     "Examples:\n"
     "  femlod simplify cover.obj cover-3k.obj --target 3000\n"
     "  femlod simplify cover.obj cover-3k.obj target=3000 min_stretch=0.3\n"
     "  femlod simplify cover.obj cover-3k.obj --target 3000 --hierarchy cover.flh\n"},
    {"lod", "  lod PART.flh OUT write a mesh from a saved hierarchy",
     "lod PART.flh OUT --size T | --target N\n"
     "\n"
     "Writes a mesh from a hierarchy that simplify --hierarchy saved.\n"
     "\n"
     "Options (one of them):\n"
     "  --size T         the coarsest front refined where a vertex's e_size (mean\n"
     "                   edge length) exceeds T (0 gives the input, inf the\n"
     "                   coarsest mesh)\n"
     "  --target N       N triangles from the saved front, its density kept\n"
     "\n"
     "Examples:\n"
     "  femlod lod cover.flh cover-fine.obj --size 0.02\n"
     "  femlod lod cover.flh cover-5k.obj --target 5000\n"},
    {"sweep", "  sweep RECIPE.lua run the recipe once per point of a parameter grid",
     "sweep RECIPE.lua [name=value ...] --grid NAME=V1,V2,... [--grid ...] [options]\n"
     "\n"
     "Runs the recipe once per grid point (the last --grid varies fastest), each\n"
     "in its own process; writes DIR/points/NNN/, DIR/manifest.json,\n"
     "DIR/results.csv. The name=value pairs are the recipe's fixed parameters.\n"
     "Points run --sandbox, writing only in their folder.\n"
     "\n"
     "Options:\n"
     "  --grid NAME=V1,V2,...  one axis of the grid\n"
     "  --jobs N         at most N points at once (default 2)\n"
     "  --out DIR        the sweep's folder (default sweep)\n"
     "  --emit-jobs      print one command per point instead of running them\n"
     "  --point N        run point N only\n"
     "  --collect        write the manifest from the points already run\n"
     "  --allow DIR      the points may also read and write DIR\n"
     "  --no-sandbox     run the points without the sandbox\n"
     "\n"
     "Examples:\n"
     "  femlod sweep part.lua --grid target=1000,3000 --grid min_stretch=0.2,0.3\n"
     "  femlod sweep part.lua --grid target=1000,3000 --out run1 --emit-jobs\n"},
    {"report", "  report MESH      print the quality report; write an HTML page",
     "report MESH [options]\n"
     "\n"
     "Prints the quality report and the Table 1 rows of MESH; writes an HTML page\n"
     "with histograms and the mesh in a 3D viewer.\n"
     "\n"
     "Options:\n"
     "  --reference ORIGINAL  also the deviation from ORIGINAL\n"
     "  --html OUT.html  write the page\n"
     "  --no-viewer      leave the 3D view out of the page\n"
     "  --max-deviation D  with --reference: flag a deviation above D (length)\n"
     "\n"
     "Examples:\n"
     "  femlod report cover-3k.obj --reference cover.obj --html cover-3k.html\n"},
    {"help", "  help [COMMAND]   print this help, or a command's",
     "help [COMMAND]\n"
     "\n"
     "Prints the overview, or COMMAND's usage, options and examples (as\n"
     "femlod COMMAND --help does).\n"
     "\n"
     "Examples:\n"
     "  femlod help simplify\n"},
};
#define N_PAGES (sizeof pages / sizeof pages[0])

const char *const fl_cli_command_names[] = {"run",    "-e",    "info",   "convert",
                                            "repair", "improve", "simplify", "lod", "sweep",
                                            "report", "help",  NULL};

/* Formats femlod writes but does not read. */
static int write_only(const char *name) {
    return strcmp(name, "vtk") == 0 || strcmp(name, "inp") == 0;
}

/* Prints the names of the formats that are (or are not) write only, after
 * a label of width 16, wrapped before column 80. */
static void print_format_row(FILE *f, const char *label, int writing_only) {
    int col = fprintf(f, "%-16s", label);
    for (const char *const *n = femlod_format_names(); *n; n++) {
        if (write_only(*n) != writing_only) continue;
        if (col + 1 + (int)strlen(*n) >= 80) col = fprintf(f, "\n%16s", "") - 1;
        col += fprintf(f, " %s", *n);
    }
    fputc('\n', f);
}

/* FMT: every format name, the ones read and written first. */
static void print_formats(FILE *f) {
    print_format_row(f, "FMT, read+write:", 0);
    print_format_row(f, "     write only:", 1);
}

static void print_values(FILE *f) {
    fputs("Options of a command: --name VALUE, --name=VALUE or name=VALUE (name with _\n"
          "for -); a switch alone is true. A value is a number when Lua reads it as one\n"
          "(3, -2.5, 1e3, 0x10), true and false are booleans, anything else is a string.\n",
          f);
    print_formats(f);
    fputs("Exit status: 0 success, 1 error, 2 usage error, 3 a limit was exceeded.\n", f);
}

void fl_cli_help_overview(FILE *f) {
    fputs("usage: femlod [options] COMMAND [ARGS] [options of the command]\n"
          "       femlod [options] RECIPE.lua [name=value ...]\n"
          "\n"
          "Commands (femlod help COMMAND, or femlod COMMAND --help: its options):\n",
          f);
    for (size_t i = 0; i < N_PAGES; i++) fprintf(f, "%s\n", pages[i].line);
    fputs("\n"
          "Options:\n"
          "  --seed N         seed math.random with the integer N (default 0: runs repeat)\n"
          "  -q, --quiet      print nothing but what the command is for\n"
          "  -v, --verbose    also print each stage (load, simplify, build hierarchy,\n"
          "                   write ...) with its time and key figures on stderr\n"
          "  --traceback      add a Lua stack traceback to error messages\n"
          "  --sandbox        run and -e: no os.execute, io.popen, os.remove ...; read\n"
          "                   only the recipe's folder and --allow folders, write only\n"
          "                   --allow folders (these four also follow the word run)\n"
          "  --allow DIR      with --sandbox: let the recipe read and write DIR\n"
          "  --max-memory SIZE  stop (exit 3) past SIZE bytes (suffix K, M, G)\n"
          "  --max-time SECONDS stop (exit 3) after SECONDS of wall-clock time\n"
          "  --record FILE    run: also write FILE, a JSON record of the parameters,\n"
          "                   the files read and written (SHA-256) and the meshes saved\n"
          "  -h, --help       print this help and exit\n"
          "  --version        print the version and exit\n"
          "\n",
          f);
    print_values(f);
}

const char *fl_cli_help_synopsis(const char *name, int *len) {
    for (size_t i = 0; i < N_PAGES; i++) {
        if (strcmp(pages[i].name, name) != 0) continue;
        *len = (int)strcspn(pages[i].text, "\n");
        return pages[i].text;
    }
    return NULL;
}

int fl_cli_help_command(FILE *f, const char *name) {
    for (size_t i = 0; i < N_PAGES; i++) {
        if (strcmp(pages[i].name, name) != 0) continue;
        fprintf(f, "usage: femlod %s", pages[i].text);
        /* The pages of the commands that read or write meshes end with the
         * value rules and the formats. */
        static const char *const with_files[] = {"info", "convert", "repair", "improve", "simplify",
                                                 "lod", "report", NULL};
        for (const char *const *w = with_files; *w; w++) {
            if (strcmp(*w, name) != 0) continue;
            fputc('\n', f);
            print_values(f);
        }
        return 0;
    }
    return -1;
}
