-- femlod.report: quality tables (mesh:quality()) as text.
--
--   local report = require "femlod.report"
--   print(report.text(mesh:quality(), "part.obj"))    -- multi-line report with histogram
--   print(report.header()); print(report.row(q, "part.obj", "original"))  -- a Table 1 row
--   print(report.fields(q))                            -- "key value" lines, sorted
--   print(report.stats(h:stats()))                     -- how a simplification went
--
-- Each function also takes a femlod.Mesh instead of its quality table
-- (report.stats a femlod.Hierarchy instead of its stats table).
-- Pure Lua over the table's fields: nothing here touches mesh data.

local type, error, pairs, ipairs, tostring, getmetatable = type, error, pairs, ipairs, tostring, getmetatable
local format, rep, concat, sort = string.format, string.rep, table.concat, table.sort
local floor, max = math.floor, math.max
local mtype = math.type

local _ENV = nil -- no global access after this point (LPeg's re.lua)

local M = {}

-- A quality table, or a Mesh whose quality is computed; blames the caller of
-- the public function (level 3: this function, the public one, its caller).
local function quality_of(q, fname)
  local mt = type(q) == "userdata" and getmetatable(q)
  local tname = type(mt) == "table" and mt.__name
  if tname == "femlod.Mesh" then return q:quality() end
  if type(q) ~= "table" or type(q.triangles) ~= "number" then
    error(format("bad argument #1 to '%s' (quality table or femlod.Mesh expected, got %s)",
      fname, type(q) == "table" and "table without quality fields" or tname or type(q)), 3)
  end
  return q
end

local function check_string(v, n, fname)
  if v ~= nil and type(v) ~= "string" then
    error(format("bad argument #%d to '%s' (string expected, got %s)", n, fname, type(v)), 3)
  end
end

-- Numbers in the report: enough digits to compare with published figures,
-- few enough to read. %g, so no locale-dependent thousands separators.
local function num(x)
  if mtype(x) == "integer" then return format("%d", x) end
  return format("%.6g", x)
end

local function point(p)
  return format("(%s, %s, %s)", num(p[1]), num(p[2]), num(p[3]))
end

local function plural(n, one, many)
  return format("%d %s", n, n == 1 and one or many or one .. "s")
end

-- The paper's Table 1 columns: model (dimensions), state, elements,
-- stretch (avg, min), size (max), valence (max).
function M.header()
  return "model (H x W x D) | state | elements | stretch (avg, min) | size (max) | valence (max)"
end

function M.row(q, name, state)
  q = quality_of(q, "row")
  check_string(name, 2, "row")
  check_string(state, 3, "row")
  local b = q.bbox
  local dims = format("%.4g x %.4g x %.4g", b.max[1] - b.min[1], b.max[2] - b.min[2],
    b.max[3] - b.min[3])
  return format("%s (%s) | %s | %d | %.3f, %.3f | %.4g | %d", name or "mesh", dims, state or "-",
    q.triangles, q.stretch_avg, q.stretch_min, q.size_max, q.valence_max)
end

local BAR = 40

-- The stretch histogram, one line per bin: bin k holds [k/10, (k+1)/10),
-- the last one is closed at 1.
local function histogram_lines(h, out)
  local total, most = 0, 0
  for _, n in ipairs(h) do total, most = total + n, max(most, n) end
  local nbins = #h
  for k, n in ipairs(h) do
    local lo, hi = (k - 1) / nbins, k / nbins
    local bar = most > 0 and rep("#", floor(n * BAR / most + 0.5)) or ""
    local pct = total > 0 and 100 * n / total or 0
    out[#out + 1] = format("    [%.1f, %.1f%s %8d %5.1f%%%s", lo, hi, k == nbins and "]" or ")",
      n, pct, bar ~= "" and "  " .. bar or "")
  end
end

function M.text(q, name)
  q = quality_of(q, "text")
  check_string(name, 2, "text")
  local out = {}
  local function line(label, fmt, ...)
    out[#out + 1] = format("  %-11s " .. fmt, label, ...)
  end
  out[1] = format("%s: %s, %s", name or "mesh", plural(q.triangles, "triangle"),
    plural(q.vertices, "vertex", "vertices"))
  line("stretch", "avg %s  min %s  max %s", num(q.stretch_avg), num(q.stretch_min),
    num(q.stretch_max))
  line("size", "avg %s  min %s  max %s (longest edge)", num(q.size_avg), num(q.size_min),
    num(q.size_max))
  line("valence", "avg %s  max %s", num(q.valence_avg), num(q.valence_max))
  line("angles", "min %s  max %s (degrees)", num(q.angle_min), num(q.angle_max))
  line("area", "%s", num(q.area))
  line("bbox", "%s - %s", point(q.bbox.min), point(q.bbox.max))
  line("topology", "%s, %s, %s; %s, %s", q.closed and "closed" or "open",
    q.manifold and "manifold" or "non-manifold", q.oriented and "oriented" or "not oriented",
    plural(q.components, "component"), plural(q.edges or 0, "edge"))
  line("edges", "%d boundary, %d non-manifold, %d inconsistent", q.boundary_edges,
    q.nonmanifold_edges, q.inconsistent_edges)
  line("triangles", "%d degenerate, %d duplicate", q.degenerate, q.duplicate)
  line("vertices", "%d non-manifold, %d isolated", q.nonmanifold_vertices,
    q.isolated_vertices or 0)
  if q.hausdorff then
    line("hausdorff", "%s (%s of the reference's diagonal; forward %s, backward %s)",
      num(q.hausdorff), num(q.hausdorff_rel), num(q.hausdorff_forward), num(q.hausdorff_backward))
  end
  out[#out + 1] = "  stretch histogram:"
  histogram_lines(q.histogram, out)
  return concat(out, "\n")
end

-- Every scalar field as "key value", sorted by key (pairs order is not
-- repeatable), bbox and histogram flattened: for scripts and diffs.
function M.fields(q)
  q = quality_of(q, "fields")
  local flat = {}
  for k, v in pairs(q) do
    if type(v) ~= "table" then flat[k] = v end
  end
  flat.bbox_min = point(q.bbox.min)
  flat.bbox_max = point(q.bbox.max)
  local hist = {}
  for i, n in ipairs(q.histogram) do hist[i] = format("%d", n) end
  flat.histogram = concat(hist, " ")
  local keys = {}
  for k in pairs(flat) do keys[#keys + 1] = k end
  sort(keys)
  local out = {}
  for i, k in ipairs(keys) do
    local v = flat[k]
    out[i] = format("%s %s", k, type(v) == "number" and num(v) or tostring(v))
  end
  return concat(out, "\n")
end

-- {====== simplification statistics (h:stats())

local REJECTED = { "tolerance", "deviation", "stretch", "size", "valence", "foldover", "topology",
  "intersection" }
local THRESHOLDS = { "target", "tolerance", "max_deviation", "min_stretch", "max_size", "max_valence",
  "feature_angle", "feature_weight", "max_normal_change" }

local function stats_of(s, fname)
  local mt = type(s) == "userdata" and getmetatable(s)
  local tname = type(mt) == "table" and mt.__name
  if tname == "femlod.Hierarchy" then return s:stats() end
  if type(s) ~= "table" or type(s.stop_reason) ~= "string" or type(s.rejected) ~= "table"
      or type(s.thresholds) ~= "table" then
    error(format("bad argument #1 to '%s' (stats table or femlod.Hierarchy expected, got %s)",
      fname, type(s) == "table" and "table without stats fields" or tname or type(s)), 3)
  end
  return s
end

-- Four lines: why and after how much work it stopped, which checks refused
-- collapses (counts of edge evaluations), the input triangles left breaking
-- a threshold, and the thresholds in force ("off" when switched off, target
-- "none" when there was none).
function M.stats(s)
  s = stats_of(s, "stats")
  local rej, th = {}, {}
  for i, k in ipairs(REJECTED) do rej[i] = format("%s %d", k, s.rejected[k] or 0) end
  for i, k in ipairs(THRESHOLDS) do
    local v = s.thresholds[k]
    local off = k == "target" and "none" or "off"
    th[i] = format("%s %s", k, v == false and off or type(v) == "number" and num(v) or "?")
  end
  return concat({
    format("stop: %s; %s (%d in the pre-phase) in %.3f s", s.stop_reason,
      plural(s.collapses, "collapse"), s.prephase_collapses, s.seconds),
    "rejected: " .. concat(rej, ", "),
    format("violating input: %s; dropped degenerate: %d", plural(s.violating_input, "triangle"),
      s.dropped_degenerate),
    "thresholds: " .. concat(th, ", "),
  }, "\n")
end

-- }======

return M
