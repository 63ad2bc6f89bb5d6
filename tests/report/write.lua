-- write.lua: the pages tests/report/check.js opens in Chromium (ctest
-- report_pages): fandisk simplified to 3,000 triangles with the input as
-- reference (OUT_fandisk.html), and the page of a 2x2 sweep of
-- examples/sweep.lua (OUT_sweep/report.html), written by `femlod sweep`.
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

local function quote(s) return "'" .. tostring(s):gsub("'", "'\\''") .. "'" end
local dir = P.out .. "_sweep"
os.execute("rm -rf " .. quote(dir))
local ok = os.execute(table.concat({ quote(P.femlod), "-q", "sweep", quote(P.examples .. "/sweep.lua"),
  "--grid", "target=1500,3000", "--grid", "min_stretch=0.3,0.5", "--out", quote(dir) }, " "))
assert(ok, "the sweep ran")
local f = assert(io.open(dir .. "/report.html"), "sweep page written")
f:close()
print("pages written")
