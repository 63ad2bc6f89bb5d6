-- module.lua: femlod.so in the stock interpreter (lua5.4 has the Lua core
-- built in; the module must bring no second copy). Run by ctest as
--   LUA_CPATH_5_4="BUILD/?.so;;" lua5.4 module.lua TESTS/data
-- arg[1] is the tests/data folder; the examples are two folders up from it.

local T = dofile((arg[0]:match("^(.*)/") or ".") .. "/check.lua")
local data = assert(arg[1], "usage: lua5.4 module.lua TESTS_DATA_DIR")
local examples = data .. "/../../examples"

T.eq(params, nil, "the stock interpreter has no params")

-- The helper first: the all-in-one loader finds luaopen_femlod_report in
-- femlod.so, so the embedded helper loads without any package.path.
local globals_before = {}
for k in pairs(_G) do globals_before[k] = true end
local report = require "femlod.report"
T.eq(type(report), "table", "require 'femlod.report' before 'femlod'")
T.eq(type(report.text), "function", "report.text")

local femlod = require "femlod"
T.eq(type(femlod), "table", "require 'femlod'")
T.eq(femlod._VERSION, "femlod 0.1.0", "_VERSION")
T.check(package.searchpath("femlod", package.cpath), "found through LUA_CPATH_5_4")
T.eq(require "femlod", femlod, "require returns the same table")
T.eq(require "femlod.report", report, "the helper is loaded once")
local new_globals = {}
for k in pairs(_G) do if not globals_before[k] then new_globals[#new_globals + 1] = k end end
T.eq(table.concat(new_globals, ","), "", "require sets no globals")
T.eq(package.preload["femlod.report"] ~= nil, true, "luaopen_femlod registers its helpers in package.preload")

-- Load the example mesh, and build and save one.
local m = femlod.load(examples .. "/data/fandisk.obj")
T.eq(tostring(m), "femlod.Mesh (12946 triangles, 6475 vertices)", "fandisk loaded")
local c = m:counts()
T.eq(c.triangles, 12946, "fandisk triangles")
T.eq(c.vertices, 6475, "fandisk vertices")
T.eq(m:quality().valence_max, 9, "quality works")
T.check(report.text(m, "fandisk.obj"):find("^fandisk%.obj: 12946 triangles, 6475 vertices\n"), "report of a Mesh")

local tmp = os.tmpname()
local file = tmp .. ".ply"
local tri = femlod.mesh { positions = { 0, 0, 0, 1, 0, 0, 0, 1, 0 }, triangles = { 1, 2, 3 } }
tri:save(file)
local back = femlod.load(file)
T.eq(back:counts().triangles, 1, "saved and loaded")
T.eq(back:positions()[2][1], 1, "positions survive")
os.remove(file)
os.remove(tmp)

-- Errors carry the caller's position in the stock interpreter too.
local line, msg = T.line(), select(2, pcall(function() femlod.load(nil) end))
T.check(tostring(msg):find("module%.lua:" .. line .. ": bad argument #1 to 'load' %(string expected, got nil%)"),
  "error position: " .. tostring(msg))

-- Life cycle under the stock collector.
do
  local x <close> = m:copy()
  T.eq(x:counts().vertices, 6475, "copy")
end
m:close()
T.checkerr("attempt to use a closed femlod%.Mesh", function() return m:counts() end)
for _ = 1, 20 do local _ = tri:subdivide(3) end
collectgarbage()

-- The quickstart example runs here too (params is nil, arg[0] is the script).
do
  local saved_arg = arg
  arg = { [0] = examples .. "/quickstart.lua" }
  local out = {}
  local saved_print = print
  print = function(s) out[#out + 1] = s end
  local ok, err = pcall(dofile, examples .. "/quickstart.lua")
  print, arg = saved_print, saved_arg
  T.check(ok, "quickstart in lua5.4: " .. tostring(err))
  T.check((out[1] or ""):find("^fandisk%.obj: 12946 triangles"), "quickstart output")
end

T.summary("module")
