-- test_sandbox.lua: `femlod run --sandbox [--allow DIR]... [--max-memory SIZE]
-- [--max-time SECONDS]` from outside (docs/design.md, "Safe recipes"). Every
-- forbidden action is refused with its message at the recipe's line and
-- leaves the files outside the roots as they were; the allowed ones work;
-- the caps stop runaway recipes, whatever they catch, with exit status 3.
-- No check depends on timing: the time caps only have to stop loops that
-- would never end.

local T = dofile((arg[0]:match("^(.*)/") or ".") .. "/check.lua")

local P = params
assert(P and P.femlod and P.tmp and P.shared, "run through ctest: needs femlod=, tmp=, shared=")
local FEMLOD = P.femlod

local function quote(s) return "'" .. tostring(s):gsub("'", "'\\''") .. "'" end
local function sh(cmd)
  local ok, how, code = os.execute(cmd)
  return ok, how, code
end

-- A fresh tree in tmp, entered by every run (relative paths are relative to it):
--   recipes/   the recipe folder (read only for the recipe)
--   allowed/   the --allow folder
--   allowed2/  a sibling whose name starts with "allowed"
--   outside/   neither
local ROOT = P.tmp .. "/sandbox"
sh("chmod -R u+w " .. quote(ROOT) .. " 2>/dev/null; rm -rf " .. quote(ROOT))
for _, d in ipairs { "", "/recipes", "/recipes/sub", "/allowed", "/allowed2", "/outside" } do
  assert(sh("mkdir -p " .. quote(ROOT .. d)))
end
local function at(p) return ROOT .. "/" .. p end

local TRI = "femlod.mesh { positions = { 0, 0, 0, 1, 0, 0, 0, 1, 0 }, triangles = { 1, 2, 3 } }"
T.writefile(at("outside/secret.txt"), "secret\n")
T.writefile(at("outside/part.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
T.writefile(at("outside/mod.lua"), "return 'outside'\n")
T.writefile(at("recipes/part.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
T.writefile(at("recipes/notes.txt"), "line one\nline two\n")
T.writefile(at("recipes/helper.lua"), "return { answer = 42 }\n")
T.writefile(at("recipes/sub/mod.lua"), "return 'sub.mod'\n")
T.writefile(at("recipes/code.lua"), "return 7\n")
T.writefile(at("allowed/data.txt"), "allowed data\n")
T.writefile(at("recipes/fandisk.obj"), assert(T.readfile(P.shared .. "/fandisk.obj")))
-- A binary chunk, made here where string.dump exists.
T.writefile(at("recipes/chunk.luac"), string.dump(function() return 1 end))
-- Links: out of a root, into a root, to nowhere.
assert(sh("ln -s ../outside/secret.txt " .. quote(at("recipes/link_out.txt"))))
assert(sh("ln -s ../outside " .. quote(at("allowed/outdir"))))
assert(sh("ln -s ../outside/new.txt " .. quote(at("allowed/dangling.txt"))))
assert(sh("ln -s data.txt " .. quote(at("allowed/link_in.txt"))))
assert(sh("ln -s ../allowed/data.txt " .. quote(at("outside/link_to_allowed.txt"))))

local ERR = at("stderr.txt")
-- Runs femlod in ROOT with the arguments (prefix: a shell command put before);
-- returns exit code, stdout, stderr.
local shell = T.runner(FEMLOD, ERR)
local function run_in(prefix, ...)
  local parts = { "cd " .. quote(ROOT) .. " &&", prefix or "", quote(FEMLOD) }
  for i = 1, select("#", ...) do parts[#parts + 1] = quote((select(i, ...))) end
  return shell.sh(table.concat(parts, " "))
end
local function run(...) return run_in(nil, ...) end

local n_recipes = 0
-- Writes a recipe into recipes/ and returns its path relative to ROOT.
local function recipe(text)
  n_recipes = n_recipes + 1
  local name = string.format("recipes/r%02d.lua", n_recipes)
  T.writefile(at(name), text)
  return name
end

local SANDBOX = { "run", "--sandbox", "--allow", "allowed" }
local function sandboxed(name, ...)
  local args = { table.unpack(SANDBOX) }
  for i = 1, select("#", ...) do args[#args + 1] = (select(i, ...)) end
  args[#args + 1] = name
  return run(table.unpack(args))
end

local function tree_listing()
  local p = assert(io.popen("cd " .. quote(ROOT) .. " && find outside recipes -print | LC_ALL=C sort"))
  local s = p:read("a")
  p:close()
  return (s:gsub("recipes/r%d+%.lua\n", "")) -- the recipes this test writes
end
local before = tree_listing()

-- {====== forbidden: each one line 2 of its own recipe; exit 1 and the
-- message at that line
local function refused(code, message, what)
  local name = recipe("-- " .. (what or code) .. "\n" .. code .. "\nprint('not reached')\n")
  local st, out, err = sandboxed(name)
  T.eq(st, 1, "exit 1 for: " .. code)
  T.eq(out, "", "nothing printed for: " .. code)
  T.eq(err, "femlod: " .. name .. ":2: " .. message .. "\n", "message for: " .. code)
end

local function nil_field(f) return "attempt to call a nil value (field '" .. f .. "')" end
refused("os.execute('touch outside/executed')", nil_field("execute"))
refused("io.popen('touch outside/popened')", nil_field("popen"))
refused("os.remove('outside/secret.txt')", nil_field("remove"))
refused("os.rename('outside/secret.txt', 'allowed/stolen.txt')", nil_field("rename"))
refused("os.exit(0)", nil_field("exit"))
refused("os.getenv('HOME')", nil_field("getenv"))
refused("os.tmpname()", nil_field("tmpname"))
refused("io.tmpfile()", nil_field("tmpfile"))
refused("package.loadlib('libc.so.6', 'system')", nil_field("loadlib"))
refused("package.searchpath('x', '/etc/?')", nil_field("searchpath"))
refused("string.dump(print)", nil_field("dump"))
refused("('').dump(print)", nil_field("dump"))
refused("debug.sethook()", "attempt to index a nil value (global 'debug')")
refused("package.loaded.debug.sethook()", "attempt to index a nil value (field 'debug')")

-- Binary chunks, however asked for.
local BIN = "attempt to load a binary chunk (mode is 't')"
refused("assert(load(io.open('recipes/chunk.luac', 'rb'):read('a'), 'c', 'b'))", BIN)
refused("assert(load(io.open('recipes/chunk.luac', 'rb'):read('a'), 'c', 'bt', {}))", BIN)
refused("assert(loadfile('recipes/chunk.luac', 'b'))", BIN)
refused("dofile('recipes/chunk.luac')", BIN)

-- Reading outside the recipe's folder and the --allow folders.
local function no_read(p) return p .. ": not allowed in the sandbox (reading outside the recipe's folder and the --allow folders)" end
local function no_write(p) return p .. ": not allowed in the sandbox (writing outside the --allow folders)" end
local abs_secret = at("outside/secret.txt")
refused("io.open('outside/secret.txt')", no_read("outside/secret.txt"))
refused("io.open(" .. ("%q"):format(abs_secret) .. ", 'rb')", no_read(abs_secret))
refused("io.lines('outside/secret.txt')", no_read("outside/secret.txt"))
refused("io.input('outside/secret.txt')", no_read("outside/secret.txt"))
refused("dofile('outside/mod.lua')", no_read("outside/mod.lua"))
refused("loadfile('outside/mod.lua')", no_read("outside/mod.lua"))
refused("femlod.load('outside/part.obj')", no_read("outside/part.obj"))
refused("femlod.load_hierarchy('outside/part.flh')", no_read("outside/part.flh"))
refused("io.open('/etc/passwd')", no_read("/etc/passwd"))
-- .. and links: judged by where the path leads.
refused("io.open('allowed/../outside/secret.txt')", no_read("allowed/../outside/secret.txt"))
refused("io.open('recipes/../outside/secret.txt')", no_read("recipes/../outside/secret.txt"))
refused("io.open('recipes/link_out.txt')", no_read("recipes/link_out.txt"), "a link out of the recipe folder")
refused("io.open('allowed/outdir/secret.txt')", no_read("allowed/outdir/secret.txt"), "a folder link out of --allow")
-- A missing file outside says the same: nothing tells what exists there.
refused("io.open('outside/missing/deeper.txt')", no_read("outside/missing/deeper.txt"))

-- Writing outside the --allow folders: the recipe's folder is read-only.
refused("io.open('recipes/new.txt', 'w')", no_write("recipes/new.txt"))
refused("io.open('recipes/notes.txt', 'a')", no_write("recipes/notes.txt"))
refused("io.open('recipes/notes.txt', 'r+')", no_write("recipes/notes.txt"))
refused("io.output('outside/new.txt')", no_write("outside/new.txt"))
refused("femlod.write_file('outside/new.txt', 'x')", no_write("outside/new.txt"))
refused("femlod.report(femlod.mesh{ positions = {{0,0,0},{1,0,0},{0,1,0}}, triangles = {{1,2,3}} }, "
  .. "{ html = 'outside/r.html', viewer = false })", no_write("outside/r.html"))
refused("io.open('allowed2/new.txt', 'w')", no_write("allowed2/new.txt"), "a sibling named like the root")
refused("io.open('allowed/outdir/new.txt', 'w')", no_write("allowed/outdir/new.txt"))
refused("io.open('allowed/dangling.txt', 'w')",
  "allowed/dangling.txt: not allowed in the sandbox (a symbolic link to nowhere)")
refused(TRI .. ":save('outside/out.obj')", no_write("outside/out.obj"))
refused(TRI .. ":save('recipes/out.stl')", no_write("recipes/out.stl"))
refused(TRI .. ":save('allowed/../outside/out.ply')", no_write("allowed/../outside/out.ply"))
refused("femlod.load('recipes/part.obj'):subdivide(1):simplify{ ratio = 0.5 }:save('outside/out.flh')",
  no_write("outside/out.flh"))

-- require: only preload and the recipe's folder.
local RECIPES = io.popen("cd " .. quote(at("recipes")) .. " && pwd -P"):read("l") -- canonical
refused("require 'lfs'", "module 'lfs' not found:\n\tno field package.preload['lfs']\n\tno file '"
  .. RECIPES .. "/lfs.lua' (sandbox)")
refused("package.path = " .. ("%q"):format(at("outside/?.lua")) .. "\nrequire 'mod'",
  "module 'mod' not found:\n\tno field package.preload['mod']\n\tno file '" .. RECIPES .. "/mod.lua" .. "' (sandbox)")

T.eq(tree_listing(), before, "no file created or removed outside the --allow folder")
T.eq(T.readfile(at("outside/secret.txt")), "secret\n", "outside/secret.txt unchanged")
T.check(not T.exists(at("outside/new.txt")), "the dangling link made no file")
-- }======

-- {====== allowed: everything works as without the sandbox
do
  local name = recipe([[
local femlod = require "femlod"
local report = require "femlod.report"
assert(type(report.header) == "function")
assert(require("helper").answer == 42)
assert(require("sub.mod") == "sub.mod")
assert(dofile("recipes/code.lua") == 7)
assert(loadfile("recipes/code.lua")() == 7)
assert(load("return 1 + 1")() == 2)
assert(load("return 2", "=c", "bt")() == 2)
local lines = {}
for l in io.lines("recipes/notes.txt") do lines[#lines + 1] = l end
assert(#lines == 2 and lines[2] == "line two")
assert(io.open("allowed/data.txt"):read("a") == "allowed data\n")
assert(io.open("allowed/link_in.txt"):read("a") == "allowed data\n")
assert(io.open("outside/link_to_allowed.txt"):read("a") == "allowed data\n")
assert(io.open("allowed/../allowed/data.txt"):read("a") == "allowed data\n")
local f = assert(io.open("allowed/written.txt", "w"))
f:write("written\n")
f:close()
io.output("allowed/output.txt")
io.write("via io.output\n")
io.close()
io.output(io.stdout)
local m = femlod.load("recipes/part.obj")
m:save("allowed/part.stl")
m:save("allowed/new_folder_not_made/part.obj") -- fails below: no such folder
]])
  local st, _, err = sandboxed(name)
  T.eq(st, 1, "allowed recipe: fails only at its last line")
  T.eq(err, "femlod: " .. name .. ":26: allowed/new_folder_not_made/part.obj: cannot create temporary file: No such file or directory\n",
    "a missing folder inside --allow is the writer's own error")
  T.eq(T.readfile(at("allowed/written.txt")), "written\n", "io.open wrote in --allow")
  T.eq(T.readfile(at("allowed/output.txt")), "via io.output\n", "io.output wrote in --allow")
  T.check(T.exists(at("allowed/part.stl")), "mesh:save wrote in --allow")
end
do -- hierarchies, a sibling module and the femlod readers over the written files
  local name = recipe([[
local m = femlod.load("allowed/part.stl"):subdivide(2)
local h = m:simplify { ratio = 0.5 }
h:save("allowed/part.flh")
local h2 = femlod.load_hierarchy("allowed/part.flh")
h2:mesh():save("allowed/front.ply")
print(femlod.load("allowed/front.ply"):counts().triangles == h:mesh():counts().triangles)
print(os.time() > 0, type(os.clock()), os.date("!%Y", 0))
]])
  local st, out, err = sandboxed(name)
  T.eq(st, 0, "hierarchy recipe exit: " .. err)
  T.eq(out, "true\ntrue\tnumber\t1970\n", "hierarchy recipe output")
end
do -- -e and a recipe from stdin have no folder: only --allow is readable
  local st, _, err = run("--sandbox", "--allow", "allowed", "-e", "print(io.open('allowed/data.txt'):read('l')) io.open('recipes/notes.txt')")
  T.eq(st, 1, "-e sandboxed: exit")
  T.eq(err, "femlod: (command line):1: " .. no_read("recipes/notes.txt") .. "\n", "-e sandboxed: no recipe folder")
end
-- }======

-- {====== the memory cap: exit 3 and one line
local function capped(name, args, code, message)
  local st, _, err = run(table.unpack(args))
  T.eq(st, code, name .. ": exit status")
  T.eq(err, message, name .. ": message")
end
local MEM = "memory limit of 200M exceeded (--max-memory)"
local strings = recipe("local t = {} while true do t[#t + 1] = ('x'):rep(1e6) end\n")
capped("Lua strings", { "run", "--sandbox", "--max-memory", "200M", strings }, 3, "femlod: " .. MEM .. "\n")
capped("Lua strings, caps alone", { "run", "--max-memory=200M", strings }, 3, "femlod: " .. MEM .. "\n")
local meshes = recipe("local m = femlod.load(" .. "'recipes/fandisk.obj'" .. ")\n"
  .. "while true do m = m:subdivide(1) end\n")
capped("subdivided meshes", { "run", "--sandbox", "--max-memory", "200M", meshes }, 3,
  "femlod: " .. meshes .. ":2: " .. MEM .. "\n")
-- Copies keep every mesh alive: the charge, not the Lua heap, reaches the cap.
local copies = recipe("local m = femlod.load(" .. "'recipes/fandisk.obj'" .. ")\n"
  .. "local t = {}\nwhile true do t[#t + 1] = m:copy() end\n")
do -- the charge or the Lua heap, whichever passes the cap first
  local st, _, err = run("run", "--max-memory", "64M", copies)
  T.eq(st, 3, "kept copies: exit status")
  T.check(err == "femlod: " .. copies .. ":3: memory limit of 64M exceeded (--max-memory)\n"
    or err == "femlod: memory limit of 64M exceeded (--max-memory)\n", "kept copies: message " .. err)
end
-- Dropped copies are collected: the same loop with a bound ends normally.
local dropped = recipe("local m = femlod.load(" .. "'recipes/fandisk.obj'" .. ")\n"
  .. "for i = 1, 2000 do local c = m:copy() end print('ok')\n")
do
  local st, out, err = run("run", "--max-memory", "64M", dropped)
  T.eq(st, 0, "dropped copies: exit " .. err)
  T.eq(out, "ok\n", "dropped copies: ran to the end")
end
-- A caught memory error followed by another error is that other error.
local caught = recipe("print(pcall(string.rep, 'x', 1 << 30))\nerror('something else')\n")
do
  local st, out, err = run("run", "--max-memory", "200M", caught)
  T.eq(st, 1, "caught memory error then another: exit 1")
  T.eq(out, "false\tnot enough memory\n", "the recipe saw the memory error")
  T.eq(err, "femlod: " .. caught .. ":2: something else\n", "the other error is reported")
end
-- Hierarchies are charged too: kept ones reach the cap (fandisk's is about 2.5 MB,
-- its work memory about 8 MB), dropped ones are refunded.
local hiers = recipe("local m = femlod.load('recipes/fandisk.obj')\n"
  .. "local t = {}\nwhile true do t[#t + 1] = m:simplify { target = 6000 } end\n")
capped("kept hierarchies", { "run", "--max-memory", "40M", hiers }, 3,
  "femlod: " .. hiers .. ":3: memory limit of 40M exceeded (--max-memory)\n")
local hdropped = recipe("local m = femlod.load('recipes/fandisk.obj')\n"
  .. "for i = 1, 30 do local h <close> = m:simplify { target = 6000 } end print('ok')\n")
do
  local st, out, err = run("run", "--max-memory", "40M", hdropped)
  T.eq(st, 0, "closed hierarchies: exit " .. err)
  T.eq(out, "ok\n", "closed hierarchies: refunded, ran to the end")
end
-- A simplification whose work memory would pass the cap is refused before it starts.
local big = recipe("local m = femlod.load('recipes/fandisk.obj'):subdivide(2)\n"
  .. "print(#m:triangles())\nlocal h = m:simplify { target = 1000 }\n")
do
  local st, out, err = run("run", "--max-memory", "100M", big)
  T.eq(st, 3, "simplify past the cap: exit")
  T.eq(out, "207136\n", "simplify past the cap: the mesh was made")
  T.eq(err, "femlod: " .. big .. ":3: memory limit of 100M exceeded (--max-memory)\n",
    "simplify past the cap: refused at its line")
end
-- The cap on a command without a recipe.
capped("info under 64K", { "--max-memory", "64K", "info", P.shared .. "/fandisk.obj" }, 3,
  "femlod: memory limit of 64K exceeded (--max-memory)\n")
-- }======

-- {====== the time cap: exit 3, the recipe line where it stopped
local function timed(what, text, line, extra)
  local name = recipe(text)
  local args = { "run", "--sandbox", "--max-time", "1" }
  for _, a in ipairs(extra or {}) do args[#args + 1] = a end
  args[#args + 1] = name
  capped(what, args, 3, "femlod: " .. name .. ":" .. line .. ": time limit of 1 s exceeded (--max-time)\n")
end
timed("while true", "-- spin\nwhile true do end\n", 2)
-- Stopped inside pcall, then at the next instruction, after the pcall on line 2.
timed("pcall inside the loop", "while true do\n  pcall(function() while true do end end)\nend\n", 2)
timed("error handler that retries", "local function spin() while true do end end\n"
  .. "while true do xpcall(spin, function() return spin() end) end\n", 2)
timed("coroutines", "while true do\n  pcall(coroutine.wrap(function() while true do end end))\nend\n", 2)
do -- uncaught, through coroutine.wrap, which puts its own position in front
  local name = recipe("local spin = coroutine.wrap(function()\n  while true do end\nend)\nspin()\n")
  local st, _, err = run("run", "--sandbox", "--max-time", "1", name)
  T.eq(st, 3, "coroutine.wrap uncaught: exit 3")
  T.eq(err, "femlod: " .. name .. ":4: " .. name .. ":2: time limit of 1 s exceeded (--max-time)\n",
    "coroutine.wrap uncaught: message")
end
-- A long simplify (bunny, 75408 triangles to 4: about 2.7 s of CPU here, of
-- which 0.2 s of set-up before its first progress poll), stopped from inside
-- through the poll: the message names the simplify line (a broken poll would
-- let it finish and stop at line 4). The deadline is wall-clock time: on a
-- machine so loaded that loading takes the whole budget, the stop comes
-- before "simplifying" is printed, and the line is not checked.
local function long_simplify(what, body, line)
  local name = recipe("local m = femlod.load(" .. ("%q"):format(P.shared .. "/bunny.obj") .. ")\n"
    .. "print('simplifying') io.stdout:flush()\n" .. body .. "print('finished')\n")
  local st, out, err = run("run", "--max-time", "0.5", name)
  T.eq(st, 3, what .. ": exit status")
  T.check(not out:find("finished"), what .. ": did not finish")
  local pattern = "^femlod: " .. name:gsub("%p", "%%%0") .. ":%d+: time limit of 0%.5 s exceeded %(%-%-max%-time%)\n$"
  T.check(err:find(pattern) ~= nil, what .. ": message " .. err)
  if out == "simplifying\n" then
    T.eq(err:match(":(%d+): time"), tostring(line), what .. ": stopped at the simplify line")
  else
    print(what .. ": the deadline passed before simplify started (a loaded machine); line not checked")
  end
end
long_simplify("a long simplify", "local h = m:simplify { target = 4 }\n", 3)
long_simplify("a long simplify inside pcall", "while true do pcall(m.simplify, m, { target = 4 }) end\n", 3)
-- The other long operations poll the cap the same way: the curvature of
-- bunny with a wide ball (about 2 s of CPU here) stops at its own line.
long_simplify("a long curvature", "local k = m:curvature { radius = 0.05 }\n", 3)
timed("both caps: memory errors caught forever", "while true do\n  pcall(function() local t = {} while true do t[#t + 1] = ('x'):rep(1e6) end end)\nend\n", 2,
  { "--max-memory", "100M" })
do -- caps alone, with -e
  local st, _, err = run("--max-time", "0.5", "-e", "while true do end")
  T.eq(st, 3, "-e under --max-time: exit 3")
  T.eq(err, "femlod: (command line):1: time limit of 0.5 s exceeded (--max-time)\n", "-e under --max-time")
end
-- }======

-- {====== usage errors: exit 2
local function usage(first, ...)
  local st, out, err = run(...)
  T.eq(st, 2, "exit 2 for: " .. table.concat({ ... }, " "))
  T.eq(out, "", "nothing on stdout")
  T.eq(err:match("^[^\n]*"), first, "message for: " .. table.concat({ ... }, " "))
end
usage("femlod: --allow: nothere: No such file or directory", "run", "--sandbox", "--allow", "nothere", "x.lua")
usage("femlod: --allow: recipes/notes.txt: Not a directory", "run", "--sandbox", "--allow", "recipes/notes.txt", "x.lua")
usage("femlod: --allow needs a value", "run", "--sandbox", "--allow")
usage("femlod: --allow needs --sandbox", "run", "--allow", "allowed", "x.lua")
usage("femlod: --max-memory: size of at least 64K expected (a number with K, M or G), got '12Q'",
  "run", "--max-memory", "12Q", "x.lua")
usage("femlod: --max-memory: size of at least 64K expected (a number with K, M or G), got '1K'",
  "--max-memory=1K", "-e", "")
usage("femlod: --max-time: number of seconds > 0 expected, got '-1'", "run", "--max-time", "-1", "x.lua")
usage("femlod: --max-time: number of seconds > 0 expected, got 'soon'", "--max-time", "soon", "-e", "")
usage("femlod: --sandbox applies to run and -e only", "--sandbox", "info", "recipes/part.obj")
usage("femlod: unknown option '--sandbx'; did you mean --sandbox?", "run", "--sandbx", "x.lua")
usage("femlod: unknown option '--zzz' (valid: --sandbox, --allow, --max-memory, --max-time)", "run", "--zzz", "x.lua")
-- }======

-- {====== femlod's own writers work inside: write_file, a report page with its viewer
do
  local name = recipe([[
femlod.write_file("allowed/table.csv", "a,b\n1,2\n")
local m = femlod.mesh { positions = { {0,0,0}, {1,0,0}, {0,1,0}, {0,0,1} },
  triangles = { {1,3,2}, {1,2,4}, {1,4,3}, {2,3,4} } }
assert(#m:encode("m.glb") > 0)
femlod.report(m, { html = "allowed/page.html" })
print("done")
]])
  local st, out, err = sandboxed(name)
  T.eq(st, 0, "sandboxed report: exit 0: " .. err)
  T.eq(out, "done\n", "sandboxed report: ran to the end")
  T.eq(T.readfile(at("allowed/table.csv")), "a,b\n1,2\n", "write_file in an --allow folder")
  local page = T.readfile(at("allowed/page.html")) or ""
  T.check(page:find("<model%-viewer") and page:find("data:model/gltf%-binary;base64,"),
    "sandboxed report: the page has the viewer and the mesh")
  os.remove(at("allowed/table.csv"))
  os.remove(at("allowed/page.html"))
end
-- }======

T.summary("test_sandbox")
