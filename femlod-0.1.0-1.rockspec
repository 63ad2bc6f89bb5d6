-- The Lua module femlod.so and its pure-Lua helpers (femlod.report,
-- femlod.sweep, femlod.progress), and the `femlod` program, for Lua 5.4:
--
--   luarocks --lua-version=5.4 make                       # in the checkout
--   luarocks --lua-version=5.4 --tree /tmp/rocks make     # into a private tree
--   eval "$(luarocks --lua-version=5.4 --tree /tmp/rocks path)"
--   lua5.4 -e 'print(require("femlod")._VERSION)'
--
-- CMake builds, as `cmake -S . -B build` does (the same dependencies:
-- README's first command); LuaRocks then copies the files named in
-- build.install into the tree. CMake's own install step is skipped: it
-- would put the static library and the header in the rock's lib/, which
-- LuaRocks deploys as Lua modules. The test `luarocks_make` (tests/luarocks/
-- make.sh) runs this from a copy of the tree, checks that every
-- lua/femlod/*.lua is listed below and that the version is the program's.
rockspec_format = "3.0"
package = "femlod"
version = "0.1.0-1"
source = {
  -- No published repository yet: `luarocks make` builds the checkout the
  -- rockspec sits in and never fetches this.
  url = ".",
}
description = {
  summary = "Finite-element surface meshes from dense triangle meshes, driven by Lua recipes",
  detailed = [[
femlod turns dense triangle meshes into finite-element surface meshes whose
every element meets the thresholds you set for geometric tolerance, shape,
size and valence (Lee et al.'s quality-controlled simplification and
adaptive LOD). A C core with a Lua 5.4 binding: require "femlod".
]],
}
dependencies = {
  "lua >= 5.4, < 5.5",
}
build = {
  type = "cmake",
  variables = {
    -- The headers of the Lua LuaRocks builds for (FindLua would find them
    -- too, but this way a tree for another 5.4 gets its own).
    LUA_INCLUDE_DIR = "$(LUA_INCDIR)",
    FEMLOD_BUILD_TESTS = "OFF",
    BUILD_TESTING = "OFF",
  },
  install_pass = false,
  install = {
    lib = {
      femlod = "build.luarocks/femlod.so",
    },
    lua = {
      ["femlod.progress"] = "lua/femlod/progress.lua",
      ["femlod.report"] = "lua/femlod/report.lua",
      ["femlod.sweep"] = "lua/femlod/sweep.lua",
    },
    bin = {
      femlod = "build.luarocks/femlod",
    },
  },
  copy_directories = { "docs" },
}
