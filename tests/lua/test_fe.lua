-- test_fe.lua: the finite-element formats from Lua (docs/formats.md): exact
-- round trips through .msh (4.1 and format = "msh2") and .mesh, the .inp
-- sets given as nsets/elsets (lists and functions, sorted names), every
-- option error with its text, and `femlod convert` choosing by extension.
-- The real tools (gmsh, tetgen, ccx) run in fe_tools.lua (label heavy).

local T = dofile((arg[0]:match("^(.*)/") or ".") .. "/check.lua")
local femlod = require "femlod"

local P = params
assert(P and P.tmp and P.shared and P.femlod, "run through ctest: needs tmp=, shared= and femlod=")
local function path(name) return P.tmp .. "/fe_" .. name end

local function same(a, b, msg)
  local pa, pb, ta, tb = a:positions(), b:positions(), a:triangles(), b:triangles()
  local ok = #pa == #pb and #ta == #tb
  for i = 1, ok and #pa or 0 do
    for k = 1, 3 do ok = ok and pa[i][k] == pb[i][k] end
  end
  for i = 1, ok and #ta or 0 do
    for k = 1, 3 do ok = ok and ta[i][k] == tb[i][k] end
  end
  T.check(ok, msg)
end

local fandisk <close> = femlod.load(P.shared .. "/fandisk.obj")

-- {====== round trips: every double, every index
for _, case in ipairs {
  { "fandisk.msh" }, { "fandisk2.msh", { format = "msh2" } }, { "fandisk.mesh" },
  { "fandisk_medit.txt", { format = "medit" } },
} do
  local p = path(case[1])
  fandisk:save(p, case[2])
  local back <close> = femlod.load(p, case[2] and { format = case[2].format } or nil)
  same(fandisk, back, "round trip through " .. case[1])
end
local text = T.readfile(path("fandisk2.msh"))
T.check(text:find("^%$MeshFormat\n2%.2 0 8\n"), "format = 'msh2' writes MSH 2.2")
text = T.readfile(path("fandisk.msh"))
T.check(text:find("^%$MeshFormat\n4%.1 0 8\n"), ".msh writes MSH 4.1")
-- }======

-- {====== .inp sets
local plane <close> = femlod.mesh {
  positions = { { 0, 0, 0 }, { 1, 0, 0 }, { 1, 1, 0 }, { 0, 1, 0 } },
  triangles = { { 1, 2, 3 }, { 1, 3, 4 } },
}
local inp = path("plane.inp")
plane:save(inp, {
  nsets = { left = function(x) return x == 0 end, Corner = { 3, 3, 1 } },
  elsets = { upper = function(x, y) return y > x end, first = { 1 } },
})
T.eq(T.readfile(inp),
  "** " .. femlod._VERSION .. ": 4 nodes, 2 S3 elements\n" ..
  "*NODE, NSET=NALL\n1, 0, 0, 0\n2, 1, 0, 0\n3, 1, 1, 0\n4, 0, 1, 0\n" ..
  "*ELEMENT, TYPE=S3, ELSET=EALL\n1, 1, 2, 3\n2, 1, 3, 4\n" ..
  "*NSET, NSET=NBOUNDARY\n1, 2, 3, 4\n*NSET, NSET=NFEATURE\n1, 2, 3, 4\n" ..
  "*NSET, NSET=Corner\n1, 3\n*NSET, NSET=left\n1, 4\n" ..
  "*ELSET, ELSET=first\n1\n*ELSET, ELSET=upper\n2\n",
  "the .inp file with sets sorted by name")

local env = { plane = plane, p = inp, msh = path("sets.msh") }
T.errmsg("code:1: bad argument #2 to 'save' (nsets: table of name = indices or function expected, got number)",
  "plane:save(p, { nsets = 5 })", env)
T.errmsg("code:1: bad argument #2 to 'save' (nsets: fixed[2]: index 5 out of range (1..4))",
  "plane:save(p, { nsets = { fixed = { 1, 5 } } })", env)
T.errmsg("code:1: bad argument #2 to 'save' (nsets: fixed[1]: integer index expected, got number)",
  "plane:save(p, { nsets = { fixed = { 1.5 } } })", env)
T.errmsg("code:1: bad argument #2 to 'save' (elsets: e: function returned number for triangle 1 (boolean or nil expected))",
  "plane:save(p, { elsets = { e = function() return 1 end } })", env)
T.errmsg("code:1: bad argument #2 to 'save' (nsets: set names must be strings, got number)",
  "plane:save(p, { nsets = { { 1 } } })", env)
T.errmsg("code:1: bad argument #2 to 'save' (nsets: s: list of indices or function expected, got string)",
  "plane:save(p, { nsets = { s = 'x' } })", env)
T.errmsg("code:1: " .. inp .. ": node set name 'NALL' is reserved (NALL, EALL, NBOUNDARY, NFEATURE)",
  "plane:save(p, { nsets = { NALL = { 1 } } })", env)
T.errmsg("code:1: " .. inp .. ": node set 'nothing' is empty",
  "plane:save(p, { nsets = { nothing = function() return false end } })", env)
T.errmsg("code:1: " .. inp .. ": node set name 'a-b' is not valid (a letter, then letters, digits or '_', at most 80)",
  "plane:save(p, { nsets = { ['a-b'] = { 1 } } })", env)
T.errmsg("code:1: " .. env.msh .. ": node and element sets are written to .inp only (format msh)",
  "plane:save(msh, { nsets = { a = { 1 } } })", env)
T.check(not T.exists(env.msh), "a refused save writes nothing")
-- the .inp from before is intact after the refused saves
T.check(T.readfile(inp):find("NSET=Corner", 1, true), "refused saves leave the old file")
T.errmsg("code:1: " .. path("x.vtk") .. ": femlod writes vtk files but does not read them " ..
  "(formats read: obj, stl, off, ply, gltf, glb, msh, medit)",
  "femlod.load(p)", { femlod = femlod, p = (plane:save(path("x.vtk")) or path("x.vtk")) })
-- }======

-- {====== femlod convert: format by extension, msh2 by name
local function run(...)
  local parts = { string.format("%q", P.femlod) }
  for _, a in ipairs { ... } do parts[#parts + 1] = string.format("%q", a) end
  local p = assert(io.popen(table.concat(parts, " ") .. " 2>&1", "r"))
  local out = p:read("a")
  local ok, _, code = p:close()
  return ok and 0 or code, out
end
local code, out = run("convert", P.shared .. "/fandisk.obj", path("cli.msh"), "format=msh2")
T.eq(code, 0, "convert to msh2")
T.eq(out, path("cli.msh") .. ": 12946 triangles, 6475 vertices (msh2)\n", "convert output")
code, out = run("convert", path("cli.msh"), path("cli.vtk"))
T.eq(out, path("cli.vtk") .. ": 12946 triangles, 6475 vertices (vtk)\n", "convert msh to vtk")
T.check(T.readfile(path("cli.vtk")):find("\nCELLS 12946 51784\n", 1, true), "vtk CELLS line")
code, out = run("convert", path("cli.msh"), path("cli.x"), "format=msh3")
T.eq(code, 2, "an unknown format is a usage error (exit 2)")
T.check(out:find("unknown format 'msh3'; did you mean msh? (valid: obj, stl, stl_ascii, stl_binary, off, ply, " ..
  "ply_ascii, ply_binary, gltf, glb, msh, msh2, vtk, inp, medit)", 1, true), "lists the formats")
-- }======

for _, f in ipairs { "fandisk.msh", "fandisk2.msh", "fandisk.mesh", "fandisk_medit.txt", "plane.inp",
  "x.vtk", "cli.msh", "cli.vtk" } do os.remove(path(f)) end
T.summary("test_fe")
