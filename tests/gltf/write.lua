-- write.lua: the glTF files ctest's gltf_validator hands to the Khronos
-- glTF-Validator (validate.js): every writer mode on fandisk (colour by
-- stretch, valence and size, normals, GLB and JSON), the 2CylinderEngine
-- (degenerate triangles, more than 65535 vertices: 32-bit indices) and an
-- empty mesh. Run: femlod run write.lua out=PREFIX shared=examples/data
local femlod = require "femlod"
local out, shared = assert(params.out, "out="), assert(params.shared, "shared=")

local fandisk <close> = femlod.load(shared .. "/fandisk.obj")
local extras = { recipe = "tests/gltf/write.lua", mesh = "fandisk.obj" }
fandisk:save(out .. "fandisk_stretch.glb", { color_by = "stretch", normals = true, extras = extras })
fandisk:save(out .. "fandisk_stretch.gltf", { color_by = "stretch", normals = true, extras = extras })
fandisk:save(out .. "fandisk_valence.glb", { color_by = "valence", normals = true })
fandisk:save(out .. "fandisk_size.gltf", { color_by = "size" })
fandisk:save(out .. "fandisk_plain.glb")

local engine <close> = femlod.load(shared .. "/2CylinderEngine.glb")
engine:save(out .. "engine_valence.glb", { color_by = "valence", normals = true })

local empty <close> = femlod.mesh { positions = {}, triangles = {} }
empty:save(out .. "empty.glb")
