-- check.lua: the test harness of tests/lua (tests/c/check.h in Lua; the
-- error checks follow Lua's testes/errors.lua). Load it with
--   local T = dofile((arg[0]:match("^(.*)/") or ".") .. "/check.lua")
-- Checks count failures and go on; T.summary() prints the closing line
-- "N passed, N failed" and raises when anything failed, so the recipe (and
-- ctest) fails.
--
-- Error positions: luaL_error names the *Lua* function that called the
-- failing C function. pcall(femlod.load, x) has no Lua caller (pcall is C),
-- so its message has no position: wrap the call in a Lua function, or use
-- T.errmsg with a code string, whose chunk is named "code" so that the
-- message reads "code:1: ..." and the position is pinned exactly.

local M = { passed = 0, failed = 0 }

-- "test_x.lua:LINE" of the check's caller, for failure reports.
local function where(level)
  local info = debug.getinfo(level + 1, "Sl")
  return (info.short_src:match("[^/]*$") or "?") .. ":" .. tostring(info.currentline)
end

local function pass() M.passed = M.passed + 1 end

local function fail(level, fmt, ...)
  M.failed = M.failed + 1
  io.stderr:write(where(level + 1), ": check failed: ", string.format(fmt, ...), "\n")
end

-- Quote a value for a failure message.
local function show(v)
  if type(v) == "string" then return string.format("%q", v) end
  if math.type(v) == "float" then return string.format("%.17g", v) end
  return tostring(v)
end
M.show = show

function M.check(cond, msg)
  if cond then pass() else fail(2, "%s", msg or "condition is false") end
  return cond
end

function M.eq(got, expected, msg)
  if got == expected then pass() return true end
  fail(2, "%s: got %s, expected %s", msg or "value", show(got), show(expected))
  return false
end

-- |got - expected| <= tol (absolute).
function M.near(got, expected, tol, msg)
  if type(got) == "number" and math.abs(got - expected) <= tol then pass() return true end
  fail(2, "%s: got %s, expected %s (tolerance %g)", msg or "value", show(got), show(expected), tol)
  return false
end

-- Relative tolerance, as the reference figures are given: 1e-6 relative.
function M.rel(got, expected, tol, msg)
  local scale = math.max(math.abs(expected), 1e-300)
  if type(got) == "number" and math.abs(got - expected) <= tol * scale then pass() return true end
  fail(2, "%s: got %s, expected %s (relative tolerance %g)", msg or "value", show(got),
    show(expected), tol)
  return false
end

-- f(...) must raise an error whose message matches the Lua pattern; returns
-- the message (or nil).
function M.checkerr(pattern, f, ...)
  local ok, msg = pcall(f, ...)
  if ok then
    fail(2, "no error, expected one matching %s", show(pattern))
  elseif type(msg) ~= "string" then
    fail(2, "error value is a %s, expected a string matching %s", type(msg), show(pattern))
  elseif not string.find(msg, pattern) then
    fail(2, "error %s does not match %s", show(msg), show(pattern))
  else
    pass()
    return msg
  end
end

-- Runs code (a string, chunk name "code", so the first line is "code:1:")
-- with the names in env visible beside the globals, and checks that its
-- error message equals expected exactly.
function M.errmsg(expected, code, env)
  local e = setmetatable({}, { __index = function(_, k)
    if env and env[k] ~= nil then return env[k] end
    return _ENV[k]
  end })
  local chunk, cerr = load(code, "=code", "t", e)
  if not chunk then
    fail(2, "code does not compile: %s", cerr)
    return
  end
  local ok, msg = pcall(chunk)
  if ok then
    fail(2, "no error from %s, expected %s", show(code), show(expected))
  elseif msg ~= expected then
    fail(2, "error from %s:\n    got      %s\n    expected %s", show(code), show(msg),
      show(expected))
  else
    pass()
  end
end

-- The line number of the caller, to pin positions inside the test file.
function M.line()
  return debug.getinfo(2, "l").currentline
end

-- Whole file as a string, or nil.
function M.readfile(path, mode)
  local f = io.open(path, mode or "rb")
  if not f then return nil end
  local s = f:read("a")
  f:close()
  return s
end

function M.writefile(path, text)
  local f = assert(io.open(path, "wb"))
  assert(f:write(text))
  assert(f:close())
end

function M.exists(path)
  local f = io.open(path, "rb")
  if f then f:close() return true end
  return false
end

-- A CSV file (a sweep's results.csv) as a list of rows (name -> text) and
-- the header, RFC 4180 quoting.
function M.read_csv(file)
  local text = assert(M.readfile(file), file)
  local rows, header = {}, nil
  local pos = 1
  while pos <= #text do
    local fields = {}
    while true do
      local v
      if text:sub(pos, pos) == '"' then
        local s, i = {}, pos + 1
        while true do
          local q = text:find('"', i, true)
          s[#s + 1] = text:sub(i, q - 1)
          if text:sub(q + 1, q + 1) == '"' then
            s[#s + 1] = '"'
            i = q + 2
          else
            pos = q + 1
            break
          end
        end
        v = table.concat(s)
      else
        local e = text:find("[,\n]", pos) or #text + 1
        v = text:sub(pos, e - 1)
        pos = e
      end
      fields[#fields + 1] = v
      local c = text:sub(pos, pos)
      pos = pos + 1
      if c ~= "," then break end
    end
    if not header then
      header = fields
    else
      local row = {}
      for i, k in ipairs(header) do row[k] = fields[i] end
      rows[#rows + 1] = row
    end
  end
  return rows, header
end

-- s single-quoted for sh.
function M.quote(s)
  return "'" .. tostring(s):gsub("'", "'\\''") .. "'"
end

-- A shell runner whose stderr goes to errfile: runner.sh(line) runs a
-- command line, runner.run(...) the program with the words as arguments
-- (quoted); each returns exit code, stdout, stderr. A signal is a failure.
function M.runner(program, errfile)
  local r = {}
  function r.sh(line)
    local p = assert(io.popen(line .. " 2>" .. M.quote(errfile) .. " </dev/null", "r"))
    local out = p:read("a")
    local _, how, code = p:close()
    if how ~= "exit" then fail(2, "ended by signal %s: %s", tostring(code), line) end
    return code, out, M.readfile(errfile) or ""
  end
  function r.run(...)
    local parts = { M.quote(program) }
    for i = 1, select("#", ...) do parts[#parts + 1] = M.quote((select(i, ...))) end
    return r.sh(table.concat(parts, " "))
  end
  -- A usage error: exit 2, nothing on stdout, expect as stderr's first line.
  function r.usage(expect, ...)
    local code, out, err = r.run(...)
    local args = table.concat({ ... }, " ")
    M.eq(code, 2, "exit 2 for: " .. args)
    M.eq(out, "", "nothing on stdout for: " .. args)
    M.eq(err:match("^[^\n]*"), expect, "message for: " .. args)
  end
  return r
end

-- The closing line CI reads; raises (level 0: no position) on any failure.
function M.summary(name)
  print(string.format("%d passed, %d failed", M.passed, M.failed))
  if M.failed > 0 then error(string.format("%s: %d check(s) failed", name, M.failed), 0) end
  if M.passed == 0 then error(name .. ": no check ran", 0) end
end

-- False under FEMLOD_TEST_HEAVY=0 (the sanitizer pass): tests skip their
-- slow parts (whole example recipes on the cover) there.
M.heavy = os.getenv("FEMLOD_TEST_HEAVY") ~= "0"

return M
