-- test_progress.lua: femlod.progress (the bar's text, throttling, close,
-- options) and the bar of `femlod simplify` on a terminal (script(1)) and
-- its absence elsewhere.

local T = dofile((arg[0]:match("^(.*)/") or ".") .. "/check.lua")
local femlod = require "femlod"
local progress = require "femlod.progress"

local P = params
assert(P and P.femlod and P.tmp and P.shared, "run through ctest: needs femlod=, tmp=, shared=")
local quote = T.quote

-- A stream that keeps what is written.
local function sink()
  local s = { text = "", flushes = 0 }
  function s:write(x) self.text = self.text .. x return self end
  function s:flush() self.flushes = self.flushes + 1 return true end
  return s
end

-- A clock the test moves by hand.
local function fake_clock(t0)
  local c = { now = t0 or 100 }
  c.fn = function() return c.now end
  return c
end

do
  local out = sink()
  local clk = fake_clock()
  local bar = progress.bar { label = "work", stream = out, force = true, clock = clk.fn }
  T.eq(type(bar.update), "function", "bar.update is the progress function")
  T.check(out.text:find("^\r\27%[Kwork %[===%.+%]   0%%  0%.0 s  starting$"),
    "drawn when made, before any call: " .. T.show(out.text))
  -- set-up: done stays 0, the marker moves and the time counts
  local frames = {}
  for i = 1, 3 do
    clk.now = clk.now + 0.4
    T.eq(bar.update(0), nil, "update returns nothing: never stops the work")
    frames[i] = out.text:match("%[([^%]]*)%][^\r]*$")
  end
  T.check(frames[1] ~= frames[2] and frames[2] ~= frames[3], "the marker moves during the set-up: "
    .. table.concat(frames, " | "))
  T.check(out.text:find("1%.2 s  starting$"), "wall time counts during the set-up: " .. T.show(out.text))
  -- work: 1% a second after 1.2 s of set-up; no ETA below a few percent
  local function at(t, done)
    clk.now = 100 + t
    bar.update(done)
    return out.text:match("[^\r]*$")
  end
  local line = at(2.2, 0.01)
  T.check(line:find("  1%%  2%.2 s  %? %%/s  ETA %?$"), "no rate before half a second of progress: " .. line)
  line = at(2.7, 0.015)
  T.check(line:find("%[%.+%]   2%%  2%.7 s  1%.00 %%/s  ETA %?$"), "a rate with digits, no ETA at 1.5%: " .. line)
  line = at(4.2, 0.03)
  T.check(line:find("3%%  4%.2 s  1%.00 %%/s  ETA 1 min 37 s$"), "ETA from 3% on, from the rate: " .. line)
  -- a burst (3% in half a second) moves the smoothed rate only part way
  line = at(4.7, 0.06)
  T.check(line:find("6%%  4%.7 s  2%.50 %%/s  ETA 38 s$"), "smoothed rate: " .. line)
  local n = #out.text
  clk.now = clk.now + 0.05
  bar.update(0.07)
  T.eq(#out.text, n, "redraws at most 10 times a second")
  clk.now = clk.now + 0.01
  bar.update(1)
  T.check(out.text:find("%[########################%] 100%%", n + 1), "done is always drawn")
  bar:close()
  T.check(out.text:find("\r\27%[K$"), "close clears the line")
  local m = #out.text
  bar.update(0.7)
  bar:close()
  T.eq(#out.text, m, "a closed bar draws nothing")
  local quiet = sink()
  do
    local b <close> = progress.bar { stream = quiet }
    b.update(0.3)
  end
  T.eq(quiet.text, "", "a given stream without force: no bar")
  T.eq(progress.enabled(), false, "ctest's stderr is not a terminal")
  local clamp = sink()
  local c = progress.bar { stream = clamp, force = true, clock = fake_clock().fn }
  c.update(7)
  T.check(clamp.text:find("100%%"), "done above 1 is 1")
  T.checkerr("unknown option 'lable'; valid: clock, force, label, stream", progress.bar, { lable = "x" })
  T.checkerr("label: string expected, got number", progress.bar, { label = 1 })
  T.checkerr("clock: function expected, got number", progress.bar, { clock = 1 })
  T.checkerr("table expected, got string", progress.bar, "x")
  T.checkerr("0, 1 or 2 expected", femlod._isatty, 7)
end

-- The numbers: rates with two or three significant digits, durations as
-- people read them.
do
  local rt, tt = progress.rate_text, progress.time_text
  T.eq(rt(1.234), "1.23", "rate 1.23")
  T.eq(rt(0.35), "0.35", "rate 0.35")
  T.eq(rt(12.34), "12.3", "rate 12.3")
  T.eq(rt(123.4), "123", "rate 123")
  T.eq(rt(9.999), "10.0", "rate rounds up a range")
  T.eq(rt(0.0001), "<0.001", "rate below 0.001")
  T.eq(tt(4.14), "4.1 s", "4.1 s")
  T.eq(tt(35.4), "35 s", "35 s")
  T.eq(tt(125), "2 min 05 s", "2 min 05 s")
  T.eq(tt(3725), "1 h 02 min", "1 h 02 min")
end

-- Wall time, not CPU time: femlod._clock follows the wall while the
-- process sleeps (os.clock stands still).
do
  T.eq(type(femlod._clock), "function", "femlod._clock")
  local w0, c0 = femlod._clock(), os.clock()
  os.execute("sleep 0.3")
  local dw, dc = femlod._clock() - w0, os.clock() - c0
  T.check(dw >= 0.25 and dw < 5, "the wall clock moved across a sleep: " .. dw)
  T.check(dc < 0.2, "CPU time did not: " .. dc)
  local out = sink()
  local bar = progress.bar { stream = out, force = true }
  os.execute("sleep 0.3")
  bar.update(0)
  T.check(out.text:find("0%.[3-9] s  starting$") or out.text:find("[1-4]%.%d s  starting$"),
    "the default clock is the wall clock: " .. T.show(out.text))
  bar:close()
end

-- With simplify, as the CLI uses it: the result is the same as without.
do
  local m <close> = femlod.load(P.shared .. "/fandisk.obj")
  local out = sink()
  local bar <close> = progress.bar { label = "simplify", stream = out, force = true }
  local h1 <close> = m:simplify { target = 3000, progress = bar.update }
  local h2 <close> = m:simplify { target = 3000 }
  T.check(out.text:find("simplify %[#+%.*%]"), "the bar moved")
  T.eq(h1:mesh():quality().stretch_avg, h2:mesh():quality().stretch_avg, "the bar changes nothing")
  T.eq(h1:stats().stop_reason, "target", "not cancelled")
end

-- femlod simplify: a bar on a terminal, none in a pipe or with --quiet.
do
  local out_mesh = P.tmp .. "/progress_fan.obj"
  local line = quote(P.femlod) .. " simplify " .. quote(P.shared .. "/fandisk.obj") .. " " .. quote(out_mesh)
    .. " --target 3000"
  local p = io.popen("script -qec " .. quote(line) .. " /dev/null </dev/null")
  local tty = p:read("a")
  T.check(p:close(), "simplify under a terminal")
  T.check(tty:find("\27%[Ksimplify %[#+%.*%] +%d+%%"), "bar on the terminal")
  T.check(tty:find("\r\27%[Kmodel %(H x W x D%)"), "cleared before the report")
  p = io.popen(line .. " 2>&1 </dev/null")
  local piped = p:read("a")
  p:close()
  T.check(not piped:find("simplify %["), "no bar in a pipe")
  T.check(piped:find("^model %(H x W x D%)"), "report first")
  p = io.popen("script -qec " .. quote(quote(P.femlod) .. " -q simplify " .. quote(P.shared .. "/fandisk.obj") .. " "
    .. quote(out_mesh) .. " --target 3000") .. " /dev/null </dev/null")
  local q = p:read("a")
  p:close()
  T.eq(q, "", "--quiet: nothing, not even the bar")
  os.remove(out_mesh)
end

-- {====== the progress option of the long operations: called about every
-- 1%, non-decreasing in [0, 1], ending at 1; it changes nothing; true
-- cancels with the error "cancelled" and leaves the hierarchy valid; an
-- error in it comes through; another result type is an argument error.
local function recorder(stop_at)
  local r = { calls = 0, ordered = true, last = -1 }
  r.fn = function(d)
    r.calls = r.calls + 1
    r.ordered = r.ordered and type(d) == "number" and d >= r.last and d <= 1
    r.last = d
    return stop_at ~= nil and r.calls == stop_at or nil
  end
  return r
end
local function finished(r, what)
  T.check(r.calls >= 20 and r.calls <= 205, what .. ": calls about every 1%: " .. r.calls)
  T.check(r.ordered, what .. ": non-decreasing in [0, 1]")
  T.eq(r.last, 1, what .. ": ends at 1")
end
local function serial(m)
  local t = {}
  for _, p in ipairs(m:positions()) do t[#t + 1] = ("%.17g %.17g %.17g"):format(p[1], p[2], p[3]) end
  for _, f in ipairs(m:triangles()) do t[#t + 1] = table.concat(f, " ") end
  return table.concat(t, "\n")
end
local function cancelled(f, what)
  local ok, e = pcall(f)
  T.check(not ok and tostring(e):find("^[^:]*test_progress%.lua:%d+: cancelled$") ~= nil,
    what .. ": true cancels with 'cancelled' at the caller's line: " .. tostring(e))
end

do
  local m <close> = femlod.load(P.shared .. "/fandisk.obj")
  local b = m:bbox()
  local c, d = {}, 0
  for k = 1, 3 do c[k] = (b.min[k] + b.max[k]) / 2; d = d + (b.max[k] - b.min[k]) ^ 2 end
  local sphere = { center = c, radius = math.sqrt(d) / 4 }

  -- simplify: its bar covers the building of the hierarchy, up to 1
  local r = recorder()
  local h <close> = m:simplify { target = 1500, progress = r.fn }
  finished(r, "simplify")

  -- curvature
  r = recorder()
  local k1 = m:curvature { progress = r.fn }
  local k0 = m:curvature()
  finished(r, "curvature")
  T.eq(table.concat(k1.kappa, " "), table.concat(k0.kappa, " "), "curvature: the same with progress")
  cancelled(function() return m:curvature { progress = recorder(5).fn } end, "curvature")

  -- refine_region, refine_curvature and rescale, each on a fresh hierarchy
  -- against the same call without progress
  local ops = {
    { "refine_region", function(x, p) return x:refine_region { sphere = sphere, size = 0, progress = p } end, 10 },
    -- the curvature is the first 90% (about 100 calls): a cancel at 120 comes in the refinement
    { "refine_curvature", function(x, p) return x:refine_curvature { progress = p } end, 120 },
    { "rescale", function(x, p) return x:rescale { factor = 3, progress = p } end, 10 },
  }
  for _, op in ipairs(ops) do
    local name, call = op[1], op[2]
    local a <close> = m:simplify { target = 1500 }
    local g <close> = m:simplify { target = 1500 }
    r = recorder()
    T.eq(call(a, r.fn), call(g, nil), name .. ": the same operations with progress")
    finished(r, name)
    T.eq(serial(a:mesh()), serial(g:mesh()), name .. ": the same front with progress")
    local x <close> = m:simplify { target = 1500 }
    cancelled(function() return call(x, recorder(op[3]).fn) end, name)
    T.eq(x:validate(), true, name .. ": valid after a cancel")
    local n = x:mesh():counts().triangles
    T.check(n > 1500 and n < a:mesh():counts().triangles, name .. ": cancelled part way: " .. n)
    local boom = setmetatable({}, { __tostring = function() return "boom" end })
    local ok, e = pcall(call, x, function() error(boom) end)
    T.check(not ok and e == boom, name .. ": the function's error value comes through")
    T.checkerr("progress: function returned number %(boolean or nil expected%)", call, x, function() return 1 end)
    T.checkerr("progress: function expected, got string", call, x, "yes")
    T.eq(x:validate(), true, name .. ": valid after the errors")
    ok, e = pcall(call, x, function() return x:counts() end)
    T.check(not ok and e:find("attempt to use a femlod.Hierarchy inside its own size or progress function$"),
      name .. ": the hierarchy is busy inside its progress function: " .. tostring(e))
    T.eq(x:validate(), true, name .. ": usable again after")
  end

  -- the deviation of m:quality(reference) and femlod.report
  local s <close> = h:mesh()
  r = recorder()
  local q1 = s:quality(m, { progress = r.fn })
  finished(r, "hausdorff")
  T.eq(q1.hausdorff, s:quality(m).hausdorff, "hausdorff: the same with progress")
  cancelled(function() return s:quality(m, { progress = recorder(3).fn }) end, "hausdorff")
  T.checkerr("options without a reference", s.quality, s, nil, { progress = print })
  T.checkerr("unknown key 'progres'", s.quality, s, m, { progres = print })
  r = recorder()
  local rep = femlod.report(s, { reference = m, progress = r.fn })
  finished(r, "report")
  T.eq(rep.hausdorff or q1.hausdorff, q1.hausdorff, "report: the same deviation")
  T.checkerr("progress: function expected, got number", femlod.report, s, { reference = m, progress = 1 })
end
-- }======

-- {====== bars in the program: the deviation of report and info on a
-- terminal, none in a pipe or with --quiet; femlod.quiet turns femlod.progress off
do
  local fan = P.shared .. "/fandisk.obj"
  local small = P.tmp .. "/progress_small.obj"
  local m <close> = femlod.load(fan)
  local h <close> = m:simplify { target = 2000 }
  h:mesh():save(small)
  for _, args in ipairs { { "report", small, "--reference", fan }, { "info", small, "reference=" .. fan } } do
    local line = quote(P.femlod) .. " " .. table.concat({ quote(args[1]), quote(args[2]), quote(args[3]), args[4] and quote(args[4]) or "" }, " ")
    local p = io.popen("script -qec " .. quote(line) .. " /dev/null </dev/null")
    local tty = p:read("a")
    T.check(p:close(), args[1] .. " under a terminal")
    T.check(tty:find("\27%[Khausdorff %[#+%.*%] +%d+%%"), args[1] .. ": a bar on the terminal")
    T.check(tty:find("\r\27%[K[%w(]"), args[1] .. ": cleared before the report")
    p = io.popen(line .. " 2>&1 </dev/null")
    local piped = p:read("a")
    p:close()
    T.check(not piped:find("hausdorff %[") and not piped:find("\27"), args[1] .. ": no bar in a pipe")
    p = io.popen("script -qec " .. quote(quote(P.femlod) .. " -q " .. line:sub(#quote(P.femlod) + 2)) .. " /dev/null </dev/null")
    local q = p:read("a")
    p:close()
    T.check(not q:find("hausdorff %["), args[1] .. " --quiet: no bar")
  end
  local code = "io.write(tostring(require('femlod.progress').enabled()))"
  local p = io.popen("script -qec " .. quote(quote(P.femlod) .. " -e " .. quote(code)) .. " /dev/null </dev/null")
  T.eq(p:read("a"), "true", "a terminal: femlod.progress draws")
  p:close()
  p = io.popen("script -qec " .. quote(quote(P.femlod) .. " -q -e " .. quote(code)) .. " /dev/null </dev/null")
  T.eq(p:read("a"), "false", "a terminal with --quiet: femlod.progress does not draw")
  p:close()
  os.remove(small)
end
-- }======

T.summary("test_progress")
