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

-- {====== from a recipe file run by the program: the recipe's file:line,
-- then the core's own file:line or byte, on stderr, with exit status 1
local FEMLOD = P.femlod
local function quote(s) return "'" .. tostring(s):gsub("'", "'\\''") .. "'" end
local ERRF = path("stderr.txt")
-- Runs `cd DIR && PREFIX femlod ARGS...`; returns exit code, stdout, stderr.
local function spawn(dir, prefix, ...)
  local parts = { "cd " .. quote(dir) .. " &&", prefix or "", quote(FEMLOD) }
  for i = 1, select("#", ...) do parts[#parts + 1] = quote((select(i, ...))) end
  local f = assert(io.popen(table.concat(parts, " ") .. " 2>" .. quote(ERRF) .. " </dev/null", "r"))
  local out = f:read("a")
  local _, how, code = f:close()
  T.check(how == "exit", "femlod ended by a signal: " .. tostring(code))
  return code, out, T.readfile(ERRF) or ""
end
if FEMLOD then
  local dir = tmp .. "/positions"
  os.execute("rm -rf " .. quote(dir) .. " && mkdir -p " .. quote(dir))
  T.writefile(dir .. "/range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
  T.writefile(dir .. "/bad.flh", "FLH")
  T.writefile(dir .. "/trunc.stl", "solid x\n  facet normal 0 0 1\n")
  T.writefile(dir .. "/nan.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
    .. "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n")
  local cases = {
    -- recipe line 3 calls the reader; the core names the file's line 4
    { "femlod.load('range.obj')", "range.obj:4: face index 9 out of range (3 vertices)" },
    { "femlod.load_hierarchy('bad.flh')", "bad.flh: byte 0: not a femlod hierarchy file" },
    { "femlod.load('trunc.stl')", "trunc.stl:2: expected 'outer', found the end of the file" },
    { "femlod.mesh { positions = { 0, 0, 0 }, triangles = { 1, 1, 2 } }",
      "bad argument #1 to 'mesh' (triangles[3]: index 2 out of range (1..1))" },
    { "femlod.load('range.obj', { format = 'off' })", nil },
  }
  for i, c in ipairs(cases) do
    local name = string.format("pos%d.lua", i)
    T.writefile(dir .. "/" .. name, "-- a recipe\nlocal femlod = require 'femlod'\nlocal m = " .. c[1] .. "\nprint(m)\n")
    local code, out, err = spawn(dir, nil, "run", name)
    T.eq(code, 1, name .. ": exit 1")
    T.eq(out, "", name .. ": nothing printed")
    if c[2] then
      T.eq(err, "femlod: " .. name .. ":3: " .. c[2] .. "\n", name .. ": message")
    else
      T.check(err:find("^femlod: " .. name .. ":3: range%.obj:1: ") ~= nil, name .. ": recipe line, file line: " .. err)
    end
  end
  -- Through a function: the line inside it that called femlod, and with
  -- --traceback the calling lines too.
  T.writefile(dir .. "/nested.lua", "local function load_it(p)\n  return femlod.load(p)\nend\n\nload_it('range.obj')\n")
  local code, _, err = spawn(dir, nil, "--traceback", "run", "nested.lua")
  T.eq(code, 1, "nested: exit 1")
  T.eq(err:match("^[^\n]*"), "femlod: nested.lua:2: range.obj:4: face index 9 out of range (3 vertices)", "nested: first line")
  T.check(err:find("\n\tnested%.lua:5: in main chunk\n") ~= nil, "nested: traceback names line 5: " .. err)
end
-- }======

-- {====== nothing lost: every writer, from Lua and from the program, under
-- every way a write fails; each gives one error naming the file, leaves the
-- old file byte for byte, and leaves no temporary behind
if FEMLOD then
  local LOST = tmp .. "/lost"
  os.execute("chmod -R u+w " .. quote(LOST) .. " 2>/dev/null; rm -rf " .. quote(LOST))
  assert(os.execute("mkdir -p " .. quote(LOST)))
  local mesh = P.shared .. "/spider_binary.stl" -- every output of it is over 2 KiB
  -- A hierarchy for lod, made in a good folder.
  local flh = LOST .. "/good.flh"
  local code, _, err = spawn(LOST, nil, "simplify", mesh, LOST .. "/good.obj", "--ratio", "0.5", "--hierarchy", flh)
  T.eq(code, 0, "the lod input: " .. err)

  local WRITERS = { "obj", "stl", "stl_ascii", "off", "ply", "ply_ascii", "gltf", "glb", "flh" }
  local EXT = { stl_ascii = "stl", ply_ascii = "ply" }
  T.writefile(LOST .. "/writers.lua", [[
local dir, mesh = params.dir, params.mesh
local m = femlod.load(mesh)
local h = m:simplify { ratio = 0.5 }
local function save(fmt, p)
  if fmt == "flh" then h:save(p) else m:save(p, { format = fmt }) end
end
for fmt in params.writers:gmatch("[%w_]+") do
  local ok, msg = pcall(save, fmt, dir .. "/" .. fmt .. "." .. (params[fmt] or fmt))
  print(fmt, ok, msg)
end
]])
  -- The program's writers: name, arguments, the file whose error it reports.
  local function cli_writes(dir)
    return {
      { "convert", { "convert", mesh, dir .. "/convert.obj" }, dir .. "/convert.obj" },
      { "simplify", { "simplify", mesh, dir .. "/simplify.stl", "--ratio", "0.5" }, dir .. "/simplify.stl" },
      { "simplify --hierarchy", { "simplify", mesh, dir .. "/simplify2.off", "--ratio", "0.5", "--hierarchy",
        dir .. "/simplify2.flh" }, dir .. "/simplify2.flh" },
      { "lod", { "lod", flh, dir .. "/lod.ply", "--size", "0" }, dir .. "/lod.ply" },
    }
  end
  local function targets(dir)
    local t = {}
    for _, fmt in ipairs(WRITERS) do t[#t + 1] = dir .. "/" .. fmt .. "." .. (EXT[fmt] or fmt) end
    for _, w in ipairs(cli_writes(dir)) do
      t[#t + 1] = w[2][3]
      if w[2][#w[2] - 1] == "--hierarchy" then t[#t + 1] = w[2][#w[2]] end
    end
    return t
  end
  local function listing(dir)
    local f = io.popen("ls -A " .. quote(dir) .. " 2>/dev/null | LC_ALL=C sort")
    local s = f:read("a")
    f:close()
    return s
  end

  -- Runs every writer into dir (made by setup, undone by teardown); each must
  -- fail with "FILE: " .. expected, leave dir's listing and old files as
  -- they were.
  -- cli: the program's own check of the output before any work (exit 2),
  -- when the case is one it can see: the first line it prints, %s the folder.
  local function case(name, dir, expected, prefix, setup, teardown, cli)
    if setup ~= "missing" then os.execute("mkdir -p " .. quote(dir)) end
    local old = {}
    if setup ~= "missing" then
      for _, t in ipairs(targets(dir)) do
        if setup == "folders" then
          os.execute("mkdir -p " .. quote(t))
        else
          old[t] = "old content of " .. t .. "\n"
          T.writefile(t, old[t])
        end
      end
    end
    if type(setup) == "function" then setup(dir) end
    local before = listing(dir)
    local args = { "run", "writers.lua", "dir=" .. dir, "mesh=" .. mesh,
      "writers=" .. table.concat(WRITERS, ","), "stl_ascii=stl", "ply_ascii=ply" }
    local code, out, err = spawn(LOST, prefix, table.unpack(args))
    T.eq(code, 0, name .. ": the writers recipe ran: " .. err)
    local seen = 0
    for fmt, ok, msg in out:gmatch("([%w_]+)\t(%a+)\t([^\n]*)\n") do
      seen = seen + 1
      local p = dir .. "/" .. fmt .. "." .. (EXT[fmt] or fmt)
      T.eq(ok, "false", name .. ": " .. fmt .. " must fail")
      T.eq(msg, "writers.lua:5: " .. p .. ": " .. expected, name .. ": " .. fmt .. " message")
    end
    T.eq(seen, #WRITERS, name .. ": every writer tried")
    for _, w in ipairs(cli_writes(dir)) do
      local c, o, e = spawn(LOST, prefix, table.unpack(w[2]))
      T.eq(c, cli and 2 or 1, name .. ": " .. w[1] .. " exit status")
      T.eq(o, "", name .. ": " .. w[1] .. " prints no report")
      if cli then
        T.eq(e:match("^[^\n]*"), "femlod: " .. w[3] .. ": " .. cli:format(dir), name .. ": " .. w[1] .. " message")
      else
        T.eq(e, "femlod: " .. w[3] .. ": " .. expected .. "\n", name .. ": " .. w[1] .. " message")
      end
    end
    if teardown then teardown(dir) end
    T.eq(listing(dir), before, name .. ": no file made or removed, no temporary left")
    for t, content in pairs(old) do
      T.eq(T.readfile(t), content, name .. ": " .. t .. " intact")
    end
  end

  -- A full disk: the file size limit makes write() fail with EFBIG (SIGXFSZ
  -- ignored), part-way through every output (dash counts 512-byte blocks).
  case("disk full", LOST .. "/full", "cannot write: File too large", "trap '' XFSZ; ulimit -f 4;")
  -- A folder the user cannot write: as root, without CAP_DAC_OVERRIDE.
  local root = io.popen("id -u"):read("l") == "0"
  case("read-only folder", LOST .. "/rodir", "cannot create temporary file: Permission denied",
    root and "setpriv --bounding-set=-dac_override,-dac_read_search" or nil,
    function(dir) os.execute("chmod 555 " .. quote(dir)) end,
    function(dir) os.execute("chmod 755 " .. quote(dir)) end, "cannot write in folder %s: Permission denied")
  -- Existing read-only files: refused even as root, whose rename would work.
  case("read-only files", LOST .. "/rofiles", "cannot write: file is read-only (mode 0444)", nil,
    function(dir) os.execute("chmod 444 " .. quote(dir) .. "/*") end,
    function(dir) os.execute("chmod 644 " .. quote(dir) .. "/*") end, "cannot write: file is read-only (mode 0444)")
  case("targets are folders", LOST .. "/folders", "cannot write: Is a directory", nil, "folders", nil,
    "is a folder; give a file name")
  case("missing folder", LOST .. "/missing/sub", "cannot create temporary file: No such file or directory",
    nil, "missing", nil, "folder %s does not exist")
  T.check(not T.exists(LOST .. "/missing/sub/."), "the missing folder was not made")
end
-- }======

T.summary("test_errors")
