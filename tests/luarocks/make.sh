#!/usr/bin/env bash
# luarocks_make: the rockspec at the root builds and installs the module from
# a fresh copy of the tree into a private LuaRocks tree, and the stock lua5.4
# loads it from there:
#
#   luarocks --lua-version=5.4 --tree TREE make
#   eval "$(luarocks --lua-version=5.4 --tree TREE path)"
#   lua5.4 -e 'require "femlod"'
#
# Then: the module and every helper come from TREE (not from a system
# install), every lua/femlod/*.lua is installed (the rockspec lists them by
# hand), the rockspec's version is the program's, and the installed program
# runs a recipe. Usage: make.sh SOURCE_DIR WORK_DIR. Fails when luarocks or
# lua5.4 is missing (README's second command installs luarocks).
set -euo pipefail
src=$(cd "$1" && pwd)
work=$2
fail() { echo "luarocks_make: $*" >&2; exit 1; }
command -v luarocks >/dev/null || fail "luarocks not found (README's second command installs it)"
command -v lua5.4 >/dev/null || fail "lua5.4 not found"

rm -rf "$work"
mkdir -p "$work/src"
# A fresh tree: the sources without build folders, npm's node_modules or git.
tar -C "$src" --exclude='./build*' --exclude='./.git' --exclude=node_modules -cf - . | tar -C "$work/src" -xf -
shopt -s nullglob
specs=("$work"/src/*.rockspec)
[ ${#specs[@]} -eq 1 ] || fail "expected one rockspec at the root, found ${#specs[@]}"
spec=$(basename "${specs[0]}")

tree=$work/tree
lr() { luarocks --lua-version=5.4 --tree "$tree" "$@"; }
# luarocks' cmake back-end runs `cmake --build` without -j.
export CMAKE_BUILD_PARALLEL_LEVEL=${CMAKE_BUILD_PARALLEL_LEVEL:-2}
(cd "$work/src" && lr make) > "$work/make.log" 2>&1 || { tail -n 40 "$work/make.log" >&2; fail "luarocks make failed (log: $work/make.log)"; }
tail -n 1 "$work/make.log"

# The environment `luarocks path` gives, and nothing left over from ours.
unset LUA_PATH LUA_CPATH LUA_PATH_5_4 LUA_CPATH_5_4 LUA_INIT LUA_INIT_5_4
eval "$(lr path)"
lua5.4 -e 'require "femlod"' || fail "lua5.4 -e 'require \"femlod\"' failed"

# Where each module came from, and the version.
TREE=$tree SPEC=$spec lua5.4 - <<'EOF'
local tree, spec = os.getenv("TREE"), os.getenv("SPEC")
local function fail(msg) io.stderr:write("luarocks_make: ", msg, "\n"); os.exit(1) end
local so = package.searchpath("femlod", package.cpath)
if so ~= tree .. "/lib/lua/5.4/femlod.so" then fail("femlod.so found at " .. tostring(so) .. ", not in the tree") end
local femlod = require "femlod"
local version = spec:match("^femlod%-(.-)%-%d+%.rockspec$")
if femlod._VERSION ~= "femlod " .. version then
  fail(spec .. " says " .. version .. ", the module says " .. tostring(femlod._VERSION))
end
for _, name in ipairs { "report", "sweep", "progress" } do
  local p = package.searchpath("femlod." .. name, package.path)
  if p ~= tree .. "/share/lua/5.4/femlod/" .. name .. ".lua" then
    fail("femlod." .. name .. " found at " .. tostring(p) .. ", not in the tree")
  end
  require("femlod." .. name)
end
local m = femlod.mesh { positions = { 0, 0, 0, 1, 0, 0, 0, 1, 0 }, triangles = { 1, 2, 3 } }
if m:quality().triangles ~= 1 then fail("a one-triangle mesh has not 1 triangle") end
print(femlod._VERSION .. ": " .. so)
EOF

# Every helper of the tree is installed, unchanged (a new one must be added
# to the rockspec's build.install.lua).
for f in "$src"/lua/femlod/*.lua; do
    cmp -s "$f" "$tree/share/lua/5.4/femlod/$(basename "$f")" ||
        fail "lua/femlod/$(basename "$f") is not installed as is: add it to $spec's build.install.lua"
done

# The program the rock installs, on the PATH `luarocks path` set.
[ "$(command -v femlod)" = "$tree/bin/femlod" ] || fail "femlod on PATH is $(command -v femlod), not the tree's"
out=$(femlod -e 'print(require("femlod.report").header())')
[ "$out" = "model (H x W x D) | state | elements | stretch (avg, min) | size (max) | valence (max)" ] ||
    fail "femlod -e gave: $out"
echo "luarocks_make: ok ($spec into $tree)"
