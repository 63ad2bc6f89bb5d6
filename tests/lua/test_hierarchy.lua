-- test_hierarchy.lua: the vertex hierarchy from Lua (femlod.Hierarchy):
-- refine(0) gives back the input and coarsen(math.huge) the simplification
-- result, a size function that is small inside a sphere gives a mesh fine
-- inside and coarse outside, refine/coarsen leave no node to split/pair to
-- collapse, split/collapse by id with their dependencies, h:front() maps the
-- mesh's vertices to nodes, save/load round trips, damaged files, errors
-- (text and position), the size function's failures, determinism, and the
-- life cycle. Node ids are 1-based throughout.
-- Run by ctest: femlod run test_hierarchy.lua femlod=... tmp=... data=... shared=... examples=...

local T = dofile((arg[0]:match("^(.*)/") or ".") .. "/check.lua")
local femlod = require "femlod"
local report = require "femlod.report"

local P = params
assert(P and P.shared and P.tmp, "run through ctest: needs shared= and tmp= parameters")

local sqrt, max, huge = math.sqrt, math.max, math.huge
local function tmp(name) return P.tmp .. "/hier_" .. name end

-- {====== helpers

local function key(p) return string.format("%.17g %.17g %.17g", p[1], p[2], p[3]) end

-- The arrays as one string, for exact comparisons.
local function serial(mesh)
  local out = {}
  for _, p in ipairs(mesh:positions()) do out[#out + 1] = key(p) end
  for _, t in ipairs(mesh:triangles()) do out[#out + 1] = table.concat(t, " ") end
  return table.concat(out, "\n")
end

-- The triangles as sorted corner-position triples, each rotated to start at
-- its smallest corner (orientation kept): equal for the same triangles up to
-- renumbering of vertices and triangles.
local function triangle_set(mesh)
  local pos, keys = mesh:positions(), {}
  for i, t in ipairs(mesh:triangles()) do
    local a, b, c = key(pos[t[1]]), key(pos[t[2]]), key(pos[t[3]])
    if b < a and b < c then a, b, c = b, c, a elseif c < a and c < b then a, b, c = c, a, b end
    keys[i] = a .. " | " .. b .. " | " .. c
  end
  table.sort(keys)
  return table.concat(keys, "\n")
end

local function dist(p, q) return sqrt((p[1] - q[1]) ^ 2 + (p[2] - q[2]) ^ 2 + (p[3] - q[3]) ^ 2) end

-- Triangles whose centroid lies within r_in of c, and beyond r_out: count
-- and longest edge of each region.
local function regions(mesh, c, r_in, r_out)
  local pos = mesh:positions()
  local r = { inside = 0, inside_max = 0, outside = 0, outside_max = 0 }
  for _, t in ipairs(mesh:triangles()) do
    local a, b, d = pos[t[1]], pos[t[2]], pos[t[3]]
    local g = { (a[1] + b[1] + d[1]) / 3, (a[2] + b[2] + d[2]) / 3, (a[3] + b[3] + d[3]) / 3 }
    local size = max(dist(a, b), dist(b, d), dist(d, a))
    local e = dist(g, c)
    if e < r_in then
      r.inside, r.inside_max = r.inside + 1, max(r.inside_max, size)
    elseif e > r_out then
      r.outside, r.outside_max = r.outside + 1, max(r.outside_max, size)
    end
  end
  return r
end

-- The front as a set of node ids.
local function front_set(h)
  local set = {}
  for _, id in ipairs(h:front()) do set[id] = true end
  return set
end

local function read(path) return T.readfile(path) end
-- Writes a file anew: truncating one that has data makes ext4 flush it to
-- disk on close (auto_da_alloc), which made the loops below take seconds.
local function put(path, bytes)
  os.remove(path)
  T.writefile(path, bytes)
end

-- CRC-32 (zlib's), to make damaged files that pass the checksum.
local CRC = {}
for i = 0, 255 do
  local c = i
  for _ = 1, 8 do c = (c & 1 == 1) and (0xEDB88320 ~ (c >> 1)) or (c >> 1) end
  CRC[i] = c
end
local function crc32(s)
  local c = 0xFFFFFFFF
  for i = 1, #s, 4096 do
    local bytes = { s:byte(i, math.min(i + 4095, #s)) }
    for k = 1, #bytes do c = CRC[(c ~ bytes[k]) & 0xFF] ~ (c >> 8) end
  end
  return c ~ 0xFFFFFFFF
end
-- The body (everything but the CRC) of a .flh, sealed with a fresh CRC.
local function seal(body) return body .. string.pack("<I4", crc32(body)) end

-- }======

local fandisk = femlod.load(P.shared .. "/fandisk.obj")
local V = fandisk:counts().vertices
T.eq(V, 6475, "fandisk vertices")
local input_set = triangle_set(fandisk)
local input_pos = fandisk:positions()

local t0 = os.clock()
-- hierarchy_floor = false: this hierarchy stops at the target, so that
-- coarsen(math.huge) gives the simplification result (the hierarchy below
-- the target has its own section)
local h = fandisk:simplify { target = 2000, hierarchy_floor = false }
local simplify_seconds = os.clock() - t0
local S = h:stats()
local coarse = h:mesh()          -- the simplification result
local coarse_serial = serial(coarse)
local N = V + S.collapses

-- {====== right after simplify: the front is the simplification result
do
  T.eq(S.triangles, 2000, "simplified to 2000")
  local c = h:counts()
  T.eq(c.nodes, N, "counts.nodes: input vertices + collapses")
  T.eq(c.input_vertices, V, "counts.input_vertices")
  T.eq(c.collapses, S.collapses, "counts.collapses is stats.collapses")
  T.eq(c.front_nodes, S.vertices, "counts.front_nodes (fandisk has no unused vertex)")
  T.eq(c.triangles, 2000, "counts.triangles")
  T.eq(c.vertices, S.vertices, "counts.vertices")
  T.eq(math.type(c.bytes), "integer", "counts.bytes is an integer")
  T.check(c.bytes > 50 * V, "counts.bytes: the hierarchy's memory, " .. c.bytes)
  print(string.format("hierarchy of fandisk -> 2000: %d nodes, %d bytes (%.0f per input vertex)",
    c.nodes, c.bytes, c.bytes / V))
  local n = 0
  for _ in pairs(c) do n = n + 1 end
  T.eq(n, 7, "counts has 7 keys")
  T.eq(tostring(h), string.format("femlod.Hierarchy (%d nodes, 2000 triangles on the front)", N), "tostring")
  T.eq(h:collapses(), S.collapses, "h:collapses()")
  T.eq(h:input_vertices(), V, "h:input_vertices()")
  T.check(h:log_bytes() > 16 * S.collapses, "h:log_bytes(): the log it was built from")
  T.eq(h:validate(), true, "validate() right after simplify")
  T.eq(coarse:counts().triangles, 2000, "h:mesh() is the simplification result's size")
  T.eq(coarse:counts().vertices, S.vertices, "h:mesh() vertices")
  local q = coarse:quality()
  T.check(q.closed and q.manifold and q.oriented, "simplification result closed, manifold, oriented")
  T.check(q.stretch_min >= S.thresholds.min_stretch, "simplification result meets min_stretch")
  T.eq(serial(h:mesh()), coarse_serial, "h:mesh() twice: the same arrays")
end
-- }======

-- {====== h:front() and h:node()
do
  local front, pos = h:front(), coarse:positions()
  T.eq(#front, #pos, "h:front() has one id per vertex of h:mesh()")
  local increasing, states, placed, leaves = true, true, true, 0
  for i, id in ipairs(front) do
    if i > 1 and id <= front[i - 1] then increasing = false end
    local n = h:node(id)
    if n.state ~= "front" or n.id ~= id then states = false end
    -- a leaf is an input vertex, at its input position; another node at its own
    local want = id <= V and input_pos[id] or n.position
    if key(pos[i]) ~= key(want) then placed = false end
    if id <= V then leaves = leaves + 1 end
  end
  T.check(increasing, "h:front() ids increase (vertices in node order)")
  T.check(states, "every h:front() node is on the front")
  T.check(placed, "every vertex sits at its node's position (leaves: the input vertex)")
  T.check(leaves > 0 and leaves < #front, "the coarse front holds leaves and internal nodes: " .. leaves)

  -- node tables
  local leaf = h:node(1)
  T.eq(leaf.id, 1, "node(1).id")
  T.eq(leaf.children, nil, "a leaf has no children")
  T.eq(key(leaf.position), key(input_pos[1]), "node(1).position is input vertex 1")
  T.check(leaf.e_size > 0, "a leaf's e_size: the mean of its input edges")
  local root = h:node(N)
  T.eq(root.parent, nil, "the last node is a root")
  T.eq(root.state, "front", "a root of the coarse front is on it")
  T.eq(root.depth, 0, "a root has depth 0")
  T.eq(#root.children, 2, "an internal node has two children")
  for k = 1, 2 do
    local child = h:node(root.children[k])
    T.eq(child.parent, N, "children point back to their parent")
    T.eq(child.depth, 1, "a child of a root has depth 1")
    T.eq(child.state, "below", "children of a front node are below it")
  end
  T.eq(h:node(root.children[1]).id, root.children[1], "node ids round trip")
  T.check(leaf.parent > V and leaf.parent <= N, "the parent of a leaf is a collapse node")
  T.check(root.e_size > 0 and math.type(root.depth) == "integer", "e_size and depth")
  -- A root's children were born before it, and every node's parent after it.
  T.check(root.children[1] < N and root.children[2] < N, "children have smaller ids")
end
-- }======

-- {====== refine(0) gives back the input, coarsen(math.huge) the result
do
  local t = os.clock()
  local ops = h:refine(0)
  local refine_s = os.clock() - t
  T.eq(ops, S.collapses, "refine(0) splits every collapse")
  local fine = h:mesh()
  T.eq(triangle_set(fine), input_set, "refine(0): the input's triangles, up to renumbering")
  T.eq(fine:counts().vertices, V, "refine(0): every input vertex")
  local front = h:front()
  local identity = #front == V
  for i = 1, #front do if front[i] ~= i then identity = false end end
  T.check(identity, "refine(0): the front is the leaves 1..V in order")
  -- The front mesh is the input with its own vertex numbering: same arrays.
  T.eq(serial(fine), serial(fandisk), "refine(0): the input's arrays exactly (fandisk has no unused vertex)")
  T.eq(h:counts().triangles, 12946, "counts after refine(0)")
  T.eq(h:validate(), true, "validate after refine(0)")
  T.eq(h:refine(0), 0, "refine(0) again: nothing left to split")

  t = os.clock()
  ops = h:coarsen(huge)
  local coarsen_s = os.clock() - t
  T.eq(ops, S.collapses, "coarsen(math.huge) redoes every collapse")
  T.eq(serial(h:mesh()), coarse_serial, "coarsen(math.huge): the simplification result, same arrays")
  T.eq(h:validate(), true, "validate after coarsen")
  T.eq(h:coarsen(huge), 0, "coarsen(math.huge) again: nothing to collapse")
  print(string.format("refine(0): %d splits in %.4f s; coarsen(math.huge): %d collapses in %.4f s "
    .. "(simplify took %.3f s)", S.collapses, refine_s, S.collapses, coarsen_s, simplify_seconds))
end
-- }======

-- {====== uniform thresholds: refine leaves no node to split, coarsen no pair to collapse
do
  for _, size in ipairs { 0.06, 0.03, 0.015 } do
    h:coarsen(huge)
    local ops = h:refine(size)
    local c = h:counts()
    local bad = 0
    for id in pairs(front_set(h)) do
      if id > V and h:node(id).e_size > size then bad = bad + 1 end
    end
    T.eq(bad, 0, "refine(" .. size .. "): no front node with e_size above it")
    T.check(ops > 0, "refine(" .. size .. ") split something: " .. ops)
    T.eq(c.front_nodes, S.vertices + ops, "refine(" .. size .. "): one more front node per split")
    T.eq(c.triangles, 2000 + 2 * ops, "refine(" .. size .. "): two more triangles per split (closed manifold)")
    T.eq(h:validate(), true, "validate after refine(" .. size .. ")")
  end
  -- Finer thresholds give finer meshes.
  h:coarsen(huge)
  h:refine(0.03)
  local n1 = h:counts().triangles
  h:refine(0.015)
  local n2 = h:counts().triangles
  T.check(2000 < n1 and n1 < n2 and n2 < 12946, "0.03 then 0.015: " .. n1 .. " < " .. n2)

  -- coarsen(size) from the input: no pair of front nodes left whose parent's e_size is <= size.
  h:refine(0)
  local ops = h:coarsen(0.03)
  local on = front_set(h)
  local left = 0
  for id in pairs(on) do
    local p = h:node(id).parent
    if p then
      local pn = h:node(p)
      if on[pn.children[1]] and on[pn.children[2]] and pn.e_size <= 0.03 then left = left + 1 end
    end
  end
  T.eq(left, 0, "coarsen(0.03): no collapsible pair left")
  T.check(ops > 0 and ops < S.collapses, "coarsen(0.03) collapsed part of the hierarchy: " .. ops)
  T.eq(h:counts().triangles, 12946 - 2 * ops, "coarsen(0.03): two triangles fewer per collapse")
  T.eq(h:validate(), true, "validate after coarsen(0.03)")
  -- Negative and infinite sizes are thresholds like any other.
  T.eq(h:refine(-1), ops, "refine(-1) splits everything, as refine(0)")
  T.eq(h:refine(huge), 0, "refine(math.huge) splits nothing")
  T.eq(h:coarsen(-1), 0, "coarsen(-1) collapses nothing")
  h:coarsen(huge)
end
-- }======

-- {====== a size function: fine inside a sphere around a sharp corner, coarse outside
local CORNER, R = { 0.4603, 0.25555, -0.5 }, 0.2
local function sphere_size(x, y, z)
  return dist({ x, y, z }, CORNER) < R and 0.01 or huge
end
do
  local kinds = { id = "integer", e_size = "float", depth = "integer", state = "string" }
  local calls, well_formed, first = 0, true, nil
  local t = os.clock()
  local ops = h:refine(function(x, y, z, node)
    calls = calls + 1
    first = first or node.id
    for k, kind in pairs(kinds) do
      if (math.type(node[k]) or type(node[k])) ~= kind then well_formed = false end
    end
    if node.state ~= "front" or node.id <= V or #node.children ~= 2 or node.position ~= nil then
      well_formed = false
    end
    if node.parent ~= nil and node.parent <= node.id then well_formed = false end
    return sphere_size(x, y, z)
  end)
  local seconds = os.clock() - t
  T.check(well_formed, "refine's size function gets {id, e_size, depth, state, parent, children}")
  T.check(calls >= ops, "the function is called at least once per split")
  local lod = h:mesh()
  local r_in, r_out = 0.8 * R, 1.5 * R
  local a, b, c = regions(fandisk, CORNER, r_in, r_out), regions(coarse, CORNER, r_in, r_out),
    regions(lod, CORNER, r_in, r_out)
  print(string.format("sphere refine: %d splits, %d calls in %.4f s; %d triangles", ops, calls, seconds,
    lod:counts().triangles))
  print(string.format("  inside (r < %.2f): input %d (max %.4f), simplified %d (max %.4f), refined %d (max %.4f)",
    r_in, a.inside, a.inside_max, b.inside, b.inside_max, c.inside, c.inside_max))
  print(string.format("  outside (r > %.2f): input %d (max %.4f), simplified %d (max %.4f), refined %d (max %.4f)",
    r_out, a.outside, a.outside_max, b.outside, b.outside_max, c.outside, c.outside_max))
  -- Inside: as fine as the input (every node there is split down to the leaves).
  T.check(a.inside > 4 * b.inside, "the corner region is much coarser after simplification")
  T.eq(c.inside, a.inside, "inside: as many triangles as the input")
  T.check(c.inside_max <= a.inside_max, "inside: no triangle larger than the input's largest there")
  -- Outside: still coarse (dependencies split a little beyond the sphere).
  T.check(c.outside_max > a.outside_max, "outside: coarse elements remain: " .. c.outside_max)
  -- How far the dependencies reach depends on the order: these bars hold
  -- for the paper's order (measured 2231 outside against 1842 simplified,
  -- 1.21x); the default, the error order, measured 3159 against 1876
  -- (1.68x, 0.27 of the input): its hierarchy's dependencies reach farther.
  do
    local hp = fandisk:simplify { target = 2000, hierarchy_floor = false, error_order = false }
    local bp = regions(hp:mesh(), CORNER, r_in, r_out)
    hp:refine(function(x, y, z) return sphere_size(x, y, z) end)
    local cp = regions(hp:mesh(), CORNER, r_in, r_out)
    print(string.format("  paper's order: outside simplified %d, refined %d; the default: %d, %d", bp.outside,
      cp.outside, b.outside, c.outside))
    T.eq(cp.inside, a.inside, "paper's order, inside: as many triangles as the input")
    T.check(cp.outside < 0.25 * a.outside, "paper's order, outside: far fewer triangles than the input: " .. cp.outside)
    T.check(cp.outside < 1.5 * bp.outside, "paper's order, outside: close to the simplification result: " .. cp.outside)
    hp:close()
  end
  local q = lod:quality()
  T.check(q.closed and q.manifold and q.oriented, "the refined mesh is closed, manifold and oriented")
  -- Input triangles as they were, created ones within the thresholds.
  T.check(q.stretch_min >= S.thresholds.min_stretch, "stretch >= min_stretch: " .. q.stretch_min)
  T.check(q.size_max <= max(S.thresholds.max_size, fandisk:quality().size_max), "size <= max_size")
  T.check(q.valence_max <= S.thresholds.max_valence, "valence <= max_valence")
  T.eq(q.degenerate + q.duplicate, 0, "no degenerate or duplicate triangle")
  T.eq(h:validate(), true, "validate after the sphere refine")
  -- The same number twice is a no-op.
  T.eq(h:refine(function(x, y, z) return sphere_size(x, y, z) end), 0, "the same size function again: no split")

  -- coarsen with a function: parent nodes, above the front, with both
  -- children on it; afterwards no pair is left that the function lets collapse.
  local before = h:counts().triangles
  local T_in, T_out = -1, huge
  local function coarse_size(x, y, z) return dist({ x, y, z }, CORNER) < R and T_in or T_out end
  local parents_ok = true
  local n = h:coarsen(function(x, y, z, parent)
    if parent.state ~= "above" or parent.id <= V or #parent.children ~= 2 then parents_ok = false end
    return coarse_size(x, y, z)
  end)
  T.check(parents_ok, "coarsen's size function gets parents above the front")
  T.check(n > 0, "coarsen(function) collapsed something: " .. n)
  T.eq(h:counts().triangles, before - 2 * n, "two triangles fewer per collapse")
  local on, left = front_set(h), 0
  for id in pairs(on) do
    local p = h:node(id).parent
    if p then
      local pn = h:node(p)
      if on[pn.children[1]] and on[pn.children[2]] and pn.e_size <= coarse_size(table.unpack(pn.position)) then
        left = left + 1
      end
    end
  end
  T.eq(left, 0, "coarsen(function): no pair left that the function lets collapse")
  local r = regions(h:mesh(), CORNER, r_in, r_out)
  T.check(r.outside <= c.outside and r.inside <= c.inside, "coarsen made nothing finer")
  -- A collapse needs its neighbours collapsed first, so coarsening outside
  -- also coarsens inside, though the function refuses every collapse there:
  -- the figures say how much.
  print(string.format("  coarsen (%g inside, math.huge outside): %d collapses; inside %d (max %.4f), "
    .. "outside %d (max %.4f)", T_in, n, r.inside, r.inside_max, r.outside, r.outside_max))
  T.eq(h:validate(), true, "validate after the function coarsen")
  h:refine(function(x, y, z) return sphere_size(x, y, z) end)
  T.eq(h:coarsen(function() return -1 end), 0, "coarsen with a function refusing everything: nothing")
  local remaining = (h:counts().triangles - 2000) // 2
  T.eq(h:coarsen(function() return huge end), remaining, "coarsen(function() return math.huge end): every remaining collapse")
  T.eq(serial(h:mesh()), coarse_serial, "back at the simplification result")
end
-- }======

-- {====== split and collapse by id, with dependencies
local deep_front, deep_child -- a front node with an internal child (for the errors below)
do
  -- Find a front node whose split needs others first.
  local split_id, split_ops
  for _, id in ipairs(h:front()) do
    if id > V then
      local before = h:counts()
      local ops = h:split(id)
      local after = h:counts()
      T.eq(after.front_nodes, before.front_nodes + ops, "split(" .. id .. "): one more front node per split")
      T.eq(after.triangles, before.triangles + 2 * ops, "split(" .. id .. "): two more triangles per split")
      T.eq(h:node(id).state, "above", "split(" .. id .. "): the node left the front")
      if ops > 1 then
        split_id, split_ops = id, ops
        break
      end
      T.eq(h:coarsen(huge), ops, "coarsen undoes the split")
    end
  end
  T.check(split_id ~= nil, "some split has dependencies")
  if split_id then
    T.eq(h:validate(), true, "validate after a split with dependencies")
    local n = h:node(split_id)
    T.eq(h:node(n.children[1]).state, "front", "its children are on the front")
    print(string.format("split(%d): %d splits with its dependencies", split_id, split_ops))
    -- collapse(id) puts it back (its dependents need not be collapsed)
    local ops = h:collapse(split_id)
    T.eq(ops, 1, "collapse(" .. split_id .. "): one collapse")
    T.eq(h:node(split_id).state, "front", "collapsed back onto the front")
    T.eq(h:validate(), true, "validate after collapse")
    T.eq(h:coarsen(huge), split_ops - 1, "coarsen(math.huge) redoes the dependencies")
  end

  -- From the input, collapsing the last node needs a whole subtree and its neighbours.
  h:refine(0)
  local before = h:counts()
  local ops = h:collapse(N)
  local after = h:counts()
  T.check(ops > 2, "collapse(" .. N .. ") from the input collapses its dependencies too: " .. ops)
  T.eq(after.front_nodes, before.front_nodes - ops, "one front node fewer per collapse")
  T.eq(after.triangles, before.triangles - 2 * ops, "two triangles fewer per collapse")
  T.eq(h:node(N).state, "front", "the node is on the front")
  T.eq(h:validate(), true, "validate after collapse with dependencies")

  -- A list: done in order, ids already done as a dependency skipped, duplicates too.
  h:coarsen(huge)
  local ids, kids = {}, {}
  for _, id in ipairs(h:front()) do
    if id > V and #ids < 40 then ids[#ids + 1] = id end
  end
  local list_ops = h:split { ids[1], ids[2], ids[1], ids[3] }
  T.check(list_ops >= 3, "split{a, b, a, c}: at least three splits, the repeat skipped: " .. list_ops)
  for k = 1, 3 do T.eq(h:node(ids[k]).state, "above", "split list: node " .. ids[k] .. " split") end
  for k = 1, 3 do
    local ch = h:node(ids[k]).children
    kids[#kids + 1] = ch[1]
  end
  T.eq(h:collapse { ids[3], ids[2], ids[1], ids[1] } >= 3, true, "collapse list")
  for k = 1, 3 do T.check(h:node(ids[k]).state ~= "above", "collapse list: node " .. ids[k] .. " collapsed") end
  T.eq(h:split {}, 0, "split{}: nothing")
  T.eq(h:collapse {}, 0, "collapse{}: nothing")
  h:coarsen(huge) -- (the splits above left dependencies split)
  local all = h:split(ids)
  T.check(all >= #ids, "split of 40 front nodes: " .. all)
  T.eq(h:validate(), true, "validate after a split list")
  h:coarsen(huge)
  T.eq(serial(h:mesh()), coarse_serial, "back at the simplification result")

  for _, id in ipairs(h:front()) do
    if id > V and h:node(id).children[1] > V then
      deep_front, deep_child = id, h:node(id).children[1]
      break
    end
  end
  T.check(deep_front ~= nil, "a front node with an internal child")
end
-- }======

-- {====== errors: text and position
do
  local env = { h = h, huge = huge }
  local E = "code:1: bad argument #1 to '%s' (%s)"
  local function msg(fname, text) return string.format(E, fname, text) end
  T.errmsg(msg("split", "node id or list of node ids expected, got string"), "h:split('x')", env)
  T.errmsg(msg("split", "node id or list of node ids expected, got no value"), "h:split()", env)
  T.errmsg(msg("split", "node 0 does not exist (1.." .. N .. ")"), "h:split(0)", env)
  T.errmsg(msg("split", string.format("node %d does not exist (1..%d)", N + 1, N)), "h:split(" .. N + 1 .. ")", env)
  T.errmsg(msg("split", "node id expected, got 2.5"), "h:split(2.5)", env)
  T.errmsg(msg("split", "node 1 is an input vertex: it has no split"), "h:split(1)", env)
  T.errmsg(msg("split", string.format("node %d is below the front (inside front node %d)", deep_child, deep_front)),
    "h:split(" .. deep_child .. ")", env)
  T.errmsg(msg("split", "ids[2]: node id expected, got boolean"), "h:split { " .. deep_front .. ", true }", env)
  T.errmsg(msg("split", "ids[3]: node 5 is an input vertex: it has no split"),
    "h:split { " .. deep_front .. ", " .. N .. ", 5 }", env)
  T.eq(serial(h:mesh()), coarse_serial, "a failing list changes nothing")
  T.errmsg(string.format("code:1: bad argument #2 to 'split' (no more arguments expected)"),
    "h:split(" .. deep_front .. ", {})", env)
  h:split(deep_front)
  T.errmsg(msg("split", string.format("node %d is above the front (already split)", deep_front)),
    "h:split(" .. deep_front .. ")", env)
  T.errmsg(msg("collapse", string.format("node %d is already collapsed (it is on the front)", deep_child)),
    "h:collapse(" .. deep_child .. ")", env)
  h:coarsen(huge)
  T.errmsg(msg("collapse", string.format("node %d is already collapsed (inside front node %d)", deep_child, deep_front)),
    "h:collapse(" .. deep_child .. ")", env)
  T.errmsg(msg("collapse", "node 7 is an input vertex: it has no children to collapse"), "h:collapse(7)", env)
  T.errmsg(msg("collapse", "ids[1]: node -3 does not exist (1.." .. N .. ")"), "h:collapse { -3 }", env)
  T.errmsg(msg("node", "node id expected, got no value"), "h:node()", env)
  T.errmsg(msg("node", "node 0 does not exist (1.." .. N .. ")"), "h:node(0)", env)
  T.errmsg(msg("refine", "number or function expected, got nil"), "h:refine(nil)", env)
  T.errmsg(msg("refine", "number or function expected, got string"), "h:refine('0.1')", env)
  T.errmsg(msg("refine", "size is NaN"), "h:refine(0/0)", env)
  T.errmsg(msg("coarsen", "size is NaN"), "h:coarsen(0/0)", env)
  T.errmsg("code:1: bad argument #2 to 'refine' (no more arguments expected)", "h:refine(0.1, { max = 3 })", env)
  T.errmsg("code:1: bad argument #1 to 'mesh' (no more arguments expected)", "h:mesh { format = 'obj' }", env)
  T.errmsg("code:1: bad argument #2 to 'save' (no more arguments expected)", "h:save('x.flh', {})", env)
  T.errmsg("code:1: bad argument #1 to 'save' (string expected, got no value)", "h:save()", env)
  T.errmsg("code:1: bad argument #2 to 'load_hierarchy' (no more arguments expected)",
    "femlod.load_hierarchy('x.flh', { format = 'flh' })", env)
  T.errmsg("code:1: calling 'refine' on bad self (femlod.Hierarchy expected, got table)",
    "local t = { refine = h.refine }; t:refine(0)", env)
  T.eq(serial(h:mesh()), coarse_serial, "argument errors change nothing")
  -- Option tables of the functions that take them still reject unknown keys.
  -- The CLI's --hierarchy PATH is no simplify option: hierarchy is a boolean.
  T.errmsg("code:1: bad argument #1 to 'simplify' (hierarchy: boolean expected, got string)",
    "m:simplify { target = 2000, hierarchy = 'x.flh' }", { m = fandisk })
  T.errmsg("code:1: bad argument #1 to 'simplify' (unknown key 'flh'; valid keys: area_weighted, "
    .. "error_order, fast_above, feature_angle, feature_weight, hierarchy, hierarchy_floor, improve, keep_boundary, lock, max_deviation, max_normal_change, max_size, "
    .. "max_valence, min_stretch, progress, ratio, target, threads, tolerance)",
    "m:simplify { target = 2000, flh = 'x.flh' }", { m = fandisk })
end
-- }======

-- {====== the size function's failures: raised after the operation, the front stays valid
do
  local env = { h = h, huge = huge, V = V }
  -- The first node asked about, to pin the messages that name it.
  local first
  h:refine(function(_, _, _, node) first = first or node.id; return huge end)
  T.check(first and first > V, "a first node")
  T.errmsg("code:2: boom", "return h:refine(function()\n  error('boom')\nend)", env)
  T.errmsg(string.format("code:1: bad argument #1 to 'refine' (size function returned string for node %d "
    .. "(number expected))", first), "h:refine(function() return '0.1' end)", env)
  T.errmsg(string.format("code:1: bad argument #1 to 'refine' (size function returned nil for node %d "
    .. "(number expected))", first), "h:refine(function() end)", env)
  T.errmsg(string.format("code:1: bad argument #1 to 'refine' (size function returned nan for node %d "
    .. "(number expected))", first), "h:refine(function() return 0/0 end)", env)
  T.eq(serial(h:mesh()), coarse_serial, "failed calls from the simplification result split nothing")
  h:refine(0)
  local parent
  T.eq(h:coarsen(function(_, _, _, node) parent = parent or node.id; return -1 end), 0, "coarsen(-1 everywhere)")
  T.errmsg(string.format("code:1: bad argument #1 to 'coarsen' (size function returned boolean for node %d "
    .. "(number expected))", parent), "h:coarsen(function() return true end)", env)
  T.eq(h:counts().triangles, 12946, "a failed coarsen from the input collapses nothing")
  h:coarsen(huge)
  -- An error after some work: the work done stays, and the front is valid.
  local n = 0
  local ok, e = pcall(h.refine, h, function()
    n = n + 1
    if n > 200 then error({ code = 42 }) end
    return 0
  end)
  T.check(not ok and type(e) == "table" and e.code == 42, "any error value comes through as it was")
  local c = h:counts()
  T.check(c.triangles > 2000 and c.triangles < 12946, "the splits before the error stay: " .. c.triangles)
  T.eq(h:validate(), true, "the front is valid after a failed refine")
  T.eq(triangle_set(femlod.load(P.shared .. "/fandisk.obj")), input_set, "(the input is untouched)")
  h:refine(0)
  T.eq(triangle_set(h:mesh()), input_set, "refine(0) still gives the input after a failed refine")
  h:coarsen(huge)
  -- The hierarchy is busy while its size function runs: no use, no close.
  T.errmsg("code:2: attempt to use a femlod.Hierarchy inside its own size or progress function",
    "h:refine(function()\n  return h:counts()\nend)", env)
  T.errmsg("code:2: attempt to close a femlod.Hierarchy inside its own size or progress function",
    "h:refine(function()\n  h:close()\nend)", env)
  T.eq(h:counts().triangles, 2000, "usable after those errors")
  T.eq(tostring(h), string.format("femlod.Hierarchy (%d nodes, 2000 triangles on the front)", N),
    "tostring works")
  -- ... but another hierarchy is free to use.
  local other = fandisk:simplify { target = 6000 }
  local seen = 0
  h:refine(function(x, y, z)
    seen = other:node(1).id
    return sphere_size(x, y, z)
  end)
  T.eq(seen, 1, "another hierarchy works inside a size function")
  h:coarsen(huge)
  other:close()
end
-- }======

-- {====== save and load
local saved = tmp("fandisk.flh")
do
  h:refine(function(x, y, z) return sphere_size(x, y, z) end)
  local front_mesh = serial(h:mesh())
  os.remove(saved)
  h:save(saved)
  T.check(T.exists(saved), "save wrote the file")
  local g = femlod.load_hierarchy(saved)
  T.eq(getmetatable(g).__name, "femlod.Hierarchy", "load_hierarchy gives a Hierarchy")
  T.eq(serial(g:mesh()), front_mesh, "load: the same front mesh")
  T.eq(table.concat(g:front(), " "), table.concat(h:front(), " "), "load: the same front ids")
  local hc, gc = h:counts(), g:counts()
  for _, k in ipairs { "nodes", "input_vertices", "collapses", "front_nodes", "triangles", "vertices" } do
    T.eq(gc[k], hc[k], "load: counts." .. k)
  end
  T.eq(tostring(g), tostring(h), "load: tostring")
  T.eq(g:validate(), true, "load: valid")
  local gs = g:stats()
  T.eq(gs.triangles, S.triangles, "load: stats.triangles")
  T.eq(gs.collapses, S.collapses, "load: stats.collapses")
  T.eq(gs.seconds, 0, "load: stats.seconds (the wall time is not stored)")
  T.eq(gs.stop_reason, S.stop_reason, "load: stats.stop_reason")
  T.eq(gs.thresholds.max_size, S.thresholds.max_size, "load: thresholds.max_size")
  T.eq(gs.thresholds.max_deviation, false, "load: an off threshold stays false")
  T.eq(gs.rejected.foldover, S.rejected.foldover, "load: rejected.foldover")
  -- the same report but for the time and the fast passes' share, which a file does not keep
  local function untimed(text)
    return (text:gsub(" in [%d.]+ s", ""):gsub(", %d+ in fast passes on %d+ threads?", ""))
  end
  T.eq(untimed(report.stats(g)), untimed(report.stats(h)), "load: report.stats")
  T.eq(g:collapses(), S.collapses, "load: collapses()")
  T.eq(g:input_vertices(), V, "load: input_vertices()")
  T.eq(g:log_bytes(), 0, "load: no collapse log")
  for k = 1, 3 do
    local a, b = g:node(N - k), h:node(N - k)
    T.eq(key(a.position) .. a.e_size .. a.state .. a.depth, key(b.position) .. b.e_size .. b.state .. b.depth,
      "load: node " .. N - k)
  end
  -- Saved again, the same bytes; a loaded hierarchy does everything a fresh one does.
  local again = tmp("fandisk_again.flh")
  g:save(again)
  T.check(read(again) == read(saved), "load then save: byte-identical file")
  g:refine(0)
  T.eq(triangle_set(g:mesh()), input_set, "loaded: refine(0) gives the input")
  g:coarsen(huge)
  T.eq(serial(g:mesh()), coarse_serial, "loaded: coarsen(math.huge) gives the simplification result")
  T.check(g:split(deep_front) >= 1 and g:collapse(deep_front) == 1, "loaded: split and collapse")
  T.eq(g:validate(), true, "loaded: valid after operations")
  -- The file keeps the front, not the way to it.
  h:coarsen(huge)
  h:refine(0)
  h:coarsen(huge)
  h:refine(function(x, y, z) return sphere_size(x, y, z) end)
  h:save(again)
  T.check(read(again) == read(saved), "the same front reached another way: byte-identical file")
  h:coarsen(huge)
  g:close()
  -- A failed save leaves nothing.
  T.checkerr("no_such_dir/x%.flh: ", function() h:save(P.tmp .. "/no_such_dir/x.flh") end)
  T.check(not T.exists(P.tmp .. "/no_such_dir/x.flh"), "nothing written")
end
-- }======

-- {====== damaged and foreign files: a clear error, never a crash
do
  local good = read(saved)
  local function load_error(name, bytes)
    local p = tmp(name)
    put(p, bytes)
    local line = T.line() + 1
    local ok, e = pcall(function() return femlod.load_hierarchy(p) end)
    T.check(not ok, name .. ": refused")
    local want = string.format("test_hierarchy.lua:%d: %s: ", line, p)
    local at = type(e) == "string" and e:find(want, 1, true)
    T.check(at, name .. ": the message gives the position and the path: " .. tostring(e))
    return at and e:sub(at + #want) or ""
  end
  T.eq(load_error("empty.flh", ""), "byte 0: not a femlod hierarchy file", "an empty file")
  T.eq(load_error("foreign.flh", read(P.shared .. "/fandisk.obj")), "byte 0: not a femlod hierarchy file",
    "an OBJ file")
  T.eq(load_error("short.flh", good:sub(1, 10)), "byte 0: not a femlod hierarchy file", "10 bytes")
  T.eq(load_error("truncated.flh", good:sub(1, #good // 2)), "checksum mismatch: the file is damaged",
    "half a file")
  T.eq(load_error("tail.flh", good:sub(1, -2)), "checksum mismatch: the file is damaged", "one byte short")
  local mid = #good // 2
  local flipped = good:sub(1, mid - 1) .. string.char(good:byte(mid) ~ 0x10) .. good:sub(mid + 1)
  T.eq(load_error("flipped.flh", flipped), "checksum mismatch: the file is damaged", "a flipped byte")
  T.eq(load_error("extra.flh", good .. "x"), "checksum mismatch: the file is damaged", "a byte appended")
  -- Damage that passes the checksum: the parser and the rebuild catch it.
  local body = good:sub(1, -5)
  T.eq(seal(body), good, "(the CRC here is zlib's)")
  T.eq(load_error("version.flh", seal(body:sub(1, 8) .. string.pack("<I4", 2) .. body:sub(13))),
    "byte 8: version 2 (this femlod reads 1)", "a newer version")
  local nv, nf, nc, nvs, nlog, nfront = string.unpack("<I8I8I8I8I8I8", body, 17)
  T.eq(nv, V, "(header: input vertices)")
  T.eq(load_error("count.flh", seal(body:sub(1, 32) .. string.pack("<I8", 1 << 32) .. body:sub(41))),
    "byte 32: collapse count 4294967296 does not fit the file", "a huge count")
  -- The front block: the front's node ids (0-based in the file), increasing.
  local ids, g = {}, femlod.load_hierarchy(saved)
  local gfront = g:front()
  for i, id in ipairs(gfront) do ids[i] = string.pack("<I4", id - 1) end
  T.eq(#ids, nfront, "(the file's front is the front)")
  local fs, fe = body:find(table.concat(ids), 1, true)
  T.check(fs ~= nil, "(the front block is in the file)")
  fs, fe = fs or 1, fe or 0
  local e = load_error("front.flh", seal(body:sub(1, fs - 1) .. ids[2] .. body:sub(fs + 4)))
  T.check(e:find("front node " .. string.unpack("<I4", ids[2]) .. " is listed twice", 1, true),
    "a front with a node listed twice: " .. e)
  e = load_error("front_gap.flh", seal(body:sub(1, 56) .. string.pack("<I8", nfront - 1)
    .. body:sub(65, fs - 1) .. body:sub(fs + 4)))
  T.check(gfront[1] <= V, "(the first front node is an input vertex)")
  T.check(e:find("input vertex " .. gfront[1] - 1 .. " is not covered by the front", 1, true),
    "a front missing a node: " .. e)
  local parent
  for _, id in ipairs(gfront) do parent = parent or g:node(id).parent end
  e = load_error("front_overlap.flh", seal(body:sub(1, fe - 4) .. string.pack("<I4", parent - 1) .. body:sub(fe + 1)))
  T.check(e:find("front", 1, true), "a front node and its ancestor: " .. e)
  g:close()
  T.check(nf > 0 and nc > 0 and nvs > 0 and nlog > 0, "(header counts)")
  local missing = tmp("missing.flh")
  os.remove(missing)
  T.checkerr(": cannot open: No such file or directory", function() return femlod.load_hierarchy(missing) end)

  -- Every truncation behind a valid checksum, on a small hierarchy: an error
  -- naming the file (the parser checks every read against the file's end).
  local small = femlod.load(P.shared .. "/sphereWithHole.stl"):simplify()
  local sp = tmp("small.flh")
  small:save(sp)
  local sbody = read(sp):sub(1, -5)
  local tp = tmp("truncated_sealed.flh")
  local c, refused, other = 0xFFFFFFFF, 0, {}
  for k = 1, #sbody - 1 do
    c = CRC[(c ~ sbody:byte(k)) & 0xFF] ~ (c >> 8)
    if k >= 12 and (k < 200 or k % 5 == 0 or #sbody - k < 200) then
      put(tp, sbody:sub(1, k) .. string.pack("<I4", c ~ 0xFFFFFFFF))
      local ok, r = pcall(femlod.load_hierarchy, tp)
      if not ok and type(r) == "string" and r:find(tp, 1, true) == 1 then
        refused = refused + 1
      else
        other[#other + 1] = k .. ": " .. tostring(r)
      end
    end
  end
  T.eq(#other, 0, "every truncation refused with the file's name: " .. table.concat(other, "; "):sub(1, 300))
  T.check(refused > 1000, "truncations tried: " .. refused)

  -- Random damage behind a valid checksum, on a small hierarchy: an error
  -- naming the file, or a hierarchy that is valid; never a crash.
  local seed = 20240611
  math.randomseed(seed)
  print("random .flh damage: seed " .. seed)
  local refused, loaded, bad = 0, 0, 0
  local dp = tmp("damaged.flh")
  for _ = 1, 150 do
    local at = math.random(13, #sbody) -- past the magic, the version and the flags
    local b = sbody:sub(1, at - 1) .. string.char(sbody:byte(at) ~ (1 << math.random(0, 7))) .. sbody:sub(at + 1)
    put(dp, seal(b))
    local ok, r = pcall(femlod.load_hierarchy, dp)
    if ok then
      loaded = loaded + 1
      local vok = pcall(r.validate, r)
      local mok = pcall(r.mesh, r)
      if not (vok and mok) then bad = bad + 1 end
      r:close()
    elseif type(r) == "string" and r:find(dp, 1, true) == 1 then
      refused = refused + 1
    else
      bad = bad + 1
      print("unexpected: " .. tostring(r))
    end
  end
  T.eq(bad, 0, "random damage: every load refused with the file's name, or valid")
  T.check(refused > 50, "random damage: most refused (" .. refused .. " refused, " .. loaded .. " loaded)")
end
-- }======

-- {====== determinism: the same operations give byte-identical files
do
  local function run(path_mesh, path_flh)
    local x = fandisk:simplify { target = 2000 }
    x:refine(function(a, b, c) return sphere_size(a, b, c) end)
    local deep -- a front node with an internal child, on this front
    for _, id in ipairs(x:front()) do
      if id > V and x:node(id).children[1] > V then deep = id break end
    end
    x:split { deep }
    x:coarsen(0.02)
    x:refine(0.04)
    x:mesh():save(path_mesh)
    x:save(path_flh)
    x:close()
  end
  local a, b = tmp("det1.obj"), tmp("det2.obj")
  run(a, tmp("det1.flh"))
  run(b, tmp("det2.flh"))
  T.check(#read(a) > 0 and read(a) == read(b), "two runs: byte-identical meshes")
  -- The .flh stores no wall time: two runs give the same bytes.
  T.check(#read(tmp("det1.flh")) > 0 and read(tmp("det1.flh")) == read(tmp("det2.flh")),
    "two runs: byte-identical .flh files")
end
-- }======

-- {====== life cycle
do
  local x = fandisk:simplify { target = 6000 }
  local m = x:mesh()
  x:close()
  T.eq(tostring(x), "femlod.Hierarchy (closed)", "a closed hierarchy prints")
  for _, call in ipairs { "mesh()", "front()", "refine(0)", "coarsen(1)", "split(1)", "collapse(1)", "counts()",
    "node(1)", "validate()", "save('x.flh')", "stats()", "collapses()", "input_vertices()", "log_bytes()" } do
    T.errmsg("code:1: attempt to use a closed femlod.Hierarchy", "x:" .. call, { x = x })
  end
  T.check(pcall(x.close, x), "closing twice is no error")
  T.eq(m:counts().triangles, 6000, "a mesh taken before close stays valid")
  do
    local g <close> = femlod.load_hierarchy(saved)
    x = g
    T.eq(g:validate(), true, "<close> on a loaded hierarchy")
  end
  T.eq(tostring(x), "femlod.Hierarchy (closed)", "<close> closed it")
  for _ = 1, 3 do femlod.load_hierarchy(saved):refine(0) end
  collectgarbage()
  collectgarbage()
end
-- }======

-- {====== rescale: global LOD keeping the density (paper 5.3.2)
do
  local h = fandisk:simplify { target = 2000 }
  local base = h:counts().triangles
  T.check(h:rescale { factor = 1.5 } > 0, "rescale up does operations")
  T.eq(h:counts().triangles, math.floor(1.5 * base + 0.5), "rescale by 1.5: the count")
  h:rescale { target = 2500 }
  T.eq(h:counts().triangles, 2500, "rescale to 2500: the count")
  T.eq(h:validate(), true, "valid after rescale")
  -- below the coarsest front the coarsest is the answer (fandisk's
  -- defaults allow nothing coarser than the target here)
  h:rescale { target = 10 }
  T.eq(h:counts().triangles, h:stats().hierarchy_triangles, "rescale below the coarsest: the coarsest front")
  local env = { h = h }
  T.errmsg("code:1: bad argument #1 to 'rescale' (give exactly one of target and factor)",
    "h:rescale{ target = 3, factor = 2 }", env)
  T.errmsg("code:1: bad argument #1 to 'rescale' (give exactly one of target and factor)", "h:rescale{}", env)
  T.errmsg("code:1: bad argument #1 to 'rescale' (unknown key 'targt'; valid keys: factor, progress, target)",
    "h:rescale{ targt = 3 }", env)
  T.errmsg("code:1: bad argument #1 to 'rescale' (factor: must be a positive finite number)",
    "h:rescale{ factor = -2 }", env)
  T.errmsg("code:1: bad argument #1 to 'rescale' (target: must be an integer in 1..4294967295)",
    "h:rescale{ target = 0 }", env)
  T.errmsg("code:1: bad argument #1 to 'rescale' (table expected, got number)", "h:rescale(3)", env)
end
-- }======

-- {====== the hierarchy below the target (docs/design.md "The hierarchy below the target")

-- The input vertices whose kappa is at or above its 95th percentile (the
-- default radius, as refine_curvature's) that are vertices of h's front.
local function high_kappa_kept(m, h)
  local kappa, sorted = m:curvature().kappa, {}
  for i = 1, #kappa do sorted[i] = kappa[i] end
  table.sort(sorted)
  local top, n = sorted[math.ceil(0.95 * #sorted)], 0
  for _, id in ipairs(h:front()) do
    if id <= #kappa and kappa[id] >= top then n = n + 1 end
  end
  return n
end

-- A generated part: a plate 100 x 100 of 150 x 150 cells (45,000
-- triangles) with three narrow Gaussian bumps {x, y, height, sigma}.
local function bumpy_plate()
  local n, pos, tri = 150, {}, {}
  local bumps = { { 30, 30, 4, 2.5 }, { 70, 40, 3, 2 }, { 45, 75, 5, 3 } }
  for j = 0, n do
    for i = 0, n do
      local x, y, z = 100 * i / n, 100 * j / n, 0
      for _, b in ipairs(bumps) do z = z + b[3] * math.exp(-((x - b[1]) ^ 2 + (y - b[2]) ^ 2) / (2 * b[4] ^ 2)) end
      pos[#pos + 1] = { x, y, z }
    end
  end
  local function id(i, j) return j * (n + 1) + i + 1 end
  for j = 0, n - 1 do
    for i = 0, n - 1 do
      tri[#tri + 1] = { id(i, j), id(i + 1, j), id(i + 1, j + 1) }
      tri[#tri + 1] = { id(i, j), id(i + 1, j + 1), id(i, j + 1) }
    end
  end
  return femlod.mesh { positions = pos, triangles = tri }
end

do
  local cover <close> = femlod.load(P.shared .. "/cover.obj")
  local opts = { target = 12000, tolerance = 0.15, min_stretch = 0.2, max_size = 15, max_valence = 12 }
  local function with(t, k, v) local c = {} for a, b in pairs(t) do c[a] = b end c[k] = v return c end
  local plain <close> = cover:simplify(with(opts, "hierarchy_floor", false))
  local h <close> = cover:simplify(opts)
  local S, PS = h:stats(), plain:stats()
  -- the mesh at the target is the plain simplification's, byte for byte
  T.eq(serial(h:mesh()), serial(plain:mesh()), "hierarchy_floor: the first front is the plain result")
  T.eq(S.collapses, PS.collapses, "stats.collapses: those up to the target")
  T.eq(PS.hierarchy_triangles, 12000, "hierarchy_floor = false: the log stops at the target")
  T.check(h:collapses() > S.collapses, "the hierarchy goes on past the target: " .. h:collapses())
  T.check(S.hierarchy_triangles < 6000, "to the coarsest mesh the thresholds allow: " .. S.hierarchy_triangles)
  T.eq(S.hierarchy_stop, "no_valid_edge", "the extension stops where no edge is valid")
  T.check(S.hierarchy_binding ~= nil, "and knows which check stopped it")
  T.eq(h:validate(), true, "valid at the target")
  print(string.format("cover -> 12000: %d collapses to the target, %d in the hierarchy, coarsest %d triangles (%s)",
    S.collapses, h:collapses(), S.hierarchy_triangles, S.hierarchy_binding))

  -- every threshold at every front visited: created triangles only (input
  -- triangles are as they were); cover's input meets them
  local function check_front(label)
    local q = h:mesh():quality()
    T.check(q.closed == cover:quality().closed and q.manifold, label .. ": closed and manifold as the input")
    T.check(q.stretch_min >= 0.2 - 1e-12, label .. ": min stretch " .. q.stretch_min)
    T.check(q.size_max <= 15 + 1e-9, label .. ": max size " .. q.size_max)
    T.check(q.valence_max <= 12, label .. ": max valence " .. q.valence_max)
    T.eq(h:validate(), true, label .. ": valid")
  end

  -- half the target: reached within 0.5%, no reason given
  local ops, n, why = h:rescale { target = 6000 }
  T.check(ops > 0 and math.abs(n - 6000) <= 30, "rescale to half the target: " .. n)
  T.eq(why, nil, "no reason when the count is met")
  T.eq(h:counts().triangles, n, "rescale returns the count reached")
  check_front("rescaled to 6000")
  -- below the coarsest: the coarsest, and why
  ops, n, why = h:rescale { target = 100 }
  T.eq(n, S.hierarchy_triangles, "rescale below the coarsest reaches the coarsest")
  T.eq(why, S.hierarchy_binding, "and names the check that stopped the simplification")
  check_front("coarsest")
  T.eq(h:coarsen(huge), 0, "coarsen(math.huge) at the coarsest: nothing to collapse")
  -- above the input: the input's count
  ops, n, why = h:rescale { target = 200000 }
  T.eq(n, cover:counts().triangles, "rescale above the input reaches the input")
  T.eq(why, "the input's count", "and says so")
  -- the order size: from the input, a rescale to the target retraces the
  -- simplification (the plain result is a front of uniform density)
  h:rescale { target = 12000 }
  T.eq(serial(h:mesh()), serial(plain:mesh()), "rescale from the input to 12,000: the plain simplification")
  -- the card's recipe: simplify to 12k, refine curvature, rescale back
  h:refine_curvature {}
  check_front("refine_curvature below and above the target")
  local fine = h:counts().triangles
  -- (the paper's order: more than 30,000, below; the default measured 29,430)
  T.check(fine > 24000, "refine_curvature from 12,000: " .. fine)
  ops, n, why = h:rescale { target = 12000 }
  T.check(math.abs(n - 12000) <= 60, "the recipe's rescale back: within 0.5% of 12,000: " .. n)
  T.eq(why, nil, "the recipe's rescale: no reason")
  T.check(serial(h:mesh()) ~= serial(plain:mesh()), "the recipe does not give the plain simplification back")
  check_front("the recipe's result")
  -- and it keeps the curved parts finer than the plain simplification: in
  -- the paper's order. The default (the error order) keeps the curved parts
  -- in its plain result already (measured 557 high-kappa input vertices
  -- against the paper's order's 147), and the recipe adds little to it
  -- (576, 1.03x): what the default must do is keep at least as many as the
  -- paper's order's recipe.
  local kept, k_plain = high_kappa_kept(cover, h), high_kappa_kept(cover, plain)
  print(string.format("cover recipe, default order: %d high-kappa input vertices kept against the plain "
    .. "simplification's %d (%.2fx)", kept, k_plain, kept / k_plain))
  do
    local pp <close> = cover:simplify(with(with(opts, "hierarchy_floor", false), "error_order", false))
    local hp <close> = cover:simplify(with(opts, "error_order", false))
    hp:refine_curvature {}
    local pfine = hp:counts().triangles
    T.check(pfine > 30000, "paper's order: refine_curvature from 12,000: " .. pfine)
    local _, pn = hp:rescale { target = 12000 }
    T.check(math.abs(pn - 12000) <= 60, "paper's order: the recipe's rescale back within 0.5% of 12,000: " .. pn)
    local pkept, pk_plain = high_kappa_kept(cover, hp), high_kappa_kept(cover, pp)
    T.check(pkept >= 1.25 * pk_plain, string.format("paper's order: the recipe keeps >= 1.25x the plain "
      .. "simplification's high-kappa input vertices: %d against %d", pkept, pk_plain))
    print(string.format("cover recipe, paper's order: %d high-kappa input vertices kept against the plain "
      .. "simplification's %d (%.2fx)", pkept, pk_plain, pkept / pk_plain))
    T.check(k_plain >= pkept and kept >= pkept, string.format("the default keeps at least the paper's order's recipe's "
      .. "high-kappa input vertices: plain %d, recipe %d against %d", k_plain, kept, pkept))
  end
  -- region and coarsen below the target
  h:rescale { target = 4000 }
  h:refine_region { sphere = { center = { 0, 0, 0 }, radius = 20 }, size = 0 }
  check_front("refine_region below the target")
  -- a floor: the log stops there
  local f <close> = cover:simplify(with(opts, "hierarchy_floor", 8000))
  T.eq(f:stats().hierarchy_triangles, 8000, "hierarchy_floor = 8000: the log stops at 8000")
  T.eq(f:stats().hierarchy_stop, "target", "at its floor")
  f:rescale { target = 8000 }
  T.eq(f:counts().triangles, 8000, "a floor is reachable")
  -- half the target where the floor does not allow it: the floor, and why
  ops, n, why = f:rescale { target = 6000 }
  T.eq(n, 8000, "rescale to half the target under a floor of 8000: stops at the floor")
  T.eq(why, "the hierarchy goes no coarser (hierarchy_floor)", "and says why")
  -- saved and loaded: the whole hierarchy
  h:rescale { target = 12000 }
  h:save(tmp("below.flh"))
  local g <close> = femlod.load_hierarchy(tmp("below.flh"))
  T.eq(g:collapses(), h:collapses(), "the .flh keeps the whole hierarchy")
  ops, n, why = g:rescale { target = 100 }
  T.eq(n, S.hierarchy_triangles, "a loaded hierarchy reaches the coarsest")
  T.eq(why, S.hierarchy_binding, "and knows why it stops there")
  T.errmsg("code:1: bad argument #1 to 'simplify' (hierarchy_floor: integer >= 1 or boolean expected, got 0)",
    "m:simplify { target = 10, hierarchy_floor = 0 }", { m = fandisk })
end

-- the card's recipe on a generated part: the plate to 8,000 with the card's
-- thresholds (at 4,000 the plain simplification keeps 3 of the 1,141
-- high-kappa vertices, too few to compare)
do
  local plate <close> = bumpy_plate()
  -- in the paper's order: the default keeps every high-kappa vertex of the
  -- plate at 8,000 (1,141 of 1,141; refine_curvature then finds nothing to
  -- refine: 8,004 triangles), checked below
  local opts = { target = 8000, tolerance = 0.15, min_stretch = 0.2, max_size = 15, max_valence = 12,
    error_order = false }
  do
    local d <close> = plate:simplify { target = 8000, tolerance = 0.15, min_stretch = 0.2, max_size = 15,
      max_valence = 12 }
    local sorted = {}
    for i, k in ipairs(plate:curvature().kappa) do sorted[i] = k end
    table.sort(sorted)
    local top, total = sorted[math.ceil(0.95 * #sorted)], 0
    for _, k in ipairs(sorted) do if k >= top then total = total + 1 end end
    local dk = high_kappa_kept(plate, d)
    print(string.format("plate, default order: %d of the %d high-kappa input vertices kept at 8,000", dk, total))
    T.eq(dk, total, "plate, default order: every high-kappa input vertex kept at 8,000")
  end
  local h <close> = plate:simplify(opts)
  local k_plain = high_kappa_kept(plate, h)
  h:refine_curvature {}
  T.check(h:counts().triangles > 20000, "plate: refine_curvature from 8,000: " .. h:counts().triangles)
  local _, n, why = h:rescale { target = 8000 }
  T.check(math.abs(n - 8000) <= 40, "plate: the recipe's rescale back: within 0.5% of 8,000: " .. n)
  T.eq(why, nil, "plate: no reason")
  local kept = high_kappa_kept(plate, h)
  T.check(k_plain >= 20, "plate: the plain simplification keeps some high-kappa vertices: " .. k_plain)
  T.check(kept >= 1.25 * k_plain, string.format(
    "plate: the recipe keeps >= 1.25x the plain simplification's high-kappa input vertices: %d against %d", kept, k_plain))
  print(string.format("plate recipe: %d high-kappa input vertices kept against the plain simplification's %d (%.2fx)",
    kept, k_plain, kept / k_plain))
  local q = h:mesh():quality()
  T.check(q.manifold and q.stretch_min >= 0.2 - 1e-12 and q.size_max <= 15 + 1e-9 and q.valence_max <= 12,
    "plate: the recipe's result meets the thresholds")
  T.eq(h:validate(), true, "plate: valid")
  -- half the target from the recipe's front: the thresholds allow it
  _, n, why = h:rescale { target = 4000 }
  T.check(math.abs(n - 4000) <= 20 and why == nil, "plate: rescale to half the target within 0.5%: " .. n)
  q = h:mesh():quality()
  T.check(q.manifold and q.stretch_min >= 0.2 - 1e-12 and q.size_max <= 15 + 1e-9 and q.valence_max <= 12,
    "plate: half the target meets the thresholds")
end
-- }======

-- {====== refine_region: region LOD (paper 5.3.1b)
do
  local h <close> = fandisk:simplify { target = 1500, hierarchy_floor = false }
  local base = h:counts().triangles
  local c = fandisk:positions()[1]
  local function inside_nodes(test)
    local fine, n = true, 0
    for _, id in ipairs(h:front()) do
      local node = h:node(id)
      if test(node.position[1], node.position[2], node.position[3]) then
        n = n + 1
        if node.children and node.e_size > 0.01 then fine = false end
      end
    end
    return n, fine
  end
  local r = 0.1
  local function in_sphere(x, y, z) return (x - c[1]) ^ 2 + (y - c[2]) ^ 2 + (z - c[3]) ^ 2 <= r * r end
  local splits, inside = h:refine_region { sphere = { center = c, radius = r }, size = 0.01 }
  T.check(splits > 0 and inside > 0, "sphere: splits and nodes inside")
  local n, fine = inside_nodes(in_sphere)
  T.check(n > 0 and fine, "sphere: every front node inside has e_size <= 0.01 or is a vertex")
  T.eq(h:validate(), true, "valid after refine_region")
  local after = h:counts().triangles
  T.check(after > base, "sphere: more triangles")
  -- the same region again: nothing left to do
  T.eq((h:refine_region { sphere = { center = c, radius = r }, size = 0.01 }), 0, "idempotent")
  -- where: the same sphere as a function; coarsen(math.huge) goes back to
  -- the simplification's result, so one simplification serves every case
  h:coarsen(math.huge)
  T.eq(h:counts().triangles, base, "back to the simplification's result")
  h:refine_region { where = in_sphere, size = 0.01 }
  local n2, fine2 = inside_nodes(in_sphere)
  T.check(n2 > 0 and fine2, "where: every front node inside is fine")
  -- box, vertices, grading false
  local b = h
  b:coarsen(math.huge)
  local s1 = b:refine_region { box = { min = { c[1] - r, c[2] - r, c[3] - r }, max = { c[1] + r, c[2] + r, c[3] + r } },
    size = 0, grading = false }
  T.check(s1 > 0, "box: splits")
  local s2, in2 = b:refine_region { vertices = { 100, 200, 300 }, size = 0 }
  T.check(s2 > 0 and in2 >= 3, "vertices: splits, the 3 leaves inside")
  for _, v in ipairs { 100, 200, 300 } do
    T.eq(b:node(v).state, "front", "vertices: input vertex " .. v .. " is on the front")
  end
  -- a sharp border refines less than a graded one
  local sharp = h
  sharp:coarsen(math.huge)
  sharp:refine_region { sphere = { center = c, radius = r }, size = 0.01, grading = false }
  T.check(sharp:counts().triangles < after, "grading = false: fewer triangles than the default grading")
  local env = { h = h, c = c }
  local pre = "code:1: bad argument #1 to 'refine_region' ("
  T.errmsg(pre .. "no region: give sphere, box, vertices or where)", "h:refine_region{ size = 1 }", env)
  T.errmsg(pre .. "give one region: sphere or box, not both)",
    "h:refine_region{ sphere = { center = c, radius = 1 }, box = {}, size = 1 }", env)
  T.errmsg(pre .. "size: the element size inside the region is required)",
    "h:refine_region{ sphere = { center = c, radius = 1 } }", env)
  T.errmsg(pre .. "size: must be a finite number >= 0)",
    "h:refine_region{ sphere = { center = c, radius = 1 }, size = -1 }", env)
  T.errmsg(pre .. "grading: must be a number >= 1 (or false))",
    "h:refine_region{ sphere = { center = c, radius = 1 }, size = 1, grading = 0.5 }", env)
  T.errmsg(pre .. "grading: number >= 1 or false expected, got true)",
    "h:refine_region{ sphere = { center = c, radius = 1 }, size = 1, grading = true }", env)
  T.errmsg(pre .. "sphere: center: {x, y, z} expected, got nil)",
    "h:refine_region{ sphere = { radius = 1 }, size = 1 }", env)
  T.errmsg(pre .. "sphere: unknown key 'centre'; valid keys: center, radius)",
    "h:refine_region{ sphere = { centre = c, radius = 1 }, size = 1 }", env)
  T.errmsg(pre .. "sphere: radius: finite number >= 0 expected)",
    "h:refine_region{ sphere = { center = c, radius = -1 }, size = 1 }", env)
  T.errmsg(pre .. "sphere: center[2]: finite number expected)",
    "h:refine_region{ sphere = { center = { 1, 'a', 3 }, radius = 1 }, size = 1 }", env)
  T.errmsg(pre .. "box: min[2] > max[2])",
    "h:refine_region{ box = { min = { 0, 1, 0 }, max = { 1, 0, 1 } }, size = 1 }", env)
  T.errmsg(pre .. "vertices: [2]: 0 is not an input vertex (1..6475))",
    "h:refine_region{ vertices = { 1, 0 }, size = 1 }", env)
  T.errmsg(pre .. "vertices: [1]: integer expected, got string)",
    "h:refine_region{ vertices = { 'x' }, size = 1 }", env)
  T.errmsg(pre .. "where: function returned number for node 1 (boolean or nil expected))",
    "h:refine_region{ where = function() return 1 end, size = 1 }", env)
  T.errmsg("code:1: boom", "h:refine_region{ where = function() error('boom') end, size = 1 }", env)
  T.errmsg("code:1: attempt to use a femlod.Hierarchy inside its own size or progress function",
    "h:refine_region{ where = function() h:counts() end, size = 1 }", env)
  T.eq(h:validate(), true, "still valid after the errors")
end
-- }======

-- {====== refine_curvature: curvature LOD (paper 5.3.1a)
do
  local h = fandisk:simplify { target = 2000 }
  local base = h:counts().triangles
  local kappa = fandisk:curvature().kappa -- the same default radius as refine_curvature's
  local sorted = {}
  for i = 1, #kappa do sorted[i] = kappa[i] end
  table.sort(sorted)
  local k_hi, k_lo = sorted[math.ceil(0.95 * #sorted)], sorted[math.ceil(0.1 * #sorted)] -- k_lo: flat (0)
  -- input vertices in a grid of cells, for the nearest input vertex of a point
  local cell, grid = 3 * fandisk:quality().size_max, {}
  local function cell_key(i, j, k) return i .. " " .. j .. " " .. k end
  for i, p in ipairs(input_pos) do
    local ck = cell_key(math.floor(p[1] / cell), math.floor(p[2] / cell), math.floor(p[3] / cell))
    local list = grid[ck] or {}
    grid[ck] = list
    list[#list + 1] = i
  end
  local function nearest(g)
    local ci, cj, ck = math.floor(g[1] / cell), math.floor(g[2] / cell), math.floor(g[3] / cell)
    local best, bd = nil, huge
    for i = ci - 1, ci + 1 do for j = cj - 1, cj + 1 do for k = ck - 1, ck + 1 do
      for _, v in ipairs(grid[cell_key(i, j, k)] or {}) do
        local d = dist(g, input_pos[v])
        if d < bd then best, bd = v, d end
      end
    end end end
    return best
  end
  -- mean triangle area near high-kappa (>= 95th percentile) and flat
  -- (<= 10th percentile: kappa 0 on fandisk) input vertices
  local function sizes(mesh)
    local pos, hi, lo = mesh:positions(), { n = 0, a = 0 }, { n = 0, a = 0 }
    for _, t in ipairs(mesh:triangles()) do
      local a, b, c = pos[t[1]], pos[t[2]], pos[t[3]]
      local u = { b[1] - a[1], b[2] - a[2], b[3] - a[3] }
      local w = { c[1] - a[1], c[2] - a[2], c[3] - a[3] }
      local area = 0.5 * sqrt((u[2] * w[3] - u[3] * w[2]) ^ 2 + (u[3] * w[1] - u[1] * w[3]) ^ 2
        + (u[1] * w[2] - u[2] * w[1]) ^ 2)
      local v = nearest({ (a[1] + b[1] + c[1]) / 3, (a[2] + b[2] + c[2]) / 3, (a[3] + b[3] + c[3]) / 3 })
      local r = v and (kappa[v] >= k_hi and hi or kappa[v] <= k_lo and lo)
      if r then r.n, r.a = r.n + 1, r.a + area end
    end
    return hi.a / hi.n, lo.a / lo.n, hi.n, lo.n
  end
  local hi0, lo0 = sizes(h:mesh())
  local ops = h:refine_curvature {}
  local n = h:counts().triangles
  T.check(ops > 0 and n > base, "refine_curvature{} splits: " .. base .. " -> " .. n)
  local mesh = h:mesh()
  local hi1, lo1, nhi, nlo = sizes(mesh)
  print(string.format("refine_curvature on fandisk -> 2000: %d splits, %d triangles; mean area near "
    .. "high kappa %.4g -> %.4g (%d), near low kappa %.4g -> %.4g (%d)", ops, n, hi0, hi1, nhi, lo0, lo1, nlo))
  T.check(hi1 < 0.5 * lo1, "finer near high curvature than on flat parts")
  T.check(hi1 < 0.5 * hi0, "high-curvature regions became finer")
  local q = mesh:quality()
  T.check(q.stretch_min >= math.min(S.thresholds.min_stretch, fandisk:quality().stretch_min),
    "stretch >= min_stretch or the input's: " .. q.stretch_min)
  T.check(q.valence_max <= S.thresholds.max_valence, "valence <= max_valence")
  T.check(q.closed and q.manifold and q.oriented, "closed, manifold and oriented")
  T.eq(q.degenerate + q.duplicate, 0, "no degenerate or duplicate triangle")
  T.eq(h:validate(), true, "validate after refine_curvature")
  -- coarse defaults to the front's largest e_size, which the refine lowered:
  -- with the values given, a second call has nothing left to split
  T.check(h:refine_curvature { coarse = 0.05 } >= 0, "coarse given")
  T.eq(h:refine_curvature { coarse = 0.05 }, 0, "the same call again: no split")
  -- fine = coarse = 0 everywhere with a map: the input mesh
  T.check(h:refine_curvature { map = function() return 0 end } > 0, "a map function")
  T.eq(h:counts().triangles, fandisk:counts().triangles, "map returning 0: the input's count")
  -- map = "log" refines moderately curved parts more than the linear map
  do
    h:coarsen(math.huge)
    h:refine_curvature {}
    local linear = h:counts().triangles
    h:coarsen(math.huge)
    h:refine_curvature { map = "log" }
    T.check(h:counts().triangles > linear, "log map: more triangles than linear: "
      .. h:counts().triangles .. " vs " .. linear)
    T.eq(h:validate(), true, "valid after the log map")
  end
  -- a map that raises: raised after the core returned, the front still valid
  local h2 = fandisk:simplify { target = 2000 }
  local env = { h = h2 }
  T.errmsg("code:1: boom", "h:refine_curvature { map = function(k) error('boom') end }", env)
  T.eq(h2:validate(), true, "valid after a failing map")
  T.errmsg("code:1: bad argument #1 to 'refine_curvature' (map: function returned string for kappa 32.419175034135 "
    .. "(number expected))", "h:refine_curvature { map = function(k) return 'x' end }", env)
  T.errmsg("code:1: bad argument #1 to 'refine_curvature' (unknown key 'fien'; valid keys: coarse, fine, "
    .. "map, percentile, progress, radius)", "h:refine_curvature { fien = 1 }", env)
  T.errmsg("code:1: bad argument #1 to 'refine_curvature' (map: 'linear', 'log' or function expected, got 'cubic')",
    "h:refine_curvature { map = 'cubic' }", env)
  T.errmsg("code:1: bad argument #1 to 'refine_curvature' (map: 'linear', 'log' or function expected, got number)",
    "h:refine_curvature { map = 3 }", env)
  T.errmsg("code:1: bad argument #1 to 'refine_curvature' (fine: must be a finite number >= 0)",
    "h:refine_curvature { fine = -1 }", env)
  T.errmsg("code:1: bad argument #1 to 'refine_curvature' (coarse: must be a finite number >= 0)",
    "h:refine_curvature { coarse = math.huge }", env)
  T.errmsg("code:1: bad argument #1 to 'refine_curvature' (percentile: must be in (0, 1])",
    "h:refine_curvature { percentile = 0 }", env)
  T.errmsg("code:1: bad argument #1 to 'refine_curvature' (radius: must be a finite number >= 0)",
    "h:refine_curvature { radius = -1 }", env)
  T.errmsg("code:1: bad argument #1 to 'refine_curvature' (a map function replaces fine, coarse and "
    .. "percentile: give one or the other)", "h:refine_curvature { map = function() return 0 end, fine = 1 }", env)
  T.errmsg("code:1: bad argument #1 to 'refine_curvature' (fine: number expected, got string)",
    "h:refine_curvature { fine = 'x' }", env)
  -- an explicit radius recomputes; linear map, explicit values
  T.check(h2:refine_curvature { radius = 0.05, fine = 0.01, percentile = 0.9, map = "linear" } > 0,
    "explicit radius, fine and percentile")
  T.eq(h2:validate(), true, "valid after explicit options")
end
-- }======

T.summary("test_hierarchy")
