-- write.lua: the pages tests/report/check.js opens in Chromium (ctest
-- report_pages): fandisk simplified to 3,000 triangles with the input as
-- reference (OUT_fandisk.html); the 121k-triangle engine, shown through a
-- copy simplified for display, in a page under 3 MB (OUT_engine.html); the
-- page of a 2x2 sweep of examples/sweep.lua (OUT_sweep/report.html) and of
-- a sweep whose every point fails (OUT_failed/report.html), both written by
-- `femlod sweep`.
local femlod = require "femlod"
local P = params
assert(P and P.out and P.shared and P.femlod and P.examples, "needs out=, shared=, femlod=, examples=")

local input <close> = femlod.load(P.shared .. "/fandisk.obj")
local h <close> = input:simplify { target = 3000, min_stretch = 0.3 }
local result <close> = h:mesh()
local r = femlod.report(result, { reference = input, html = P.out .. "_fandisk.html", name = "fandisk 3000",
  reference_name = "fandisk.obj" })
assert(r.viewer, "the page has the 3D view")
print(r.row)

local engine <close> = femlod.load(P.shared .. "/2CylinderEngine.glb")
local e = femlod.report(engine, { html = P.out .. "_engine.html", name = "2CylinderEngine.glb" })
local ef = assert(io.open(P.out .. "_engine.html", "rb"))
local bytes = ef:seek("end")
ef:close()
print(("engine page: %d bytes, %d of %d triangles shown"):format(bytes, e.display_triangles or -1,
  e.quality.triangles))
assert(e.display_triangles and e.display_triangles < e.quality.triangles, "the engine is shown through a copy")
assert(bytes < 3e6, "the engine's page stays under 3 MB: " .. bytes)

local function quote(s) return "'" .. tostring(s):gsub("'", "'\\''") .. "'" end
local dir = P.out .. "_sweep"
os.execute("rm -rf " .. quote(dir))
local ok = os.execute(table.concat({ quote(P.femlod), "-q", "sweep", quote(P.examples .. "/sweep.lua"),
  "--grid", "target=1500,3000", "--grid", "min_stretch=0.3,0.5", "--out", quote(dir) }, " "))
assert(ok, "the sweep ran")
local f = assert(io.open(dir .. "/report.html"), "sweep page written")
f:close()
-- every point fails (target is not an integer): the sweep exits 1, its page is written
local fdir = P.out .. "_failed"
os.execute("rm -rf " .. quote(fdir))
ok = os.execute(table.concat({ quote(P.femlod), "-q", "sweep", quote(P.examples .. "/sweep.lua"),
  "--grid", "target=many,few", "--grid", "min_stretch=0.3,0.5", "--out", quote(fdir) }, " "))
assert(not ok, "every point failed")
f = assert(io.open(fdir .. "/report.html"), "all-failed sweep page written")
f:close()
print("pages written")
