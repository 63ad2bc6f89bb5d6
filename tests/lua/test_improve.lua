-- test_improve.lua: m:improve and `femlod improve`: the report's counts are
-- the output's (measured here), option errors, determinism, the command.
-- Run by ctest: femlod run test_improve.lua femlod=... tmp=... shared=...

local T = dofile((arg[0]:match("^(.*)/") or ".") .. "/check.lua")
local femlod = require "femlod"

local P = params
assert(P and P.shared and P.tmp and P.femlod, "run through ctest: needs shared=, tmp=, femlod=")

local m = femlod.load(P.shared .. "/spider_binary.stl")
local better, rep = m:improve{}
local q = better:quality()
T.check(rep.triangles == q.triangles, "triangles")
-- the remaining count is the output's
local below = 0
for k = 1, 2 do below = below + (q.histogram[k] or 0) end
T.check(rep.remaining.stretch == below, "remaining stretch " .. rep.remaining.stretch .. " vs " .. below)
T.check(rep.remaining.stretch < rep.input.stretch, "fewer below min_stretch")
local sum = 0
for _, n in pairs(rep.remaining_by.stretch) do sum = sum + n end
T.check(sum == rep.remaining.stretch, "reasons add up")
T.check(rep.min_stretch == 0.2 and rep.max_valence == 12 and rep.max_size == false, "defaults")
T.check(rep.operations.flip > 0 and rep.operations.split > 0, "operations counted")
-- deterministic
local again = m:improve{}
local function bytes(mesh, name)
  mesh:save(P.tmp .. "/" .. name)
  local f = assert(io.open(P.tmp .. "/" .. name, "rb"))
  local s = f:read("a")
  f:close()
  return s
end
T.check(bytes(again, "improve_a.obj") == bytes(better, "improve_b.obj"), "same bytes")
-- options
local function err_has(opts, text)
  local ok, msg = pcall(function() return m:improve(opts) end)
  T.check(not ok and tostring(msg):find(text, 1, true) ~= nil, "error " .. tostring(msg) .. " lacks " .. text)
end
err_has({ min_stretch = 2 }, "min_stretch: number in (0, 1] or false expected")
err_has({ min_strech = 0.3 }, "unknown key 'min_strech'")
err_has({ lock = { 99999 } }, "lock[1]: index out of range")
local _, off = m:improve{ max_valence = false, min_stretch = 0.1 }
T.check(off.max_valence == false and off.min_stretch == 0.1, "false switches off")

-- the command
local out = P.tmp .. "/improve_spider.obj"
local cmd = string.format("%q improve %q %q --max-rounds 5 > %q", P.femlod, P.shared .. "/spider_binary.stl", out,
  P.tmp .. "/improve_spider.txt")
T.check(os.execute(cmd) == true, "femlod improve runs")
local f = assert(io.open(P.tmp .. "/improve_spider.txt"))
local text = f:read("a")
f:close()
T.check(text:find("triangles below min_stretch", 1, true) ~= nil, "prints the counts")
T.check(femlod.load(out):quality().triangles > 0, "writes OUT")

T.summary("test_improve")
