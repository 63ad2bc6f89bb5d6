-- test_mesh.lua: the femlod.Mesh type: construction, counts, bbox,
-- subdivision, copies, quality (fandisk against ../shared/data/README.md),
-- Hausdorff, and the life cycle (close, <close>, __gc).
-- Run by ctest: femlod run test_mesh.lua femlod=... tmp=... data=... shared=... examples=...

local T = dofile((arg[0]:match("^(.*)/") or ".") .. "/check.lua")
local femlod = require "femlod"
local report = require "femlod.report"

local P = params
assert(P and P.shared and P.tmp, "run through ctest: needs shared= and tmp= parameters")

-- {====== module basics
T.eq(femlod._VERSION, "femlod 0.1.0", "_VERSION")
T.check(_G.femlod == femlod, "femlod run makes the module the global femlod")
T.eq(type(femlod.load), "function", "femlod.load")
T.eq(type(femlod.mesh), "function", "femlod.mesh")
-- }======

-- A regular tetrahedron (outward normals), as nested and as flat lists.
local s = 1 / math.sqrt(2)
local tet_pos = { { 1, 0, -s }, { -1, 0, -s }, { 0, 1, s }, { 0, -1, s } }
local tet_tri = { { 1, 3, 2 }, { 1, 2, 4 }, { 1, 4, 3 }, { 2, 3, 4 } }

local function flat(list)
  local f = {}
  for _, t in ipairs(list) do for _, x in ipairs(t) do f[#f + 1] = x end end
  return f
end

-- {====== construction and accessors
local tet = femlod.mesh { positions = tet_pos, triangles = tet_tri }
T.eq(getmetatable(tet).__name, "femlod.Mesh", "metatable name")
T.eq(tostring(tet), "femlod.Mesh (4 triangles, 4 vertices)", "tostring")
local c = tet:counts()
T.eq(c.vertices, 4, "tet vertices")
T.eq(c.triangles, 4, "tet triangles")
T.eq(math.type(c.vertices), "integer", "counts are integers")

local b = tet:bbox()
T.eq(b.min[1], -1, "bbox min x"); T.eq(b.min[2], -1, "bbox min y"); T.eq(b.min[3], -s, "bbox min z")
T.eq(b.max[1], 1, "bbox max x"); T.eq(b.max[2], 1, "bbox max y"); T.eq(b.max[3], s, "bbox max z")

-- positions() and triangles() give back exactly what went in, 1-based.
local pos, tri = tet:positions(), tet:triangles()
T.eq(#pos, 4, "#positions")
T.eq(#tri, 4, "#triangles")
for i = 1, 4 do
  for k = 1, 3 do
    T.eq(pos[i][k], tet_pos[i][k], "position " .. i .. "," .. k)
    T.eq(tri[i][k], tet_tri[i][k], "triangle " .. i .. "," .. k)
  end
end

-- The flat form builds the same mesh.
local tet2 = femlod.mesh { positions = flat(tet_pos), triangles = flat(tet_tri) }
local pos2, tri2 = tet2:positions(), tet2:triangles()
local same = true
for i = 1, 4 do
  for k = 1, 3 do same = same and pos2[i][k] == pos[i][k] and tri2[i][k] == tri[i][k] end
end
T.check(same, "flat and nested lists give the same mesh")

-- An empty mesh is a mesh.
local empty = femlod.mesh {}
T.eq(empty:counts().vertices, 0, "empty vertices")
T.eq(empty:counts().triangles, 0, "empty triangles")
T.eq(tostring(empty), "femlod.Mesh (0 triangles, 0 vertices)", "empty tostring")
-- Vertices no triangle uses are kept.
local lonely = femlod.mesh { positions = { 0, 0, 0, 1, 0, 0, 0, 1, 0, 5, 5, 5 }, triangles = { 1, 2, 3 } }
T.eq(lonely:counts().vertices, 4, "isolated vertex kept")
T.eq(lonely:quality().isolated_vertices, 1, "isolated vertex counted")
-- }======

-- {====== quality of a known shape
local q = tet:quality()
T.eq(q.triangles, 4, "q.triangles")
T.eq(q.vertices, 4, "q.vertices")
T.near(q.stretch_min, 1, 1e-12, "regular tetrahedron: stretch 1")
T.near(q.stretch_avg, 1, 1e-12, "stretch avg 1")
T.near(q.size_max, 2, 1e-12, "edge length 2")
T.near(q.angle_min, 60, 1e-9, "angles 60")
T.near(q.angle_max, 60, 1e-9, "angles 60")
T.near(q.area, 4 * math.sqrt(3), 1e-12, "area of four equilateral triangles of side 2")
T.eq(q.valence_max, 3, "valence 3")
T.eq(q.closed, true, "closed"); T.eq(q.manifold, true, "manifold"); T.eq(q.oriented, true, "oriented")
T.eq(q.components, 1, "one component"); T.eq(q.edges, 6, "six edges")
T.eq(q.boundary_edges, 0, "no boundary")
T.eq(#q.histogram, 10, "10 bins")
T.eq(q.histogram[10], 4, "stretch 1 falls in the closed last bin")
T.eq(q.hausdorff, nil, "no hausdorff without reference")

-- Defects: one open triangle, a degenerate one and a duplicate.
local defects = femlod.mesh {
  positions = { { 0, 0, 0 }, { 1, 0, 0 }, { 0, 1, 0 } },
  triangles = { { 1, 2, 3 }, { 1, 1, 2 }, { 3, 2, 1 } },
}
local dq = defects:quality()
T.eq(dq.degenerate, 1, "a repeated vertex is degenerate")
T.eq(dq.duplicate, 1, "the reversed copy is a duplicate")
T.eq(dq.closed, false, "not closed")
T.eq(dq.stretch_min, 0, "degenerate stretch is 0")
-- }======

-- {====== subdivision: 4 triangles per level, midpoints on the edges
local function edge_midpoints(m)
  -- Every midpoint of an edge of m, as "x y z" keys.
  local p, set = m:positions(), {}
  for _, t in ipairs(m:triangles()) do
    for k = 1, 3 do
      local a, bb = p[t[k]], p[t[k % 3 + 1]]
      set[string.format("%.17g %.17g %.17g", 0.5 * (a[1] + bb[1]), 0.5 * (a[2] + bb[2]),
        0.5 * (a[3] + bb[3]))] = true
    end
  end
  return set
end

local sub = tet:subdivide()
T.eq(sub:counts().triangles, 16, "1 level: 4 x 4 triangles")
T.eq(sub:counts().vertices, 10, "1 level: 4 vertices + 6 edge midpoints")
local sub2 = tet:subdivide(2)
T.eq(sub2:counts().triangles, 64, "2 levels: 4^2 x 4 triangles")
T.eq(sub2:counts().vertices, 34, "2 levels: 10 vertices + 24 edges")
local sub0 = tet:subdivide(0)
T.eq(sub0:counts().triangles, 4, "0 levels copies")
T.check(sub0 ~= tet, "0 levels makes a new Mesh")

do
  local mids, spos = edge_midpoints(tet), sub:positions()
  for i = 1, 4 do T.eq(spos[i][1], pos[i][1], "original vertices kept first") end
  local on_edge = 0
  for i = 5, #spos do
    local key = string.format("%.17g %.17g %.17g", spos[i][1], spos[i][2], spos[i][3])
    if mids[key] then on_edge = on_edge + 1 end
  end
  T.eq(on_edge, 6, "every new vertex is the midpoint of an original edge")
  -- Child 4t+4 (1-based) is the middle triangle of original triangle t:
  -- its corners are the midpoints of t's sides.
  local stri = sub:triangles()
  for t = 1, 4 do
    local mid = stri[4 * t]
    for k = 1, 3 do T.check(mid[k] > 4, "middle child of triangle " .. t .. " uses midpoints only") end
  end
  -- Subdividing an equilateral triangle gives equilateral triangles of half size.
  local sq = sub:quality()
  T.near(sq.stretch_min, 1, 1e-12, "children are similar to their parent")
  T.near(sq.size_max, 1, 1e-12, "children have half the edge length")
  T.near(sq.area, q.area, 1e-12, "area kept")
  T.eq(sq.closed, true, "subdivision keeps closed")
  T.eq(sq.oriented, true, "subdivision keeps orientation")
end

-- Subdividing a flat grid keeps it flat and every position on the plane.
do
  local quad = femlod.mesh { positions = { 0, 0, 2, 4, 0, 2, 4, 2, 2, 0, 2, 2 },
    triangles = { 1, 2, 3, 1, 3, 4 } }
  local fine = quad:subdivide(3)
  T.eq(fine:counts().triangles, 2 * 4 ^ 3, "3 levels of a quad")
  T.eq(fine:counts().vertices, 9 * 9, "3 levels of a quad: a 9 x 9 grid")
  local fb = fine:bbox()
  T.eq(fb.min[3], 2, "flat: min z"); T.eq(fb.max[3], 2, "flat: max z")
  T.eq(fb.max[1], 4, "bbox kept")
  T.near(fine:quality().area, 8, 1e-12, "area kept")
end
-- }======

-- {====== copies are independent
do
  local a = femlod.mesh { positions = tet_pos, triangles = tet_tri }
  local cp = a:copy()
  T.check(cp ~= a, "copy is a new object")
  a:close()
  T.eq(cp:counts().triangles, 4, "copy survives closing the original")
  T.eq(cp:positions()[3][3], s, "copy holds the data")
  T.eq(tostring(a), "femlod.Mesh (closed)", "closed tostring")
  cp:close()
end
-- }======

-- {====== fandisk against the reference figures (../shared/data/README.md)
local fandisk_path = P.shared .. "/fandisk.obj"
local fandisk = femlod.load(fandisk_path)
T.eq(tostring(fandisk), "femlod.Mesh (12946 triangles, 6475 vertices)", "fandisk tostring")
local fq = fandisk:quality()
T.eq(fq.triangles, 12946, "fandisk triangles")
T.eq(fq.vertices, 6475, "fandisk vertices")
T.rel(fq.stretch_avg, 0.744457267, 1e-6, "fandisk stretch avg")
T.rel(fq.stretch_min, 0.355560587, 1e-6, "fandisk stretch min")
T.rel(fq.size_max, 0.0546586681, 1e-6, "fandisk size max")
T.eq(fq.valence_max, 9, "fandisk valence max")
T.eq(fq.degenerate, 0, "fandisk degenerate")
T.eq(fq.closed, true, "fandisk closed")
T.eq(fq.manifold, true, "fandisk manifold")
T.eq(fq.oriented, true, "fandisk oriented")
T.eq(fq.boundary_edges, 0, "fandisk boundary edges")
T.eq(fq.nonmanifold_edges, 0, "fandisk non-manifold edges")
T.eq(fq.components, 1, "fandisk components")
T.eq(fq.edges, 12946 * 3 // 2, "closed mesh: E = 3F/2")
T.eq(fq.bbox.min[1], -0.4603, "fandisk bbox min x")
T.eq(fq.bbox.min[2], -0.25555, "fandisk bbox min y")
T.eq(fq.bbox.max[3], 0.5, "fandisk bbox max z")
local hsum = 0
for _, n in ipairs(fq.histogram) do hsum = hsum + n end
T.eq(hsum, 12946, "histogram counts every triangle")
T.eq(fq.histogram[1] + fq.histogram[2] + fq.histogram[3], 0, "no stretch below 0.3 (min is 0.356)")
-- Euler: V - E + F = 2 for a closed genus-0 surface.
T.eq(fq.vertices - fq.edges + fq.triangles, 2, "fandisk genus 0")

-- Hausdorff: a mesh against itself, against its subdivision (same surface),
-- and two parallel squares a known distance apart.
-- Against itself the distance is 0 up to the rounding of the projections.
local self_q = fandisk:quality(fandisk)
T.near(self_q.hausdorff, 0, 1e-12, "hausdorff to itself")
T.near(self_q.hausdorff_rel, 0, 1e-12, "relative hausdorff to itself")
T.near(self_q.hausdorff_forward, 0, 1e-12, "forward to itself")
T.near(self_q.hausdorff_backward, 0, 1e-12, "backward to itself")
T.eq(self_q.triangles, 12946, "quality fields are still there with a reference")
do
  local fine = tet:subdivide(1)
  T.near(fine:quality(tet).hausdorff, 0, 1e-12, "subdivision lies on the original surface")
  local sq0 = femlod.mesh { positions = { 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0 }, triangles = { 1, 2, 3, 1, 3, 4 } }
  local sq1 = femlod.mesh { positions = { 0, 0, 0.25, 1, 0, 0.25, 1, 1, 0.25, 0, 1, 0.25 },
    triangles = { 1, 2, 3, 1, 3, 4 } }
  local hq = sq1:quality(sq0)
  T.near(hq.hausdorff, 0.25, 1e-12, "parallel squares 0.25 apart")
  T.near(hq.hausdorff_forward, 0.25, 1e-12, "forward")
  T.near(hq.hausdorff_backward, 0.25, 1e-12, "backward")
  T.near(hq.hausdorff_rel, 0.25 / math.sqrt(2), 1e-12, "relative to the reference's diagonal")
end

-- The report helper reads the table (and takes a Mesh too).
do
  local text = report.text(fq, "fandisk.obj")
  T.check(text:find("^fandisk.obj: 12946 triangles, 6475 vertices\n"), "report first line")
  T.check(text:find("valence     avg [%d.]+  max 9"), "report valence line")
  T.check(text:find("\n    %[0%.0, 0%.1%)%s+0 "), "report histogram: first bin half-open")
  T.check(text:find("\n    %[0%.9, 1%.0%]%s+" .. fq.histogram[10] .. " "),
    "report histogram: last bin closed, with its count")
  T.check(not text:find("hausdorff"), "no hausdorff line without a reference")
  T.check(report.text(self_q):find("\n  hausdorff   [%d.e+-]+ %(.* of the reference's diagonal"),
    "hausdorff line with a reference")
  T.eq(report.row(fandisk, "fandisk.obj", "original"),
    "fandisk.obj (0.9206 x 0.5111 x 1) | original | 12946 | 0.744, 0.356 | 0.05466 | 9", "Table 1 row")
  T.check(report.header():find("^model"), "row header")
  local fields = report.fields(fq)
  T.check(fields:find("\ntriangles 12946\n"), "fields: triangles")
  T.check(fields:find("^angle_max "), "fields sorted: angle_max first")
  T.check(fields:find("\nhistogram " .. table.concat(fq.histogram, " ") .. "\n"), "fields: histogram")
end
-- }======

-- {====== curvature: a sphere of radius 2 from a subdivided octahedron
do
  local R = 2
  local oct = femlod.mesh {
    positions = { { 1, 0, 0 }, { -1, 0, 0 }, { 0, 1, 0 }, { 0, -1, 0 }, { 0, 0, 1 }, { 0, 0, -1 } },
    triangles = { { 1, 3, 5 }, { 3, 2, 5 }, { 2, 4, 5 }, { 4, 1, 5 },
                  { 3, 1, 6 }, { 2, 3, 6 }, { 4, 2, 6 }, { 1, 4, 6 } }, -- outward
  }
  local fine = oct:subdivide(4)
  local pts = fine:positions()
  for _, p in ipairs(pts) do
    local l = math.sqrt(p[1] ^ 2 + p[2] ^ 2 + p[3] ^ 2)
    for k = 1, 3 do p[k] = R * p[k] / l end
  end
  local sphere = femlod.mesh { positions = pts, triangles = fine:triangles() }
  local n = sphere:counts().vertices
  for _, opts in ipairs { false, { radius = 0.3 } } do
    local c = opts and sphere:curvature(opts) or sphere:curvature()
    local what = opts and "radius 0.3" or "default radius"
    T.eq(#c.k1, n, what .. ": one k1 per vertex"); T.eq(#c.k2, n, what .. ": k2")
    T.eq(#c.kappa, n, what .. ": kappa"); T.eq(#c.dir1, n, what .. ": dir1"); T.eq(#c.dir2, n, what .. ": dir2")
    local worst, frame_ok = 0, true
    for v = 1, n do
      worst = math.max(worst, math.abs(c.k1[v] * R - 1), math.abs(c.k2[v] * R - 1))
      local d1, d2, p = c.dir1[v], c.dir2[v], pts[v]
      local function dot(a, b) return a[1] * b[1] + a[2] * b[2] + a[3] * b[3] end
      frame_ok = frame_ok and c.k1[v] >= c.k2[v]
        and c.kappa[v] == math.max(math.abs(c.k1[v]), math.abs(c.k2[v]))
        and math.abs(dot(d1, d1) - 1) < 1e-12 and math.abs(dot(d2, d2) - 1) < 1e-12
        and math.abs(dot(d1, d2)) < 1e-12 and math.abs(dot(d1, p)) < 0.05 * R
        and math.abs(dot(d2, p)) < 0.05 * R
    end
    T.check(worst <= 0.05, string.format("%s: k1, k2 within 5%% of 1/R (worst %.4f)", what, worst))
    T.check(frame_ok, what .. ": k1 >= k2, kappa = max |k|, unit tangent perpendicular directions")
  end
  -- A plane does not bend; an empty options table is the default.
  local flat = femlod.mesh { positions = { 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0 }, triangles = { 1, 2, 3, 1, 3, 4 } }
  local fc = flat:curvature {}
  T.eq(fc.kappa[1] + fc.kappa[2] + fc.kappa[3] + fc.kappa[4], 0, "a plane is flat")
  -- Errors name the recipe line.
  local env = { m = sphere }
  T.errmsg("code:1: curvature: radius must be a finite number >= 0 (got -1)",
    "m:curvature { radius = -1 }", env)
  T.errmsg("code:1: curvature: radius must be a finite number >= 0 (got nan)",
    "m:curvature { radius = 0/0 }", env)
  T.errmsg("code:1: curvature: radius must be a finite number >= 0 (got inf)",
    "m:curvature { radius = math.huge }", env)
  T.errmsg("code:1: bad argument #1 to 'curvature' (unknown key 'raduis'; valid keys: progress, radius)",
    "m:curvature { raduis = 1 }", env)
  T.errmsg("code:1: bad argument #1 to 'curvature' (radius: number expected, got string)",
    "m:curvature { radius = 'big' }", env)
  T.errmsg("code:1: bad argument #1 to 'curvature' (table expected, got number)",
    "m:curvature(1)", env)
  T.errmsg("code:2: bad argument #1 to 'curvature' (femlod.Mesh expected, got table)",
    "local t = {}\nm.curvature(t)", env)
end
-- }======

-- {====== life cycle: close, <close>, __gc
do
  local kept
  do
    local m <close> = femlod.load(fandisk_path)
    kept = m
    T.eq(m:counts().triangles, 12946, "usable inside the block")
  end
  T.eq(tostring(kept), "femlod.Mesh (closed)", "<close> released the mesh")
  T.checkerr("attempt to use a closed femlod.Mesh", function() return kept:counts() end)
  kept:close() -- close is idempotent, and __gc will run on it again
  T.checkerr("attempt to use a closed femlod.Mesh", function() return kept:quality() end)
  -- <close> also runs when the block is left by an error.
  local m2
  T.checkerr("boom", function()
    local m <close> = tet:copy()
    m2 = m
    error("boom")
  end)
  T.eq(tostring(m2), "femlod.Mesh (closed)", "<close> runs on error")
end
-- Many meshes left to the collector: the sanitizer build checks for leaks.
for _ = 1, 50 do
  local m = fandisk:subdivide(0)
  local _ = m:subdivide(1)
end
collectgarbage()
collectgarbage()
T.eq(fandisk:counts().vertices, 6475, "still usable after collection")
-- }======

-- {====== repair: explicit, every change counted
do
  local spider = femlod.load(P.shared .. "/spider_binary.stl")
  local fixed, r = spider:repair()
  T.eq(r.triangles_in, 1368, "repair: triangles in")
  T.eq(r.degenerate, 56, "repair: spider's degenerate triangles dropped")
  T.eq(r.triangles, fixed:counts().triangles, "repair: the report counts the new mesh")
  local q = fixed:quality()
  T.check(q.manifold and q.oriented and q.degenerate == 0, "repair: manifold, oriented, no degenerate")
  T.eq(spider:counts().triangles, 1368, "repair leaves its input alone")
  -- a soup: every corner its own vertex, welded back
  local pos, tri = {}, {}
  for i, t in ipairs(tet:triangles()) do
    for k = 1, 3 do pos[#pos + 1] = tet:positions()[t[k]] end
    tri[i] = { 3 * i - 2, 3 * i - 1, 3 * i }
  end
  local s = femlod.mesh { positions = pos, triangles = tri }
  local w, rw = s:repair()
  T.eq(rw.welded, 8, "repair: 12 corners welded into 4 vertices")
  T.eq(w:counts().vertices, 4, "repair: 4 vertices")
  T.check(w:quality().closed, "repair: the welded soup is closed")
  local _, off = s:repair { weld = false }
  T.eq(off.welded, 0, "weld = false: nothing welded")
  local _, tol = s:repair { weld = 1e-9, orient = false, split_nonmanifold = false }
  T.eq(tol.welded, 8, "weld = 1e-9")
  local env = { s = s }
  T.errmsg("code:1: bad argument #1 to 'repair' (unknown key 'wled'; valid keys: drop_degenerate, "
    .. "drop_duplicates, drop_unused, orient, split_nonmanifold, weld)", "s:repair{ wled = 1 }", env)
  T.errmsg("code:1: bad argument #1 to 'repair' (weld: must be a finite length >= 0, or false)",
    "s:repair{ weld = -1 }", env)
  T.errmsg("code:1: bad argument #1 to 'repair' (orient: boolean expected, got number)",
    "s:repair{ orient = 1 }", env)
end
-- }======

T.summary("test_mesh")
