-- test_help.lua: the help of the femlod program. `femlod --help` names every
-- command; `femlod help COMMAND` and `femlod COMMAND --help` print the same
-- page (usage, options, examples) for each of them; the FMT line names every
-- format with read and write marked; and docs/cli.md shows each text exactly
-- as the program prints it (the blocks "$ femlod --help" and
-- "$ femlod help COMMAND"), so the docs cannot drift from the program.

local T = dofile((arg[0]:match("^(.*)/") or ".") .. "/check.lua")
local femlod = require "femlod"

local P = params
assert(P and P.femlod and P.tmp and P.examples, "run through ctest: needs femlod=, tmp=, examples=")
local run = T.runner(P.femlod, P.tmp .. "/help_stderr.txt").run
local clidoc = T.readfile(P.examples .. "/../docs/cli.md")

-- The text of a ```text block that starts with the line `$ femlod ARGS`, or nil.
local function doc_block(args)
  local head = "```text\n$ femlod " .. args .. "\n"
  local at = clidoc:find(head, 1, true)
  if not at then return nil end
  local body = at + #head
  local stop = clidoc:find("\n```\n", body - 1, true)
  return clidoc:sub(body, stop)
end

-- {====== the overview
local code, overview, err = run("--help")
T.eq(code, 0, "--help: exit 0")
T.eq(err, "", "--help: nothing on stderr")
T.eq(doc_block("--help"), overview, "docs/cli.md shows `femlod --help` as the program prints it")
local commands = {}
for line in (overview:match("\nCommands[^\n]*\n(.-)\n\n") or ""):gmatch("[^\n]+") do
  commands[#commands + 1] = line:match("^  (%-?[a-z]+) ")
end
T.eq(table.concat(commands, " "), "run -e info convert repair improve simplify lod sweep report help",
  "--help lists every command")
-- }======

-- {====== a page per command
for _, name in ipairs(commands) do
  local c, page, e = run("help", name)
  T.eq(c, 0, "help " .. name .. ": exit 0")
  T.eq(e, "", "help " .. name .. ": nothing on stderr")
  T.check(page:find("^usage: femlod " .. name:gsub("%p", "%%%0") .. "[ \n]"), "help " .. name .. ": usage line: " .. page)
  T.check(page:find("\nExamples:\n  femlod ", 1, false), "help " .. name .. ": examples")
  T.eq(doc_block("help " .. name), page, "docs/cli.md shows `femlod help " .. name .. "` as the program prints it")
  if name ~= "help" then
    local c2, page2, e2 = run(name, "--help")
    T.eq(c2, 0, name .. " --help: exit 0")
    T.eq(page2, page, name .. " --help is help " .. name)
    T.eq(e2, "", name .. " --help: nothing on stderr")
  end
end
-- -h too, and after the operands and options of a command
T.eq(select(2, run("simplify", "-h")), select(2, run("help", "simplify")), "simplify -h")
T.eq(select(2, run("simplify", "a.obj", "b.obj", "--target", "10", "--help")), select(2, run("help", "simplify")),
  "simplify IN OUT ... --help")
T.eq(select(2, run("info", "--help")), select(2, run("help", "info")), "info --help is not a file name")
T.eq(select(2, run("help", "--help")), select(2, run("help", "help")), "help --help")
-- after a recipe, --help is the recipe's
local r = P.tmp .. "/help_recipe.lua"
T.writefile(r, "print(select('#', ...), ...)\n")
local c, out, e = run("run", r, "--help")
T.eq(c, 2, "run RECIPE --help: a malformed pair")
T.eq(e:match("^[^\n]*"), "femlod: expected name=value, got '--help'", "run RECIPE --help: message")
os.remove(r)

-- The options the help of simplify must name (its docs once lacked some).
local _, simplify = run("help", "simplify")
for _, flag in ipairs { "--target N", "--ratio R", "--tolerance X", "--max-deviation X", "--min-stretch X",
  "--max-size X", "--max-valence N", "--feature-angle DEG", "--feature-weight W", "--max-normal-change DEG",
  "--keep-boundary", "--area-weighted", "--lock I,J,K", "--fast-above F|off", "--threads N",
  "--hierarchy PART.flh", "--hierarchy-floor N|off" } do
  T.check(simplify:find("  " .. flag, 1, true), "help simplify names " .. flag)
end
-- Every option of a command's page is accepted by it: an unknown one would
-- be a usage error naming it (each run stops before any work: no files).
for name, words in pairs {
  info = { "--report", "--format", "--reference" },
  convert = { "--format", "--input-format", "--color-by", "--normals" },
  repair = { "--weld", "--drop-degenerate", "--drop-duplicates", "--split-nonmanifold", "--orient", "--drop-unused",
    "--format", "--input-format" },
  lod = { "--size", "--target" },
  report = { "--reference", "--html", "--no-viewer" },
} do
  local _, page = run("help", name)
  for _, w in ipairs(words) do
    T.check(page:find("\n  " .. w:gsub("%p", "%%%0") .. "[ \n]"), "help " .. name .. " names " .. w)
  end
end
-- }======

-- {====== unknown topics
c, out, e = run("help", "simplfy")
T.eq(c, 2, "help of an unknown command: exit 2")
T.eq(out, "", "help of an unknown command: stdout empty")
T.eq(e:match("^[^\n]*"), "femlod: unknown command 'simplfy'; did you mean simplify?", "help simplfy: message")
c, out, e = run("help", "simplify", "lod")
T.eq(c, 2, "help of two commands: exit 2")
T.eq(e:match("^[^\n]*"), "femlod: help: one command expected, got 'lod' too", "help of two commands: message")
-- }======

-- {====== FMT: every format, read and write marked
do
  local rw = overview:match("\nFMT, read%+write:(.-)\n%s+write only:")
  local wo = overview:match("\n%s+write only:([^\n]*)\n")
  T.check(rw and wo, "the FMT lines: " .. overview)
  local listed = {}
  for f in (rw or ""):gmatch("[%w_]+") do listed[f] = "rw" end
  for f in (wo or ""):gmatch("[%w_]+") do listed[f] = "w" end
  local n = 0
  for _ in pairs(listed) do n = n + 1 end
  T.eq(n, 15, "FMT names the 15 formats")
  -- The marks are true: a read-and-write format round-trips a mesh through
  -- convert; a write-only one is written and refused on reading.
  local fan = P.examples .. "/data/fandisk.obj"
  local ext = { stl_ascii = "stl", stl_binary = "stl", ply_ascii = "ply", ply_binary = "ply", msh2 = "msh",
    medit = "mesh" }
  for f, mark in pairs(listed) do
    local file = P.tmp .. "/help_fmt_" .. f .. "." .. (ext[f] or f)
    local wc, _, we = run("-q", "convert", fan, file, "format=" .. f)
    T.eq(wc, 0, "FMT " .. f .. ": written: " .. we)
    local ok, m = pcall(femlod.load, file, { format = f })
    T.eq(ok, mark == "rw", "FMT " .. f .. ": read back " .. (ok and "ok" or tostring(m)))
    if ok then T.eq(m:counts().triangles, 12946, "FMT " .. f .. ": the triangles read back") end
    os.remove(file)
  end
end
-- }======

T.summary("test_help")
