-- test_simplify.lua: femlod.simplify / mesh:simplify and the femlod.Hierarchy
-- type: every output triangle meets the thresholds in force (measured here,
-- per triangle, from the output's own positions), topology is kept, the
-- stats table, `false` switching thresholds off, option errors (text and
-- position), lock by indices and by function, keep_boundary, progress,
-- determinism, the life cycle (close, <close>, __gc), and hierarchy = false
-- (the same mesh and stats without a log or hierarchy; the LOD methods raise).
-- Run by ctest: femlod run test_simplify.lua femlod=... tmp=... data=... shared=... examples=...

local T = dofile((arg[0]:match("^(.*)/") or ".") .. "/check.lua")
local femlod = require "femlod"
local report = require "femlod.report"

local P = params
assert(P and P.shared and P.tmp, "run through ctest: needs shared= and tmp= parameters")

local sqrt, max, min = math.sqrt, math.max, math.min

-- {====== measures, computed here from positions and triangles (not by the core)

local function sub(a, b) return a[1] - b[1], a[2] - b[2], a[3] - b[3] end
local function len(x, y, z) return sqrt(x * x + y * y + z * z) end

-- Stretch (sqrt(12) * inradius / longest edge) and size (longest edge).
local function stretch_size(a, b, c)
  local ux, uy, uz = sub(b, a)
  local vx, vy, vz = sub(c, a)
  local la, lb, lc = len(sub(c, b)), len(ux, uy, uz), len(vx, vy, vz)
  local area2 = len(uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx) -- twice the area
  local longest = max(la, lb, lc)
  local inradius = area2 / (la + lb + lc)
  return sqrt(12) * inradius / longest, longest
end

-- Per-triangle and per-vertex facts of a mesh.
local function measure(mesh)
  local pos, tri = mesh:positions(), mesh:triangles()
  local m = { triangles = #tri, vertices = #pos, stretch_min = math.huge, size_max = 0, valence_max = 0 }
  local nbr = {}
  for _, t in ipairs(tri) do
    local s, z = stretch_size(pos[t[1]], pos[t[2]], pos[t[3]])
    m.stretch_min, m.size_max = min(m.stretch_min, s), max(m.size_max, z)
    for k = 1, 3 do
      local a, b = t[k], t[k % 3 + 1]
      nbr[a] = nbr[a] or {}; nbr[b] = nbr[b] or {}
      nbr[a][b], nbr[b][a] = true, true
    end
  end
  for _, set in pairs(nbr) do
    local n = 0
    for _ in pairs(set) do n = n + 1 end
    m.valence_max = max(m.valence_max, n)
  end
  m.pos, m.tri = pos, tri
  return m
end

-- Output triangles breaking min_stretch or max_size (false: off).
local function violations(m, th)
  local bad = 0
  for _, t in ipairs(m.tri) do
    local s, z = stretch_size(m.pos[t[1]], m.pos[t[2]], m.pos[t[3]])
    if (th.min_stretch and s < th.min_stretch) or (th.max_size and z > th.max_size) then bad = bad + 1 end
  end
  return bad
end

local function key(p) return string.format("%.17g %.17g %.17g", p[1], p[2], p[3]) end
local function position_set(mesh)
  local set = {}
  for _, p in ipairs(mesh:positions()) do set[key(p)] = true end
  return set
end

-- The arrays as one string, for exact comparisons.
local function serial(mesh)
  local out = {}
  for _, p in ipairs(mesh:positions()) do out[#out + 1] = key(p) end
  for _, t in ipairs(mesh:triangles()) do out[#out + 1] = table.concat(t, " ") end
  return table.concat(out, "\n")
end

-- }======

local fandisk = femlod.load(P.shared .. "/fandisk.obj")
local IN = fandisk:quality()
T.eq(IN.triangles, 12946, "fandisk input triangles")
T.check(IN.closed and IN.manifold and IN.oriented, "fandisk input closed, manifold, oriented")

-- {====== module basics
T.eq(type(femlod.simplify), "function", "femlod.simplify")
T.eq(fandisk.simplify, femlod.simplify, "mesh:simplify is femlod.simplify")
-- }======

-- {====== thresholds hold on every output triangle and vertex
-- Checks h against the thresholds it reports in force; returns the stats
-- and the measures of its mesh.
local function check_run(label, h, input_triangles)
  local s = h:stats()
  local th = s.thresholds
  local out = h:mesh()
  local m, q = measure(out), out:quality()
  T.eq(s.triangles, m.triangles, label .. ": stats.triangles is the mesh's")
  T.eq(s.vertices, m.vertices, label .. ": stats.vertices is the mesh's")
  T.check(m.triangles < input_triangles, label .. ": simplified at all")
  -- The measure here agrees with the core's quality report ...
  T.near(m.stretch_min, q.stretch_min, 1e-9, label .. ": stretch_min (here vs quality())")
  T.near(m.size_max, q.size_max, 1e-12, label .. ": size_max (here vs quality())")
  T.eq(m.valence_max, q.valence_max, label .. ": valence_max (here vs quality())")
  -- ... and every triangle meets the thresholds, but the input ones the
  -- simplification reports it could not remove.
  T.eq(violations(m, th), s.violating_input, label .. ": triangles breaking min_stretch/max_size")
  if th.max_valence then
    T.check(m.valence_max <= th.max_valence,
      string.format("%s: valence %d <= max_valence %d", label, m.valence_max, th.max_valence))
  end
  T.check(q.closed and q.manifold and q.oriented, label .. ": closed, manifold and oriented kept")
  T.eq(q.components, 1, label .. ": one component")
  T.eq(q.degenerate, 0, label .. ": no degenerate triangle")
  T.eq(q.duplicate, 0, label .. ": no duplicate triangle")
  -- On a closed manifold mesh every collapse removes two triangles.
  -- (from the improve stage's mesh when it ran first)
  if s.improved then input_triangles = s.improve_triangles end
  T.eq(input_triangles - 2 * s.collapses, s.triangles, label .. ": two triangles per collapse")
  return s, m, q
end

local A -- the default run, reused below
do
  local h = fandisk:simplify { target = 3000 }
  A = h
  local s, m = check_run("defaults", h, 12946)
  T.eq(s.stop_reason, "target", "defaults: target 3000 reached")
  T.eq(s.triangles, 3000, "defaults: 3000 triangles")
  T.eq(s.violating_input, 0, "defaults: fandisk meets the default thresholds")
  T.check(m.stretch_min >= s.thresholds.min_stretch, "defaults: stretch_min >= default min_stretch")
  T.eq(s.thresholds.min_stretch, 0.2, "default min_stretch")
  T.eq(s.thresholds.max_valence, 12, "default max_valence")
  T.eq(s.thresholds.max_deviation, false, "max_deviation is off by default")
  T.eq(s.thresholds.target, 3000, "thresholds.target")
  print(report.header())
  print(report.row(fandisk, "fandisk.obj", "original"))
  print(report.row(h:mesh(), "fandisk.obj", "simplified"))
  print(report.stats(h))
end

do
  -- Stricter than some input triangles (two have stretch below 0.4): the
  -- pre-phase removes them or violating_input counts them.
  local h = fandisk:simplify { target = 2000, min_stretch = 0.4, max_size = 0.1, max_valence = 8 }
  local s, m = check_run("strict", h, 12946)
  T.eq(s.thresholds.min_stretch, 0.4, "strict: min_stretch in force")
  T.eq(s.thresholds.max_size, 0.1, "strict: max_size in force")
  T.eq(s.thresholds.max_valence, 8, "strict: max_valence in force")
  T.check(m.size_max <= 0.1, "strict: size_max <= 0.1")
  T.check(s.improved and s.improve_operations > 0, "strict: the improve stage ran on the input's thin triangles")
  T.check(s.stop_reason == "target" or s.stop_reason == "no_valid_edge", "strict: stop reason")
end

do
  -- max_size below what a reduction to a quarter needs is binding: the run
  -- stops where no edge is left rather than break it.
  local h = fandisk:simplify { ratio = 0.25, min_stretch = 0.3, max_size = 0.06, max_valence = 10,
    feature_angle = 30 }
  local s, m = check_run("ratio", h, 12946)
  T.eq(s.thresholds.target, 3237, "ratio 0.25 of 12946 rounds to 3237")
  T.check(m.size_max <= 0.06, "ratio: size_max <= 0.06")
  T.check(s.triangles <= 3237 or s.stop_reason == "no_valid_edge", "ratio: target or a reason")
  T.eq(s.thresholds.feature_angle, 30, "ratio: feature_angle in force")
end

do
  -- An unreachable target: stops with no valid edge, never breaking a threshold.
  local h = fandisk:simplify { target = 10 }
  local s = check_run("unreachable", h, 12946)
  T.eq(s.stop_reason, "no_valid_edge", "unreachable target: no_valid_edge")
  T.check(s.triangles > 10, "unreachable target: not reached")
end
-- }======

-- {====== the stats table
do
  local s = A:stats()
  local ints = { "triangles", "vertices", "collapses", "prephase_collapses", "fast_collapses", "violating_input",
    "dropped_degenerate" }
  for _, k in ipairs(ints) do T.eq(math.type(s[k]), "integer", "stats." .. k .. " is an integer") end
  T.eq(math.type(s.seconds), "float", "stats.seconds is a float")
  T.check(s.seconds >= 0 and s.seconds < 60, "stats.seconds is a duration: " .. tostring(s.seconds))
  T.eq(type(s.stop_reason), "string", "stats.stop_reason")
  local names = { "tolerance", "deviation", "stretch", "size", "valence", "foldover", "topology",
    "intersection" }
  local n, sum = 0, 0
  for k, v in pairs(s.rejected) do
    n = n + 1
    T.eq(math.type(v), "integer", "rejected." .. tostring(k) .. " is an integer")
    sum = sum + v
  end
  T.eq(n, #names, "rejected has 8 keys")
  for _, k in ipairs(names) do T.check(s.rejected[k] ~= nil, "rejected." .. k) end
  T.check(sum > 0, "some evaluations were refused")
  local tkeys = { "target", "tolerance", "max_deviation", "min_stretch", "max_size", "max_valence",
    "feature_angle", "feature_weight", "max_normal_change" }
  n = 0
  for _ in pairs(s.thresholds) do n = n + 1 end
  T.eq(n, #tkeys, "thresholds has 9 keys")
  for _, k in ipairs(tkeys) do
    local v = s.thresholds[k]
    T.check(v == false or (type(v) == "number" and v > 0), "thresholds." .. k .. ": false or > 0")
  end
  T.eq(math.type(s.thresholds.target), "integer", "thresholds.target is an integer")
  T.eq(math.type(s.thresholds.max_valence), "integer", "thresholds.max_valence is an integer")
  -- The default size bound is 0.1 x the bounding-box diagonal (include/femlod.h).
  T.near(s.thresholds.max_size, 0.1 * sqrt(0.9206 ^ 2 + 0.5111 ^ 2 + 1), 1e-4, "default max_size")

  T.check(A:collapses() >= s.collapses, "h:collapses(): those to the target and those past it")
  T.eq(A:input_vertices(), 6475, "h:input_vertices()")
  T.eq(math.type(A:log_bytes()), "integer", "h:log_bytes() is an integer")
  T.check(A:log_bytes() > 16 * s.collapses, "the log holds every collapse: " .. A:log_bytes())
  T.eq(tostring(A), string.format("femlod.Hierarchy (%d nodes, 3000 triangles on the front)", 6475 + A:collapses()),
    "tostring")
  T.eq(getmetatable(A).__name, "femlod.Hierarchy", "metatable name")
  -- Each call gives a new table and a new mesh.
  T.check(A:stats() ~= A:stats(), "stats() makes a new table")
  local m1, m2 = A:mesh(), A:mesh()
  T.check(m1 ~= m2, "mesh() makes a new Mesh")
  m1:close()
  T.eq(m2:counts().triangles, 3000, "meshes from h:mesh() are independent")
  -- report.stats prints it.
  local text = report.stats(s)
  T.check(text:find("^stop: target; " .. s.collapses .. " collapses %(0 in the pre%-phase, %d+ in fast passes on %d threads?%) in [%d.]+ s\n"),
    "report.stats first line: " .. text)
  T.check(text:find("\nrejected: tolerance %d+, deviation 0, stretch %d+, size %d+, valence %d+, foldover %d+, "
    .. "topology %d+, intersection %d+\n"), "report.stats rejected line")
  T.check(text:find("\nthresholds: target 3000, tolerance [%d.e+-]+, max_deviation off, min_stretch 0.2, "), "report.stats thresholds")
  T.eq(report.stats(A), text:gsub("in [%d.]+ s", "in " .. string.format("%.3f", s.seconds) .. " s"),
    "report.stats takes the Hierarchy")
end
-- }======

-- {====== false switches a threshold off; numbers given are the numbers in force
do
  -- (the paper's order: the error order's cap refuses as "tolerance" even
  -- with the tolerance off, docs/simplify.md "The error order")
  local h = fandisk:simplify { target = 3000, tolerance = false, max_valence = false,
    max_normal_change = false, feature_weight = false, max_deviation = 0.002, min_stretch = 0.25,
    error_order = false }
  local s = check_run("false", h, 12946)
  local th = s.thresholds
  T.eq(th.tolerance, false, "tolerance = false is off")
  T.eq(th.max_valence, false, "max_valence = false is off")
  T.eq(th.max_normal_change, false, "max_normal_change = false is off")
  T.eq(th.feature_weight, false, "feature_weight = false is off")
  T.eq(th.max_deviation, 0.002, "max_deviation as given")
  T.eq(th.min_stretch, 0.25, "min_stretch as given")
  T.eq(s.rejected.tolerance, 0, "no refusal by an off tolerance")
  T.eq(s.rejected.valence, 0, "no refusal by an off valence bound")
  T.check(A:stats().rejected.tolerance > 0, "the default tolerance does refuse (so the check above means something)")
  local h2 = fandisk:simplify { target = 3000, min_stretch = false, max_size = false, feature_angle = false }
  th = h2:stats().thresholds
  T.eq(th.min_stretch, false, "min_stretch = false is off")
  T.eq(th.max_size, false, "max_size = false is off")
  T.eq(th.feature_angle, false, "feature_angle = false is off")
  -- Off, only degenerate (zero-area) triangles are still refused as stretch.
  T.check(h2:stats().rejected.stretch * 10 < A:stats().rejected.stretch,
    string.format("an off min_stretch refuses far less: %d vs %d", h2:stats().rejected.stretch,
      A:stats().rejected.stretch))
  T.eq(h2:stats().violating_input, 0, "nothing violates an off threshold")
  local none = fandisk:simplify {}
  T.eq(none:stats().thresholds.target, false, "no target: thresholds.target is false")
  T.check(report.stats(none):find("\nthresholds: target none, tolerance "), "report.stats: target none")
  T.check(report.stats(h):find(", max_valence off, feature_angle 40, feature_weight off, max_normal_change off$"),
    "report.stats: off thresholds: " .. report.stats(h))
end
-- }======

-- {====== the error order, the default: far closer to the input at the same count
do
  local paper = fandisk:simplify { target = 2000, error_order = false }:mesh()
  local eo = fandisk:simplify { target = 2000 }:mesh()
  local qp, qe = paper:quality(fandisk), eo:quality(fandisk)
  T.eq(qe.triangles, 2000, "the default (error order) reaches the target")
  -- measured 0.00177 against 0.0110; stretch 0.659 against 0.805
  T.check(qe.hausdorff * 3 <= qp.hausdorff, "error order: hausdorff " .. qe.hausdorff .. " vs " .. qp.hausdorff)
  T.check(qe.stretch_min >= 0.2 and qe.valence_max <= 12, "the error order keeps the thresholds")
  T.eq(serial(fandisk:simplify { target = 2000, error_order = true }:mesh()), serial(eo), "error_order = true: the default")
  T.check(serial(paper) ~= serial(eo), "error_order = false: another order")
end
-- }======

-- {====== fast passes: the same guarantees, fewer exact collapses
do
  local exact = fandisk:simplify { target = 2000, fast_above = false }
  local fast = fandisk:simplify { target = 2000, fast_above = 2 }
  local fast2 = fandisk:simplify { target = 2000, fast_above = true }
  local s, e = fast:stats(), exact:stats()
  T.eq(e.fast_collapses, 0, "fast_above = false: the exact order")
  T.check(fandisk:simplify { target = 2000 }:stats().fast_collapses > 0, "fast passes by default (the error order)")
  T.eq(fandisk:simplify { target = 2000, error_order = false }:stats().fast_collapses, 0,
    "the paper's order: exact by default")
  T.check(s.fast_collapses > 0 and s.fast_collapses < s.collapses,
    "fast_above = 2: " .. s.fast_collapses .. " of " .. s.collapses .. " collapses in passes")
  T.eq(fast2:stats().fast_collapses, s.fast_collapses, "fast_above = true is 2")
  local q, qe = fast:mesh():quality(), exact:mesh():quality()
  T.check(q.stretch_min >= 0.2 and q.valence_max <= 12, "fast passes keep the thresholds")
  T.check(q.stretch_avg >= qe.stretch_avg - 0.05, "fast quality near exact: " .. q.stretch_avg .. " vs " .. qe.stretch_avg)
  T.check(report.stats(fast):find("in fast passes on %d+ threads?%)"), "report.stats tells the fast passes")
  -- threads: the same mesh, log and counts for any number
  local one, three = fandisk:simplify { target = 2000, fast_above = 2, threads = 1 },
    fandisk:simplify { target = 2000, fast_above = 2, threads = 3 }
  T.eq(one:stats().threads, 1, "threads = 1 in the stats")
  T.eq(three:stats().threads, 3, "threads = 3 in the stats")
  T.eq(serial(one:mesh()), serial(fast:mesh()), "threads = 1 and the default: the same mesh")
  T.eq(serial(three:mesh()), serial(fast:mesh()), "threads = 3 and the default: the same mesh")
  for k, v in pairs(s.rejected) do T.eq(three:stats().rejected[k], v, "threads = 3: the same rejected." .. k) end
  T.check(not report.stats(exact):find("fast passes"), "and says nothing without them")
end
-- }======

-- {====== option errors: text and position
local env = { m = fandisk, femlod = femlod }
local E = "code:1: bad argument #1 to 'simplify' ("
T.errmsg(E .. "unknown key 'targt'; valid keys: area_weighted, error_order, fast_above, feature_angle, feature_weight, hierarchy, hierarchy_floor, improve, "
  .. "keep_boundary, lock, max_deviation, max_normal_change, max_size, max_valence, min_stretch, "
  .. "progress, ratio, target, threads, tolerance)", "m:simplify { targt = 100 }", env)
T.errmsg(E .. "unexpected number key 1; valid keys: area_weighted, error_order, fast_above, feature_angle, feature_weight, hierarchy, hierarchy_floor, improve, "
  .. "keep_boundary, lock, max_deviation, max_normal_change, max_size, max_valence, min_stretch, "
  .. "progress, ratio, target, threads, tolerance)", "m:simplify { 100 }", env)
T.errmsg(E .. "target: integer >= 1 expected, got 0)", "m:simplify { target = 0 }", env)
T.errmsg(E .. "target: integer >= 1 expected, got 2.5)", "m:simplify { target = 2.5 }", env)
T.errmsg(E .. "target: integer >= 1 expected, got string)", "m:simplify { target = '100' }", env)
T.errmsg(E .. "ratio: number in (0, 1] expected, got 2)", "m:simplify { ratio = 2 }", env)
T.errmsg(E .. "ratio: number in (0, 1] expected, got 0.0)", "m:simplify { ratio = 0.0 }", env)
T.errmsg(E .. "give target or ratio, not both)", "m:simplify { target = 100, ratio = 0.5 }", env)
T.errmsg(E .. "min_stretch: number in (0, 1] or false expected, got -1)", "m:simplify { min_stretch = -1 }", env)
T.errmsg(E .. "min_stretch: number in (0, 1] or false expected, got 0)", "m:simplify { min_stretch = 0 }", env)
T.errmsg(E .. "min_stretch: number in (0, 1] or false expected, got 1.5)", "m:simplify { min_stretch = 1.5 }", env)
T.errmsg(E .. "min_stretch: number in (0, 1] or false expected, got true)", "m:simplify { min_stretch = true }", env)
T.errmsg(E .. "tolerance: number > 0 or false expected, got -0.5)", "m:simplify { tolerance = -0.5 }", env)
T.errmsg(E .. "max_size: number > 0 or false expected, got inf)", "m:simplify { max_size = math.huge }", env)
T.checkerr("^code:1: bad argument #1 to 'simplify' %(max_deviation: number > 0 or false expected, got %-?nan%)$",
  load("m:simplify { max_deviation = 0/0 }", "=code", "t", env))
T.errmsg(E .. "feature_angle: number in (0, 180] or false expected, got 181)", "m:simplify { feature_angle = 181 }", env)
T.errmsg(E .. "max_normal_change: number in (0, 180] or false expected, got string)",
  "m:simplify { max_normal_change = '30' }", env)
T.errmsg(E .. "feature_weight: number > 0 or false expected, got 0)", "m:simplify { feature_weight = 0 }", env)
T.errmsg(E .. "max_valence: integer >= 3 or false expected, got 2)", "m:simplify { max_valence = 2 }", env)
T.errmsg(E .. "max_valence: integer >= 3 or false expected, got 7.5)", "m:simplify { max_valence = 7.5 }", env)
T.errmsg(E .. "keep_boundary: boolean expected, got 1)", "m:simplify { keep_boundary = 1 }", env)
T.errmsg(E .. "area_weighted: boolean expected, got string)", "m:simplify { area_weighted = 'yes' }", env)
T.errmsg(E .. "error_order: boolean expected, got 1)", "m:simplify { error_order = 1 }", env)
T.errmsg(E .. "fast_above: number >= 1 or boolean expected, got 0.5)", "m:simplify { fast_above = 0.5 }", env)
T.errmsg(E .. "fast_above: number >= 1 or boolean expected, got string)", "m:simplify { fast_above = '2' }", env)
T.errmsg(E .. "threads: integer >= 0 expected, got -1)", "m:simplify { threads = -1 }", env)
T.errmsg(E .. "threads: integer >= 0 expected, got 1.5)", "m:simplify { threads = 1.5 }", env)
T.errmsg(E .. "threads: integer >= 0 expected, got string)", "m:simplify { threads = 'all' }", env)
T.errmsg(E .. "lock[2]: index 6476 out of range (1..6475))", "m:simplify { lock = { 1, 6476 } }", env)
T.errmsg(E .. "lock[1]: index 0 out of range (1..6475))", "m:simplify { lock = { 0 } }", env)
T.errmsg(E .. "lock[2]: index 1.5 is not a valid index)", "m:simplify { lock = { 1, 1.5 } }", env)
T.errmsg(E .. "lock[1]: number expected, got string)", "m:simplify { lock = { 'x' } }", env)
T.errmsg(E .. "lock: list of vertex indices expected, found key 5)", "m:simplify { lock = { [5] = true } }", env)
T.errmsg(E .. "lock: list of vertex indices expected, found key name)", "m:simplify { lock = { 1, name = 2 } }", env)
T.errmsg(E .. "lock: table or function expected, got number)", "m:simplify { lock = 5 }", env)
T.errmsg(E .. "lock: function returned number for vertex 1 (boolean or nil expected))",
  "m:simplify { lock = function() return 1 end }", env)
T.errmsg(E .. "progress: function expected, got boolean)", "m:simplify { progress = true }", env)
-- The function form names argument #2; both forms are one function.
T.errmsg("code:1: bad argument #2 to 'simplify' (target: integer >= 1 expected, got 0)",
  "femlod.simplify(m, { target = 0 })", env)
T.errmsg("code:1: bad argument #2 to 'simplify' (table expected, got number)", "femlod.simplify(m, 5)", env)
T.errmsg("code:1: bad argument #1 to 'simplify' (femlod.Mesh expected, got nil)", "femlod.simplify(nil)", env)
T.errmsg("code:1: bad argument #1 to 'simplify' (femlod.Mesh expected, got femlod.Hierarchy)",
  "femlod.simplify(h)", { femlod = femlod, h = A })
T.errmsg("code:1: bad argument #1 to 'stats' (stats table or femlod.Hierarchy expected, got number)",
  "local s = report.stats(5)", { report = report })
T.errmsg("code:1: bad argument #1 to 'stats' (stats table or femlod.Hierarchy expected, got table without stats fields)",
  "local s = report.stats({})", { report = report })
T.errmsg("code:1: bad argument #1 to 'stats' (stats table or femlod.Hierarchy expected, got femlod.Mesh)",
  "local s = report.stats(m)", { report = report, m = fandisk })
-- A raising lock function: its own error, at its own line, comes through.
T.errmsg("code:2: no lock for vertex 1", "local f = function(x, y, z, i)\n  error('no lock for vertex ' .. i)\nend\n"
  .. "return m:simplify { lock = f }", env)
do
  local line, msg = T.line(), select(2, pcall(function() return fandisk:simplify { lock = function() error("lk") end } end))
  T.check(type(msg) == "string" and msg:find("test_simplify%.lua:" .. line .. ": lk$"),
    "lock function error keeps its position: " .. tostring(msg))
  -- Errors that are not strings come through unchanged.
  local tag = {}
  local ok, e = pcall(fandisk.simplify, fandisk, { lock = function() error(tag) end })
  T.check(not ok and e == tag, "a lock function's error value comes through unchanged")
  ok, e = pcall(fandisk.simplify, fandisk, { target = 3000, progress = function() error(tag) end })
  T.check(not ok and e == tag, "a progress function's error value comes through unchanged")
end
-- A lock function that closes the mesh: the next vertex finds it closed.
do
  local c = fandisk:copy()
  T.errmsg("code:1: attempt to use a closed femlod.Mesh",
    "c:simplify { lock = function() c:close() end }", { c = c })
  T.eq(tostring(c), "femlod.Mesh (closed)", "the lock function closed it")
  T.errmsg("code:1: attempt to use a closed femlod.Mesh", "c:simplify()", { c = c })
end
-- }======

-- {====== lock: the locked vertices keep their exact positions
do
  local pos = fandisk:positions()
  local Aset = position_set(A:mesh())
  -- by indices: every 37th vertex
  local list, lost = {}, 0
  for i = 1, #pos, 37 do
    list[#list + 1] = i
    if not Aset[key(pos[i])] then lost = lost + 1 end
  end
  T.check(lost > #list / 2, "without lock most of these vertices move or go: " .. lost .. " of " .. #list)
  local h = fandisk:simplify { target = 3000, lock = list }
  local s = check_run("lock list", h, 12946)
  local set = position_set(h:mesh())
  local kept = 0
  for _, i in ipairs(list) do if set[key(pos[i])] then kept = kept + 1 end end
  T.eq(kept, #list, "lock list: every locked vertex keeps its exact position")
  T.check(s.triangles <= 3200, "lock list: still simplified to about the target: " .. s.triangles)
  -- Duplicates and an empty list are fine.
  T.check(pcall(fandisk.simplify, fandisk, { target = 6000, lock = { 5, 5, 5 } }), "duplicate lock indices")
  T.eq(serial(fandisk:simplify { target = 3000, lock = {} }:mesh()), serial(A:mesh()), "an empty lock list locks nothing")

  -- by function: every vertex above z = 0.3, called once per vertex in order
  local calls, in_order, want = 0, true, {}
  local h2 = fandisk:simplify { target = 3000, lock = function(x, y, z, i)
    calls = calls + 1
    in_order = in_order and i == calls and x == pos[i][1] and y == pos[i][2] and z == pos[i][3]
    if z > 0.3 then
      want[#want + 1] = key(pos[i])
      return true
    end
  end }
  T.eq(calls, #pos, "lock function: called once per vertex")
  T.check(in_order, "lock function: (x, y, z, i) in index order")
  T.check(#want > 100, "lock function: a region of vertices: " .. #want)
  check_run("lock function", h2, 12946)
  set = position_set(h2:mesh())
  kept, lost = 0, 0
  for _, k in ipairs(want) do
    if set[k] then kept = kept + 1 end
    if not Aset[k] then lost = lost + 1 end
  end
  T.eq(kept, #want, "lock function: every locked vertex keeps its exact position")
  T.check(lost > 0, "without lock some of them move: " .. lost)
end
-- }======

-- {====== keep_boundary on an open mesh (a flat 16 x 16 grid)
do
  local N = 16
  local pos, tri = {}, {}
  for j = 0, N do for i = 0, N do pos[#pos + 1] = { i, j, 0 } end end
  local function id(i, j) return j * (N + 1) + i + 1 end
  for j = 0, N - 1 do
    for i = 0, N - 1 do
      tri[#tri + 1] = { id(i, j), id(i + 1, j), id(i + 1, j + 1) }
      tri[#tri + 1] = { id(i, j), id(i + 1, j + 1), id(i, j + 1) }
    end
  end
  local grid = femlod.mesh { positions = pos, triangles = tri }
  local free = grid:simplify { target = 100 }:mesh():quality()
  local h = grid:simplify { target = 100, keep_boundary = true }
  local q = h:mesh():quality()
  T.check(free.boundary_edges < 64, "without keep_boundary the boundary is simplified: " .. free.boundary_edges)
  T.eq(q.boundary_edges, 64, "keep_boundary: every boundary edge kept")
  local set, kept = position_set(h:mesh()), 0
  for _, p in ipairs(pos) do
    if p[1] == 0 or p[1] == N or p[2] == 0 or p[2] == N then kept = kept + (set[key(p)] and 1 or 0) end
  end
  T.eq(kept, 64, "keep_boundary: every boundary vertex in place")
  T.check(h:stats().triangles < 512, "keep_boundary: the interior is simplified")
end
-- }======

-- {====== progress
do
  local seen, ordered = {}, true
  local h = fandisk:simplify { target = 3000, progress = function(done)
    ordered = ordered and done >= (seen[#seen] or 0) and done <= 1
    seen[#seen + 1] = done
  end }
  T.check(#seen >= 10, "progress called along the way: " .. #seen)
  T.check(ordered, "progress values grow within [0, 1]")
  T.eq(serial(h:mesh()), serial(A:mesh()), "a progress function changes nothing")

  local n = 0
  h = fandisk:simplify { target = 3000, progress = function() n = n + 1; return n == 3 end }
  local s = h:stats()
  T.eq(s.stop_reason, "cancelled", "returning true cancels")
  T.check(s.triangles > 3000 and s.triangles < 12946, "cancelled part way: " .. s.triangles)
  T.eq(n, 3, "no call after the cancelling one")
  check_run("cancelled", h, 12946)

  T.errmsg("code:2: stop here", "return m:simplify { target = 3000, progress = function()\n  error('stop here')\nend }", env)
  T.errmsg(E .. "progress: function returned number (boolean or nil expected))",
    "m:simplify { target = 3000, progress = function() return 0 end }", env)
  -- While the simplification runs, its input mesh is busy: closing it does
  -- nothing and using it fails (the failure stops the run and is raised).
  h = fandisk:simplify { target = 3000, progress = function() fandisk:close() end }
  T.eq(h:stats().triangles, 3000, "closing the input inside progress: the run goes on")
  T.eq(fandisk:counts().triangles, 12946, "and the input stays open")
  T.errmsg("code:1: attempt to use a closed femlod.Mesh",
    "m:simplify { target = 3000, progress = function() return m:counts() end }", env)
  T.eq(fandisk:counts().triangles, 12946, "the input is open again after the error")
end
-- }======

-- {====== determinism: the same input and options give the same mesh and file
do
  local opts = { target = 3000, min_stretch = 0.3, max_valence = 9 }
  local h1, h2 = fandisk:simplify(opts), femlod.simplify(fandisk, opts)
  T.eq(serial(h1:mesh()), serial(h2:mesh()), "two runs: identical positions and triangles")
  T.eq(serial(A:mesh()), serial(fandisk:simplify { target = 3000 }:mesh()), "the default run repeats")
  local f1, f2 = P.tmp .. "/simplify_det1.obj", P.tmp .. "/simplify_det2.obj"
  h1:mesh():save(f1)
  h2:mesh():save(f2)
  local a, b = T.readfile(f1), T.readfile(f2)
  T.check(a and #a > 0 and a == b, "two runs: byte-identical files")
  T.eq(h1:stats().collapses, h2:stats().collapses, "two runs: same collapses")
  local r1, r2 = h1:stats().rejected, h2:stats().rejected
  for k, v in pairs(r1) do T.eq(r2[k], v, "two runs: same rejected." .. k) end
end
-- }======

-- {====== life cycle
do
  local h = fandisk:simplify { target = 6000 }
  local copy = h:mesh()
  h:close()
  T.eq(tostring(h), "femlod.Hierarchy (closed)", "a closed hierarchy still prints")
  for _, method in ipairs { "mesh", "stats", "collapses", "input_vertices", "log_bytes" } do
    T.errmsg("code:1: attempt to use a closed femlod.Hierarchy", "h:" .. method .. "()", { h = h })
  end
  T.check(pcall(h.close, h), "closing twice is no error")
  T.eq(copy:counts().triangles, 6000, "a mesh taken before close stays valid")
  T.errmsg("code:1: calling 'stats' on bad self (femlod.Hierarchy expected, got table)",
    "local t = { stats = h.stats }; t:stats()", { h = A })
  T.errmsg("code:1: bad argument #1 to 'mesh' (femlod.Hierarchy expected, got femlod.Mesh)",
    "h.mesh(m)", { h = A, m = fandisk })
  local seen
  do
    local h2 <close> = fandisk:simplify { target = 6000 }
    seen = h2
    T.eq(h2:stats().triangles, 6000, "<close> hierarchy usable in its scope")
  end
  T.eq(tostring(seen), "femlod.Hierarchy (closed)", "<close> closed it at the end of the scope")
  -- Dropped hierarchies are freed by the collector (the sanitizers check it).
  for _ = 1, 3 do fandisk:simplify { target = 10000 } end
  collectgarbage()
  collectgarbage()
end
-- }======

-- {====== hierarchy = false: no log, no hierarchy; the same mesh when the polish does nothing
-- The triangles as a sorted list of vertex-index triples (femlod_simplify
-- orders them by the input triangles they descend from, the hierarchy's
-- front by when they appeared).
local function triangle_set(mesh)
  local out = {}
  for _, t in ipairs(mesh:triangles()) do out[#out + 1] = table.concat(t, " ") end
  table.sort(out)
  return table.concat(out, "\n")
end
local function vertex_serial(mesh)
  local out = {}
  for _, p in ipairs(mesh:positions()) do out[#out + 1] = key(p) end
  return table.concat(out, "\n")
end
-- The stats but the times and the hierarchy's extent (hierarchy_*: the
-- default hierarchy goes past the target), as one string.
local function stats_serial(s)
  local out = {}
  local function walk(prefix, t)
    local keys = {}
    for k in pairs(t) do keys[#keys + 1] = k end
    table.sort(keys)
    for _, k in ipairs(keys) do
      local v = t[k]
      if type(v) == "table" then walk(prefix .. k .. ".", v)
      elseif k ~= "seconds" and k ~= "improve_seconds" and not k:find("^hierarchy_") then out[#out + 1] = prefix .. k .. "=" .. tostring(v) end
    end
  end
  walk("", s)
  return table.concat(out, "\n")
end
-- Output triangles below stretch t, measured here.
local function count_below(mesh, t)
  local pos, n = mesh:positions(), 0
  for _, tr in ipairs(mesh:triangles()) do
    if stretch_size(pos[tr[1]], pos[tr[2]], pos[tr[3]]) < t then n = n + 1 end
  end
  return n
end
do
  local A <close> = fandisk:simplify { target = 2000 }
  local B <close> = fandisk:simplify { target = 2000, hierarchy = false }
  local ma, mb = A:mesh(), B:mesh()
  T.eq(mb:counts().triangles, 2000, "hierarchy = false: fandisk to 2000")
  T.check(vertex_serial(ma) == vertex_serial(mb), "hierarchy = false: fandisk: the same vertices, in the same order")
  T.check(triangle_set(ma) == triangle_set(mb), "hierarchy = false: fandisk: the same triangles")
  T.check(serial(mb) == serial(B:mesh()), "hierarchy = false: each h:mesh() gives the same mesh")
  T.eq(stats_serial(B:stats()), stats_serial(A:stats()), "hierarchy = false: fandisk: the same stats")
  T.eq(B:stats().hierarchy_triangles, 2000, "hierarchy = false: hierarchy_triangles is the output's count")
  T.eq(B:stats().hierarchy_stop, "target", "hierarchy = false: hierarchy_stop is the run's stop")
  T.check(report.stats(B):find("^stop: target; ") ~= nil, "hierarchy = false: report.stats takes it")
  T.eq(B:log_bytes(), 0, "hierarchy = false: no log")
  T.check(A:log_bytes() > 0, "with a hierarchy: a log")
  T.eq(tostring(B), "femlod.Hierarchy (no hierarchy, 2000 triangles)", "hierarchy = false: tostring")
  check_run("hierarchy = false", B, IN.triangles)
  local NOH = "code:1: this femlod.Hierarchy has only its mesh and stats: simplify with hierarchy = false keeps no hierarchy"
  local envb = { h = B, tmp = P.tmp }
  T.errmsg(NOH, "h:refine(0)", envb)
  T.errmsg(NOH, "h:coarsen(1)", envb)
  T.errmsg(NOH, "h:rescale { target = 1000 }", envb)
  T.errmsg(NOH, "h:front()", envb)
  T.errmsg(NOH, "h:counts()", envb)
  T.errmsg(NOH, "h:node(1)", envb)
  T.errmsg(NOH, "h:save(tmp .. '/nohier.flh')", envb)
  T.errmsg(NOH, "h:collapses()", envb)
  B:close()
  T.eq(tostring(B), "femlod.Hierarchy (closed)", "hierarchy = false: closed")
  T.errmsg("code:1: attempt to use a closed femlod.Hierarchy", "h:mesh()", envb)
  T.errmsg("code:1: attempt to use a closed femlod.Hierarchy", "h:stats()", envb)
  local E2 = "code:1: bad argument #1 to 'simplify' ("
  T.errmsg(E2 .. "hierarchy: boolean expected, got number)", "m:simplify { hierarchy = 0 }", { m = fandisk })
  T.errmsg(E2 .. "hierarchy_floor: needs the hierarchy (hierarchy = false keeps none))",
    "m:simplify { hierarchy = false, hierarchy_floor = 100 }", { m = fandisk })
  local last, calls = nil, 0
  local P2 <close> = fandisk:simplify { target = 2000, hierarchy = false,
    progress = function(d) last, calls = d, calls + 1 end }
  T.eq(last, 1, "hierarchy = false: progress ends at 1 (" .. calls .. " calls)")
  T.check(serial(P2:mesh()) == serial(mb), "hierarchy = false: progress changes nothing")
  local C <close> = fandisk:simplify { target = 2000, hierarchy = false, hierarchy_floor = false }
  T.check(serial(C:mesh()) == serial(mb), "hierarchy = false with hierarchy_floor = false: the same mesh")
  local D <close> = fandisk:simplify { target = 2000, hierarchy = true }
  T.check(serial(D:mesh()) == serial(ma), "hierarchy = true is the default")
end
-- The spider breaks min_stretch: the improve stage runs first, and without
-- a log its polish runs at the end; it leaves no more triangles below 0.2.
do
  local spider = femlod.load(P.shared .. "/spider_binary.stl")
  local A <close> = spider:simplify { ratio = 0.3 }
  local B <close> = spider:simplify { ratio = 0.3, hierarchy = false }
  local sa, sb = A:stats(), B:stats()
  T.check(sa.improved and sb.improved, "spider: the improve stage ran")
  local na, nb = count_below(A:mesh(), 0.2), count_below(B:mesh(), 0.2)
  print(string.format("spider ratio 0.3: below stretch 0.2: %d with the hierarchy, %d without (%d -> %d triangles)",
    na, nb, sa.triangles, sb.triangles))
  T.check(nb <= na, "spider: hierarchy = false leaves no more triangles below 0.2: " .. nb .. " <= " .. na)
  T.eq(sb.violating_input, nb, "spider: hierarchy = false: violating_input is the measured count")
  T.eq(sb.triangles, B:mesh():counts().triangles, "spider: hierarchy = false: stats().triangles is the mesh's")
  local m2 = B:mesh():quality()
  T.check(m2.closed == spider:quality().closed, "spider: hierarchy = false keeps closedness")
  spider:close()
end
-- }======

-- {====== cover.obj with the paper's thresholds (0.15, 0.2, 15, 12) to 12,000
do
  local cover = femlod.load(P.shared .. "/cover.obj")
  local n = cover:counts().triangles
  local h = cover:simplify { target = 12000, tolerance = 0.15, min_stretch = 0.2, max_size = 15, max_valence = 12 }
  local s, m = check_run("cover", h, n)
  T.eq(s.stop_reason, "target", "cover: 12,000 reached")
  T.eq(s.triangles, 12000, "cover: 12,000 triangles")
  T.check(m.stretch_min >= 0.2, "cover: every triangle's stretch >= 0.2: " .. m.stretch_min)
  T.check(m.size_max <= 15, "cover: every triangle's size <= 15: " .. m.size_max)
  T.check(m.valence_max <= 12, "cover: valence <= 12: " .. m.valence_max)
  local hf <close> = cover:simplify { target = 12000, tolerance = 0.15, min_stretch = 0.2, max_size = 15, max_valence = 12,
    hierarchy = false }
  T.check(vertex_serial(hf:mesh()) == vertex_serial(h:mesh()) and triangle_set(hf:mesh()) == triangle_set(h:mesh()),
    "cover: hierarchy = false gives the same mesh")
  T.eq(stats_serial(hf:stats()), stats_serial(s), "cover: hierarchy = false: the same stats")
  print(report.row(cover, "cover.obj", "original"))
  print(report.row(h:mesh(), "cover.obj", "simplified 1"))
  print(string.format("cover.obj -> 12000: %.3f s", s.seconds))
  cover:close()
end
-- }======

T.summary("test_simplify")
