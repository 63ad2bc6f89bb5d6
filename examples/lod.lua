-- lod.lua: one simplification, then local level of detail from its vertex
-- hierarchy: the mesh made fine again near a sharp corner, in milliseconds,
-- without simplifying again.
--
--   femlod examples/lod.lua                      -- writes fandisk.flh and fandisk_lod.obj here
--   femlod examples/lod.lua out=/tmp radius=0.3 size=0.02
--
-- size is the threshold inside the sphere (a length, 0: as fine as the
-- input); outside, the mesh stays as the simplification left it.
local femlod = require "femlod"
local report = require "femlod.report"

local here = (arg and arg[0] or ""):match("^(.*)/") or "."
local P = params or {}
local out = P.out and tostring(P.out) or "."
local radius = tonumber(P.radius) or 0.2
local fine = tonumber(P.size) or 0

-- The expensive pass, once: simplify to 2,000 triangles and keep its
-- hierarchy in a file.
local input <close> = femlod.load(here .. "/data/fandisk.obj")
do
  local h <close> = input:simplify { target = 2000 }
  h:save(out .. "/fandisk.flh")
end

-- Any time later (another run, a parameter sweep): load the hierarchy. Its
-- front is where it was saved: the simplification's result.
local h <close> = femlod.load_hierarchy(out .. "/fandisk.flh")
local simplified <close> = h:mesh()

-- Fine inside a sphere around a sharp corner of the part, unchanged outside:
-- a front node is split while its e_size exceeds the size returned here.
local corner = { 0.4603, 0.25555, -0.5 }
local splits = h:refine(function(x, y, z)
  local d = math.sqrt((x - corner[1]) ^ 2 + (y - corner[2]) ^ 2 + (z - corner[3]) ^ 2)
  return d < radius and fine or math.huge
end)
local refined <close> = h:mesh()
refined:save(out .. "/fandisk_lod.obj")

print(report.header())
print(report.row(input, "fandisk.obj", "original"))
print(report.row(simplified, "fandisk.obj", "simplified"))
print(report.row(refined, "fandisk.obj", "refined near a corner"))
local c = h:counts()
print(string.format("%d splits; the front: %d vertices, %d triangles; the hierarchy: %d nodes",
  splits, c.vertices, c.triangles, c.nodes))
