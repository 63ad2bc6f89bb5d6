-- fe_tools.lua: what femlod writes, read by the real tools (issue 7's "done
-- when"): the cover simplified to 6000 triangles (the paper's thresholds
-- and order)
-- is loaded by gmsh from .msh 4.1 and 2.2 with its exact node and element
-- counts (and from .mesh and .vtk) and re-exported to a file femlod reads
-- back; TetGen
-- tetrahedralizes the closed .mesh surface keeping every surface triangle
-- (-Y); CalculiX solves a static S3 shell analysis on the .inp with a fixed
-- edge and a load given as nsets. A missing tool fails the test (CI installs
-- gmsh, tetgen and calculix-ccx). Label heavy: not under the sanitizers.

local T = dofile((arg[0]:match("^(.*)/") or ".") .. "/check.lua")
local femlod = require "femlod"

local P = params
assert(P and P.tmp and P.shared, "run through ctest: needs tmp= and shared=")
local dir = P.tmp .. "/fe_tools"
os.execute("rm -rf '" .. dir .. "' && mkdir -p '" .. dir .. "'")
local function path(name) return dir .. "/" .. name end

-- Runs a shell command in dir; returns its exit code and output (both streams).
local function sh(cmd)
  local p = assert(io.popen("cd '" .. dir .. "' && " .. cmd .. " 2>&1", "r"))
  local out = p:read("a")
  local ok, _, code = p:close()
  return ok and 0 or code, out
end

local function have(tool)
  local code = sh("command -v " .. tool .. " >/dev/null")
  return T.check(code == 0, tool .. " not found (apt-get install gmsh tetgen calculix-ccx)")
end

local input <close> = femlod.load(P.shared .. "/cover.obj")
-- In the paper's order: its walls at y = min and max keep 54 and 49 nodes
-- for the clamp and the load; the default order leaves 25 and 1 node
-- exactly on them.
local h <close> = femlod.simplify(input, {
  target = 6000, tolerance = 0.15, min_stretch = 0.2, max_size = 15, max_valence = 12, error_order = false,
})
local cover <close> = h:mesh()
local counts = cover:counts()
T.eq(counts.triangles, 6000, "simplified to 6000 triangles")
local q = cover:quality()
T.check(q.closed and q.manifold, "the simplified cover is closed and manifold")
local box = cover:bbox()
local ymin, ymax = box.min[2], box.max[2]

cover:save(path("cover.msh"))
cover:save(path("cover22.msh"), { format = "msh2" })
cover:save(path("cover.mesh"))
cover:save(path("cover.vtk"))
local sets = {
  FIXED = function(_, y) return y == ymin end,   -- the side wall at y = 0: clamped
  LOADED = function(_, y) return y == ymax end,  -- the opposite wall: pushed down
}
cover:save(path("cover.inp"), { nsets = sets })
local nfixed, nloaded = 0, 0
for _, p in ipairs(cover:positions()) do
  if p[2] == ymin then nfixed = nfixed + 1 end
  if p[2] == ymax then nloaded = nloaded + 1 end
end
T.check(nfixed >= 10 and nloaded >= 10, "both walls have nodes")

-- The same input gives the same bytes.
cover:save(path("again.msh"))
T.check(T.readfile(path("again.msh")) == T.readfile(path("cover.msh")), "deterministic .msh")

-- {====== gmsh
if have("gmsh") then
  local code, out
  for _, f in ipairs { "cover.msh", "cover22.msh" } do
    code, out = sh("gmsh -check " .. f)
    T.eq(code, 0, "gmsh -check " .. f)
    T.eq(tonumber(out:match("Info%s*: (%d+) nodes")), counts.vertices, f .. ": gmsh's node count")
    T.eq(tonumber(out:match("Info%s*: (%d+) elements")), 6000, f .. ": gmsh's element count")
    T.check(not out:find("Warning") and not out:find("Error"), f .. ": gmsh has no warning: " .. out)
  end
  -- gmsh also reads the Medit and VTK files: the same 6000 triangles.
  for _, f in ipairs { "cover.mesh", "cover.vtk" } do
    code, out = sh("gmsh -check " .. f)
    T.eq(code, 0, "gmsh -check " .. f)
    T.eq(tonumber(out:match("Checking mesh coherence %((%d+) elements%)")), 6000,
      f .. ": gmsh's element count")
    T.check(not out:find("Warning") and not out:find("Error"), f .. ": gmsh has no warning: " .. out)
  end
  -- An open surface: its boundary edges are 2-node lines in the physical
  -- curve "boundary", which gmsh keeps and femlod skips on reading.
  local open <close> = femlod.load(P.shared .. "/sphereWithHole.stl")
  local nb = open:quality().boundary_edges
  T.check(nb > 0, "sphereWithHole has a boundary")
  open:save(path("open.msh"))
  code, out = sh("gmsh -check open.msh")
  T.eq(tonumber(out:match("Info%s*: (%d+) elements")), open:counts().triangles + nb,
    "open.msh: gmsh counts the triangles and the boundary lines")
  T.eq(sh("gmsh -0 open.msh -format msh22 -o open22.msh"), 0, "gmsh re-exports open.msh")
  local open22 <close> = femlod.load(path("open22.msh"))
  T.eq(open22:counts().triangles, open:counts().triangles, "the re-export has the triangles")
  local lines = 0
  for line in T.readfile(path("open22.msh")):gmatch("[^\n]+") do
    if line:match("^%d+ 1 2 2 1 %d+ %d+$") then lines = lines + 1 end
  end
  T.eq(lines, nb, "gmsh's re-export keeps the boundary lines in physical group 2")
  -- gmsh's own re-export (4.1 to 2.2) reads back to the same surface.
  code = sh("gmsh -0 cover.msh -format msh22 -o gmsh22.msh")
  T.eq(code, 0, "gmsh -0 re-export")
  local back <close> = femlod.load(path("gmsh22.msh"))
  local pa, pb = cover:positions(), back:positions()
  local ta, tb = cover:triangles(), back:triangles()
  T.eq(#tb, 6000, "gmsh's file has 6000 triangles")
  T.eq(#pb, #pa, "and every node")
  local worst, same_tri = 0, #ta == #tb
  for i = 1, math.min(#pa, #pb) do
    for k = 1, 3 do worst = math.max(worst, math.abs(pa[i][k] - pb[i][k])) end
  end
  for i = 1, same_tri and #ta or 0 do
    for k = 1, 3 do same_tri = same_tri and ta[i][k] == tb[i][k] end
  end
  T.check(worst <= 1e-12, "gmsh keeps the coordinates (max difference " .. worst .. ")")
  T.check(same_tri, "gmsh keeps the triangles and their order")
end
-- }======

-- {====== TetGen: the figure 1 step from surface to volume mesh
if have("tetgen") then
  -- -p: a piecewise linear complex (the surface), -Y: keep its triangles,
  -- -q1.4: radius-edge ratio bound.
  local code, out = sh("tetgen -pYq1.4 cover.mesh")
  T.eq(code, 0, "tetgen exits 0: " .. out:sub(-400))
  local tets = tonumber(out:match("Mesh tetrahedra: (%d+)"))
  T.check(tets and tets > 6000, "tetgen made tetrahedra: " .. tostring(tets))
  T.eq(tonumber(out:match("Mesh faces on facets: (%d+)")), 6000,
    "every surface triangle is a face of the volume mesh")
  local ele = T.readfile(path("cover.1.ele")) or ""
  T.eq(tonumber(ele:match("^%s*(%d+)")), tets, "cover.1.ele holds them")
end
-- }======

-- {====== CalculiX: a static S3 shell analysis on the exported mesh
if have("ccx") then
  T.writefile(path("job.inp"), [[
*HEADING
femlod cover, 6000 S3 shell elements, clamped at y = 0, pushed down at y = ymax
*INCLUDE, INPUT=cover.inp
*MATERIAL, NAME=STEEL
*ELASTIC
210000.0, 0.3
*SHELL SECTION, ELSET=EALL, MATERIAL=STEEL
0.5
*BOUNDARY
FIXED, 1, 6
*STEP
*STATIC
*CLOAD
LOADED, 3, -1.0
*NODE PRINT, NSET=LOADED
U
*NODE PRINT, NSET=FIXED
U
*END STEP
]])
  local code, out = sh("OMP_NUM_THREADS=1 ccx -i job")
  T.eq(code, 0, "ccx exits 0")
  T.check(out:find("Job finished", 1, true), "ccx ends with 'Job finished': " .. out:sub(-400))
  local dat = T.readfile(path("job.dat")) or ""
  local function block(set)
    local rows = {}
    local body = dat:match("displacements %(vx,vy,vz%) for set " .. set .. " and time[^\n]*\n\n(.-)\n\n")
      or dat:match("displacements %(vx,vy,vz%) for set " .. set .. " and time[^\n]*\n\n(.*)$") or ""
    for id, x, y, z in body:gmatch("(%d+)%s+(%S+)%s+(%S+)%s+(%S+)") do
      rows[#rows + 1] = { tonumber(id), tonumber(x), tonumber(y), tonumber(z) }
    end
    return rows
  end
  local loaded, fixed = block("LOADED"), block("FIXED")
  T.eq(#loaded, nloaded, "a displacement row for every loaded node")
  T.eq(#fixed, nfixed, "a displacement row for every fixed node")
  local down, zero = true, true
  for _, r in ipairs(loaded) do
    down = down and r[4] and r[4] < 0 and r[4] > -1e3 and r[2] == r[2] and r[3] == r[3]
  end
  -- The solver's round-off leaves ~1e-24 on a clamped node or two.
  for _, r in ipairs(fixed) do
    zero = zero and math.abs(r[2]) < 1e-12 and math.abs(r[3]) < 1e-12 and math.abs(r[4]) < 1e-12
  end
  T.check(#loaded > 0 and down, "every loaded node moves down by a finite amount")
  T.check(#fixed > 0 and zero, "the clamped nodes do not move")
end
-- }======

T.summary("fe_tools")
