-- sweep.lua: one point of a parameter sweep over the element count and the
-- minimum stretch of the simplification, on the fandisk CAD part.
--
--   femlod sweep examples/sweep.lua --grid target=1500,3000,6000 --grid min_stretch=0.3,0.5 --out /tmp/fandisk-sweep
--   femlod run examples/sweep.lua target=3000 min_stretch=0.5 out_dir=/tmp   -- one point by hand
--   femlod run examples/sweep.lua          -- target 3000, min_stretch 0.2, writes mesh.obj here
--
-- Each point loads the mesh, simplifies it with the point's target (default
-- 3000 triangles) and minimum stretch (default 0.2; tolerance=X sets the
-- geometric tolerance, default the library's; size 15 and valence 12 as in
-- the paper), saves the result in its own folder (params.out_dir, default
-- the current folder) and records how the simplification stopped.
-- `femlod sweep` logs the files read and written with their SHA-256 and the
-- saved mesh's Table 1 figures and deviation from the input.
local femlod = require "femlod"
local sweep = require "femlod.sweep"
local report = require "femlod.report"

local here = (arg and arg[0] or ""):match("^(.*)/") or "."
local P = params or {}
local path = P.mesh and tostring(P.mesh) or here .. "/data/fandisk.obj"
local target = 3000
if P.target ~= nil then
  target = math.tointeger(P.target) or error("target: integer expected, got " .. tostring(P.target))
end
local min_stretch = tonumber(P.min_stretch) or 0.2
local tolerance = tonumber(P.tolerance) -- nil: the library's default
local out_dir = P.out_dir or "."

local input <close> = femlod.load(path)
local h <close> = input:simplify {
  target = target, tolerance = tolerance, min_stretch = min_stretch, max_size = 15, max_valence = 12,
}
local result <close> = h:mesh()
result:save(out_dir .. "/mesh.obj")

local s = h:stats()
sweep.record { collapses = s.collapses, stop = s.stop_reason }
print(report.row(result, path:match("[^/]*$"), string.format("target %d, stretch >= %g", target, min_stretch)))
