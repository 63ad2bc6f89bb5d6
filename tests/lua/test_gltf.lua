-- test_gltf.lua: glTF from Lua and the command line: femlod.load of .glb and
-- .gltf, mesh:save with color_by, normals and extras (written where a viewer
-- and a script find them), round trips to float32, the option errors (with
-- the valid keys and values listed), and `femlod convert` to glTF.

local T = dofile((arg[0]:match("^(.*)/") or ".") .. "/check.lua")
local femlod = require "femlod"

local P = params
assert(P and P.femlod and P.tmp and P.shared and P.data, "run through ctest: needs femlod=, tmp=, shared=, data=")
local function path(name) return P.tmp .. "/gltf_" .. name end

local function f32(x) return (string.unpack("<f", string.pack("<f", x))) end

-- The triangle soup (corner positions in triangle order), optionally rounded.
local function soup(m, round)
  local p, out = m:positions(), {}
  for _, t in ipairs(m:triangles()) do
    for k = 1, 3 do
      for c = 1, 3 do
        local x = p[t[k]][c]
        out[#out + 1] = round and round(x) or x
      end
    end
  end
  return out
end

local function same_soup(a, b, msg)
  if #a ~= #b then return T.eq(#b, #a, msg .. ": soup size") end
  for i = 1, #a do
    if a[i] ~= b[i] then return T.eq(b[i], a[i], msg .. ": corner coordinate " .. i) end
  end
  return T.check(true)
end

-- The JSON chunk of a GLB file.
local function glb_json(file)
  local s = assert(T.readfile(file))
  T.eq(s:sub(1, 4), "glTF", file .. ": GLB magic")
  local len = string.unpack("<I4", s, 13)
  return s:sub(21, 20 + len)
end

-- {====== loading
do
  local m <close> = femlod.load(P.shared .. "/2CylinderEngine.glb")
  local c = m:counts()
  T.eq(c.triangles, 121496, "2CylinderEngine triangles")
  T.eq(c.vertices, 60041, "2CylinderEngine welded vertices")
  local b = m:bbox()
  T.rel(b.min[1], -371.692, 1e-5, "bbox min x")
  T.rel(b.max[2], 92.0416, 1e-5, "bbox max y")
  T.rel(m:quality().stretch_avg, 0.40900522, 1e-6, "stretch avg")

  local e <close> = femlod.load(P.data .. "/tiny_external.gltf", { format = "gltf" })
  T.eq(e:counts().triangles, 2, "external buffer")
  T.eq(e:positions()[1][1], 10.0, "node translation applied")
end
-- }======

-- {====== saving with color_by, normals, extras
do
  local m <close> = femlod.load(P.shared .. "/fandisk.obj")
  local want = soup(m, f32)
  local glb = path("fandisk.glb")
  m:save(glb, { color_by = "stretch", normals = true,
                extras = { recipe = "test_gltf.lua", min_stretch = 0.3, steps = 2, dry = false,
                           note = 'quote " and \\ and \n' } })
  local json = glb_json(glb)
  T.check(json:find('"generator":"femlod 0.1.0"', 1, true), "generator")
  T.check(json:find('"COLOR_0":', 1, true), "COLOR_0 written")
  T.check(json:find('"_STRETCH":', 1, true), "_STRETCH written")
  T.check(json:find('"NORMAL":', 1, true), "NORMAL written")
  T.check(json:find('"KHR_materials_unlit":{}', 1, true), "unlit material")
  T.check(json:find('"params":{"dry":false,"min_stretch":0.3,"note":"quote \\" and \\\\ and \\n",'
                    .. '"recipe":"test_gltf.lua","steps":2}', 1, true), "extras as params, sorted: " .. json:sub(1, 600))
  T.check(json:find('"triangles":12946', 1, true), "quality in extras")
  local back <close> = femlod.load(glb)
  T.eq(back:counts().vertices, 6475, "welded back")
  same_soup(want, soup(back), "OBJ -> GLB (flat colours) -> mesh, to float32")

  local gltf = path("fandisk.gltf")
  m:save(gltf, { color_by = "valence" })
  local text = assert(T.readfile(gltf))
  T.eq(text:sub(1, 1), "{", ".gltf is JSON")
  T.check(text:find('"uri": "data:application/octet-stream;base64,', 1, true), "embedded buffer")
  local back2 <close> = femlod.load(gltf)
  same_soup(want, soup(back2), "OBJ -> glTF -> mesh, to float32")

  -- "gltf" names the family: GLB for a .glb name; "glb" forces GLB.
  m:save(path("forced.bin"), { format = "glb" })
  T.eq(assert(T.readfile(path("forced.bin"))):sub(1, 4), "glTF", "format = glb")
  m:save(path("family.glb"), { format = "gltf" })
  T.eq(assert(T.readfile(path("family.glb"))):sub(1, 4), "glTF", "format = gltf, .glb name")
end
-- }======

-- {====== errors
do
  local m <close> = femlod.mesh { positions = { { 0, 0, 0 }, { 1, 0, 0 }, { 0, 1, 0 } }, triangles = { { 1, 2, 3 } } }
  local env = { m = m, out = path("e.glb"), obj = path("e.obj") }
  T.errmsg("code:1: bad argument #2 to 'save' (unknown key 'colour_by'; valid keys: color_by, elsets, extras, format, normals, nsets)",
    "m:save(out, { colour_by = 'stretch' })", env)
  T.errmsg("code:1: bad argument #2 to 'save' (color_by: invalid value 'quality'; valid values: none, stretch, size, valence)",
    "m:save(out, { color_by = 'quality' })", env)
  T.errmsg("code:1: bad argument #2 to 'save' (normals: boolean expected, got number)",
    "m:save(out, { normals = 1 })", env)
  T.errmsg("code:1: bad argument #2 to 'save' (extras: table expected, got string)",
    "m:save(out, { extras = '{}' })", env)
  T.errmsg("code:1: bad argument #2 to 'save' (extras: keys must be strings, got number)",
    "m:save(out, { extras = { 1 } })", env)
  T.errmsg("code:1: bad argument #2 to 'save' (extras: x: string, finite number or boolean expected, got table)",
    "m:save(out, { extras = { x = {} } })", env)
  T.errmsg("code:1: bad argument #2 to 'save' (extras: x: string, finite number or boolean expected, got number)",
    "m:save(out, { extras = { x = 0/0 } })", env)
  T.errmsg("code:1: " .. env.obj .. ": color_by, normals and extras are glTF options (format obj)",
    "m:save(obj, { color_by = 'stretch' })", env)
  T.check(not T.exists(env.obj), "nothing written")
  T.errmsg("code:1: " .. P.data .. "/bad/climb_out.gltf: /buffers/0: buffer uri '../../../../etc/hostname' climbs out of the asset's folder ('..' is not allowed)",
    "femlod.load(file)", { file = P.data .. "/bad/climb_out.gltf" })
  T.errmsg("code:1: " .. P.data .. "/bad/draco.gltf: /meshes/0/primitives/0: compressed with KHR_draco_mesh_compression, which femlod does not decode",
    "femlod.load(file)", { file = P.data .. "/bad/draco.gltf" })
end
-- }======

-- {====== femlod convert
do
  local function quote(s) return "'" .. tostring(s):gsub("'", "'\\''") .. "'" end
  local function run(...)
    local parts = { quote(P.femlod) }
    for i = 1, select("#", ...) do parts[#parts + 1] = quote((select(i, ...))) end
    local err = path("stderr.txt")
    local p = assert(io.popen(table.concat(parts, " ") .. " 2>" .. quote(err) .. " </dev/null", "r"))
    local out = p:read("a")
    local _, _, code = p:close()
    return code, out, T.readfile(err) or ""
  end
  local out = path("convert.glb")
  local code, text, err = run("convert", P.shared .. "/fandisk.obj", out, "color_by=size", "normals=true")
  T.eq(code, 0, "convert exit: " .. err)
  T.eq(text, out .. ": 12946 triangles, 6475 vertices (glb)\n", "convert output")
  local json = glb_json(out)
  T.check(json:find('"_SIZE":', 1, true) and json:find('"NORMAL":', 1, true), "convert passes color_by and normals")
  code, text, err = run("convert", P.shared .. "/fandisk.obj", path("c.obj"), "normals=true")
  T.eq(code, 2, "glTF option for OBJ: a usage error")
  T.eq(err:match("^[^\n]*"), "femlod: " .. path("c.obj") .. ": color_by and normals are glTF options; " .. path("c.obj")
    .. " is obj, not gltf or glb", "convert error")
  code, text, err = run("convert", P.shared .. "/fandisk.obj", out, "format=gltf2")
  T.eq(code, 2, "unknown format: usage error")
  T.check(err:find("valid: obj, stl, stl_ascii, stl_binary, off, ply, ply_ascii, ply_binary, gltf, glb", 1, true),
    "format list: " .. err)
end
-- }======

T.summary("test_gltf.lua")
