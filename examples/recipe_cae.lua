-- recipe_cae.lua: the CAE recipe of the paper's section 5.3, exactly
-- "simplify to 12k, refine curvature, then globally rescale", on the hard
-- disk cover, printing a Table 1 row after each step.
--
--   femlod examples/recipe_cae.lua                   -- examples/data/cover.obj
--   femlod examples/recipe_cae.lua mesh=part.obj target=12000 [factor=0.5]
--
-- 1. simplify to `target` triangles with the paper's thresholds for the
--    cover (tolerance 0.15, stretch 0.2, size 15, valence 12);
-- 2. refine by curvature (h:refine_curvature{}): fine (input elements) where
--    kappa reaches its 95th percentile, unchanged where the part is flat;
-- 3. rescale globally back to `target` (or by `factor`, when given)
--    keeping the density that step 2 gave (h:rescale, the paper's "global"
--    row). The hierarchy goes on past the target to the coarsest mesh the
--    thresholds allow, so the rescale can coarsen the flat parts below the
--    simplification's density while the curved parts stay finer.
-- The last line counts the input vertices of highest curvature (kappa at or
-- above its 95th percentile) still in the mesh after steps 1 and 3.
local femlod = require "femlod"
local report = require "femlod.report"

local here = (arg and arg[0] or ""):match("^(.*)/") or "."
local P = params or {}
local path = P.mesh and tostring(P.mesh) or here .. "/data/cover.obj"
local target = math.tointeger(tonumber(P.target)) or 12000
local factor = tonumber(P.factor)
local name = path:match("[^/]*$")

local input <close> = femlod.load(path)
print(report.header())
print(report.row(input, name, "original"))

local h <close> = input:simplify {
  target = target, tolerance = 0.15, min_stretch = 0.2, max_size = 15, max_valence = 12,
}
local function deviation(m)
  return string.format("  (Hausdorff distance to the input %.4g)", m:quality(input).hausdorff)
end
print(report.row(h:mesh(), name, "simplified") .. deviation(h:mesh()))

-- the input vertices of highest curvature (kappa at or above its 95th
-- percentile) that are still vertices of the mesh: what step 3 should keep
local kappa, sorted = input:curvature().kappa, {}
for i = 1, #kappa do sorted[i] = kappa[i] end
table.sort(sorted)
local top = sorted[math.ceil(0.95 * #sorted)]
local function kept()
  local n = 0
  for _, id in ipairs(h:front()) do
    if id <= #kappa and kappa[id] >= top then n = n + 1 end
  end
  return n
end
local kept_simplified = kept()

h:refine_curvature {}
print(report.row(h:mesh(), name, "curvature") .. deviation(h:mesh()))

if factor then h:rescale { factor = factor } else h:rescale { target = target } end
print(report.row(h:mesh(), name, "global") .. deviation(h:mesh()))
print(string.format("high-curvature input vertices kept: simplified %d, global %d (%.2fx)",
  kept_simplified, kept(), kept() / math.max(kept_simplified, 1)))
