-- test_sweep.lua: `femlod sweep` from outside (examples/sweep.lua's 3x2 grid
-- twice with identical hashes, failed and crashed points, --emit-jobs then
-- --collect, usage errors), `femlod run --record`, and femlod.sweep's Lua side.

local T = dofile((arg[0]:match("^(.*)/") or ".") .. "/check.lua")
local femlod = require "femlod"
local sweep = require "femlod.sweep"

local P = params
assert(P and P.femlod and P.tmp and P.shared and P.examples, "run through ctest: needs femlod=, tmp=, shared=, examples=")
local FEMLOD = P.femlod
local function path(name) return P.tmp .. "/sweep_" .. name end
local quote = T.quote
local R = T.runner(FEMLOD, path("stderr.txt"))
local sh, run = R.sh, R.run
local function rmrf(p) os.execute("rm -rf " .. quote(p)) end

-- The SHA-256 that coreutils computes, to check the manifest's.
local function sha256sum(file)
  local p = assert(io.popen("sha256sum " .. quote(file)))
  local s = p:read("a")
  p:close()
  return s:match("^(%x+)")
end

local read_csv = T.read_csv

-- The manifest's digest and every "sha256" in it, in order (cJSON's layout).
local function manifest_hashes(dir)
  local m = assert(T.readfile(dir .. "/manifest.json"), dir .. "/manifest.json")
  local hashes = {}
  for h in m:gmatch('"sha256":%s*"(%x+)"') do hashes[#hashes + 1] = h end
  return m:match('"digest":%s*"(%x+)"'), hashes, m
end

-- {====== examples/sweep.lua: the 3x2 grid, twice, identical hashes
local GRID = { "--grid", "target=1500,3000,6000", "--grid", "min_stretch=0.3,0.5" }
local EXAMPLE = P.examples .. "/sweep.lua"
local digests, all_hashes, csvs = {}, {}, {}
-- Input triangles below a threshold may survive (nothing can collapse them
-- better), so the guarantee is min(threshold, the input's minimum).
local input_min = femlod.load(P.examples .. "/data/fandisk.obj"):quality().stretch_min
for k, jobs in ipairs { "2", "3" } do
  local dir = path("example" .. k)
  rmrf(dir)
  local code, out, err = run("sweep", EXAMPLE, GRID[1], GRID[2], GRID[3], GRID[4], "--jobs", jobs,
    "--out", dir)
  T.eq(code, 0, "example sweep exit; stderr: " .. err)
  T.check(out:find("6 points: 6 ok, 0 failed; digest %x+\n"), "summary line: " .. out)
  local n = 0
  for _ in out:gmatch("point %d%d%d target=%d+ min_stretch=0%.%d: ok") do n = n + 1 end
  T.eq(n, 6, "one line per point")
  digests[k], all_hashes[k] = manifest_hashes(dir)
  csvs[k] = read_csv(dir .. "/results.csv")
  local rows = csvs[k]
  T.eq(#rows, 6, "6 rows in results.csv")
  local targets, stretches = { 1500, 1500, 3000, 3000, 6000, 6000 }, { 0.3, 0.5, 0.3, 0.5, 0.3, 0.5 }
  for i, r in ipairs(rows) do
    T.eq(r.point, tostring(i - 1), "point index")
    T.eq(r.dir, string.format("points/%03d", i - 1), "point folder")
    T.eq(r.status, "ok", "status")
    T.eq(tonumber(r.target), targets[i], "grid order: target (first --grid, slowest)")
    T.eq(tonumber(r.min_stretch), stretches[i], "grid order: min_stretch (last --grid, fastest)")
    T.eq(r.mesh, string.format("points/%03d/mesh.obj", i - 1), "the mesh the point saved")
    T.eq(tonumber(r.triangles), targets[i], "triangles = target")
    local bound = math.min(stretches[i], input_min)
    T.check(tonumber(r.stretch_min) >= bound, "every triangle has stretch >= " .. bound .. ": " .. r.stretch_min)
    T.check(tonumber(r.valence_max) <= 12, "valence <= 12")
    T.check(tonumber(r.hausdorff) > 0 and tonumber(r.hausdorff_rel) < 0.05,
      "deviation from the input measured: " .. r.hausdorff_rel)
    T.check(tonumber(r.seconds) > 0 and tonumber(r.max_rss_kb) > 1000, "time and peak memory")
    T.eq(r["recorded.stop"], "target", "recorded by the recipe: stop reason")
    T.check(tonumber(r["recorded.collapses"]) > 0, "recorded: collapses")
    T.eq(r.error, "", "no error")
    -- The manifest's hashes are the files'.
    local mesh = dir .. "/" .. r.mesh
    T.check(select(3, manifest_hashes(dir)):find('"path":%s*"' .. r.mesh .. '",%s*"sha256":%s*"'
      .. sha256sum(mesh) .. '"'), "manifest has the SHA-256 of " .. r.mesh)
    T.check(T.exists(dir .. "/" .. r.dir .. "/stdout.txt"), "stdout kept")
  end
  local m = select(3, manifest_hashes(dir))
  T.check(m:find('"path":%s*"' .. EXAMPLE:gsub("%p", "%%%0") .. '",%s*"sha256":%s*"' .. sha256sum(EXAMPLE)),
    "the recipe's hash")
  local input = P.examples .. "/data/fandisk.obj"
  T.check(m:find('"path":%s*"' .. input:gsub("%p", "%%%0") .. '",%s*"sha256":%s*"' .. sha256sum(input)),
    "the input read through femlod.load, with its hash")
  T.check(m:find('"femlod":%s*"femlod 0%.1%.0"'), "femlod's version")
end
T.check(digests[1] and #digests[1] == 64, "a digest")
T.eq(digests[2], digests[1], "the same sweep twice: the same digest")
T.eq(#all_hashes[1], 6 * 3 + 1, "hashes: the recipe, and per point the recipe, the input, the output")
for i, h in ipairs(all_hashes[1]) do T.eq(all_hashes[2][i], h, "hash " .. i .. " identical") end
for i = 1, 6, 2 do
  T.check(csvs[1][i].stretch_avg ~= csvs[1][i + 1].stretch_avg, "min_stretch changes the mesh")
end
for i, r in ipairs(csvs[1]) do
  for _, k in ipairs { "triangles", "vertices", "stretch_avg", "stretch_min", "size_max", "hausdorff" } do
    T.eq(csvs[2][i][k], r[k], "results.csv " .. k .. " identical at point " .. i - 1)
  end
end
-- A recipe that is not there: one message, nothing run.
do
  local code, out, err = run("sweep", path("missing.lua"), "--grid", "a=1,2", "--out", path("missing"))
  T.eq(code, 1, "missing recipe: exit 1")
  T.eq(out, "", "nothing run")
  T.eq(err, "femlod: " .. path("missing.lua") .. ": cannot open: No such file or directory\n", "names the file")
  T.check(not T.exists(path("missing") .. "/manifest.json"), "no manifest")
end
-- A second sweep into the same folder is refused (stale points would mix in).
do
  local code, _, err = run("sweep", EXAMPLE, "--grid", "target=1500", "--out", path("example1"))
  T.eq(code, 1, "existing sweep folder: exit 1")
  T.check(err:find("already holds a sweep"), err)
end
-- }======

-- {====== points run sandboxed unless --no-sandbox
do
  local SB = path("sandboxed.lua")
  T.writefile(SB, [[
if params.mode == "exec" then os.execute("true") end
local m = femlod.load(params.mesh)
m:save(params.out_dir .. "/copy.off")
if params.mode == "outside" then m:save(params.out_dir .. "/../escape.off") end
]])
  local dir = path("sandboxed")
  rmrf(dir)
  local code, out = R.run("sweep", SB, "mesh=" .. P.shared .. "/fandisk.obj", "--grid", "mode=ok,exec,outside",
    "--out", dir, "--allow", P.shared)
  T.eq(code, 1, "sandboxed points: two fail")
  local rows = read_csv(dir .. "/results.csv")
  T.eq(rows[1].status, "ok", "sandboxed: reads an --allow folder, writes its own folder")
  T.eq(rows[2].status, "failed", "sandboxed: os.execute refused")
  T.check(rows[2].error:find("execute"), "sandboxed: the refusal names execute: " .. tostring(rows[2].error))
  T.eq(rows[3].status, "failed", "sandboxed: writing outside the point's folder refused")
  T.check(not T.exists(dir .. "/points/escape.off"), "sandboxed: nothing written outside")
  -- without --allow the shared mesh is out of reach
  rmrf(dir)
  code, out = R.run("sweep", SB, "mesh=" .. P.shared .. "/fandisk.obj", "--grid", "mode=ok", "--out", dir)
  T.eq(code, 1, "sandboxed: a mesh outside the allowed folders cannot be read: " .. out)
end
-- }======

-- {====== failed and crashed points: reported, the others go on
local CRASH = path("crash.lua")
T.writefile(CRASH, [[
local m = femlod.load(params.mesh)
if params.mode == "error" then error("point failed on purpose") end
if params.mode == "crash" then
  local pid = io.open("/proc/self/stat"):read("n")
  os.execute("kill -KILL " .. pid)
end
if params.mode == "exit" then os.exit(0) end
m:save(params.out_dir .. "/copy.off")
require("femlod.sweep").record { mode = params.mode, scale = params.scale, r = math.random(1000000) }
]])
do
  local dir = path("crash")
  rmrf(dir)
  local code, out, err = R.run("--seed", "7", "sweep", CRASH, "mesh=" .. P.shared .. "/fandisk.obj", "scale=2.5",
    "--grid", "mode=ok,error,crash,exit", "--out", dir, "--jobs", "4", "--no-sandbox")
  T.eq(code, 1, "a point failed: exit 1")
  T.eq(err, "", "the sweep itself says nothing on stderr")
  T.check(out:find("point 001 mode=error: failed %(exit 1%)"), out)
  -- the reason on the console, as results.csv has it: not just the exit status
  local esc_crash = CRASH:gsub("%p", "%%%0")
  T.check(out:find("point 001 mode=error: failed %(exit 1%), [%d.]+ s, [%d.]+ MB: " .. esc_crash
    .. ":2: point failed on purpose\n"), "a failed point's reason on the console: " .. out)
  T.check(out:find("point 000 mode=ok: ok, [%d.]+ s, [%d.]+ MB\n"), "an ok point has no reason: " .. out)
  T.check(out:find("point 002 mode=crash: crashed %(Killed%)"), out)
  T.check(out:find("4 points: 1 ok, 3 failed"), out)
  local rows = read_csv(dir .. "/results.csv")
  T.eq(rows[1].status, "ok", "ok point")
  T.eq(rows[1]["recorded.mode"], "ok", "recorded string")
  T.eq(rows[1]["recorded.scale"], "2.5", "fixed pair arrives as a number")
  local _, seven = run("--seed", "7", "-e", "print(math.random(1000000))")
  T.eq(rows[1]["recorded.r"] .. "\n", seven, "--seed reaches the points")
  T.check(T.readfile(dir .. "/manifest.json"):find('"seed":%s*7,'), "seed in the manifest")
  T.eq(rows[1].triangles, "12946", "copy's triangles")
  T.eq(rows[2].status, "failed", "error point")
  T.eq(rows[2].error, CRASH .. ":2: point failed on purpose", "the recipe's message")
  T.eq(rows[3].status, "crashed", "crashed point")
  T.eq(rows[3].error, "killed by signal 9 (Killed)", "the signal")
  T.eq(rows[4].status, "failed", "os.exit point")
  T.check(rows[4].error:find("no record"), rows[4].error)
  T.eq(T.readfile(dir .. "/points/001/stderr.txt"), "femlod: " .. CRASH .. ":2: point failed on purpose\n",
    "the failed point's stderr is kept")
  local m = T.readfile(dir .. "/manifest.json")
  T.check(m:find('"status":%s*"crashed",%s*"exit":%s*null,%s*"signal":%s*9'), "crash in the manifest")
  T.check(m:find('"fixed":%s*{%s*"mesh":%s*"[^"]*fandisk.obj",%s*"scale":%s*2.5%s*}'), "fixed pairs")
  -- The failed point still recorded what it read before failing.
  local rec = T.readfile(dir .. "/points/001/record.json")
  T.check(rec and rec:find("fandisk%.obj") and rec:find('"error":%s*"[^"]*point failed on purpose"'),
    "failed point's record")
end
-- }======

-- {====== --emit-jobs, then the jobs elsewhere, then --collect: the same digest
local COPY = path("copy.lua")
T.writefile(COPY, [[
local m <close> = femlod.load(params.mesh)
local fine <close> = m:subdivide(params.levels)
fine:save(params.out_dir .. "/fine." .. params.ext)
]])
do
  local mesh = P.data .. "/tetra.off"
  local args = { "sweep", COPY, "mesh=" .. mesh, "--grid", "levels=0,1,2", "--grid", "ext=off,ply",
    "--allow", P.data }
  local direct = path("direct")
  rmrf(direct)
  local a = { table.unpack(args) }
  a[#a + 1] = "--out"
  a[#a + 1] = direct
  T.eq((run(table.unpack(a))), 0, "direct sweep")
  local d1 = manifest_hashes(direct)

  local jobs = path("jobs")
  rmrf(jobs)
  a[#a] = jobs
  a[#a + 1] = "--emit-jobs"
  local code, out, err = run(table.unpack(a))
  T.eq(code, 0, "--emit-jobs exit")
  T.eq(err, "", "--emit-jobs stderr")
  local lines = {}
  for l in out:gmatch("[^\n]+") do lines[#lines + 1] = l end
  T.eq(#lines, 6, "one command per point")
  T.check(lines[4]:find("^cd '?/.* && '?/[^ ]*femlod'? %-%-seed=0 sweep .* %-%-grid levels=0,1,2 %-%-grid ext=off,ply %-%-allow .* %-%-out .* %-%-point 3$"),
    "self-contained command: " .. lines[4])
  T.check(not T.exists(jobs .. "/manifest.json"), "--emit-jobs runs nothing")
  -- As a scheduler would: each line alone, in any order.
  for i = #lines, 1, -1 do
    local c = sh(lines[i])
    T.eq(c, 0, "job " .. i)
  end
  T.check(not T.exists(jobs .. "/manifest.json"), "--point writes no manifest")
  a[#a] = "--collect"
  code, out = run(table.unpack(a))
  T.eq(code, 0, "--collect exit")
  T.check(out:find("6 points: 6 ok, 0 failed"), out)
  T.eq(manifest_hashes(jobs), d1, "jobs + collect: the direct sweep's digest")
  local rows = read_csv(jobs .. "/results.csv")
  T.eq(rows[6].triangles, "64", "tetra at 2 levels: 4 * 16 triangles")
  T.eq(rows[6].mesh, "points/005/fine.ply", "paths relative to the sweep folder")
  -- A damaged record or run file: that point failed, named, the others still count.
  local rec3 = jobs .. "/points/003/record.json"
  local saved = T.readfile(rec3)
  T.writefile(rec3, '{"femlod": "femlod 0.1.0", "reads": [')
  T.writefile(jobs .. "/points/004/run.json", "[1, 2]")
  code, out = run(table.unpack(a))
  T.eq(code, 1, "--collect with damaged files: exit 1")
  T.check(out:find("6 points: 4 ok, 2 failed"), out)
  rows = read_csv(jobs .. "/results.csv")
  T.eq(rows[4].status, "failed", "damaged record: failed")
  T.eq(rows[4].error, "points/003/record.json: not a JSON object (damaged?)", "names the file")
  T.eq(rows[5].error, "points/004/run.json: not a JSON object (damaged?)", "names the run file")
  T.eq(rows[6].status, "ok", "the others are unaffected")
  T.writefile(rec3, saved)
  -- --collect before the points ran says so.
  local none = path("none")
  rmrf(none)
  os.execute("mkdir -p " .. quote(none))
  a[#a - 1] = none
  code, out = run(table.unpack(a))
  T.eq(code, 1, "--collect of points not run: exit 1")
  T.check(out:find("6 points: 0 ok, 6 failed"), out)
  T.eq(read_csv(none .. "/results.csv")[1].status, "not run", "status not run")
end
-- }======

-- {====== the progress bar: on stderr when it is a terminal (script(1) gives one), never else
do
  local dir = path("tty")
  rmrf(dir)
  local line = table.concat({ quote(FEMLOD), "sweep", quote(COPY), quote("mesh=" .. P.data .. "/tetra.off"),
    "ext=off", "--grid", "levels=0,1", "--allow", quote(P.data), "--out", quote(dir) }, " ")
  local code, out = sh("script -qec " .. quote(line) .. " /dev/null")
  T.eq(code, 0, "sweep under a terminal")
  T.check(out:find("\r\27%[Ksweep %[[#.]+%] 0/2 points  [%d.]+ s  0%.00 points/s  ETA %?"), "bar before a point ends")
  T.check(out:find("\r\27%[Ksweep %[#+%.*%] 1/2 points  [%d.]+ s  [%d.]+ points/s  ETA %d+ s"), "bar with rate and ETA")
  T.check(out:find("\27%[Kpoint 00%d levels=%d: ok"), "the bar is cleared before a point's line")
  T.check(out:find("\r\27%[K2 points: 2 ok"), "and before the summary")
  rmrf(dir)
  code, out = sh("script -qec " .. quote(line:gsub("^(%S+) sweep", "%1 -q sweep")) .. " /dev/null")
  T.eq(code, 0, "-q sweep under a terminal")
  T.check(not out:find("sweep %["), "--quiet: no bar")
end
-- }======

-- {====== usage errors: exit 2, nothing run
local usage = R.usage
usage("femlod: missing a recipe", "sweep")
usage("femlod: --grid: name=v1,v2,... expected, got 'target'", "sweep", COPY, "--grid", "target")
usage("femlod: --grid target: empty value in '1,,2'", "sweep", COPY, "--grid", "target=1,,2")
usage("femlod: --grid target: value '1' given twice", "sweep", COPY, "--grid", "target=1,2,1")
usage("femlod: parameter given twice: 'target'", "sweep", COPY, "--grid", "target=1,2", "--grid", "target=3")
usage("femlod: parameter given twice: 'target=4'", "sweep", COPY, "--grid", "target=1,2", "target=4")
usage("femlod: --grid: '2x' is not a name (letters, digits, _)", "sweep", COPY, "--grid", "2x=1")
usage("femlod: out_dir is set by the sweep (DIR/points/NNN)", "sweep", COPY, "out_dir=/tmp")
usage("femlod: --jobs: integer 1..256 expected, got '0'", "sweep", COPY, "--jobs", "0")
usage("femlod: --jobs needs a value", "sweep", COPY, "--jobs")
usage("femlod: unknown option '--grids'; did you mean --grid?", "sweep", COPY, "--grids=a=1")
usage("femlod: --point 6: the grid has points 0..5", "sweep", COPY, "--grid", "a=1,2,3", "--grid", "b=x,y",
  "--point", "6")
usage("femlod: sweep: --emit-jobs, --collect and --point exclude each other", "sweep", COPY, "--collect",
  "--emit-jobs")
usage("femlod: expected name=value, got 'levels'", "sweep", COPY, "levels")
usage("femlod: sweep: the recipe must be a file (each point reads it again)", "sweep", "-")
usage("femlod: --record goes with run only", "--record", path("r.json"), "info", COPY)
-- }======

-- {====== femlod run --record FILE
do
  local rec = path("record.json")
  os.remove(rec)
  local code, _, err = run("--record", rec, "run", COPY, "mesh=" .. P.data .. "/tetra.off", "levels=1",
    "ext=obj", "out_dir=" .. P.tmp)
  T.eq(code, 0, "run --record: " .. err)
  local r = T.readfile(rec)
  T.check(r and r:find('"levels":%s*1,'), "params in the record")
  T.check(r:find('"path":%s*"' .. (P.tmp .. "/fine.obj"):gsub("%p", "%%%0") .. '",%s*"sha256":%s*"'
    .. sha256sum(P.tmp .. "/fine.obj") .. '"'), "written file and hash")
  T.check(r:find('"triangles":%s*16'), "Table 1 figures of the saved mesh")
  T.check(r:find('"hausdorff":%s*[%d.e-]+'), "deviation from the input")
  T.check(r:find('"error":%s*null'), "no error")
  os.remove(P.tmp .. "/fine.obj")
end
-- }======

-- {====== the Lua side
do
  local pts = sweep.points { { "a", { 1, 2 } }, { "b", { "x", "y", "z" } } }
  T.eq(#pts, 6, "cartesian product")
  T.eq(pts[1].a, 1, "first")
  T.eq(pts[1].b, "x", "first")
  T.eq(pts[2].b, "y", "last axis fastest")
  T.eq(pts[4].a, 2, "first axis slowest")
  T.eq(pts[4].b, "x", "wraps")
  T.eq(#sweep.points {}, 0, "no axes, no points")
  T.checkerr("axis 'a' given twice", sweep.points, { { "a", { 1 } }, { "a", { 2 } } })
  T.checkerr("axis 'b' has no values", sweep.points, { { "b", {} } })
  T.checkerr("axis 1: {name, {values...}} expected", sweep.points, { "a" })
  T.checkerr("key \"a b\": a name", sweep.record, { ["a b"] = 1 })
  T.checkerr("x: string, finite number or boolean expected, got table", sweep.record, { x = {} })
  T.checkerr("x: string, finite number or boolean expected, got number", sweep.record, { x = 0 / 0 })
  T.checkerr("femlod.Mesh expected, got nil", sweep.reference)

  T.eq(sweep.active(), false, "not recording in a plain run")
  local hook = sweep.start({ n = 3 }, { "recipe.lua" })
  T.eq(type(hook), "function", "start returns the hook")
  T.eq(sweep.active(), true, "recording")
  sweep.record { k = 1 }
  sweep.record { k = 2, s = "t" }
  local m = femlod.mesh { positions = { 0, 0, 0, 1, 0, 0, 0, 1, 0 }, triangles = { 1, 2, 3 } }
  hook("read", "in.obj", m)
  hook("write", "out.obj", m)
  hook("write", "out.obj", m)
  local r = sweep.result()
  T.eq(r.params.n, 3, "params copied")
  T.eq(table.concat(r.reads, " "), "recipe.lua in.obj", "reads in order")
  T.eq(table.concat(r.writes, " "), "out.obj", "a file written twice is listed once")
  T.eq(#r.meshes, 1, "one mesh entry per file")
  T.eq(r.meshes[1].triangles, 1, "its figures")
  T.check(r.meshes[1].hausdorff < 1e-12, "deviation from the first mesh read (itself)")
  T.eq(r.recorded.k, 2, "later record wins")
  T.eq(r.recorded.s, "t", "records add up")
  T.eq(sweep.files().reads[2], "in.obj", "files()")
end
-- }======

T.summary("test_sweep")
