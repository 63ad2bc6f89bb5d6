-- region.lua: region LOD (paper 5.3.1b) on the hard disk cover: simplify to
-- 6,000 triangles (the paper's "simplified 2"), then make the mesh fine
-- around the spindle hole only, with sizes growing smoothly away from it,
-- and print a Table 1 row after each step.
--
--   femlod examples/region.lua                        -- examples/data/cover.obj
--   femlod examples/region.lua size=0.5 grading=1.3 out=/tmp/cover_region.obj
--
-- The spindle hole of cover.obj is a through hole of radius 8 mm on the
-- axis x = 50.6, y = 90 (examples/data/geo/cover.geo), inside a raised ring
-- of radius 12 mm. The region is "within 3 mm of the hole's wall", given as
-- a function of position; `size` is the element size there (a length, 0:
-- the input's elements) and `grading` the factor by which sizes may grow
-- from one element to the next away from it (false: a sharp border).
local femlod = require "femlod"
local report = require "femlod.report"

local here = (arg and arg[0] or ""):match("^(.*)/") or "."
local P = params or {}
local size = tonumber(P.size) or 0.6
local grading = 1.5
if P.grading == false or P.grading == "false" then grading = false
elseif P.grading ~= nil then grading = assert(tonumber(P.grading), "grading: a number or false") end

local input <close> = femlod.load(here .. "/data/cover.obj")
print(report.header())
print(report.row(input, "cover.obj", "original"))

local h <close> = input:simplify {
  target = 6000, tolerance = 0.15, min_stretch = 0.2, max_size = 15, max_valence = 12,
}
print(report.row(h:mesh(), "cover.obj", "simplified"))

local cx, cy, hole = 50.6, 90.0, 8.0
local splits, inside = h:refine_region {
  where = function(x, y, z)
    local r = math.sqrt((x - cx) ^ 2 + (y - cy) ^ 2)
    return r <= hole + 3.0
  end,
  size = size, grading = grading,
}
local refined <close> = h:mesh()
print(report.row(refined, "cover.obj", "region"))
io.stderr:write(string.format("region: %d splits, %d nodes inside\n", splits, inside))
if P.out then refined:save(tostring(P.out)) end
