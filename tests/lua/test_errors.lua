-- test_errors.lua: every Lua API function raises (never returns nil, msg),
-- with a message that names the argument or the culprit, at the position of
-- the recipe line that called it. T.errmsg compiles its code as chunk "code",
-- so "code:1:" pins the position exactly; the whole message is compared.

local T = dofile((arg[0]:match("^(.*)/") or ".") .. "/check.lua")
local femlod = require "femlod"
local report = require "femlod.report"

local P = params
assert(P and P.tmp and P.shared and P.data, "run through ctest: needs tmp=, shared= and data=")

local tri = femlod.mesh { positions = { 0, 0, 0, 1, 0, 0, 0, 1, 0 }, triangles = { 1, 2, 3 } }
local closed = tri:copy()
closed:close()
local env = { m = tri, closed = closed, report = report }

-- {====== argument errors name the argument and the function
T.errmsg("code:1: bad argument #1 to 'load' (string expected, got no value)", "femlod.load()")
T.errmsg("code:1: bad argument #1 to 'load' (string expected, got nil)", "femlod.load(nil)")
T.errmsg("code:1: bad argument #1 to 'load' (path contains a zero byte)", "femlod.load('a\\0.obj')")
T.errmsg("code:1: bad argument #2 to 'load' (table expected, got number)", "femlod.load('a.obj', 5)")
T.errmsg("code:1: bad argument #1 to 'save' (string expected, got no value)", "m:save()", env)
T.errmsg("code:1: bad argument #1 to 'save' (string expected, got table)", "m:save({})", env)
T.errmsg("code:1: bad argument #1 to 'save' (femlod.Mesh expected, got nil)", "m.save(nil, 'x.obj')", env)
T.errmsg("code:1: calling 'save' on bad self (femlod.Mesh expected, got table)",
  "local t = { save = m.save }; t:save('x.obj')", env)
-- Another library's userdata is named by its own __name.
T.errmsg("code:1: bad argument #1 to 'counts' (femlod.Mesh expected, got FILE*)",
  "m.counts(io.stdout)", env)
T.errmsg("code:1: bad argument #1 to 'quality' (femlod.Mesh expected, got number)", "m:quality(5)", env)
T.errmsg("code:1: bad argument #1 to 'subdivide' (number expected, got string)", "m:subdivide('x')", env)
T.errmsg("code:1: bad argument #1 to 'subdivide' (number has no integer representation)",
  "m:subdivide(1.5)", env)
T.errmsg("code:1: bad argument #1 to 'subdivide' (levels out of range (0..16))", "m:subdivide(-1)", env)
T.errmsg("code:1: bad argument #1 to 'subdivide' (levels out of range (0..16))", "m:subdivide(17)", env)
-- Within the bound, the core's own limit: 4^15 children per triangle pass
-- UINT32_MAX triangles once there are 4 of them; it must fail before allocating.
do
  local four = femlod.mesh { positions = { 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1 },
    triangles = { 1, 2, 3, 1, 2, 4, 1, 3, 4, 2, 3, 4 } }
  T.checkerr("^code:1: .", load("return m:subdivide(15)", "=code", "t", { m = four }))
end
T.errmsg("code:1: bad argument #1 to 'mesh' (table expected, got no value)", "femlod.mesh()")
T.errmsg("code:1: bad argument #1 to 'mesh' (table expected, got string)", "femlod.mesh('x')")
-- }======

-- {====== option tables: unknown keys list the valid ones (sorted), wrong
-- types and values name the key
T.errmsg("code:1: bad argument #2 to 'load' (unknown key 'formt'; valid keys: format)",
  "femlod.load('a.obj', { formt = 'obj' })")
T.errmsg("code:1: bad argument #2 to 'load' (unexpected number key 1; valid keys: format)",
  "femlod.load('a.obj', { 'obj' })")
T.errmsg("code:1: bad argument #2 to 'load' (format: string expected, got number)",
  "femlod.load('a.obj', { format = 1 })")
T.errmsg("code:1: bad argument #2 to 'load' (format: invalid value 'stlx'; valid values: obj, stl, "
  .. "stl_ascii, stl_binary, off, ply, ply_ascii, ply_binary, gltf, glb, msh, msh2, vtk, inp, medit)", "femlod.load('a.obj', { format = 'stlx' })")
T.errmsg("code:1: bad argument #2 to 'save' (unknown key 'fmt'; valid keys: color_by, elsets, extras, format, normals, nsets)",
  "m:save('x.obj', { fmt = 'obj' })", env)
T.errmsg("code:1: bad argument #2 to 'save' (format: invalid value 'OBJ'; valid values: obj, stl, "
  .. "stl_ascii, stl_binary, off, ply, ply_ascii, ply_binary, gltf, glb, msh, msh2, vtk, inp, medit)", "m:save('x.obj', { format = 'OBJ' })", env)
T.errmsg("code:1: bad argument #1 to 'mesh' (unknown key 'position'; valid keys: positions, triangles)",
  "femlod.mesh { position = {} }")
T.errmsg("code:1: bad argument #1 to 'mesh' (unexpected boolean key true; valid keys: positions, triangles)",
  "femlod.mesh { [true] = 1 }")
-- The check happens before anything is read: a typo next to good keys still fails.
T.errmsg("code:1: bad argument #1 to 'mesh' (unknown key 'triangle'; valid keys: positions, triangles)",
  "femlod.mesh { positions = { 0, 0, 0 }, triangle = {} }")
-- An empty or nil option table is no option.
T.check(pcall(function() return tri:copy():save(P.tmp .. "/errors_ok.obj", {}) end), "empty option table")
T.check(pcall(function() return tri:copy():save(P.tmp .. "/errors_ok.obj", nil) end), "nil option table")
-- }======

-- {====== femlod.mesh elements are named as the recipe wrote them
local E = "code:1: bad argument #1 to 'mesh' "
T.errmsg(E .. "(positions: table expected, got number)", "femlod.mesh { positions = 5 }")
T.errmsg(E .. "(positions: flat list length 2 is not a multiple of 3)", "femlod.mesh { positions = { 0, 0 } }")
T.errmsg(E .. "(positions[2]: 3 entries expected, got 2)",
  "femlod.mesh { positions = { { 0, 0, 0 }, { 1, 0 } } }")
T.errmsg(E .. "(positions[1][3]: number expected, got string)",
  "femlod.mesh { positions = { { 0, 0, 'a' } } }")
T.errmsg(E .. "(positions[5]: number expected, got boolean)",
  "femlod.mesh { positions = { 0, 0, 0, 1, true, 0 } }")
T.errmsg(E .. "(positions[4]: coordinate is not finite)", "femlod.mesh { positions = { 0, 0, 0, 0/0, 0, 0 } }")
T.errmsg(E .. "(positions[2][1]: coordinate is not finite)",
  "femlod.mesh { positions = { { 0, 0, 0 }, { 1/0, 0, 0 } } }")
local P3 = "positions = { 0, 0, 0, 1, 0, 0, 0, 1, 0 }, "
T.errmsg(E .. "(triangles[1][3]: index 4 out of range (1..3))", "femlod.mesh { " .. P3 .. "triangles = { { 1, 2, 4 } } }")
T.errmsg(E .. "(triangles[3]: index 0 out of range (1..3))", "femlod.mesh { " .. P3 .. "triangles = { 1, 2, 0 } }")
T.errmsg(E .. "(triangles[2]: index 1.5 is not a valid index)",
  "femlod.mesh { " .. P3 .. "triangles = { 1, 1.5, 2 } }")
T.errmsg(E .. "(triangles[2]: table expected, got number)",
  "femlod.mesh { " .. P3 .. "triangles = { { 1, 2, 3 }, 7 } }")
T.errmsg(E .. "(triangles[1]: index 1 out of range (1..0))", "femlod.mesh { triangles = { 1, 1, 1 } }")
-- }======

-- {====== closed meshes
for _, method in ipairs { "save", "quality", "counts", "bbox", "subdivide", "copy", "positions", "triangles" } do
  T.errmsg("code:1: attempt to use a closed femlod.Mesh", "closed:" .. method .. "('x.obj')", env)
end
T.errmsg("code:1: attempt to use a closed femlod.Mesh", "m:quality(closed)", env)
T.eq(tostring(closed), "femlod.Mesh (closed)", "a closed mesh still prints")
T.check(pcall(closed.close, closed), "closing twice is no error")
-- }======

-- {====== positions in the recipe's own file, through a Lua caller
do
  local line, msg = T.line(), select(2, pcall(function() femlod.load(nil) end))
  T.check(type(msg) == "string" and msg:find("test_errors%.lua:" .. line .. ": bad argument #1 to 'load'"),
    "position of the calling line: " .. tostring(msg))
  -- Errors raised by helpers blame their caller, not the helper.
  line, msg = T.line(), select(2, pcall(function() report.text(5) end))
  T.check(type(msg) == "string" and msg:find("test_errors%.lua:" .. line
    .. ": bad argument #1 to 'text' %(quality table or femlod%.Mesh expected, got number%)$"),
    "helper blames its caller: " .. tostring(msg))
end
T.errmsg("code:2: bad argument #1 to 'row' (quality table or femlod.Mesh expected, got table without quality fields)",
  "local x = 1\nlocal r = report.row({})", env)
T.errmsg("code:1: bad argument #2 to 'row' (string expected, got number)", "report.row(m, 5)", env)
T.errmsg("code:1: bad argument #3 to 'row' (string expected, got boolean)", "report.row(m, 'a', true)", env)
T.errmsg("code:1: bad argument #1 to 'fields' (quality table or femlod.Mesh expected, got nil)", "report.fields()", env)
-- }======

-- {====== failures of the core: file:line of the recipe, then the core's message
local tmp = P.tmp
local function path(name) return tmp .. "/errors_" .. name end
local function load_error(file, opts)
  local ok, msg = pcall(load("return femlod.load(...)", "=code", "t", { femlod = femlod }), file, opts)
  T.check(not ok, "loading " .. file .. " must fail")
  return tostring(msg)
end

-- A message must start with the recipe position, then the file name, then
-- (for text formats) the line, and contain the expected words.
local function bad_file(name, content, where, words, opts)
  local p = path(name)
  T.writefile(p, content)
  local msg = load_error(p, opts)
  local prefix = "code:1: " .. p .. where
  T.check(msg:sub(1, #prefix) == prefix, string.format("%s: message %q does not start with %q", name, msg, prefix))
  T.check(msg:find(words), string.format("%s: message %q lacks %q", name, msg, words))
end

T.errmsg("code:1: " .. path("missing.obj") .. ": cannot open: No such file or directory",
  "femlod.load(p)", { p = path("missing.obj") })
T.errmsg("code:1: x.xyz: unknown file extension; supported: .obj, .stl, .off, .ply, .gltf, .glb, .msh, .vtk, .inp, .mesh (or give the format)",
  "femlod.load('x.xyz')")
T.errmsg("code:1: " .. tmp .. ": cannot read: Is a directory", "femlod.load(p, { format = 'obj' })", { p = tmp })

-- OBJ: the line of the culprit.
bad_file("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", ":4: ", "face index 9 out of range")
bad_file("zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", ":4: ", "index 0")
bad_file("negative.obj", "v 0 0 0\nf -1 -2 -5\n", ":2: ", "out of range")
bad_file("short_face.obj", "# two vertices only\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n", ":5: ", "face has 2 vertices")
bad_file("nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", ":2: ", "[Nn]a[Nn]")
bad_file("inf.obj", "v 0 0 0\nv 1 0 0\nv 0 1e999 0\nf 1 2 3\n", ":3: ", "")
bad_file("word.obj", "v 0 0 0\nv 1 zero 0\n", ":2: ", "zero")
bad_file("empty.obj", "", ": ", "empty")
-- The format option overrides the extension: an OBJ named .stl reads as OBJ.
bad_file("really_obj.stl", "v 0 0 0\nf 1 1 7\n", ":2: ", "out of range", { format = "obj" })

-- Binary STL: "FILE: byte N:" positions. A header promising 10 triangles
-- followed by only one is truncated; garbage is refused, never read past.
local function stl_header(n)
  return string.rep("\0", 80) .. string.pack("<I4", n)
end
local one = string.pack("<fff fff fff fff I2", 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0)
bad_file("truncated.stl", stl_header(10) .. one, ": ", "", { format = "stl_binary" })
bad_file("overflow.stl", stl_header(0xffffffff) .. one, ": ", "", { format = "stl_binary" })
bad_file("short.stl", string.rep("\1", 40), ": ", "")
do
  -- Deterministic garbage (a small LCG), in every format: an error, no crash.
  local bytes, x = {}, 12345
  for i = 1, 4096 do
    x = (x * 1103515245 + 12345) % 2147483648
    bytes[i] = string.char(x % 256)
  end
  local garbage = table.concat(bytes)
  for _, fmt in ipairs { "obj", "stl", "off", "ply" } do
    T.writefile(path("garbage." .. fmt), garbage)
    local msg = load_error(path("garbage." .. fmt), nil)
    local prefix = "code:1: " .. path("garbage." .. fmt)
    T.check(msg:sub(1, #prefix) == prefix, "garbage." .. fmt .. " names the file: " .. msg)
  end
end

-- The IO engineer's bad inputs, when present: each fails, naming its file.
do
  local dir = P.data .. "/bad"
  local list = io.popen("ls " .. string.format("%q", dir) .. " 2>/dev/null")
  local n = 0
  for name in list:lines() do
    if name:find("%.obj$") or name:find("%.stl$") or name:find("%.off$") or name:find("%.ply$") then
      n = n + 1
      local p = dir .. "/" .. name
      local msg = load_error(p, nil)
      T.check(msg:sub(1, #("code:1: " .. p)) == "code:1: " .. p, name .. " names its file: " .. msg)
    end
  end
  list:close()
  T.check(n > 0 or not T.exists(dir .. "/."), "tests/data/bad holds meshes when it exists")
end

-- Writing: a failed save raises and leaves nothing behind.
T.errmsg("code:1: " .. path("out.xyz") .. ": unknown file extension; supported: .obj, .stl, .off, .ply, .gltf, .glb, .msh, .vtk, .inp, .mesh (or give the format)",
  "m:save(p)", { m = tri, p = path("out.xyz") })
T.check(not T.exists(path("out.xyz")), "failed save made no file")
do
  local p = tmp .. "/no_such_dir/out.obj"
  local msg = select(2, pcall(load("m:save(p)", "=code", "t", { m = tri, p = p })))
  T.check(tostring(msg):sub(1, #("code:1: " .. p .. ": ")) == "code:1: " .. p .. ": ", "save into a missing folder: " .. tostring(msg))
  T.check(not T.exists(p), "nothing written into a missing folder")
end
-- }======

-- {====== the API raises, it never returns nil, msg
do
  local results = table.pack(pcall(femlod.load, path("missing.obj")))
  T.eq(results[1], false, "load of a missing file raises")
  T.eq(results.n, 2, "pcall gives false and one message")
  -- No Lua caller (pcall calls load directly): no position to add.
  T.eq(results[2], path("missing.obj") .. ": cannot open: No such file or directory", "message without a caller")
end
-- }======

T.summary("test_errors")
