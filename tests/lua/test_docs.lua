-- test_docs.lua: everything public is documented. Every femlod.* value and
-- every method of femlod.Mesh and femlod.Hierarchy is named in
-- docs/lua-api.md (femlod.NAME, m:NAME, h:NAME); every function of the Lua
-- modules femlod.report, femlod.sweep and femlod.progress is named there
-- (report.NAME, sweep.NAME, progress.NAME, or the module's own call); every
-- function and type declared in include/femlod.h is named in docs/api.md;
-- every command of `femlod --help` has its section in docs/cli.md. The lists
-- come from the program and the header, so a new function without docs fails
-- here.

local T = dofile((arg[0]:match("^(.*)/") or ".") .. "/check.lua")
local femlod = require "femlod"

local P = params
assert(P and P.femlod and P.examples and P.shared, "run through ctest: needs femlod=, examples=, shared=")
local ROOT = P.examples .. "/.."

local function read(rel)
  local f = assert(io.open(ROOT .. "/" .. rel, "rb"))
  local s = f:read("a")
  f:close()
  return s
end

local luadoc, apidoc, clidoc = read("docs/lua-api.md"), read("docs/api.md"), read("docs/cli.md")
local function has(doc, text) return doc:find(text, 1, true) ~= nil end

local function sorted_keys(t)
  local k = {}
  for name in pairs(t) do if type(name) == "string" then k[#k + 1] = name end end
  table.sort(k)
  return k
end

-- {====== Lua: the module table and the two object types
local checked = 0
for _, name in ipairs(sorted_keys(femlod)) do
  if not name:match("^_[a-z]") then -- _viewer_js and friends are internal; _VERSION is public
    T.check(has(luadoc, "femlod." .. name), "docs/lua-api.md names femlod." .. name)
    checked = checked + 1
  end
end
T.check(checked >= 8, "the module has its functions: " .. checked)

local function methods(obj, prefix)
  local mt = getmetatable(obj)
  local index = type(mt) == "table" and mt.__index
  T.eq(type(index), "table", prefix .. ": methods in a table")
  if type(index) ~= "table" then return end
  local n = 0
  for _, name in ipairs(sorted_keys(index)) do
    T.check(has(luadoc, prefix .. name .. "(") or has(luadoc, prefix .. name .. " ") or has(luadoc, prefix .. name .. "{"),
      "docs/lua-api.md names " .. prefix .. name)
    n = n + 1
  end
  T.check(n >= 5, prefix .. " has its methods: " .. n)
end

local m <close> = femlod.load(P.shared .. "/fandisk.obj")
methods(m, "m:")
local h <close> = m:simplify { target = 6000 }
methods(h, "h:")
-- }======

-- {====== the Lua modules of lua/femlod
for _, mod in ipairs { "report", "sweep", "progress" } do
  local M = require("femlod." .. mod)
  local n = 0
  for _, name in ipairs(sorted_keys(M)) do
    if type(M[name]) == "function" then
      T.check(has(luadoc, mod .. "." .. name) or has(luadoc, "femlod." .. mod .. "." .. name),
        "docs/lua-api.md names " .. mod .. "." .. name)
      n = n + 1
    end
  end
  T.check(n >= 1, "femlod." .. mod .. " has functions: " .. n)
end
-- }======

-- {====== C: every function and type of include/femlod.h in docs/api.md
do
  local header = read("include/femlod.h")
  -- drop comments so that names mentioned in them do not count
  header = header:gsub("/%*.-%*/", " "):gsub("//[^\n]*", " ")
  local seen, n = {}, 0
  for name in header:gmatch("(femlod_[%w_]+)%s*%(") do
    if not seen[name] then
      seen[name] = true
      n = n + 1
      T.check(has(apidoc, name), "docs/api.md names " .. name .. "()")
    end
  end
  -- types: "typedef ... name;" and "} name;"
  for _, pattern in ipairs { "typedef%s+[%w_%s%*]-(femlod_[%w_]+)%s*;", "}%s*(femlod_[%w_]+)%s*;" } do
    for name in header:gmatch(pattern) do
      if not seen[name] then
        seen[name] = true
        T.check(has(apidoc, name), "docs/api.md names the type " .. name)
      end
    end
  end
  T.check(n >= 40, "the header's functions were found: " .. n)
end
-- }======

-- {====== CLI: every command of --help has a section in docs/cli.md
do
  local p = assert(io.popen(T.quote(P.femlod) .. " --help", "r"))
  local help = p:read("a")
  p:close()
  local commands = help:match("\nCommands:\n(.-)\n\n") or help
  local n = 0
  for name in commands:gmatch("\n  ([a-z]+) ") do
    n = n + 1
    T.check(clidoc:find("\n## `femlod " .. name, 1, true) or clidoc:find("\n### `femlod " .. name, 1, true),
      "docs/cli.md has a section for femlod " .. name)
  end
  T.check(n >= 8, "--help lists the commands: " .. n)
end
-- }======

T.summary()
