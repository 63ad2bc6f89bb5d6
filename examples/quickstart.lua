-- quickstart.lua: load a mesh and print its quality report.
--
--   femlod examples/quickstart.lua                    -- examples/data/fandisk.obj
--   femlod examples/quickstart.lua mesh=part.stl      -- any OBJ, STL, OFF or PLY file
--
-- Also runs in the stock interpreter with the module on its path:
--   LUA_CPATH_5_4="build/?.so;;" lua5.4 examples/quickstart.lua
local femlod = require "femlod"
local report = require "femlod.report"

-- The mesh shipped beside this script, wherever it is run from.
local here = (arg and arg[0] or ""):match("^(.*)/") or "."
local path = params and params.mesh and tostring(params.mesh) or here .. "/data/fandisk.obj"

-- <close> frees the mesh's arrays at the end of the chunk, not at some later
-- garbage collection.
local mesh <close> = femlod.load(path)
print(report.text(mesh:quality(), path:match("[^/]*$")))
