-- Regenerates or checks the output blocks of the Markdown docs (docs/testing.md,
-- "Output blocks in the docs").
--
--   lua5.4 tests/docs/outputs.lua --check [--light] [--times] [--bin build] [FILE.md ...]
--   lua5.4 tests/docs/outputs.lua --write [--bin build] [FILE.md ...]
--   femlod run tests/docs/outputs.lua mode=check|write [light=true] [bin=build] [files=a.md,b.md]
--
-- Markers are one-line HTML comments, invisible on the rendered page:
--
--   <!-- output -->                 the next fenced block is a transcript: each line that
--                                   starts with "$ " is run, the lines up to the next "$ "
--                                   line are replaced by what it printed
--   <!-- output: COMMAND -->        the next fenced block is what COMMAND printed
--   <!-- run: COMMAND -->           run COMMAND (set-up), show nothing
--   <!-- file: NAME -->             write the next fenced block to the file NAME
--
-- Options go between the keyword and the colon: `<!-- output mask=seconds,mb heavy: ... -->`.
--   mask=A,B     replace what legitimately varies (see MASKS) before comparing; --write
--                keeps the block when the masked texts agree
--   unordered    compare the lines as a sorted list (workers finishing in any order)
--   heavy        slow: not checked with --light or FEMLOD_TEST_HEAVY=0 (--write runs it)
--
-- Every Markdown file runs in a fresh temporary folder of its own holding a copy of
-- examples/ and of every file of examples/data/ at its top level; commands run with
-- `sh`, standard error merged into standard output (2>&1), in file order, so a block may
-- use what an earlier one wrote. PATH starts with the folder's bin/ (for links a set-up
-- makes) and the build folder; FEMLOD_BUILD and FEMLOD_SOURCE name the build and source
-- folders. In what commands print, the folder's path is shown as /tmp/femlod-docs, the
-- build folder's as /usr/local/bin and the source folder's as /usr/local/src/femlod.

local MASKS = {
  -- wall, CPU and ETA times: "0.158 s", "(0.002 s)", "ETA 2 s"
  seconds = { { "%d+%.?%d* s%f[^%w]", "#.### s" } },
  -- peak memory of sweep points
  mb = { { "%d+%.?%d* MB", "#.# MB" } },
  -- process ids
  pid = { { "process %d+", "process #" } },
  -- the thread count of the fast passes (every processor by default)
  threads = { { "on %d+ threads?", "on # threads" } },
  -- the JobRuntime column of GNU parallel's job log (`cut -f 1,4,7`)
  joblog = { { "^(%d+)\t%s*[%d%.]+\t", "%1\t#\t" } },
  -- times and memory in results.csv rows: the last two numeric columns before `error`
  csvtimes = { { ",[%d%.]+,%d+,([^,]*)$", ",#,#,%1" } },
}

local SHOWN_TMP = "/tmp/femlod-docs"
-- the build folder, as an installed femlod would be (`--emit-jobs` prints the program path)
local SHOWN_BIN = "/usr/local/bin"
local SHOWN_SOURCE = "/usr/local/src/femlod"

local function die(msg, status)
  io.stderr:write("outputs.lua: ", msg, "\n")
  os.exit(status or 2)
end

local function shquote(s) return "'" .. s:gsub("'", "'\\''") .. "'" end

local function readfile(path)
  local f, err = io.open(path, "rb")
  if not f then die(err) end
  local s = f:read("a")
  f:close()
  return s
end

local function writefile(path, s)
  local f, err = io.open(path, "wb")
  if not f then die(err) end
  f:write(s)
  f:close()
end

local function capture(cmd)
  local p = io.popen(cmd, "r")
  local s = p:read("a")
  local ok, how, code = p:close()
  return s, ok, code
end

local function check_ok(cmd)
  local ok = os.execute(cmd)
  if not ok then die("failed: " .. cmd) end
end

-- arguments: from `lua5.4` (arg) or from `femlod run` (params)
local mode, bin, files, root_arg, times = nil, "build", {}, nil, false
local heavy = os.getenv("FEMLOD_TEST_HEAVY") ~= "0"
if type(params) == "table" and params.mode then
  mode = params.mode
  if params.light == true then heavy = false end
  bin = params.bin or bin
  for f in tostring(params.files or ""):gmatch("[^,]+") do files[#files + 1] = f end
  root_arg = params.root
else
  local i = 1
  while arg[i] do
    local a = arg[i]
    if a == "--check" then mode = "check"
    elseif a == "--write" then mode = "write"
    elseif a == "--light" then heavy = false
    elseif a == "--times" then times = true
    elseif a == "--bin" then i = i + 1; bin = arg[i] or die("--bin needs a folder")
    elseif a == "--root" then i = i + 1; root_arg = arg[i] or die("--root needs a folder")
    elseif a:sub(1, 1) == "-" then die("unknown option " .. a)
    else files[#files + 1] = a end
    i = i + 1
  end
end
if mode ~= "check" and mode ~= "write" then
  die("usage: lua5.4 tests/docs/outputs.lua --check|--write [--light] [--times] [--bin BUILD] [--root SRC] [FILE.md ...]")
end
if mode == "write" then heavy = true end

local root = root_arg or "."
root = (capture("cd " .. shquote(root) .. " && pwd -P")):gsub("\n$", "")
if root == "" then die("no such folder: " .. tostring(root_arg)) end
local function abspath(p)
  if p:sub(1, 1) == "/" then return p end
  return root .. "/" .. p
end
bin = (capture("cd " .. shquote(abspath(bin)) .. " 2>/dev/null && pwd -P")):gsub("\n$", "")
if bin == "" or not io.open(bin .. "/femlod", "rb") then
  die("no femlod program in the build folder (give --bin BUILD)")
end
if #files == 0 then
  files = { "README.md" }
  local ls = capture("cd " .. shquote(root) .. " && ls docs/*.md")
  for f in ls:gmatch("[^\n]+") do files[#files + 1] = f end
end

-- a fresh folder per Markdown file
local function make_tmp()
  local dir = (capture("mktemp -d /tmp/femlod-docs.XXXXXX")):gsub("\n$", "")
  if dir == "" then die("mktemp failed") end
  check_ok("cp -R " .. shquote(root .. "/examples") .. " " .. shquote(dir .. "/examples")
    .. " && cd " .. shquote(dir) .. " && for f in examples/data/*; do "
    .. "[ \"$(basename \"$f\")\" = README.md ] || cp -R \"$f\" .; done")
  return dir
end

local ENV = "export PATH=\"$PWD/bin\":" .. shquote(bin) .. ":\"$PATH\"; export LUA_CPATH_5_4="
  .. shquote(bin .. "/?.so;;") .. "; export FEMLOD_BUILD=" .. shquote(bin) .. " FEMLOD_SOURCE="
  .. shquote(root) .. "; unset FEMLOD_MODEL_VIEWER; export LC_ALL=C; "

-- Runs the commands in `cmds` one after another in one shell in `dir`; returns one output
-- text a command (standard error merged) and their exit statuses.
local SEP = "\30FEMLODDOCSSEP"
local function run_cmds(dir, cmds)
  local script = { "cd " .. shquote(dir) .. " || exit 125", ENV }
  for _, c in ipairs(cmds) do
    script[#script + 1] = "{ " .. c .. "\n} </dev/null 2>&1; __st=$?; printf '\\n" .. SEP
      .. " %d\\n' \"$__st\"; (exit $__st)"
  end
  local path = dir .. "/.outputs.sh"
  writefile(path, table.concat(script, "\n") .. "\n")
  local out = capture("sh " .. shquote(path) .. " 2>&1")
  os.remove(path)
  local outs, stats = {}, {}
  local pos = 1
  for i = 1, #cmds do
    local s, e, st = out:find("\n" .. SEP .. " (%d+)\n", pos, false)
    if not s then die("command did not finish: " .. cmds[i] .. "\n" .. out:sub(pos)) end
    local text = out:sub(pos, s - 1):gsub("\n$", "")
    text = text:gsub(dir:gsub("%p", "%%%0"), SHOWN_TMP)
    text = text:gsub(bin:gsub("%p", "%%%0"), SHOWN_BIN)
    text = text:gsub(root:gsub("%p", "%%%0"), SHOWN_SOURCE)
    outs[i], stats[i] = text, tonumber(st)
    pos = e + 1
  end
  return outs, stats
end

local function masked(text, opts)
  local lines = {}
  for line in (text .. "\n"):gmatch("(.-)\n") do
    for _, name in ipairs(opts.mask) do
      for _, rule in ipairs(MASKS[name]) do line = line:gsub(rule[1], rule[2]) end
    end
    lines[#lines + 1] = line
  end
  if opts.unordered then table.sort(lines) end
  return table.concat(lines, "\n")
end

local function parse_marker(line)
  local body = line:match("^<!%-%-%s*(.-)%s*%-%->%s*$")
  if not body then return nil end
  local kw, rest = body:match("^(%a+)(.*)$")
  if kw ~= "output" and kw ~= "run" and kw ~= "file" then return nil end
  local optstr, cmd = rest:match("^([^:]*):%s*(.-)$")
  if not optstr then optstr, cmd = rest, nil end
  local opts = { kind = kw, cmd = cmd, mask = {} }
  for w in optstr:gmatch("%S+") do
    local k, v = w:match("^(%w+)=(.*)$")
    if k == "mask" then
      for m in v:gmatch("[^,]+") do
        if not MASKS[m] then return nil, "unknown mask '" .. m .. "'" end
        opts.mask[#opts.mask + 1] = m
      end
    elseif w == "heavy" or w == "unordered" then opts[w] = true
    else return nil, "unknown option '" .. w .. "'" end
  end
  if kw ~= "output" and not cmd then return nil, kw .. " needs ': ...'" end
  return opts
end

local function unified_diff(a, b, la, lb)
  local fa, fb = os.tmpname(), os.tmpname()
  writefile(fa, a .. "\n")
  writefile(fb, b .. "\n")
  local d = capture("diff -u --label " .. shquote(la) .. " --label " .. shquote(lb) .. " "
    .. shquote(fa) .. " " .. shquote(fb))
  os.remove(fa)
  os.remove(fb)
  return d
end

local differ, errors, checked, skipped = 0, 0, 0, 0

local function process(file)
  local errors_before = errors
  local path = abspath(file)
  local text = readfile(path)
  local lines = {}
  for line in text:gmatch("([^\n]*)\n") do lines[#lines + 1] = line end
  local out, dir = {}, nil
  local i, changed = 1, false
  while i <= #lines do
    local line = lines[i]
    out[#out + 1] = line
    local opts, err = parse_marker(line)
    if err then
      io.stderr:write(file, ":", i, ": ", err, "\n")
      errors = errors + 1
    elseif opts then
      dir = dir or make_tmp()
      if opts.kind == "run" then
        local _, st = run_cmds(dir, { opts.cmd })
        if st[1] ~= 0 then
          io.stderr:write(file, ":", i, ": set-up command exited ", st[1], ": ", opts.cmd, "\n")
          errors = errors + 1
        end
        i = i + 1
      else
        local fence = lines[i + 1] and lines[i + 1]:match("^(```+)")
        if not fence then
          io.stderr:write(file, ":", i, ": a marker must be followed by a fenced block\n")
          errors = errors + 1
          i = i + 1
        else
          local j = i + 2
          while lines[j] and lines[j] ~= fence do j = j + 1 end
          if not lines[j] then die(file .. ":" .. i .. ": unclosed block") end
          local block = table.concat(lines, "\n", i + 2, j - 1)
          local fresh
          if opts.kind == "file" then
            writefile(dir .. "/" .. opts.cmd, block .. "\n")
            fresh = block
          elseif opts.heavy and not heavy then
            skipped = skipped + 1
            fresh = block
          else
            checked = checked + 1
            local cmds, parts = {}, {}
            if opts.cmd then
              cmds[1] = opts.cmd
            else
              for k = i + 2, j - 1 do
                local c = lines[k]:match("^%$ (.*)$")
                if c then cmds[#cmds + 1] = c end
              end
              if #cmds == 0 then
                io.stderr:write(file, ":", i, ": a transcript with no '$ ' line\n")
                errors = errors + 1
              end
            end
            local t0 = times and tonumber((capture("date +%s.%N")))
            local outs, st = run_cmds(dir, cmds)
            if times then
              io.stderr:write(string.format("%s:%d: %.2f s\n", file, i,
                tonumber((capture("date +%s.%N"))) - t0))
            end
            for k, c in ipairs(cmds) do
              if st[k] == 126 or st[k] == 127 then
                io.stderr:write(file, ":", i, ": cannot run (exit ", st[k], "): ", c, "\n", outs[k], "\n")
                errors = errors + 1
              end
              if not opts.cmd then parts[#parts + 1] = "$ " .. c end
              if outs[k] ~= "" then parts[#parts + 1] = outs[k] end
            end
            fresh = table.concat(parts, "\n")
            if masked(fresh, opts) == masked(block, opts) then
              fresh = block
            elseif mode == "check" then
              differ = differ + 1
              io.stdout:write(file, ":", i + 1, ": the block differs from the fresh output\n",
                unified_diff(block, fresh, file .. ":" .. (i + 2), "fresh output"))
            end
          end
          if fresh ~= block then changed = true end
          for k = i + 1, i + 1 do out[#out + 1] = lines[k] end
          if fresh ~= "" then
            for l in (fresh .. "\n"):gmatch("(.-)\n") do out[#out + 1] = l end
          end
          out[#out + 1] = fence
          i = j + 1
        end
      end
    else
      i = i + 1
    end
  end
  if dir then check_ok("rm -rf " .. shquote(dir)) end
  if mode == "write" and changed and errors == errors_before then
    writefile(path .. ".tmp", table.concat(out, "\n") .. "\n")
    assert(os.rename(path .. ".tmp", path))
    io.stdout:write("rewrote ", file, "\n")
  end
end

for _, f in ipairs(files) do process(f) end
io.stdout:write(string.format("%d blocks run, %d heavy skipped, %d differ, %d errors\n",
  checked, skipped, differ, errors))
if errors > 0 then os.exit(2) end
if differ > 0 then os.exit(1) end
