-- no_cycles.lua - fails when files of src/ use each other in a circle.
--
-- ARCHITECTURE.md: dependencies run one way; a dispatcher uses the units
-- below it and what they share sits in a unit below them. This reads the
-- object files with nm, says file A uses file B when A refers to a global
-- symbol that B defines, and fails naming every strongly connected
-- component of more than one file, with one circle through it and the
-- symbols behind each step.
--
-- Usage: lua5.4 no_cycles.lua NM LIST [LIST ...]
--   NM    the nm program (CMake's CMAKE_NM)
--   LIST  the object files of one target, separated by ';' (what
--         $<TARGET_OBJECTS:t> gives). A file is named by its path under the
--         target's CMakeFiles/<target>.dir/ folder, less ".o": the same
--         source built into two targets is one file.
--
-- Symbols are matched raw (no demangling), so C++ names match only C++
-- names; symbols no listed object defines (libc, Lua, libstdc++, zlib)
-- make no edge.

local nm, lists = arg[1], {}
for i = 2, #arg do lists[#lists + 1] = arg[i] end

local function fail(msg)
  io.stderr:write("layers_no_cycles: ", msg, "\n")
  os.exit(1)
end

if not nm or nm == "" then fail("usage: lua5.4 no_cycles.lua NM LIST [LIST ...]") end
if #lists == 0 then fail("no object lists given") end

local function quote(s) return "'" .. s:gsub("'", "'\\''") .. "'" end

-- The file an object file was built from, as CMake lays them out.
local function unit_of(obj)
  local rel = obj:match("[/\\]CMakeFiles[/\\][^/\\]+%.dir[/\\](.+)$") or obj
  return (rel:gsub("%.o$", ""):gsub("%.obj$", ""):gsub("\\", "/"))
end

local defs = {}  -- symbol -> set of units that define it
local uses = {}  -- unit -> set of symbols it refers to but does not define
local units, nobj = {}, 0

for li, list in ipairs(lists) do
  local n = 0
  for obj in list:gmatch("[^;]+") do
    n, nobj = n + 1, nobj + 1
    local f = io.open(obj, "rb")
    if not f then fail("cannot open object file " .. obj .. " (build first)") end
    f:close()
    local u = unit_of(obj)
    units[u] = true
    uses[u] = uses[u] or {}
    -- -g: global symbols only (static ones join nothing); -P: "name type
    -- [value size]"; no demangling, so a C++ name is one word.
    local p = assert(io.popen(quote(nm) .. " -g -P --no-demangle " .. quote(obj) .. " 2>&1"))
    local out = p:read("a")
    local ok = p:close()
    if not ok then fail("nm failed on " .. obj .. ":\n" .. out) end
    for line in out:gmatch("[^\n]+") do
      local name, kind, value = line:match("^(%S+) (%a)%s*(%x*)%s*%x*%s*$")
      if name then
        -- U: undefined; w/v without a value: a weak reference.
        if kind == "U" or ((kind == "w" or kind == "v") and value == "") then
          uses[u][name] = true
        else
          defs[name] = defs[name] or {}
          defs[name][u] = true
        end
      end
    end
  end
  if n == 0 then fail("object list " .. li .. " is empty: '" .. list .. "'") end
end
if nobj == 0 then fail("no object files found") end

-- The graph: edge[a][b] = sorted symbols a uses from b.
local names = {}
for u in pairs(units) do names[#names + 1] = u end
table.sort(names)
local edge, nedges = {}, 0
for _, a in ipairs(names) do
  edge[a] = {}
  for sym in pairs(uses[a]) do
    for b in pairs(defs[sym] or {}) do
      if b ~= a then
        if not edge[a][b] then
          edge[a][b] = {}
          nedges = nedges + 1
        end
        table.insert(edge[a][b], sym)
      end
    end
  end
  for _, syms in pairs(edge[a]) do table.sort(syms) end
end
-- Any real build has files calling each other: none means nm's output was
-- not understood, and a test that cannot see edges cannot fail.
if nedges == 0 then
  fail(("%d object files but no uses between them: is %s a working nm?"):format(nobj, nm))
end

local function succ(a)
  local s = {}
  for b in pairs(edge[a]) do s[#s + 1] = b end
  table.sort(s)
  return s
end

-- Tarjan's strongly connected components.
local index, low, onstack, stack, comps, counter = {}, {}, {}, {}, {}, 0
local function connect(v)
  counter = counter + 1
  index[v], low[v] = counter, counter
  stack[#stack + 1], onstack[v] = v, true
  for _, w in ipairs(succ(v)) do
    if not index[w] then
      connect(w)
      low[v] = math.min(low[v], low[w])
    elseif onstack[w] then
      low[v] = math.min(low[v], index[w])
    end
  end
  if low[v] == index[v] then
    local c = {}
    repeat
      local w = table.remove(stack)
      onstack[w] = nil
      c[#c + 1] = w
    until w == v
    table.sort(c)
    comps[#comps + 1] = c
  end
end
for _, v in ipairs(names) do
  if not index[v] then connect(v) end
end

-- A shortest circle from the component's first file back to it (BFS inside it).
local function circle(comp)
  local inside = {}
  for _, v in ipairs(comp) do inside[v] = true end
  local start, prev, queue, head = comp[1], {}, {}, 1
  for _, w in ipairs(succ(start)) do
    if inside[w] and not prev[w] then prev[w] = start; queue[#queue + 1] = w end
  end
  while head <= #queue do
    local v = queue[head]
    head = head + 1
    if v == start then break end
    for _, w in ipairs(succ(v)) do
      if inside[w] and not prev[w] then prev[w] = v; queue[#queue + 1] = w end
    end
  end
  local path, v = {start}, prev[start]
  while v ~= start do table.insert(path, 1, v); v = prev[v] end
  table.insert(path, 1, start)
  return path
end

local function syms(a, b)
  local s = edge[a][b]
  if #s > 6 then return table.concat(s, ", ", 1, 6) .. ", ... (" .. #s .. " symbols)" end
  return table.concat(s, ", ")
end

local bad = {}
for _, c in ipairs(comps) do
  if #c > 1 then bad[#bad + 1] = c end
end
table.sort(bad, function(x, y) return x[1] < y[1] end)

print(("%d object files, %d files, %d uses between files"):format(nobj, #names, nedges))
if #bad == 0 then
  print("no circles")
  os.exit(0)
end
for _, c in ipairs(bad) do
  print(("circle among %d files: %s"):format(#c, table.concat(c, " ")))
  local path = circle(c)
  for i = 1, #path - 1 do
    print(("  %s -> %s  (%s)"):format(path[i], path[i + 1], syms(path[i], path[i + 1])))
  end
  print("  all uses inside it:")
  for _, a in ipairs(c) do
    for _, b in ipairs(c) do
      if edge[a][b] then print(("    %s -> %s  (%s)"):format(a, b, syms(a, b))) end
    end
  end
end
fail(#bad .. " circle(s) between files: move the shared helpers into a unit below both")
