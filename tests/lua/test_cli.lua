-- test_cli.lua: the femlod program from outside: exit codes (0 ok, 1 error,
-- 2 usage), what goes to stdout and to stderr, the options-command-pairs
-- grammar, parameter conversion, -e, info, convert, simplify, --seed.

local T = dofile((arg[0]:match("^(.*)/") or ".") .. "/check.lua")
local femlod = require "femlod"

local P = params
assert(P and P.femlod and P.tmp and P.shared and P.examples, "run through ctest: needs femlod=, tmp=, shared=, examples=")
local FEMLOD = P.femlod
local function path(name) return P.tmp .. "/cli_" .. name end

local function quote(s) return "'" .. tostring(s):gsub("'", "'\\''") .. "'" end

-- Runs femlod with the arguments; returns exit code, stdout, stderr.
local ERR = path("stderr.txt")
local run = T.runner(FEMLOD, ERR).run

-- A recipe file in tmp.
local function recipe(name, text)
  local p = path(name)
  T.writefile(p, text)
  return p
end

-- {====== --version, --help
do
  local code, out, err = run("--version")
  T.eq(code, 0, "--version exit")
  T.check(out:find("^femlod 0%.1%.0 %(Lua 5%.4%.%d+%)\n$"), "--version text: " .. out)
  T.eq(err, "", "--version: nothing on stderr")
  T.eq(run("-v"), 2, "-v is --verbose, not --version: no command given")
  code, out, err = run("--help")
  T.eq(code, 0, "--help exit")
  T.eq(err, "", "--help: nothing on stderr")
  for _, want in ipairs { "^usage: femlod %[options%] COMMAND", "\n  run RECIPE%.lua ", "\n  info MESH ",
    "\n  convert IN OUT ", "\n  simplify IN OUT ", "\n  repair IN OUT ", "\n  report MESH ", "\n  sweep RECIPE%.lua ",
    "\n  lod PART%.flh OUT ", "\n  help %[COMMAND%] ", "\n  %-e CODE ", "\n  %-%-seed N ", "\n  %-q, %-%-quiet ",
    "\n  %-v, %-%-verbose ", "\n  %-%-traceback ", "femlod help COMMAND, or femlod COMMAND %-%-help",
    "\nFMT, read%+write: obj stl stl_ascii stl_binary off ply ply_ascii ply_binary gltf\n%s+glb msh msh2 medit\n"
    .. "     write only: vtk inp\n",
    "Exit status: 0 success, 1 error, 2 usage error, 3 a limit was exceeded" } do
    T.check(out:find(want), "--help mentions " .. want)
  end

  T.eq(select(2, run("-h")), out, "-h is --help")
  T.eq(select(2, run("help")), out, "help command")
end
-- }======

-- {====== usage errors: exit 2, stdout empty, the problem on stderr's first line
local function usage(expect_first_line, ...)
  local code, out, err = run(...)
  local args = table.concat({ ... }, " ")
  T.eq(code, 2, "exit 2 for: " .. args)
  T.eq(out, "", "stdout empty for: " .. args)
  T.eq(err:match("^[^\n]*"), expect_first_line, "message for: " .. args)
  T.check(err:find("\nusage: femlod ") ~= nil, "usage line for: " .. args)
end
usage("femlod: no command given")
usage("femlod: unknown option '--bogus' (the options of a command follow it: femlod help COMMAND)", "--bogus")
usage("femlod: unknown option '--bogus' (the options of a command follow it: femlod help COMMAND)", "--quiet",
  "--bogus", "run", "x.lua")
usage("femlod: unknown option '--verbos'; did you mean --verbose?", "--verbos", "info", "x.obj")
usage("femlod: unknown command 'frobnicate' (valid: run, -e, info, convert, repair, simplify, lod, sweep, report, "
  .. "help)", "frobnicate")
usage("femlod: unknown command 'simplfy'; did you mean simplify?", "simplfy", "a.obj", "b.obj")
usage("femlod: unknown command 'conver'; did you mean convert?", "help", "conver")
usage("femlod: missing a recipe", "run")
usage("femlod: missing a line of Lua", "-e")
usage("femlod: missing a mesh file", "info")
usage("femlod: missing an input and an output file", "convert", "a.obj")
usage("femlod: --seed needs a value", "--seed")
usage("femlod: --seed: integer expected, got 'abc'", "--seed", "abc", "-e", "")
usage("femlod: --seed: integer expected, got '1.5'", "--seed=1.5", "-e", "")
usage("femlod: expected name=value, got 'notapair'", "-e", "", "notapair")
usage("femlod: expected name=value, got '=3'", "-e", "", "=3")
usage("femlod: parameter given twice: 'a=2'", "-e", "", "a=1", "a=2")
usage("femlod: unknown parameter 'bogus' (valid: format, reference, report)", "info", "x.obj", "bogus=1")
usage("femlod: report: unknown report 'xml' (valid: text, row, fields)", "info", "x.obj", "report=xml")
usage("femlod: format: unknown format 'xyz' (valid: obj, stl, stl_ascii, stl_binary, off, ply, ply_ascii, ply_binary, gltf, glb, msh, msh2, vtk, inp, medit)",
  "convert", "a.obj", "b.obj", "format=xyz")
usage("femlod: unknown parameter 'formt'; did you mean format?", "convert", "a.obj", "b.obj", "formt=obj")
usage("femlod: unknown parameter 'zzz' (valid: format, input_format, color_by, normals)", "convert", "a.obj",
  "b.obj", "zzz=obj")
-- Options come first: after the command they are operands or pairs.
usage("femlod: expected name=value, got '--quiet'", "-e", "", "--quiet")
-- }======

-- {====== recipes: errors give file:line, exit 1
do
  local p = recipe("boom.lua", "local femlod = require 'femlod'\nlocal x = 1\nerror('boom')\n")
  local code, out, err = run("run", p)
  T.eq(code, 1, "recipe error exit 1")
  T.eq(out, "", "nothing on stdout")
  T.eq(err, "femlod: " .. p .. ":3: boom\n", "one line, with file:line")

  -- The same through the API: the position is the recipe's calling line.
  p = recipe("api.lua", "local femlod = require 'femlod'\n\nlocal m = femlod.load(nil)\n")
  code, out, err = run("run", p)
  T.eq(code, 1, "API error exit 1")
  T.eq(err, "femlod: " .. p .. ":3: bad argument #1 to 'load' (string expected, got nil)\n", "API error text")

  local missing = path("missing.obj")
  p = recipe("load.lua", "local femlod = require 'femlod'\nlocal m = femlod.load(...)\n")
  code, out, err = run("run", p, "unused=1")
  T.eq(code, 1, "load error exit 1")
  -- varargs are the pairs: femlod.load("unused=1") fails with an unknown extension
  T.eq(err, "femlod: " .. p .. ":2: unused=1: unknown file extension; supported: .obj, .stl, .off, .ply, .gltf, .glb, .msh, .vtk, .inp, .mesh (or give the format)\n",
    "load error names recipe line and file")

  -- An error inside a function is placed where it happened; --traceback adds the stack.
  p = recipe("deep.lua", "local function f(x)\n  return x.field\nend\nf(nil)\n")
  code, out, err = run("run", p)
  T.eq(code, 1, "runtime error exit 1")
  T.check(err:find("^femlod: " .. p:gsub("%p", "%%%0") .. ":2: attempt to index a nil value %(local 'x'%)\n$"),
    "runtime error text: " .. err)
  code, out, err = run("--traceback", "run", p)
  T.eq(code, 1, "with traceback exit 1")
  T.check(err:find("^femlod: " .. p:gsub("%p", "%%%0") .. ":2: attempt to index"), "traceback keeps the first line")
  T.check(err:find("\nstack traceback:\n"), "--traceback prints the stack")
  T.check(err:find(":4: in main chunk"), "the stack names the calling line")

  -- Syntax errors, missing recipes, bytecode.
  p = recipe("syntax.lua", "local x = = 1\n")
  code, out, err = run("run", p)
  T.eq(code, 1, "syntax error exit 1")
  T.check(err:find("^femlod: " .. p:gsub("%p", "%%%0") .. ":1: unexpected symbol near '='\n$"), "syntax error: " .. err)
  code, out, err = run("run", path("no_such_recipe.lua"))
  T.eq(code, 1, "missing recipe exit 1")
  T.eq(err, "femlod: " .. path("no_such_recipe.lua") .. ": cannot open: No such file or directory\n", "missing recipe")
  p = path("bytecode.lua")
  T.writefile(p, string.dump(function() print("ran") end))
  code, out, err = run("run", p)
  T.eq(code, 1, "bytecode refused")
  T.eq(out, "", "bytecode did not run")
  T.check(err:find("attempt to load a binary chunk %(mode is 't'%)"), "bytecode message: " .. err)

  -- Error values that are not strings.
  p = recipe("table_error.lua", "error({})\n")
  T.eq(select(3, run("run", p)), "femlod: (error object is a table value)\n", "table error value")
  p = recipe("tostring_error.lua", "error(setmetatable({}, { __tostring = function() return 'custom' end }))\n")
  T.eq(select(3, run("run", p)), "femlod: custom\n", "__tostring error value")

  -- os.exit passes its status through; a recipe's output reaches stdout.
  p = recipe("exit.lua", "print('before')\nos.exit(7)\n")
  code, out = run("run", p)
  T.eq(code, 7, "os.exit status")
  T.eq(out, "before\n", "output before os.exit")
end
-- }======

-- {====== exit 3: a limit was exceeded
do
  -- An OFF header declaring more vertices than 32-bit indices can number.
  local huge = path("huge.off")
  T.writefile(huge, "OFF\n5000000000 1 0\n")
  local code, out, err = run("info", huge)
  T.eq(code, 3, "info: limit exit 3")
  T.check(err:find("^femlod: " .. huge:gsub("%p", "%%%0") .. ":2: .*limit") ~= nil, "limit message: " .. err)
  code = run("-e", "femlod.load(...)", "p=" .. huge)
  T.eq(code, 1, "varargs are the raw 'p=...' strings: no such file, exit 1")
  code, out, err = run("-e", "femlod.load(params.p)", "p=" .. huge)
  T.eq(code, 3, "recipe dying of a limit: exit 3")
  T.check(err:find("^femlod: %(command line%):1: "), "with the recipe position: " .. err)
  T.eq(run("--traceback", "-e", "femlod.load(params.p)", "p=" .. huge), 3, "exit 3 with a traceback too")
  T.eq(run("-e", "local ok, e = pcall(femlod.load, params.p); error(e, 0)", "p=" .. huge), 3,
    "the limit error re-raised: exit 3")
  T.eq(run("-e", "pcall(femlod.load, params.p); error('other')", "p=" .. huge), 1,
    "a limit error caught, then another error: exit 1")
  T.eq(run("-e", "pcall(femlod.load, params.p)", "p=" .. huge), 0, "a limit error caught: success")
end
-- }======

-- {====== params, arg, varargs, the global femlod
do
  local p = recipe("params.lua", [[
local keys = {}
for k in pairs(params) do keys[#keys + 1] = k end
table.sort(keys)
for _, k in ipairs(keys) do
  local v = params[k]
  io.write(k, "=", math.type(v) or type(v), ":", tostring(v), "\n")
end
io.write("arg0=", arg[0], " arg-1=", arg[-1], " arg1=", arg[1], " n=", select("#", ...), " first=", (...), "\n")
io.write("global=", tostring(femlod == require "femlod"), "\n")
]])
  local code, out, err = run("run", p, "n=3", "f=2.5", "e=1e3", "h=0x10", "neg=-4", "dot=.5", "t=true", "fa=false",
    "s=hello", "eq=a=b", "empty=", "sp=a b", "nan=nan", "inf=inf", "up=TRUE", "comma=1,5", "ws= 7 ")
  T.eq(code, 0, "params recipe runs")
  T.eq(err, "", "params: nothing on stderr")
  T.eq(out, table.concat({
    "comma=string:1,5", "dot=float:0.5", "e=float:1000.0", "empty=string:", "eq=string:a=b", "f=float:2.5",
    "fa=boolean:false", "h=integer:16", "inf=string:inf", "n=integer:3", "nan=string:nan", "neg=integer:-4",
    "s=string:hello", "sp=string:a b", "t=boolean:true", "up=string:TRUE", "ws=integer:7",
    "arg0=" .. p .. " arg-1=run arg1=n=3 n=17 first=n=3", "global=true", "" }, "\n"), "params converted as Lua does")

  -- femlod RECIPE.lua is femlod run RECIPE.lua, without "run" in arg.
  code, out = run(p, "x=1")
  T.eq(code, 0, "recipe without run")
  T.check(out:find("\nx=integer:1\n", 1, true) or out:find("^x=integer:1\n"), "recipe without run gets params")
  T.check(out:find("arg0=" .. p .. " arg-1=" .. FEMLOD .. " arg1=x=1", 1, true), "arg table without run: " .. out)

  -- -e: a line of Lua with params and the global femlod.
  code, out, err = run("-e", "print(params.x + 1, femlod._VERSION, arg[0] ~= nil)", "x=41")
  T.eq(code, 0, "-e runs")
  T.eq(out, "42\tfemlod 0.1.0\ttrue\n", "-e output")
  code, out, err = run("-e", "error('bad')")
  T.eq(code, 1, "-e error exit 1")
  T.eq(err, "femlod: (command line):1: bad\n", "-e error text")
  code, out = run("--", "-e", "print'after --'")
  T.eq(out, "after --\n", "-- ends the options")
  -- a recipe from standard input
  local pipe = assert(io.popen("echo 'print(params.k * 2)' | " .. quote(FEMLOD) .. " run - k=21 2>" .. quote(ERR)))
  T.eq(pipe:read("a"), "42\n", "recipe from stdin")
  pipe:close()
end
-- }======

-- {====== --seed: runs repeat
do
  local p = recipe("random.lua", "print(math.random(1, 1000000000), math.random(), math.random(1, 6))\n")
  local _, a = run("--seed", "42", "run", p)
  local _, b = run("--seed=42", "run", p)
  local _, c = run("--seed", "43", "run", p)
  local _, d = run("run", p)
  local _, e = run("run", p)
  local _, z = run("--seed", "0", "run", p)
  T.check(a ~= "", "random recipe printed")
  T.eq(b, a, "same seed, same numbers")
  T.check(c ~= a, "another seed, other numbers")
  T.eq(e, d, "without --seed runs repeat")
  T.eq(d, z, "the default seed is 0")
  -- --seed N is math.randomseed(N): the same numbers as here, in this process.
  local function expected(seed)
    math.randomseed(seed)
    local x, y, z = math.random(1, 1000000000), math.random(), math.random(1, 6)
    return tostring(x) .. "\t" .. tostring(y) .. "\t" .. tostring(z) .. "\n"
  end
  T.eq(a, expected(42), "--seed 42 is math.randomseed(42)")
  T.eq(d, expected(0), "no --seed is math.randomseed(0)")
  local _, neg = run("--seed", "-5", "-e", "print(math.random(100))")
  T.check(neg:find("^%d+\n$"), "negative seeds are integers too")
end
-- }======

-- {====== info
local fandisk = P.examples .. "/data/fandisk.obj"
do
  local code, out, err = run("info", fandisk)
  T.eq(code, 0, "info exit")
  T.eq(err, "", "info: nothing on stderr")
  T.check(out:find("^fandisk%.obj: 12946 triangles, 6475 vertices\n"), "info first line: " .. out:match("^[^\n]*"))
  T.check(out:find("\n  stretch     avg 0%.744457  min 0%.355561 "), "info stretch line")
  T.check(out:find("\n  valence     avg [%d.]+  max 9\n"), "info valence line")
  T.check(out:find("\n  topology    closed, manifold, oriented; 1 component"), "info topology line")
  T.check(out:find("\n  stretch histogram:\n"), "info histogram")
  T.check(not out:find("hausdorff"), "no hausdorff without reference")
  code, out = run("info", fandisk, "report=row")
  T.eq(out, "fandisk.obj (0.9206 x 0.5111 x 1) | - | 12946 | 0.744, 0.356 | 0.05466 | 9\n", "info report=row")
  code, out = run("info", fandisk, "report=fields")
  T.check(out:find("\ntriangles 12946\n") and out:find("\nvalence_max 9\n") and out:find("\nclosed true\n"),
    "info report=fields")
  code, out = run("info", fandisk, "reference=" .. fandisk)
  T.eq(code, 0, "info with a reference")
  T.check(out:find("\n  hausdorff   [%d.e+-]+ %("), "info prints the hausdorff line with a reference")
  -- format= reads a file whose extension says nothing.
  local copy = path("fandisk.surf")
  T.writefile(copy, T.readfile(fandisk))
  code, out = run("info", copy, "format=obj")
  T.eq(code, 0, "info format=obj")
  T.check(out:find("^cli_fandisk%.surf: 12946 triangles"), "info format=obj output")
  code, out, err = run("info", copy)
  T.eq(code, 1, "info of an unknown extension fails")
  T.eq(err, "femlod: " .. copy .. ": unknown file extension; supported: .obj, .stl, .off, .ply, .gltf, .glb, .msh, .vtk, .inp, .mesh (or give the format)\n",
    "info error has no recipe position")
  code, out, err = run("info", path("missing.obj"))
  T.eq(code, 1, "info of a missing file")
  T.eq(out, "", "info of a missing file prints no report")
  T.eq(err, "femlod: " .. path("missing.obj") .. ": cannot open: No such file or directory\n", "info missing file text")
  -- The quickstart example: what README tells a newcomer to run.
  code, out, err = run(P.examples .. "/quickstart.lua")
  T.eq(code, 0, "quickstart runs")
  T.eq(err, "", "quickstart: nothing on stderr")
  T.check(out:find("^fandisk%.obj: 12946 triangles, 6475 vertices\n"), "quickstart prints the report")
  code, out = run(P.examples .. "/quickstart.lua", "mesh=" .. P.shared .. "/sphereWithHole.stl")
  T.check(out:find("^sphereWithHole%.stl: 285 triangles, 146 vertices\n"), "quickstart mesh=PATH")
end
-- }======

-- {====== convert
do
  local stl, back = path("fandisk.stl"), path("fandisk_back.obj")
  os.remove(stl)
  local code, out, err = run("convert", fandisk, stl)
  T.eq(code, 0, "convert exit")
  T.eq(err, "", "convert: nothing on stderr")
  T.eq(out, stl .. ": 12946 triangles, 6475 vertices (stl)\n", "convert summary")
  T.eq(#(T.readfile(stl) or ""), 84 + 50 * 12946, "binary STL written")
  code, out = run("--quiet", "convert", stl, back)
  T.eq(code, 0, "convert back")
  T.eq(out, "", "--quiet: no summary")
  local _, a = run("info", fandisk, "report=fields")
  local _, b = run("info", back, "report=fields")
  T.eq(a:match("\ntriangles %d+\n"), b:match("\ntriangles %d+\n"), "same triangles after OBJ -> STL -> OBJ")
  T.eq(a:match("\nvertices %d+\n"), b:match("\nvertices %d+\n"), "same vertices after OBJ -> STL -> OBJ")
  T.eq(a:match("\nclosed %a+\n"), b:match("\nclosed %a+\n"), "same topology")

  local ascii = path("fandisk_ascii.stl")
  code, out = run("convert", fandisk, ascii, "format=stl_ascii")
  T.eq(out, ascii .. ": 12946 triangles, 6475 vertices (stl_ascii)\n", "convert format=stl_ascii summary")
  T.eq((T.readfile(ascii) or ""):sub(1, 5), "solid", "format=stl_ascii wrote ASCII")
  local ply, off = path("fandisk.ply"), path("fandisk.off")
  T.eq(run("convert", ascii, ply), 0, "STL -> PLY")
  T.eq(run("convert", ply, off), 0, "PLY -> OFF")
  local _, c = run("info", off, "report=fields")
  T.eq(c:match("\nstretch_avg [%d.]+\n"), a:match("\nstretch_avg [%d.]+\n"), "quality survives STL, PLY, OFF")
  local data = path("fandisk.data")
  T.eq(run("convert", off, data, "format=obj", "input_format=off"), 0, "convert with both formats given")
  T.eq((T.readfile(data) or ""):sub(1, 2) ~= "OF", true, "format= decides the output format")

  -- A failed convert leaves no output file, and never clobbers one.
  local bad, out_file = path("bad.obj"), path("never.stl")
  T.writefile(bad, "v 0 0 0\nv 1 0 0\nf 1 2 3\n")
  os.remove(out_file)
  code, out, err = run("convert", bad, out_file)
  T.eq(code, 1, "convert of a bad file fails")
  T.eq(out, "", "no summary for a failed convert")
  T.check(err:find("^femlod: " .. bad:gsub("%p", "%%%0") .. ":3: "), "the error names the bad line: " .. err)
  T.check(not T.exists(out_file), "no output file after a failed convert")
  T.writefile(out_file, "keep me")
  T.eq(run("convert", bad, out_file), 1, "failed convert over an existing file")
  T.eq(T.readfile(out_file), "keep me", "existing output untouched")
  code, out, err = run("convert", fandisk, P.tmp .. "/no_such_dir/x.stl")
  T.eq(code, 2, "convert into a missing folder: a usage error")
  T.eq(err:match("^[^\n]*"), "femlod: " .. P.tmp .. "/no_such_dir/x.stl: folder " .. P.tmp .. "/no_such_dir does not exist",
    "convert into a missing folder: message")
  T.check(not T.exists(P.tmp .. "/no_such_dir/x.stl"), "nothing written")
end
-- }======

-- {====== repair
do
  local spider, out = P.shared .. "/spider_binary.stl", path("spider_fixed.obj")
  os.remove(out)
  local code, text, err = run("repair", spider, out)
  T.eq(code, 0, "repair exit: " .. err)
  T.eq(err, "", "repair: nothing on stderr")
  T.eq(text, spider .. ": 1368 triangles, 722 vertices\n"
    .. "         0  vertices welded into an earlier one\n"
    .. "        56  degenerate triangles dropped\n"
    .. "         0  duplicate triangles dropped\n"
    .. "         0  vertex copies cutting non-manifold vertices\n"
    .. "         4  triangles turned over\n"
    .. "         0  unused vertices dropped\n"
    .. "         0  edges left inconsistent (not orientable)\n"
    .. "         0  non-manifold edges left\n"
    .. out .. ": 1312 triangles, 722 vertices (obj)\n", "repair report")
  local q = femlod.load(out):quality()
  T.check(q.manifold and q.oriented and q.degenerate == 0, "repair wrote a manifold, oriented mesh")
  code, text = run("--quiet", "repair", spider, out, "orient=false", "weld=false")
  T.eq(code, 0, "repair with options")
  T.eq(text, "", "--quiet: no report")
  T.check(not femlod.load(out):quality().oriented, "orient=false: the orientation is left alone")
  local function usage_err(expected, ...)
    local c, o, e = run(...)
    T.eq(c, 2, "usage exit for " .. table.concat({ ... }, " "))
    T.eq(o, "", "nothing on stdout")
    T.eq(e:match("^[^\n]*"), "femlod: " .. expected, "usage message")
  end
  usage_err("weld: a finite length >= 0 or false expected, got -1", "repair", spider, out, "weld=-1")
  usage_err("orient: true or false expected, got 'yes'", "repair", spider, out, "orient=yes")
  usage_err("unknown parameter 'wled'; did you mean weld?", "repair", spider, out, "wled=1")
  usage_err("unknown parameter 'zzz' (valid: weld, drop_degenerate, drop_duplicates, split_nonmanifold, "
    .. "orient, drop_unused, format, input_format)", "repair", spider, out, "zzz=1")
  usage_err("--orient: true or false expected, got 'yes'", "repair", spider, out, "--orient=yes")
  usage_err("--weld: a finite length >= 0 or false expected, got -1", "repair", spider, out, "--weld", "-1")
  usage_err("unknown option '--wled'; did you mean --weld?", "repair", spider, out, "--wled", "1")
  usage_err("missing an input and an output file", "repair", spider)
  local before = T.readfile(out)
  code, text, err = run("repair", P.shared .. "/missing.stl", out)
  T.eq(code, 1, "repair of a missing file: exit 1")
  T.check(err:find("missing%.stl: cannot open"), "names the file: " .. err)
  T.eq(T.readfile(out), before, "the old output is kept")
end
-- }======

-- {====== simplify
do
  local out = path("simplified.obj")
  os.remove(out)
  local code, text, err = run("simplify", fandisk, out, "--target", "3000", "--min-stretch", "0.3")
  T.eq(code, 0, "simplify exit")
  T.eq(err, "", "simplify: nothing on stderr")
  local lines = {}
  for l in text:gmatch("[^\n]*") do if l ~= "" then lines[#lines + 1] = l end end
  T.eq(#lines, 8, "simplify prints 8 lines: " .. text)
  T.eq(lines[1], "model (H x W x D) | state | elements | stretch (avg, min) | size (max) | valence (max)", "header")
  T.eq(lines[2], "fandisk.obj (0.9206 x 0.5111 x 1) | original | 12946 | 0.744, 0.356 | 0.05466 | 9", "original row")
  T.check(lines[3]:find("^fandisk%.obj %(0%.9206 x 0%.5111 x 1%) | simplified | 3000 | 0%.%d%d%d, 0%.%d%d%d | [%d.]+ | %d+$"),
    "simplified row: " .. tostring(lines[3]))
  local smin = tonumber(lines[3]:match("| 0%.%d%d%d, (0%.%d%d%d) |"))
  T.check(smin and smin >= 0.3, "the row shows stretch min >= 0.3: " .. tostring(smin))
  T.check(lines[4]:find("^stop: target; %d+ collapses %(0 in the pre%-phase, %d+ in fast passes on %d threads?%) in [%d.]+ s$"),
    "stop line: " .. tostring(lines[4]))
  T.check(lines[5]:find("^rejected: tolerance %d+, deviation 0, stretch %d+, size %d+, valence %d+, foldover %d+, "
    .. "topology %d+, intersection %d+$"), "rejected line: " .. tostring(lines[5]))
  T.eq(lines[6], "violating output: 0 triangles; dropped degenerate: 0", "violating line")
  T.check(lines[7]:find("^thresholds: target 3000, tolerance [%d.e+-]+, max_deviation off, min_stretch 0%.3, "),
    "thresholds line: " .. tostring(lines[7]))
  T.eq(lines[8], out .. ": 3000 triangles, 1502 vertices (obj)", "summary line")
  local m = femlod.load(out)
  T.eq(m:counts().triangles, 3000, "simplify wrote OUT")
  T.check(m:quality().stretch_min >= 0.3, "OUT meets --min-stretch")
  -- The rows come from the row's fields alone (push_row_quality): the rows
  -- of the full quality tables (OUT reads back exactly)
  local report = require "femlod.report"
  T.eq(lines[2], report.row(femlod.load(fandisk):quality(), "fandisk.obj", "original"), "original row = report.row(quality)")
  T.eq(lines[3], report.row(m:quality(), "fandisk.obj", "simplified"), "simplified row = report.row(quality)")

  -- The name=value form is the same run: the same bytes.
  local out2 = path("simplified2.obj")
  code, text = run("--quiet", "simplify", fandisk, out2, "target=3000", "min_stretch=0.3")
  T.eq(code, 0, "simplify with name=value")
  T.eq(text, "", "--quiet: nothing printed")
  T.check(T.readfile(out2) == T.readfile(out), "flags and name=value give byte-identical output")
  code, text = run("simplify", fandisk, out2, "--target=3000", "--min-stretch=0.3")
  T.check(T.readfile(out2) == T.readfile(out), "--flag=value too")
  -- --error-order: the Lua option error_order, on by default; --no-error-order
  -- and error_order=false: the paper's order (another mesh)
  local out5, out6 = path("simplified5.obj"), path("simplified6.obj")
  T.eq(run("simplify", fandisk, out5, "--target", "3000", "--error-order"), 0, "--error-order")
  T.eq(run("simplify", fandisk, out6, "--target", "3000", "error_order=true"), 0, "error_order=true")
  T.check(T.readfile(out5) == T.readfile(out6), "--error-order is error_order=true")
  local out7 = path("simplified7.obj")
  T.eq(run("simplify", fandisk, out7, "--target", "3000"), 0, "the default order")
  T.check(T.readfile(out5) == T.readfile(out7), "--error-order is the default")
  T.eq(run("simplify", fandisk, out6, "--target", "3000", "--no-error-order"), 0, "--no-error-order")
  T.check(T.readfile(out5) ~= T.readfile(out6), "--no-error-order changes the order")
  T.eq(run("simplify", fandisk, out7, "--target", "3000", "error_order=false"), 0, "error_order=false")
  T.check(T.readfile(out7) == T.readfile(out6), "error_order=false is --no-error-order")
  code, text = run("simplify", fandisk, out7, "--target", "3000", "--error-order", "--no-error-order")
  T.eq(code, 2, "--error-order and --no-error-order together")

  -- off, switches and lock
  local out3 = path("simplified3.stl")
  code, text, err = run("simplify", fandisk, out3, "--ratio", "0.5", "--max-valence", "off", "--tolerance", "off",
    "--keep-boundary", "--area-weighted", "--lock", "1,2,3", "feature_angle=30")
  T.eq(code, 0, "simplify with off, switches and lock: " .. err)
  T.check(text:find("\nthresholds: target 6473, tolerance off, max_deviation off, min_stretch 0%.2, max_size [%d.]+, "
    .. "max_valence off, feature_angle 30, "), "off shows in the thresholds line: " .. text)
  T.check(text:find("\n" .. out3:gsub("%p", "%%%0") .. ": %d+ triangles, %d+ vertices %(stl%)\n$"), "STL summary")
  local pos, set = femlod.load(fandisk):positions(), {}
  for _, p in ipairs(femlod.load(out3):positions()) do set[string.format("%.9g %.9g %.9g", p[1], p[2], p[3])] = true end
  local kept = 0
  for i = 1, 3 do
    local p = pos[i]
    -- binary STL stores float32
    local x, y, z = string.unpack("<fff", string.pack("<fff", p[1], p[2], p[3]))
    if set[string.format("%.9g %.9g %.9g", x, y, z)] then kept = kept + 1 end
  end
  T.eq(kept, 3, "--lock 1,2,3 keeps those vertices")
  -- Without --lock they do not all stay, so the check above measures the lock.
  local out4 = path("simplified4.obj")
  T.eq(run("simplify", fandisk, out4, "--ratio", "0.5", "--max-valence", "off", "--tolerance", "off",
    "--keep-boundary", "--area-weighted", "feature_angle=30"), 0, "the same without --lock")
  set = {}
  for _, p in ipairs(femlod.load(out4):positions()) do set[string.format("%.17g %.17g %.17g", p[1], p[2], p[3])] = true end
  kept = 0
  for i = 1, 3 do kept = kept + (set[string.format("%.17g %.17g %.17g", pos[i][1], pos[i][2], pos[i][3])] and 1 or 0) end
  T.check(kept < 3, "without --lock some of vertices 1-3 move: " .. kept .. " kept")

  -- --fast-above: the passes show in the stop line, the thresholds hold
  local out5 = path("simplified_fast.obj")
  code, text, err = run("simplify", fandisk, out5, "--target", "2000", "--fast-above", "2")
  T.eq(code, 0, "simplify --fast-above 2: " .. err)
  T.check(text:find("\nstop: target; %d+ collapses %(0 in the pre%-phase, %d+ in fast passes on %d+ threads?%) in "),
    "--fast-above: the stop line counts the fast collapses: " .. text)
  -- --threads: the same file whatever the count
  local out6 = path("simplified_fast1.obj")
  code, text, err = run("simplify", fandisk, out6, "--target", "2000", "--fast-above", "2", "--threads", "1")
  T.eq(code, 0, "simplify --threads 1: " .. err)
  T.check(text:find(" in fast passes on 1 thread%) in "), "--threads 1 in the stop line: " .. text)
  code, text, err = run("simplify", fandisk, path("simplified_fast3.obj"), "--target", "2000", "--fast-above", "2",
    "threads=3")
  T.eq(code, 0, "simplify threads=3: " .. err)
  T.check(text:find(" in fast passes on 3 threads%) in "), "threads=3 in the stop line: " .. text)
  T.eq(T.readfile(out6), T.readfile(out5), "--threads 1 and the default: byte-identical files")
  T.eq(T.readfile(path("simplified_fast3.obj")), T.readfile(out5), "threads=3 and the default: byte-identical files")
  local q5 = femlod.load(out5):quality()
  T.check(q5.triangles <= 2000 and q5.stretch_min >= 0.2 and q5.valence_max <= 12, "--fast-above keeps the thresholds")
  code, text = run("simplify", fandisk, out5, "--target", "2000", "--fast-above", "off")
  T.eq(code, 0, "--fast-above off")
  T.check(text:find("\nstop: target; %d+ collapses %(0 in the pre%-phase%) in "), "--fast-above off: exact: " .. text)

  -- Usage errors: exit 2, nothing written, nothing on stdout.
  local never = path("never_simplified.obj")
  os.remove(never)
  local function simplify_usage(first_line, ...)
    usage(first_line, "simplify", fandisk, never, ...)
    T.check(not T.exists(never), "no output after: " .. table.concat({ ... }, " "))
  end
  simplify_usage("femlod: unknown option '--bogus' (valid: --target, --ratio, --tolerance, --max-deviation, "
    .. "--min-stretch, --max-size, --max-valence, --feature-angle, --feature-weight, --max-normal-change, "
    .. "--keep-boundary, --area-weighted, --error-order, --no-error-order, --no-improve, --fast-above, --threads, --lock, --hierarchy, --hierarchy-floor)", "--bogus")
  simplify_usage("femlod: --quiet is an option of femlod, not of simplify: put it before the command "
    .. "(femlod --quiet simplify ...)", "--target", "10", "--quiet")
  simplify_usage("femlod: unknown option '--targt'; did you mean --target?", "--targt", "10")
  simplify_usage("femlod: unknown option '--min-strech'; did you mean --min-stretch?", "--min-strech=0.3")
  simplify_usage("femlod: unknown parameter 'minstretch'; did you mean min_stretch?", "minstretch=0.3")
  simplify_usage("femlod: --target needs a value", "--target")
  simplify_usage("femlod: --target: number expected, got 'many'", "--target", "many")
  simplify_usage("femlod: --target: integer >= 1 expected, got 0", "--target", "0")
  simplify_usage("femlod: target: integer >= 1 expected, got 2.5", "target=2.5")
  simplify_usage("femlod: --ratio: number in (0, 1] expected, got 2", "--ratio", "2")
  simplify_usage("femlod: give --target or ratio, not both", "--target", "100", "ratio=0.5")
  simplify_usage("femlod: --min-stretch: number in (0, 1] or off expected, got -1", "--min-stretch", "-1")
  simplify_usage("femlod: --max-size: number > 0 or off expected, got 0", "--max-size=0")
  simplify_usage("femlod: --max-valence: integer >= 3 or off expected, got 2", "--max-valence", "2")
  simplify_usage("femlod: --feature-angle: number in (0, 180] or off expected, got 200", "--feature-angle", "200")
  simplify_usage("femlod: --tolerance: number or off expected, got 'none'", "--tolerance", "none")
  simplify_usage("femlod: --keep-boundary takes no value", "--keep-boundary=yes")
  simplify_usage("femlod: keep_boundary: true or false expected, got 'yes'", "keep_boundary=yes")
  simplify_usage("femlod: --lock: list of vertex indices (1, 2, ...) expected, got '1,,2'", "--lock", "1,,2")
  simplify_usage("femlod: --lock: list of vertex indices (1, 2, ...) expected, got '0'", "--lock", "0")
  simplify_usage("femlod: --lock: vertex 6476 out of range (1..6475)", "--lock", "1,6476")
  simplify_usage("femlod: option given twice: 'target'", "--target", "100", "target=200")
  simplify_usage("femlod: unknown parameter 'targt'; did you mean target?", "targt=100")
  simplify_usage("femlod: unknown parameter 'zzz' (valid: target, ratio, tolerance, max_deviation, min_stretch, "
    .. "max_size, max_valence, feature_angle, feature_weight, max_normal_change, keep_boundary, area_weighted, error_order, improve, fast_above, threads, lock, "
    .. "hierarchy, hierarchy_floor)",
    "zzz=100")
  simplify_usage("femlod: expected name=value, got '3000'", "--keep-boundary", "3000")
  simplify_usage("femlod: --fast-above: number >= 1 or off expected, got 0.5", "--fast-above", "0.5")
  simplify_usage("femlod: fast_above: number >= 1 or off expected, got 0.5", "fast_above=0.5")
  usage("femlod: missing an input and an output file", "simplify", fandisk)
  usage("femlod: simplify: IN and OUT come first, then the options", "simplify", "--target", "100", fandisk, never)

  -- Failures: exit 1, no output file, an existing one untouched.
  local bad = path("bad_simplify.obj")
  T.writefile(bad, "v 0 0 0\nv 1 0 0\nf 1 2 3\n")
  code, text, err = run("simplify", bad, never, "--target", "10")
  T.eq(code, 1, "simplify of a bad file fails")
  T.eq(text, "", "no report for a failed simplify")
  T.check(err:find("^femlod: " .. bad:gsub("%p", "%%%0") .. ":3: "), "the error names the bad line: " .. err)
  T.check(not T.exists(never), "no output after a failed simplify")
  T.writefile(never, "keep me")
  T.eq(run("simplify", bad, never), 1, "failed simplify over an existing file")
  T.eq(T.readfile(never), "keep me", "existing output untouched")
  T.eq(run("simplify", fandisk, never, "--target", "0"), 2, "usage error over an existing file")
  T.eq(T.readfile(never), "keep me", "existing output untouched by a usage error")
  code, text, err = run("simplify", fandisk, P.tmp .. "/no_such_dir/x.obj", "--target", "6000")
  T.eq(code, 2, "simplify into a missing folder: a usage error")
  T.eq(err:match("^[^\n]*"), "femlod: " .. P.tmp .. "/no_such_dir/x.obj: folder " .. P.tmp .. "/no_such_dir does not exist",
    "simplify into a missing folder: message")
  T.eq(text, "", "no report when OUT cannot be written")
  T.check(not T.exists(P.tmp .. "/no_such_dir/x.obj"), "nothing written")
end
-- }======

-- {====== simplify --hierarchy and lod
do
  local out, flh = path("hier_2000.obj"), path("hier.flh")
  os.remove(flh)
  local code, text, err = run("simplify", fandisk, out, "--target", "2000", "--hierarchy", flh)
  local text0 = text
  T.eq(code, 0, "simplify --hierarchy: " .. err)
  T.eq(err, "", "simplify --hierarchy: nothing on stderr")
  local h = femlod.load_hierarchy(flh)
  local c = h:counts()
  T.eq(c.triangles, 2000, "the .flh holds the simplification result's front")
  T.eq(c.input_vertices, 6475, "and every input vertex")
  T.check(text:find("\n" .. out:gsub("%p", "%%%0") .. ": 2000 triangles, %d+ vertices %(obj%)\n"
    .. flh:gsub("%p", "%%%0") .. ": " .. c.nodes .. " nodes: 6475 input vertices, " .. c.collapses
    .. " collapses %(hierarchy%)\n$"), "simplify --hierarchy: the hierarchy's line last: " .. text)
  T.eq(h:stats().triangles, 2000, "the .flh keeps the stats")
  local t_in = femlod.load(fandisk):triangles()
  -- hierarchy= is --hierarchy; OUT is the front mesh the .flh gives.
  local flh2, out2 = path("hier2.flh"), path("hier2_2000.obj")
  T.eq(run("--quiet", "simplify", fandisk, out2, "target=2000", "hierarchy=" .. flh2), 0, "hierarchy=PATH")
  T.check(T.readfile(out2) == T.readfile(out), "hierarchy=PATH: the same OUT")
  T.eq(femlod.load_hierarchy(flh2):counts().nodes, c.nodes, "hierarchy=PATH: the same hierarchy")

  -- lod: the simplification result refined at a uniform threshold.
  local lod_inf, lod0, lod3 = path("lod_inf.obj"), path("lod_0.obj"), path("lod_003.obj")
  code, text, err = run("lod", flh, lod_inf, "--size", "inf")
  T.eq(code, 0, "lod --size inf: " .. err)
  local coarsest = femlod.load_hierarchy(flh):stats().hierarchy_triangles
  T.check(coarsest < 2000, "simplify --hierarchy goes on past the target: " .. coarsest)
  T.eq(femlod.load(lod_inf):counts().triangles, coarsest, "lod --size inf: the coarsest mesh of the hierarchy")
  local flh_t, lod_t = path("hier_target.flh"), path("lod_inf_target.obj")
  T.eq(run("--quiet", "simplify", fandisk, path("hier_target.obj"), "--target", "2000", "--hierarchy", flh_t,
    "--hierarchy-floor", "off"), 0, "--hierarchy-floor off")
  T.eq(run("--quiet", "lod", flh_t, lod_t, "--size", "inf"), 0, "lod --size inf of a hierarchy stopped at the target")
  T.check(T.readfile(lod_t) == T.readfile(out), "--hierarchy-floor off: lod --size inf is byte-identical to simplify's OUT")
  -- Without --hierarchy no hierarchy is built (no log): the same vertices,
  -- in order, and the same triangles (listed by input triangle), the same
  -- report but for the times and the .flh line, no "build hierarchy" line.
  local plain = path("plain_2000.obj")
  local pcode, ptext, perr = run("-v", "simplify", fandisk, plain, "--target", "2000")
  T.eq(pcode, 0, "simplify without --hierarchy: " .. perr)
  T.check(not perr:find("build hierarchy"), "simplify without --hierarchy: no 'build hierarchy' line: " .. perr)
  T.check(perr:find("femlod: simplify: 12946 %-> 2000 triangles") ~= nil, "simplify without --hierarchy: -v simplify line")
  local function lines_of(file, prefix)
    local r = {}
    for l in T.readfile(file):gmatch("[^\n]+") do if l:sub(1, #prefix) == prefix then r[#r + 1] = l end end
    return r
  end
  T.eq(table.concat(lines_of(plain, "v "), "\n"), table.concat(lines_of(out, "v "), "\n"),
    "simplify without --hierarchy: the same vertices in the same order")
  local fa, fb = lines_of(plain, "f "), lines_of(out, "f ")
  table.sort(fa)
  table.sort(fb)
  T.eq(#fa, 2000, "simplify without --hierarchy: 2000 triangles")
  T.eq(table.concat(fa, "\n"), table.concat(fb, "\n"), "simplify without --hierarchy: the same triangles")
  local function untimed(t)
    return (t:gsub("in %d+%.%d+ s", "in T s"):gsub("\n[^\n]*%(hierarchy%)\n$", "\n"):gsub(out:gsub("%p", "%%%0"), "OUT")
      :gsub(plain:gsub("%p", "%%%0"), "OUT"))
  end
  T.eq(untimed(ptext), untimed(text0), "simplify without --hierarchy: the same report")
  -- On the spider the improve stage runs first; without a log its polish
  -- runs at the end too: no more triangles left below min_stretch.
  local sp = P.shared .. "/spider_binary.stl"
  local _, t_log = run("simplify", sp, path("sp_log.obj"), "--ratio", "0.3", "--hierarchy-floor", "off")
  local _, t_nolog = run("simplify", sp, path("sp_nolog.obj"), "--ratio", "0.3")
  local v_log = tonumber(t_log:match("violating output: (%d+) triangles"))
  local v_nolog = tonumber(t_nolog:match("violating output: (%d+) triangles"))
  T.check(v_log and v_nolog and v_nolog <= v_log, "spider without --hierarchy: no more violating triangles: "
    .. tostring(v_nolog) .. " <= " .. tostring(v_log))
  code, text = run("lod", flh, lod0, "--size", "0")
  T.eq(code, 0, "lod --size 0")
  local m0 = femlod.load(lod0)
  T.eq(m0:counts().triangles, 12946, "lod --size 0: every input triangle")
  local same = true
  for i, t in ipairs(m0:triangles()) do
    if t[1] ~= t_in[i][1] or t[2] ~= t_in[i][2] or t[3] ~= t_in[i][3] then same = false end
  end
  T.check(same, "lod --size 0: the input's triangles (same numbering)")
  T.eq(femlod.load(lod0):quality().stretch_avg, femlod.load(fandisk):quality().stretch_avg, "lod --size 0: the input's quality")
  code, text, err = run("lod", flh, lod3, "--size", "0.03")
  T.eq(code, 0, "lod --size 0.03")
  T.eq(err, "", "lod: nothing on stderr")
  local m3 = femlod.load(lod3)
  local n3 = m3:counts().triangles
  T.check(n3 > 2000 and n3 < 12946, "lod --size 0.03: between the two: " .. n3)
  local q3 = m3:quality()
  T.eq(text, table.concat({
    "model (H x W x D) | state | elements | stretch (avg, min) | size (max) | valence (max)",
    string.format("cli_hier.flh (0.9206 x 0.5111 x 1) | size 0.03 | %d | %.3f, %.3f | %.4g | %d", n3, q3.stretch_avg,
      q3.stretch_min, q3.size_max, q3.valence_max),
    string.format("%d splits from the coarsest front", (n3 - coarsest) // 2),
    string.format("%s: %d triangles, %d vertices (obj)", lod3, n3, m3:counts().vertices), "" }, "\n"),
    "lod prints its Table 1 row, the splits and the summary")
  local g = femlod.load_hierarchy(flh)
  g:coarsen(math.huge)
  g:refine(0.03)
  T.eq(g:counts().triangles, n3, "lod --size T is load_hierarchy + coarsen(math.huge) + refine(T)")
  -- The output depends on the file's hierarchy and T only, not on its front.
  g:refine(0.005)
  local flh_fine = path("hier_fine.flh")
  g:save(flh_fine)
  local lod3b = path("lod_003b.obj")
  T.eq(run("--quiet", "lod", flh_fine, lod3b, "size=0.03"), 0, "lod size=T, from a refined front")
  T.check(T.readfile(lod3b) == T.readfile(lod3), "lod: the same mesh whatever front the file holds")
  T.eq(run("--quiet", "lod", flh, lod3b, "--size=0.03"), 0, "lod --size=T")
  T.check(T.readfile(lod3b) == T.readfile(lod3), "--size=T is --size T")
  code, text = run("--quiet", "lod", flh, lod3b, "--size", "0.03")
  T.eq(text, "", "lod --quiet: nothing printed")
  local glb = path("lod.stl")
  code, text = run("lod", flh, glb, "--size", "0.03")
  T.check(text:find(glb:gsub("%p", "%%%0") .. ": %d+ triangles, %d+ vertices %(stl%)\n$"), "lod: the format from OUT")

  -- lod --target: from the saved front, its density kept; a count the
  -- hierarchy cannot reach is reached as near as it can, with a warning.
  local lodt = path("lod_target.obj")
  code, text, err = run("lod", flh, lodt, "--target", "3000")
  T.eq(code, 0, "lod --target 3000: " .. err)
  T.eq(femlod.load(lodt):counts().triangles, 3000, "lod --target 3000: the count")
  T.check(text:find("| target 3000 | 3000 |", 1, true) ~= nil, "lod --target: the row says target: " .. text)
  local coarse_n = femlod.load_hierarchy(flh):stats().hierarchy_triangles
  code, text, err = run("lod", flh, lodt, "target=10")
  T.eq(code, 0, "lod target=10: stops at the coarsest, exit 0")
  T.eq(err, string.format("femlod: warning: rescale: asked 10, reached %d: %s\n", coarse_n,
    femlod.load_hierarchy(flh):stats().hierarchy_binding), "lod: the warning says why")

  -- Usage errors: exit 2, nothing written.
  local never = path("never_lod.obj")
  os.remove(never)
  local function lod_usage(first_line, ...)
    usage(first_line, "lod", flh, never, ...)
    T.check(not T.exists(never), "no output after: " .. table.concat({ ... }, " "))
  end
  lod_usage("femlod: lod: --size T or --target N is required")
  lod_usage("femlod: --size needs a value", "--size")
  lod_usage("femlod: --size: number >= 0 or inf expected, got 'fine'", "--size", "fine")
  lod_usage("femlod: --size: number >= 0 or inf expected, got '-1'", "--size", "-1")
  lod_usage("femlod: size: number >= 0 or inf expected, got ''", "size=")
  lod_usage("femlod: unknown option '--targt'; did you mean --target?", "--targt", "100")
  lod_usage("femlod: unknown parameter 'targt'; did you mean target?", "targt=100")
  lod_usage("femlod: unknown option '--zzz' (valid: --size, --target)", "--zzz", "100")
  lod_usage("femlod: --target: a triangle count >= 1 expected, got '0'", "--target", "0")
  lod_usage("femlod: target: a triangle count >= 1 expected, got '1.5'", "target=1.5")
  lod_usage("femlod: give one of --size and --target, not both ('target')", "--size", "1", "--target", "100")
  lod_usage("femlod: option given twice: 'target'", "--target", "100", "target=200")
  lod_usage("femlod: option given twice: 'size'", "--size", "1", "size=2")
  lod_usage("femlod: expected name=value, got '0.03'", "0.03")
  usage("femlod: missing a hierarchy file and an output file", "lod", flh)
  usage("femlod: lod: PART.flh and OUT come first, then --size T", "lod", "--size", "1", flh, never)
  usage("femlod: --hierarchy needs a value", "simplify", fandisk, never, "--hierarchy")
  usage("femlod: hierarchy: file name expected, got ''", "simplify", fandisk, never, "hierarchy=")
  usage("femlod: option given twice: 'hierarchy'", "simplify", fandisk, never, "--hierarchy", flh, "hierarchy=x")
  T.check(not T.exists(never), "no output after the usage errors")

  -- Failures: exit 1 with the file's message, no output.
  code, text, err = run("lod", path("missing.flh"), never, "--size", "1")
  T.eq(code, 1, "lod of a missing file")
  T.eq(err, "femlod: " .. path("missing.flh") .. ": cannot open: No such file or directory\n", "lod: missing file text")
  code, text, err = run("lod", fandisk, never, "--size", "1")
  T.eq(code, 1, "lod of a mesh file")
  T.eq(err, "femlod: " .. fandisk .. ": byte 0: not a femlod hierarchy file\n", "lod: foreign file text")
  local damaged = path("damaged.flh")
  local bytes = T.readfile(flh)
  T.writefile(damaged, bytes:sub(1, 100) .. string.char(bytes:byte(101) ~ 1) .. bytes:sub(102))
  code, text, err = run("lod", damaged, never, "--size", "1")
  T.eq(code, 1, "lod of a damaged file")
  T.eq(err, "femlod: " .. damaged .. ": checksum mismatch: the file is damaged\n", "lod: damaged file text")
  T.eq(text, "", "no report after a failure")
  T.check(not T.exists(never), "no output after the failures")
  code, text, err = run("simplify", fandisk, never, "--target", "2000", "--hierarchy", P.tmp .. "/no_such_dir/x.flh")
  T.eq(code, 2, "simplify --hierarchy into a missing folder: a usage error")
  T.eq(err:match("^[^\n]*"), "femlod: " .. P.tmp .. "/no_such_dir/x.flh: folder " .. P.tmp .. "/no_such_dir does not exist",
    "simplify --hierarchy into a missing folder: message")
  T.check(not T.exists(never), "OUT is written after the hierarchy: not written when the hierarchy fails")

  -- The example recipe.
  local ex_out = path("lod_example")
  os.execute("mkdir -p " .. quote(ex_out))
  os.remove(ex_out .. "/fandisk_lod.obj")
  code, text, err = run(P.examples .. "/lod.lua", "out=" .. ex_out)
  T.eq(code, 0, "examples/lod.lua runs: " .. err)
  T.eq(err, "", "lod.lua: nothing on stderr")
  T.check(text:find("^model %(H x W x D%) | state | elements"), "lod.lua prints Table 1: " .. text)
  T.check(text:find("\nfandisk%.obj %([^)]*%) | original | 12946 | "), "lod.lua: the original's row")
  T.check(text:find("\nfandisk%.obj %([^)]*%) | simplified | 2000 | "), "lod.lua: the simplified row")
  local refined = femlod.load(ex_out .. "/fandisk_lod.obj"):counts().triangles
  T.check(refined > 2000 and refined < 12946, "lod.lua wrote the refined mesh: " .. refined)
  T.check(text:find("\nfandisk%.obj %([^)]*%) | refined near a corner | " .. refined .. " | "), "lod.lua: the refined row")
  T.check(T.exists(ex_out .. "/fandisk.flh"), "lod.lua saved the hierarchy")

  -- The sweep's recipe as is, without parameters: its defaults (target 3000,
  -- min_stretch 0.2), mesh.obj in the current folder; a bad target still
  -- says so.
  os.remove(ex_out .. "/mesh.obj")
  code, text, err = T.runner(FEMLOD, ERR).sh("cd " .. quote(ex_out) .. " && " .. quote(FEMLOD) .. " run " .. quote(P.examples .. "/sweep.lua"))
  T.eq(code, 0, "examples/sweep.lua runs without parameters: " .. err)
  T.eq(err, "", "sweep.lua: nothing on stderr")
  T.check(text:find("^fandisk%.obj %([^)]*%) | target 3000, stretch >= 0%.2 | 3000 | "), "sweep.lua's defaults: " .. text)
  T.eq(T.exists(ex_out .. "/mesh.obj") and femlod.load(ex_out .. "/mesh.obj"):counts().triangles, 3000,
    "sweep.lua wrote mesh.obj in the current folder")
  code, text, err = run(P.examples .. "/sweep.lua", "target=many", "out_dir=" .. ex_out)
  T.eq(code, 1, "sweep.lua target=many fails")
  T.check(err:find("sweep%.lua:%d+: target: integer expected, got many\n$"), "sweep.lua names the bad target: " .. err)

  -- The CAE recipe: simplify to 12k, refine curvature, rescale (docs/guide.md).
  code, text, err = run(P.examples .. "/recipe_cae.lua")
  T.eq(code, 0, "examples/recipe_cae.lua runs: " .. err)
  T.eq(err, "", "recipe_cae.lua: nothing on stderr")
  T.check(text:find("^model %(H x W x D%) | state | elements"), "recipe_cae.lua prints Table 1: " .. text)
  local rows = {}
  for state, n in text:gmatch("\ncover%.obj %([^)]*%) | ([%a ]+) | (%d+) | ") do rows[#rows + 1] = { state, tonumber(n) } end
  T.eq(#rows, 4, "recipe_cae.lua: 4 rows")
  T.eq(rows[1] and rows[1][1], "original", "recipe_cae.lua: the original's row")
  T.eq(rows[2] and rows[2][2], 12000, "recipe_cae.lua: simplified to 12000")
  T.check(rows[3] and rows[3][1] == "curvature" and rows[3][2] > 12000, "recipe_cae.lua: curvature refines")
  T.check(rows[4] and rows[4][1] == "global" and math.abs(rows[4][2] - 12000) <= 0.005 * 12000,
    "recipe_cae.lua: rescaled back to 12000 within 0.5%: " .. tostring(rows[4] and rows[4][2]))
  -- not the plain simplification again: the hierarchy goes on past the target
  local plain, recipe = text:match("| simplified | 12000 | ([^\n]*)"), text:match("| global | %d+ | ([^\n]*)")
  T.check(plain and recipe and plain ~= recipe, "recipe_cae.lua: the global row differs from the simplified one")

  -- Region LOD around the spindle hole (docs/guide.md); the release pass only
  if T.heavy then
    code, text, err = run(P.examples .. "/region.lua", "out=" .. ex_out .. "/cover_region.obj")
    T.eq(code, 0, "examples/region.lua runs: " .. err)
    rows = {}
    for state, n in text:gmatch("\ncover%.obj %([^)]*%) | ([%a ]+) | (%d+) | ") do rows[#rows + 1] = { state, tonumber(n) } end
    T.eq(#rows, 3, "region.lua: 3 rows")
    T.eq(rows[2] and rows[2][2], 6000, "region.lua: simplified to 6000")
    T.check(rows[3] and rows[3][1] == "region" and rows[3][2] > 6000, "region.lua: refined near the hole")
    T.check(err:find("^region: %d+ splits, %d+ nodes inside\n$"), "region.lua: its summary on stderr: " .. err)
    local rm = femlod.load(ex_out .. "/cover_region.obj")
    T.eq(rm:counts().triangles, rows[3] and rows[3][2], "region.lua wrote the refined mesh")
    -- near the hole the elements are small, far from it as simplified
    local near, far = 0, 0
    local pos = rm:positions()
    for _, t in ipairs(rm:triangles()) do
      local a, b, c = pos[t[1]], pos[t[2]], pos[t[3]]
      local x, y = (a[1] + b[1] + c[1]) / 3, (a[2] + b[2] + c[2]) / 3
      local r = math.sqrt((x - 50.6) ^ 2 + (y - 90) ^ 2)
      local s = 0
      for _, e in ipairs { { a, b }, { b, c }, { c, a } } do
        s = math.max(s, math.sqrt((e[1][1] - e[2][1]) ^ 2 + (e[1][2] - e[2][2]) ^ 2 + (e[1][3] - e[2][3]) ^ 2))
      end
      if r < 10 then near = math.max(near, s) elseif r > 60 then far = math.max(far, s) end
    end
    T.check(near > 0 and near < 0.25 * far, "region.lua: near the hole size " .. near .. ", far " .. far)
  end
end
-- }======

-- {====== --verbose: each stage with its time on stderr; stdout unchanged
do
  local fan = P.shared .. "/fandisk.obj"
  local out, flh = path("verbose.obj"), path("verbose.flh")
  local code, text, err = run("-v", "simplify", fan, out, "--target", "3000", "--hierarchy", flh)
  T.eq(code, 0, "-v simplify: exit 0: " .. err)
  local _, quiet_text = run("simplify", fan, out, "--target", "3000", "--hierarchy", flh)
  local function untimed(t) return (t:gsub(" in %d+%.%d+ s\n", " in T s\n")) end
  T.eq(untimed(text), untimed(quiet_text), "-v simplify: stdout as without -v")
  T.check(untimed(text) ~= text, "(the time was taken out)")
  local stages = {}
  for line in err:gmatch("[^\n]+") do
    T.check(line:find("^femlod: "), "-v simplify: every stderr line is femlod's: " .. line)
    stages[#stages + 1] = line:match("^femlod: (build hierarchy)") or line:match("^femlod: (%a+)")
  end
  T.eq(table.concat(stages, ","), "load,simplify,build hierarchy,write,write,simplify",
    "-v simplify: the stages in order: " .. err)
  local F = fan:gsub("%p", "%%%0")
  T.check(err:find("\nfemlod: simplify: 12946 %-> 3000 triangles, %d+ collapses, stopped: target %(%d+%.%d%d%d s%)\n"),
    "-v simplify: the simplification's figures")
  T.check(err:find("^femlod: load " .. F .. ": 12946 triangles, 6475 vertices %(%d+%.%d%d%d s%)\n"), "-v: load line")
  T.check(err:find("\nfemlod: build hierarchy: %d+ nodes, %d+ bytes %(%d+%.%d%d%d s%)\n"), "-v: hierarchy line")
  T.check(err:find("\nfemlod: write " .. flh:gsub("%p", "%%%0") .. ": %d+ nodes %(%d+%.%d%d%d s%)\n"), "-v: .flh line")
  T.check(err:find("\nfemlod: write " .. out:gsub("%p", "%%%0") .. ": 3000 triangles, %d+ vertices %(%d+%.%d%d%d s%)\n"),
    "-v: mesh line")
  T.check(err:find("\nfemlod: simplify: done in %d+%.%d%d%d s\n$"), "-v: the total last")

  code, text, err = run("--verbose", "lod", flh, path("verbose_lod.obj"), "--size", "0.01")
  T.eq(code, 0, "--verbose lod: exit 0")
  T.check(err:find("^femlod: load " .. flh:gsub("%p", "%%%0") .. ": %d+ nodes, front 3000 triangles"), "-v lod: load " .. err)
  T.check(err:find("\nfemlod: coarsen: %d+ collapses, front %d+ triangles"), "-v lod: coarsen")
  T.check(err:find("\nfemlod: refine: %d+ splits, front %d+ triangles"), "-v lod: refine")
  T.check(err:find("\nfemlod: lod: done in "), "-v lod: total")
  for _, c in ipairs {
    { { "convert", fan, path("verbose.off") }, { "load", "write", "convert: done" } },
    { { "repair", fan, path("verbose_rep.obj") }, { "load", "repair: 12946 %-> 12946 triangles", "write", "repair: done" } },
    { { "info", out, "reference=" .. fan }, { "load", "load", "hausdorff: [%d.e-]+ %(", "info: done" } },
    { { "report", out, "--reference", fan }, { "load", "load", "hausdorff: ", "report: done" } },
    { { "-e", "femlod.load(" .. ("%q"):format(fan) .. ")" }, { "%-e %(command line%): 0 parameters, seed 0", "load", "%-e: done" } },
  } do
    code, text, err = run("-v", table.unpack(c[1]))
    T.eq(code, 0, "-v " .. c[1][1] .. ": exit 0: " .. err)
    local at = 1
    for _, want in ipairs(c[2]) do
      local s, e = err:find("femlod: " .. want, at)
      T.check(s ~= nil, "-v " .. c[1][1] .. ": '" .. want .. "' in order in " .. err)
      at = (e or at) + 1
    end
  end
  -- a recipe sees femlod.verbose and femlod.quiet
  code, text = run("-v", "-e", "print(femlod.verbose, femlod.quiet)")
  T.eq(text, "true\tfalse\n", "-v: femlod.verbose")
  code, text, err = run("-q", "-e", "print(femlod.verbose, femlod.quiet)")
  T.eq(text, "false\ttrue\n", "-q: femlod.quiet")
  code, text, err = run("-e", "print(femlod.verbose, femlod.quiet) femlod.load(" .. ("%q"):format(fan) .. ")")
  T.eq(text, "false\tfalse\n", "neither")
  T.eq(err, "", "without -v: nothing on stderr")
  code, text, err = run("-e", "femlod.verbose = true femlod.load(" .. ("%q"):format(fan) .. ")")
  T.check(err:find("^femlod: load "), "a recipe may turn the lines on: " .. err)
  -- -q and -v exclude each other: a usage error, nothing run
  for _, args in ipairs { { "-q", "-v", "info", fan }, { "--verbose", "--quiet", "info", fan }, { "-v", "-q", "-e", "print(1)" } } do
    code, text, err = run(table.unpack(args))
    T.eq(code, 2, table.concat(args, " ") .. ": exit 2")
    T.eq(text, "", table.concat(args, " ") .. ": nothing on stdout")
    T.eq(err:match("^[^\n]*"), "femlod: --quiet and --verbose exclude each other", table.concat(args, " ") .. ": message")
  end
  os.remove(out)
  os.remove(flh)
  os.remove(path("verbose_lod.obj"))
  os.remove(path("verbose.off"))
  os.remove(path("verbose_rep.obj"))
end
-- }======

-- {====== checked before any work: outputs, inputs, values (exit 2, stdout
-- empty, nothing written, the problem named in femlod's words)
do
  local function first(...)
    local code, out, err = run(...)
    return code, out, err:match("^[^\n]*"), err
  end
  local function usage2(expected, ...)
    local code, out, line, err = first(...)
    local args = table.concat({ ... }, " ")
    T.eq(code, 2, "exit 2 for: " .. args)
    T.eq(out, "", "stdout empty for: " .. args)
    T.eq(line, expected, "message for: " .. args)
    return err
  end
  local cover = P.examples .. "/data/cover.obj"
  local dir = path("checks")
  os.execute("rm -rf " .. quote(dir) .. " && mkdir -p " .. quote(dir .. "/sub"))
  local xyz = dir .. "/o.xyz"
  usage2("femlod: " .. xyz .. ": unknown file extension (valid: .obj, .stl, .off, .ply, .gltf, .glb, .msh, .vtk, "
    .. ".inp, .mesh; or give format=FMT)", "simplify", cover, xyz, "--target", "3000")
  T.check(not T.exists(xyz), "o.xyz not written")
  usage2("femlod: nodir/o.obj: folder nodir does not exist", "simplify", cover, "nodir/o.obj", "--target", "3000")
  usage2("femlod: nodir/p.flh: folder nodir does not exist", "simplify", cover, dir .. "/o.obj", "--target", "3000",
    "--hierarchy", "nodir/p.flh")
  T.check(not T.exists(dir .. "/o.obj"), "OUT not written when --hierarchy's folder is missing")
  usage2("femlod: " .. dir .. "/sub: is a folder; give a file name", "convert", fandisk, dir .. "/sub")
  usage2("femlod: " .. dir .. "/sub/: is a folder; give a file name", "lod", "x.flh", dir .. "/sub/", "--size", "1")
  usage2("femlod: " .. fandisk .. "/x.obj: " .. fandisk .. " is not a folder", "repair", fandisk, fandisk .. "/x.obj")
  usage2("femlod: " .. xyz .. ": unknown file extension (valid: .obj, .stl, .off, .ply, .gltf, .glb, .msh, .vtk, "
    .. ".inp, .mesh; or give format=FMT)", "lod", "x.flh", xyz, "--size", "1")
  T.eq(run("-q", "convert", fandisk, xyz, "format=obj"), 0, "format= stands for the extension")
  local err = usage2("femlod: nodir/o.obj: folder nodir does not exist", "convert", fandisk, "nodir/o.obj")
  T.eq(err:match("\n([^\n]*)\n$"), "usage: femlod convert IN OUT [options] (try 'femlod help convert')",
    "the usage line is the command's")

  -- Bad values: the option, the value and the valid values; exit 2.
  local glb = dir .. "/x.glb"
  usage2("femlod: color_by: unknown measure 'stress' (valid: stretch, size, valence, none)", "convert", fandisk, glb,
    "color_by=stress")
  usage2("femlod: --color-by: unknown measure 'strech'; did you mean stretch? (valid: stretch, size, valence, none)",
    "convert", fandisk, glb, "--color-by", "strech")
  usage2("femlod: normals: true or false expected, got 'yes'", "convert", fandisk, glb, "normals=yes")
  usage2("femlod: --normals: true or false expected, got 'yes'", "convert", fandisk, glb, "--normals=yes")
  usage2("femlod: " .. dir .. "/x.obj: color_by and normals are glTF options; " .. dir .. "/x.obj is obj, not gltf or glb",
    "convert", fandisk, dir .. "/x.obj", "--color-by", "stretch")
  usage2("femlod: --format: unknown format 'stll'; did you mean stl? (valid: obj, stl, stl_ascii, stl_binary, off, "
    .. "ply, ply_ascii, ply_binary, gltf, glb, msh, msh2, vtk, inp, medit)", "convert", fandisk, glb, "--format", "stll")
  usage2("femlod: --report: unknown report 'rows' (valid: text, row, fields)", "info", fandisk, "--report", "rows")
  T.check(not T.exists(glb), "nothing written by the usage errors")

  -- One option style: --name VALUE, --name=VALUE and name=VALUE everywhere.
  local code, out = run("convert", fandisk, glb, "--color-by", "stretch", "--normals")
  T.eq(code, 0, "convert --color-by stretch --normals")
  T.eq(out, glb .. ": 12946 triangles, 6475 vertices (glb)\n", "convert --color-by: summary")
  local g = femlod.load(glb)
  T.eq(g:counts().triangles, 12946, "the glb reads back")
  T.eq(run("-q", "convert", fandisk, glb, "--color-by=size", "--no-normals"), 0, "--color-by=size --no-normals")
  T.eq(run("-q", "convert", fandisk, glb, "--normals", "false"), 0, "--normals false")
  local _, by_pair = run("info", fandisk, "reference=" .. fandisk, "report=row")
  local code2, by_flag = run("info", fandisk, "--reference", fandisk, "--report", "row")
  T.eq(code2, 0, "info --reference")
  T.eq(by_flag, by_pair, "info --reference R --report row is reference=R report=row")
  T.eq(select(2, run("info", fandisk, "--reference=" .. fandisk, "--report=row")), by_pair, "info --reference=R")
  T.eq(select(2, run("info", fandisk, "--format", "obj")), select(2, run("info", fandisk)), "info --format obj")
  usage2("femlod: option given twice: '--report'", "info", fandisk, "report=row", "--report", "text")
  usage2("femlod: --report needs a value", "info", fandisk, "--report")
  usage2("femlod: -q is an option of femlod, not of info: put it before the command (femlod -q info ...)", "info",
    fandisk, "-q")
  usage2("femlod: --quiet is an option of femlod, not of run: put it before the command (femlod --quiet run ...)",
    "run", "--quiet", "x.lua")
  local fixed = dir .. "/fixed.obj"
  local _, a = run("repair", P.shared .. "/spider_binary.stl", fixed, "orient=false", "weld=false")
  local _, b = run("repair", P.shared .. "/spider_binary.stl", fixed, "--orient", "false", "--weld=false")
  T.eq(b, a, "repair --orient false --weld=false is orient=false weld=false")
  local _, r1 = run("report", fandisk, "--reference", fandisk)
  local code3, r2 = run("report", fandisk, "reference=" .. fandisk)
  T.eq(code3, 0, "report reference=R")
  T.eq(r2, r1, "report reference=R is --reference R")
  usage2("femlod: unknown option '--refrence'; did you mean --reference?", "report", fandisk, "--refrence", fandisk)
  usage2("femlod: unknown option '--jbos'; did you mean --jobs?", "sweep", "x.lua", "--jbos", "2")

  -- Inputs that are not what the command reads.
  usage2("femlod: " .. dir .. ": is a folder, not a mesh file", "info", dir)
  usage2("femlod: " .. dir .. ": is a folder, not a mesh file", "simplify", dir, dir .. "/o.obj", "--target", "10")
  usage2("femlod: " .. dir .. ": is a folder, not a hierarchy file", "lod", dir, dir .. "/o.obj", "--size", "1")
  usage2("femlod: " .. dir .. ": is a folder, not a recipe file", "run", dir)
  usage2("femlod: part.flh: a saved vertex hierarchy, not a mesh; 'femlod lod part.flh OUT --size T' writes a mesh "
    .. "from it", "info", "part.flh")

  -- A target the input already meets: said, not hidden in "0 collapses".
  local code4, text, err4 = run("simplify", fandisk, dir .. "/same.obj", "--target", "20000")
  T.eq(code4, 0, "a target above the input's count is no error")
  T.eq(err4, "femlod: --target 20000 is not below fandisk.obj's 12946 triangles: nothing to simplify\n",
    "a target above the input's count: message")
  T.check(text:find("\nstop: target; 0 collapses"), "and the report says so too: " .. text)
  code4, text, err4 = run("simplify", fandisk, dir .. "/same.obj", "ratio=1")
  T.eq(err4, "femlod: ratio 1 keeps all of fandisk.obj's 12946 triangles: nothing to simplify\n", "ratio=1: message")
  code4, text, err4 = run("-q", "simplify", fandisk, dir .. "/same.obj", "--target", "20000")
  T.eq(err4, "", "-q: no message")

  -- Files without triangles: an error that says so, not a report of zeros.
  local empty_ascii, empty_binary = dir .. "/empty.stl", dir .. "/empty_binary.stl"
  T.writefile(empty_ascii, "solid x\nendsolid x\n")
  T.writefile(empty_binary, ("\0"):rep(84))
  for _, args in ipairs { { "info", empty_ascii }, { "info", empty_binary }, { "report", empty_ascii },
    { "simplify", empty_binary, dir .. "/e.obj", "--target", "10" }, { "convert", empty_ascii, dir .. "/e.obj" } } do
    local c, o, e = run(table.unpack(args))
    T.eq(c, 1, table.concat(args, " ") .. ": exit 1")
    T.eq(o, "", table.concat(args, " ") .. ": no report")
    T.eq(e, "femlod: " .. args[2] .. ": no triangles\n", table.concat(args, " ") .. ": message")
  end
  T.check(not T.exists(dir .. "/e.obj"), "nothing written for an empty input")
  os.execute("rm -rf " .. quote(dir))
end
-- }======

T.summary("test_cli")
