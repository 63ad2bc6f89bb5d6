-- femlod.sweep: parameter grids and the record of what a run read and wrote.
--
--   local sweep = require "femlod.sweep"
--   for i, p in ipairs(sweep.points { {"target", {6000, 12000}}, {"tolerance", {0.05, 0.15}} }) do
--     ...                      -- p.target, p.tolerance; the last name varies fastest
--   end
--   sweep.record { iterations = 12, note = "coarse" }   -- extra columns of results.csv
--   if sweep.active() then ... end                      -- run by `femlod sweep` (or --record)
--
-- `femlod sweep` runs a recipe once per grid point, each in its own process
-- started as `femlod --record FILE run RECIPE ...`. --record makes the program
-- call start() before the recipe and write the table that result() returns
-- (with SHA-256 of every file) after it. While recording, every file that
-- femlod.load, femlod.load_hierarchy, m:save and h:save read or write is
-- logged, and every mesh saved gets its Table 1 figures and, when the run
-- loaded a mesh first, its Hausdorff deviation from that mesh.
-- Plain Lua: without the program, start() and result() still work.

local type, error, pairs, ipairs, tostring, getmetatable = type, error, pairs, ipairs, tostring, getmetatable
local format, sort, table_remove = string.format, table.sort, table.remove

local _ENV = nil -- no global access after this point

local M = {}

local function typename(v)
  local mt = type(v) == "userdata" and getmetatable(v)
  return type(mt) == "table" and mt.__name or type(v)
end

-- {====== grids

-- grid: a list of {name, values} pairs, in the order of the axes. Returns
-- the cartesian product as a list of {name = value} tables, the first axis
-- varying slowest and the last fastest (like nested for loops in that
-- order, and like `femlod sweep`'s --grid flags).
function M.points(grid)
  if type(grid) ~= "table" then
    error(format("bad argument #1 to 'points' (table expected, got %s)", typename(grid)), 2)
  end
  local names, values, seen = {}, {}, {}
  for i, axis in ipairs(grid) do
    if type(axis) ~= "table" or type(axis[1]) ~= "string" or type(axis[2]) ~= "table" then
      error(format("bad argument #1 to 'points' (axis %d: {name, {values...}} expected)", i), 2)
    end
    local name, list = axis[1], axis[2]
    if seen[name] then
      error(format("bad argument #1 to 'points' (axis '%s' given twice)", name), 2)
    end
    if #list == 0 then
      error(format("bad argument #1 to 'points' (axis '%s' has no values)", name), 2)
    end
    seen[name] = true
    names[i], values[i] = name, list
  end
  local out = {}
  if #names == 0 then return out end
  local idx = {}
  for i = 1, #names do idx[i] = 1 end
  while true do
    local p = {}
    for i, name in ipairs(names) do p[name] = values[i][idx[i]] end
    out[#out + 1] = p
    local k = #names
    while k >= 1 do
      idx[k] = idx[k] + 1
      if idx[k] <= #values[k] then break end
      idx[k] = 1
      k = k - 1
    end
    if k == 0 then return out end
  end
end

-- }======

-- {====== the record

local state -- set by start()

local function fresh()
  return { reads = {}, writes = {}, seen = {}, meshes = {}, mesh_at = {}, recorded = {},
    reference = nil, active = false, params = {} }
end
state = fresh()

-- The Table 1 figures of a saved mesh (and its deviation from the reference).
local function mesh_entry(path, mesh)
  local q = mesh:quality(state.reference)
  return {
    path = path, triangles = q.triangles, vertices = q.vertices,
    stretch_avg = q.stretch_avg, stretch_min = q.stretch_min, size_max = q.size_max,
    valence_max = q.valence_max, hausdorff = q.hausdorff, hausdorff_rel = q.hausdorff_rel,
  }
end

local function hook(kind, path, object)
  local list = kind == "read" and state.reads or state.writes
  local key = kind .. "\0" .. path
  if not state.seen[key] then
    state.seen[key] = true
    list[#list + 1] = path
  end
  local tname = typename(object)
  if tname ~= "femlod.Mesh" then return end
  if kind == "read" then
    -- The first mesh read is the input the deviation is measured from.
    if not state.reference then state.reference = object:copy() end
  else
    local e = mesh_entry(path, object)
    local at = state.mesh_at[path]
    if at then
      state.meshes[at] = e
    else
      state.meshes[#state.meshes + 1] = e
      state.mesh_at[path] = #state.meshes
    end
  end
end

-- Logs a file read or written by a helper that does not go through the
-- binding (femlod.report's HTML pages); nothing when not recording.
function M.log(kind, path)
  if state.active and (kind == "read" or kind == "write") and type(path) == "string" then
    hook(kind, path)
  end
end

-- Drops a path from the log (a helper's temporary file, removed again).
function M.forget(path)
  for _, kind in ipairs { "read", "write" } do
    local key = kind .. "\0" .. path
    if state.seen[key] then
      state.seen[key] = nil
      local list = kind == "read" and state.reads or state.writes
      for i = #list, 1, -1 do
        if list[i] == path then table_remove(list, i) end
      end
    end
  end
  local at = state.mesh_at[path]
  if at then
    table_remove(state.meshes, at)
    state.mesh_at = {}
    for i, e in ipairs(state.meshes) do state.mesh_at[e.path] = i end
  end
end

-- Starts a record: params (copied now, so that the record shows what the
-- run was given) and an optional list of files already read (the recipe).
-- Returns the function the binding calls on every read and write.
function M.start(params, files)
  state = fresh()
  state.active = true
  if type(params) == "table" then
    for k, v in pairs(params) do
      if type(k) == "string" then state.params[k] = v end
    end
  end
  for _, f in ipairs(files or {}) do hook("read", f) end
  return hook
end

function M.active()
  return state.active
end

-- The mesh deviations are measured from (a copy), by default the first mesh
-- read; a recipe that builds its input another way sets it here.
function M.reference(mesh)
  if typename(mesh) ~= "femlod.Mesh" then
    error(format("bad argument #1 to 'reference' (femlod.Mesh expected, got %s)", typename(mesh)), 2)
  end
  state.reference = mesh:copy()
end

local function valid_key(k)
  return type(k) == "string" and k:match("^[%a_][%w_.-]*$") ~= nil
end

-- Figures the recipe reports: string keys (letters, digits, _ . -), values
-- finite numbers, strings or booleans. Later calls add to and overwrite
-- earlier ones.
function M.record(t)
  if type(t) ~= "table" then
    error(format("bad argument #1 to 'record' (table expected, got %s)", typename(t)), 2)
  end
  for k, v in pairs(t) do
    if not valid_key(k) then
      error(format("bad argument #1 to 'record' (key %s: a name of letters, digits, _ . - expected)",
        type(k) == "string" and format("%q", k) or tostring(k)), 2)
    end
    local ok = type(v) == "string" or type(v) == "boolean"
      or (type(v) == "number" and v == v and v ~= 1 / 0 and v ~= -1 / 0)
    if not ok then
      error(format("bad argument #1 to 'record' (%s: string, finite number or boolean expected, got %s)",
        k, typename(v)), 2)
    end
  end
  for k, v in pairs(t) do state.recorded[k] = v end
end

local function copy_list(l)
  local c = {}
  for i, v in ipairs(l) do c[i] = v end
  return c
end

-- What the run read and wrote so far: { reads = {path...}, writes = {path...} },
-- each in the order of first use.
function M.files()
  return { reads = copy_list(state.reads), writes = copy_list(state.writes) }
end

-- The record: params, reads, writes (paths), meshes (one entry per mesh file
-- written: path, triangles, vertices, stretch_avg, stretch_min, size_max,
-- valence_max, and hausdorff, hausdorff_rel when there was a reference),
-- recorded (what record() got).
function M.result()
  local meshes = {}
  for i, e in ipairs(state.meshes) do
    local c = {}
    for k, v in pairs(e) do c[k] = v end
    meshes[i] = c
  end
  local params, recorded = {}, {}
  for k, v in pairs(state.params) do params[k] = v end
  for k, v in pairs(state.recorded) do recorded[k] = v end
  return { params = params, reads = copy_list(state.reads), writes = copy_list(state.writes),
    meshes = meshes, recorded = recorded }
end

-- Names sorted, for writers that need a repeatable order.
function M.sorted_keys(t)
  local keys = {}
  for k in pairs(t) do keys[#keys + 1] = k end
  sort(keys, function(a, b) return tostring(a) < tostring(b) end)
  return keys
end

-- }======

return M
